"""The servos realisation of the two-wheel family: a planar base whose velocity servos
``forward`` and ``turn`` (and ``grip``) drive the speed along the heading and the yaw
rate directly (the paper's ``two_wheel`` robot; tasks.realisations.servos reads the
model). A turn of angle A over n substeps is the yaw rate A / (n dt), a move of D units
the speed D / (n dt); the servos are deadbeat, so the phase does it. A move ends where
the body first touches the room (Section 3.3): a substep that would reach a wall goes
just that far (tasks.kernels.two_wheel.room_ahead), and the move stops there."""
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled import records
from tasks.kernels import bindings, two_wheel as family
from tasks.kernels.body import BODY_FIELDS, base_pose, step_phase


@records.record(*BODY_FIELDS, *family.FAMILY_FIELDS, "forward_actuator", "turn_actuator",
                "turn_sign")
class ServosRecord(records.Record):
    """The servos' record: the body, the family's fields, the two servos' ids, the turn
    servo's sense (1: its control turns the base counter-clockwise; -1: a servo on a
    hinge about -z, or of a negative gear)."""


ServosRecord.constructor = njit(cache=True)(lambda *values: ServosRecord(*values))


@njit(cache=True)
def drive(s, speed, yaw_rate):
    """Servo targets: speed in units/s along the heading, yaw rate in rad/s."""
    s.ctrl[s.forward_actuator] = speed * s.unit
    s.ctrl[s.turn_actuator] = yaw_rate * s.turn_sign


@njit(cache=True)
def turn(s, angle, leftover):
    """Turns by `angle` rad counter-clockwise over the turn phase's substeps."""
    n = s.n_turn
    drive(s, 0.0, angle / (n * s.timestep))
    return step_phase(s, n), n


@njit(cache=True)
def move(s, distance):
    """Moves `distance` units forward over the move phase's substeps, at one speed, until
    the body touches the room: a substep that would go further than the room ahead
    (family.room_ahead) goes that far, and once touching the move ends. Returns (status,
    substeps run)."""
    n = s.n_move
    speed = distance / (n * s.timestep)
    _, _, heading = base_pose(s)
    if family.clear_ahead(s, heading, distance):  # the whole phase at once
        drive(s, speed, 0.0)
        return step_phase(s, n), n
    per = speed * s.timestep
    for k in range(n):
        ahead = family.room_ahead(s, heading, 2 * per)
        if ahead <= family.TOUCH:
            return bindings.OK, k
        drive(s, speed if ahead >= per else ahead / s.timestep, 0.0)
        status = step_phase(s, 1)
        if status != bindings.OK:
            return status, k + 1
    return bindings.OK, n


@njit(cache=True)
def halt(s):
    """Both servos' speeds 0."""
    drive(s, 0.0, 0.0)
    return bindings.OK, 0


#: The two-wheel family's step on this body (tasks.kernels.two_wheel.act, through
#: tasks.kernels.env_step.action): the turn, move and halt phases, then how a refused
#: move's state is kept and given back.
PHASES = (turn, move, halt, family.save_state, family.restore_state)
