"""Every task parameter, with the paper's values (and this replication's readings) as
defaults: the task's counterpart of ebrl.Config. A run records it whole in config.json,
and `ebrl run --set NAME=VALUE` changes any field, as it does the agent's.
"""
import dataclasses
import math

#: The floating drive's bump readings (docs/interpretation.md, "Floating bump").
BUMPS = ("grip", "stop", "slide", "bounce")


@dataclasses.dataclass(frozen=True)
class TaskConfig:
    # Section 3.2: readings of range 14 units, with Gaussian noise of sd 5% of 255.
    sensor_range: float = 14.0
    sensor_noise: float = 0.05 * 255
    # Section 3.3: each action part scaled by a factor drawn from [1 - 0.05, 1].
    action_noise: float = 0.05
    # Section 3.1: the start jittered by +-3 units and +-15 degrees (uniform).
    start_jitter: bool = True
    start_jitter_xy: float = 3.0
    start_jitter_heading: float = 15.0  # degrees
    # Readings the paper leaves open.
    #: The floating drive at a wall: "grip" (the bumper's friction takes the motion into
    #: the wall and most along it), "stop" (the velocity set to zero at contact),
    #: "slide" (frictionless walls: the motion along the wall is kept), "bounce" (the
    #: velocity reflected off the wall, elastically). Two-wheel robots ignore it.
    bump: str = BUMPS[0]
    #: The robot's radius in units; None keeps its file's (1.5 for the paper's robots).
    radius: float = None

    def __post_init__(self):
        for name in ("sensor_range", "sensor_noise", "action_noise", "start_jitter_xy",
                     "start_jitter_heading", "radius"):
            v = getattr(self, name)
            if v is None and name == "radius":
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
            if v < 0 or (v == 0 and name in ("sensor_range", "radius")):
                raise ValueError(f"{name} must be {'positive' if name in ('sensor_range', 'radius') else 'non-negative'}, got {v!r}")
        if self.action_noise >= 1:
            raise ValueError(f"action_noise must be below 1, got {self.action_noise!r}")
        if self.radius is not None and self.radius > 5:
            raise ValueError(f"radius must be at most 5 units (the corridors are 10 wide), got {self.radius!r}")
        if not isinstance(self.start_jitter, bool):
            raise ValueError(f"start_jitter must be true or false, got {self.start_jitter!r}")
        if self.bump not in BUMPS:
            raise ValueError(f"bump must be one of {', '.join(BUMPS)}, got {self.bump!r}")
