"""The two-wheel family on a robot file's own actuators on two named joints: ``forward``,
the joint whose motion moves the robot forward (a wheel's hinge rolling on the floor, or
a slide along the base's heading), and ``turn``, the hinge whose rotation turns it about
z (a mount's joint_motors; tasks.two_wheel.JointMotorPhysics reads the model). The plan
and its phases are the wheel motors' (tasks.kernels.motors: plan, wheel_phase): a phase
moves the joints' targets over its ramp, then lets them settle; a turn by `angle` moves
the turn joint's target by angle, a move by `distance` units the forward joint's by
distance * joint_per_unit (unit / radius for a wheel, unit for a slide). At every
substep a controller turns the targets into the actuators' controls, by the actuators'
kind (MODES):

- TORQUE (motors): the PD torques tau = kp (target - q) - kv dq, and the motors'
  controls of least norm that give them (tasks.kernels.motors.motor_controls, over the
  motors' forces measured at load, as the car's wheel motors);
- POSITION (position servos): each servo's control is its length at the targets,
  length0 + sum_j gain[k, j] (target_j - rest_j) (gain: its length per unit of joint
  j, measured at load; the servo's own gains hold it there);
- VELOCITY (velocity servos): the joints' speeds v = kp (target - q), each servo's
  control its speed at those, sum_j gain[k, j] v_j.

Each control is clipped to its actuator's range."""
from numba import njit
from numba.extending import overload

from ebrl import compiled  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from ebrl import records
from tasks.kernels import bindings, two_wheel as family
from tasks.kernels.body import BODY_FIELDS
from tasks.kernels.motors import back, hold_here, keep, motor_controls, plan, set_controls

#: The controllers, by the kind of the actuators on the joints.
TORQUE, POSITION, VELOCITY = 0, 1, 2
#: Their names, as the docs and errors write them.
MODES = ("torque motors", "position servos", "velocity servos")


@records.record(*BODY_FIELDS, *family.FAMILY_FIELDS,
                # the ramps' substeps (tasks.kernels.wheels.ramp_substeps); the forward
                # joint's motion per unit moved, the turn joint's per radian turned
                "ramp_turn", "ramp_move", "joint_per_unit", "per_rad",
                # the forward and turn joints' qpos and dof addresses and rest positions;
                # the actuators, the controller (MODES), the motors' forces and their
                # Gram matrix (TORQUE), the actuators' length per unit of each joint and
                # their lengths at rest (POSITION, VELOCITY), the controls' ranges; the
                # gains
                "joint_q", "joint_dof", "rest", "motors", "mode", "forces", "gram", "gain",
                "length0", "ctrl_lo", "ctrl_hi", "kp", "kv",
                # the plan's state (targets, their step per ramp substep, the ramp's
                # substeps left), scratch and the state a refused move returns to
                "target", "delta", "ramp_left", "tau", "controls", "target0", "ramp_left0")
class JointDrive(records.Record):
    """The joint motors' record (the fields' comments)."""


JointDrive.constructor = njit(cache=True)(lambda *values: JointDrive(*values))


@njit(cache=True)
def controls(s):
    """The actuators' controls for the joints' targets, by the controller (the module's
    docstring), into s.controls."""
    target, tau, c, q, dq = s.target, s.tau, s.controls, s.joint_q, s.joint_dof
    qpos, qvel = s.qpos, s.qvel
    if s.mode == TORQUE:
        for j in range(2):
            tau[j] = s.kp * (target[j] - qpos[q[j]]) - s.kv * qvel[dq[j]]
        motor_controls(s.forces, s.gram, tau, s.ctrl_lo, s.ctrl_hi, c)
        return
    for j in range(2):
        if s.mode == POSITION:
            tau[j] = target[j] - s.rest[j]
        else:
            tau[j] = s.kp * (target[j] - qpos[q[j]])
    for k in range(c.shape[0]):
        u = s.length0[k] if s.mode == POSITION else 0.0
        u += s.gain[k, 0] * tau[0] + s.gain[k, 1] * tau[1]
        c[k] = min(max(u, s.ctrl_lo[k]), s.ctrl_hi[k])


@njit(cache=True)
def joint_controls(s):
    """`controls`, into ctrl (the phases are the wheel motors': motors.wheel_phase)."""
    controls(s)
    for k in range(s.motors.shape[0]):
        s.ctrl[s.motors[k]] = s.controls[k]


@overload(set_controls)
def _set_controls(s):
    if isinstance(s, JointDrive.numba_type):
        return lambda s: joint_controls(s)


@njit(cache=True)
def turn(s, angle, leftover):
    """Turns by `angle` rad counter-clockwise over the turn phase."""
    return plan(s, 0.0, angle * s.per_rad, s.n_turn, s.ramp_turn)


@njit(cache=True)
def move(s, distance):
    """Moves `distance` units forward over the move phase."""
    return plan(s, distance * s.joint_per_unit, 0.0, s.n_move, s.ramp_move)


@njit(cache=True)
def stop(s):
    """The halt: the targets where the joints are (motors.hold_here)."""
    hold_here(s.target, s.ramp_left, s.qpos, s.joint_q)
    return bindings.OK, 0


family.realisation(JointDrive, turn, move, stop, keep, back)
