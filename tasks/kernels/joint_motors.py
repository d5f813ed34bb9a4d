"""The joint_motors realisation of the two-wheel family: a robot file's own actuators on
two named joints, ``forward``, the joint whose motion moves the robot forward (a wheel's
hinge rolling on the floor, or a slide along the base's heading), and ``turn``, the hinge
whose rotation turns it about z (tasks.realisations.joint_motors reads the model). They
are the target plan's two joints (tasks.kernels.plan: its phases, and its controller by
the actuators' kind: torque motors, position servos or velocity servos): a turn by
`angle` moves the turn joint's target by angle, a move by `distance` units the forward
joint's by distance * joint_per_unit (unit / radius for a wheel, unit for a slide)."""
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled import records
from tasks.kernels import two_wheel as family
from tasks.kernels.body import BODY_FIELDS, base_pose
from tasks.kernels.plan import PLAN_FIELDS, aim, back, halt, keep, phase
from tasks.kernels.wheels import RAMP_FIELDS


@records.record(*BODY_FIELDS, *family.FAMILY_FIELDS,
                # the ramps' substeps (tasks.kernels.wheels.ramp_substeps); the forward
                # joint's motion per unit moved, the turn joint's per radian turned
                *RAMP_FIELDS, "joint_per_unit", "per_rad",
                # the target plan's fields (tasks.kernels.plan: the forward joint, then
                # the turn joint)
                *PLAN_FIELDS)
class JointMotorsRecord(records.Record):
    """The joint motors' record (the fields' comments)."""


JointMotorsRecord.constructor = njit(cache=True)(lambda *values: JointMotorsRecord(*values))


@njit(cache=True)
def turn(s, angle, leftover):
    """Turns by `angle` rad counter-clockwise over the turn phase."""
    aim(s, 0.0, angle * s.per_rad, s.ramp_turn)
    return phase(s, s.n_turn, 0.0, False)


@njit(cache=True)
def move(s, distance):
    """Moves `distance` units forward over the move phase, ending where the body touches
    the room."""
    aim(s, distance * s.joint_per_unit, 0.0, s.ramp_move)
    heading = base_pose(s)[2]
    return phase(s, s.n_move, heading, not family.clear_ahead(s, heading, distance))


#: The two-wheel family's step on this body (tasks.kernels.two_wheel.act, through
#: tasks.kernels.env_step.action): the turn, move and halt phases, then how a refused
#: move's state is kept and given back.
PHASES = (turn, move, halt, keep, back)
