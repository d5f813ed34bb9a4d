"""The wheel_motors realisation of the two-wheel family: two wheel hinges (contract
names ``left``, ``right``) turned through a robot file's own torque motors
(``motor_0``, ``motor_1``, ...: on the wheel joints or on tendons over them), none
added (the MuJoCo car, models/mounts/car.toml; tasks.realisations.wheel_motors reads the
model). The wheels' angles are the target plan's two joints (tasks.kernels.plan: a
phase moves the wheels' targets over its ramp, then lets them settle), held by its
TORQUE controller: the PD torques tau = kp (target - q) - kv dq and the motors'
controls that give them."""
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled import records
from tasks.kernels import two_wheel as family
from tasks.kernels.body import BODY_FIELDS, base_pose
from tasks.kernels.plan import PLAN_FIELDS, aim, back, halt, keep, phase
from tasks.kernels.wheels import RAMP_FIELDS, WHEEL_FIELDS, move_angles, turn_angles


@records.record(*BODY_FIELDS, *family.FAMILY_FIELDS, *RAMP_FIELDS, *WHEEL_FIELDS, *PLAN_FIELDS)
class WheelMotorsRecord(records.Record):
    """The wheel motors' record: the body, the family's fields, the ramps, the wheels'
    geometry, the target plan's fields (its joints the wheel hinges)."""


WheelMotorsRecord.constructor = njit(cache=True)(lambda *values: WheelMotorsRecord(*values))


@njit(cache=True)
def turn(s, angle, leftover):
    """Turns by `angle` rad counter-clockwise over the turn phase (wheels.turn_angles)."""
    left, right = turn_angles(s, angle)
    aim(s, left, right, s.ramp_turn)
    return phase(s, s.n_turn, 0.0, False)


@njit(cache=True)
def move(s, distance):
    """Moves `distance` units forward over the move phase (wheels.move_angles), ending
    where the body touches the room."""
    left, right = move_angles(s, distance)
    aim(s, left, right, s.ramp_move)
    heading = base_pose(s)[2]
    return phase(s, s.n_move, heading, not family.clear_ahead(s, heading, distance))


#: The two-wheel family's step on this body (tasks.kernels.two_wheel.act, through
#: tasks.kernels.env_step.action): the turn, move and halt phases, then how a refused
#: move's state is kept and given back.
PHASES = (turn, move, halt, keep, back)
