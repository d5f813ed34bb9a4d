"""Every task parameter, with the paper's values (and, for a reading, its registry default:
tasks/readings.py) as defaults: the task's counterpart of ebrl.Config. A run records it whole in config.json,
and `ebrl run --set NAME=VALUE` changes any field, as it does the agent's.
"""
import dataclasses
import math

from tasks import readings

def _default(name):
    """A reading field's default: its registry entry's (tasks/readings.py)."""
    return readings.READING_BY_NAME[name].default


@dataclasses.dataclass(frozen=True)
class TaskConfig:
    # Section 3.2: rangefinders of range 14 units, with Gaussian noise of sd 5% of 255.
    sensor_range: float = 14.0
    sensor_noise: float = 0.05 * 255
    # Section 3.3: each action part scaled by a factor drawn from [1 - 0.05, 1] (a reading:
    # the floating robot's is open).
    action_noise: float = _default("action_noise")
    # Section 3.1: the start jittered by +-3 units and +-15 degrees (uniform).
    start_jitter: bool = True
    start_jitter_xy: float = 3.0
    start_jitter_heading: float = 15.0  # degrees
    # Readings the paper leaves open (tasks/readings.py: each one's values, scope and
    # description; docs/interpretation.md: its reason). Each drive ignores the others'.
    bump: str = _default("bump")
    radius: float = _default("radius")
    thrust: str = _default("thrust")
    wall_friction: float = _default("wall_friction")
    restitution: float = _default("restitution")
    velocity_noise: float = _default("velocity_noise")
    velocity_code: str = _default("velocity_code")
    #: The two-wheel drive when a collision stops a move (Section 3.3: "if the agent
    #: cannot move any more because of collision with an object, the rest portion of move
    #: is transferred into the angle of turn").
    blocked_move: str = _default("blocked_move")
    leftover_turn: str = _default("leftover_turn")

    def __post_init__(self):
        for name in ("sensor_range", "sensor_noise", "start_jitter_xy", "start_jitter_heading"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
            if v < 0 or (v == 0 and name == "sensor_range"):
                sign = "positive" if name == "sensor_range" else "non-negative"
                raise ValueError(f"{name} must be {sign}, got {v!r}")
        if not isinstance(self.start_jitter, bool):
            raise ValueError(f"start_jitter must be true or false, got {self.start_jitter!r}")
        for reading in readings.TASK:
            reading.check(getattr(self, reading.name))
