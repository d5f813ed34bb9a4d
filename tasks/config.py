"""Every task parameter, with the paper's values (and this replication's readings) as
defaults: the task's counterpart of ebrl.Config. A run records it whole in config.json,
and `ebrl run --set NAME=VALUE` changes any field, as it does the agent's.
"""
import dataclasses
import math

#: The floating drive's bump readings (docs/interpretation.md, "Floating bump").
BUMPS = ("grip", "stop", "slide", "bounce")
#: The floating drive's thrust readings (docs/interpretation.md, "Floating thrust").
THRUSTS = ("scaled", "demand", "clipped")
#: The floating drive's velocity sensing: as measured, or through a 0-255 code like the
#: rangefinders' (docs/interpretation.md, "Velocity sensing").
VELOCITY_CODES = ("none", "code")
#: The two-wheel drive's blocked move (docs/interpretation.md, "Blocked move"): "stop" at
#: contact and turn the rest, or "refuse" the move whole (undone) and turn all of it.
BLOCKED_MOVES = ("stop", "refuse")
#: Which way a blocked move's rest turns: the commanded turn's ("commanded", right when
#: a = 0), or "away" from the side whose beams read nearer at the blocked pose.
LEFTOVER_TURNS = ("commanded", "away")


@dataclasses.dataclass(frozen=True)
class TaskConfig:
    # Section 3.2: rangefinders of range 14 units, with Gaussian noise of sd 5% of 255.
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
    #: The floating drive's velocity change per step for a demand a in [-1, 1]:
    #: "scaled" 0.2 a (Section 3.3's maximum of 0.2 units per square step), "demand" a
    #: itself (Section 3.3's example read literally), "clipped" a clipped to [-0.2, 0.2].
    thrust: str = THRUSTS[0]
    #: The floating bumper's sliding friction against the walls (None: its file's, 1);
    #: acts with the bump reading "grip".
    wall_friction: float = None
    #: The share of the speed into a wall that the bump reading "bounce" reflects (1:
    #: elastic, 0: the motion into the wall stops, the motion along it is kept).
    restitution: float = 1.0
    #: The floating drive's velocity reading: Gaussian noise of this sd (units/step), then
    #: "none" (the value as it is) or "code" (the 0-255 code of the velocity over
    #: +-VELOCITY_FULL_SCALE, decoded back to units/step).
    velocity_noise: float = 0.0
    velocity_code: str = VELOCITY_CODES[0]
    #: The two-wheel drive when a collision stops a move (Section 3.3: "if the agent
    #: cannot move any more because of collision with an object, the rest portion of move
    #: is transferred into the angle of turn"): BLOCKED_MOVES, LEFTOVER_TURNS above.
    #: Floating robots ignore them.
    blocked_move: str = BLOCKED_MOVES[0]
    leftover_turn: str = LEFTOVER_TURNS[0]

    def __post_init__(self):
        for name in ("sensor_range", "sensor_noise", "action_noise", "start_jitter_xy",
                     "start_jitter_heading", "radius", "wall_friction", "restitution",
                     "velocity_noise"):
            v = getattr(self, name)
            if v is None and name in ("radius", "wall_friction"):
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
            if v < 0 or (v == 0 and name in ("sensor_range", "radius")):
                sign = "positive" if name in ("sensor_range", "radius") else "non-negative"
                raise ValueError(f"{name} must be {sign}, got {v!r}")
        if self.action_noise >= 1:
            raise ValueError(f"action_noise must be below 1, got {self.action_noise!r}")
        if self.radius is not None and self.radius > 5:
            raise ValueError("radius must be at most 5 units (the corridors are 10 wide), "
                             f"got {self.radius!r}")
        if not isinstance(self.start_jitter, bool):
            raise ValueError(f"start_jitter must be true or false, got {self.start_jitter!r}")
        if self.restitution > 1:
            raise ValueError(f"restitution must be at most 1, got {self.restitution!r}")
        for name, valid in (("bump", BUMPS), ("thrust", THRUSTS), ("velocity_code", VELOCITY_CODES),
                            ("blocked_move", BLOCKED_MOVES), ("leftover_turn", LEFTOVER_TURNS)):
            if getattr(self, name) not in valid:
                raise ValueError(f"{name} must be one of {', '.join(valid)}, got {getattr(self, name)!r}")
