"""The two-wheel family on a robot file's own motors: two wheel hinges (contract names
``left``, ``right``) turned through the file's torque motors (``motor_0``, ``motor_1``,
...: on the wheel joints or on tendons over them), none added (the MuJoCo car,
models/mounts/car.toml). The wheel-angle plan is the wheels' (tasks.two_wheel.wheels:
a phase moves the wheels' targets over its ramp, then lets them settle), its targets
held by a PD loop: at every substep the desired wheel torques are
tau = kp (target - q) - kv dq, and the motors' controls that give them
(`motor_controls`, clipped to each motor's range)."""
import numpy as np
from numba import njit
from numba.extending import overload

from ebrl import compiled  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from ebrl import records
from tasks.kernels import bindings, two_wheel as family
from tasks.kernels.body import BODY_FIELDS
from tasks.kernels.wheels import PLAN_FIELDS, move_angles, turn_angles


@records.record(*BODY_FIELDS, *family.FAMILY_FIELDS, *PLAN_FIELDS, "wheel_q", "wheel_dof",
                "motors", "forces", "gram", "ctrl_lo", "ctrl_hi", "kp", "kv", "target",
                "delta", "ramp_left", "tau", "controls", "target0", "ramp_left0")
class MotorWheelDrive(records.Record):
    """The motor wheels' record: the body, the family's and the plan's fields, the wheel
    hinges' qpos and dof addresses, the motors' ids, their measured forces on the wheels
    (`motor_forces`) and its Gram matrix (`gram`), their control ranges, the PD gains,
    the plan's state (the wheels' targets, their step per ramp substep, the ramp's
    substeps left), scratch (torques, controls) and the plan's state a refused move
    returns to."""


MotorWheelDrive.constructor = njit(cache=True)(lambda *values: MotorWheelDrive(*values))


@njit(cache=True)
def gram(forces):
    """(a, b, e, det) of M^T M = [[a, b], [b, e]] for the motors' forces M (forces[k, j]:
    motor k's generalised force on wheel dof j per unit control): what motor_controls
    inverts, computed once per model (det 0: the motors cannot turn the wheels apart)."""
    a = 0.0
    b = 0.0
    e = 0.0
    for k in range(forces.shape[0]):
        a += forces[k, 0] * forces[k, 0]
        b += forces[k, 0] * forces[k, 1]
        e += forces[k, 1] * forces[k, 1]
    return np.array([a, b, e, a * e - b * b])


@njit(cache=True)
def motor_controls(forces, mtm, tau, lo, hi, c):
    """The motors' controls c that give the two wheel dofs the generalised forces tau.

    forces[k, j] is motor k's generalised force on wheel dof j per unit of its control
    (M, measured at load: motor_forces), so the motors give tau = M^T c. The solution of
    least norm is c = M (M^T M)^-1 tau: for two motors, the one solution; for more, the
    smallest controls that do it. (M^T M is 2 x 2, mtm = gram(forces): its inverse is
    written out.) Each c[k] is then clipped to [lo[k], hi[k]], the motor's control range.
    With the car's motors ("forward", "turn" on tendons of coefficients 0.5, 0.5 and
    -0.5, 0.5), M = [[0.5, 0.5], [-0.5, 0.5]] and c = (tau_l + tau_r, tau_r - tau_l)."""
    a, b, e, det = mtm[0], mtm[1], mtm[2], mtm[3]
    y0 = (e * tau[0] - b * tau[1]) / det
    y1 = (a * tau[1] - b * tau[0]) / det
    for k in range(forces.shape[0]):
        c[k] = min(max(forces[k, 0] * y0 + forces[k, 1] * y1, lo[k]), hi[k])


def set_controls(s):
    """The actuators' controls for the targets, into ctrl: overloaded for each record type
    that runs `wheel_phase` (the wheel motors': `wheel_controls`; the joint motors':
    tasks.kernels.joints.joint_controls)."""
    raise NotImplementedError("overloaded for each record type")


@njit(cache=True)
def wheel_controls(s):
    """The desired wheel torques tau = kp (target - q) - kv dq, the motors' controls that
    give them (motor_controls), into ctrl."""
    target, tau, c = s.target, s.tau, s.controls
    qpos, qvel, ctrl, qadr, dofadr, motors = s.qpos, s.qvel, s.ctrl, s.wheel_q, s.wheel_dof, s.motors
    kp, kv = s.kp, s.kv
    for j in range(2):
        tau[j] = kp * (target[j] - qpos[qadr[j]]) - kv * qvel[dofadr[j]]
    motor_controls(s.forces, s.gram, tau, s.ctrl_lo, s.ctrl_hi, c)
    for k in range(motors.shape[0]):
        ctrl[motors[k]] = c[k]


@overload(set_controls)
def _set_controls(s):
    if isinstance(s, MotorWheelDrive.numba_type):
        return lambda s: wheel_controls(s)


@njit(cache=True)
def wheel_phase(s, n):
    """n substeps of a phase: at each, while ramp_left[0] > 0 the two targets move by
    delta (and ramp_left counts down); the controls for them go into ctrl
    (`set_controls`); one substep runs (tasks.bindings.run). Returns the first non-OK
    status of run (UNSTABLE), TIPPED when a free base ends the phase tilted past
    min_cos_tilt (checked at the end, as a phase's substeps check it), else OK."""
    target, delta, ramp_left = s.target, s.delta, s.ramp_left
    for _ in range(n):
        if ramp_left[0] > 0:
            target[0] += delta[0]
            target[1] += delta[1]
            ramp_left[0] -= 1
        set_controls(s)
        status = bindings.run(s.m, s.d, 1, s.bad_qacc, s.xmat, False, s.min_cos_tilt)
        if status != bindings.OK:
            return status
    if s.free != 0 and bindings.tilted(s.xmat, s.min_cos_tilt):
        return bindings.TIPPED
    return bindings.OK


@njit(cache=True)
def plan(s, left, right, n, ramp):
    """A phase of n substeps whose two targets move by (left, right) over `ramp`."""
    s.ramp_left[0] = ramp
    s.delta[0], s.delta[1] = left / ramp, right / ramp
    return wheel_phase(s, n), n


@njit(cache=True)
def turn(s, angle, leftover):
    """Turns by `angle` rad counter-clockwise over the turn phase (wheels.turn_angles)."""
    left, right = turn_angles(s, angle)
    return plan(s, left, right, s.n_turn, s.ramp_turn)


@njit(cache=True)
def move(s, distance):
    """Moves `distance` units forward over the move phase (wheels.move_angles)."""
    left, right = move_angles(s, distance)
    return plan(s, left, right, s.n_move, s.ramp_move)


@njit(cache=True)
def hold_here(target, ramp_left, qpos, wheel_q):
    """The targets where the wheels are, the ramp over: a stalled wheel gives up the rest."""
    target[0] = qpos[wheel_q[0]]
    target[1] = qpos[wheel_q[1]]
    ramp_left[0] = 0


@njit(cache=True)
def stop(s):
    """The halt: hold_here."""
    hold_here(s.target, s.ramp_left, s.qpos, s.wheel_q)
    return bindings.OK, 0


@njit(cache=True)
def keep(s):
    """MuJoCo's state and the plan's (targets, ramp) for a refused move."""
    family.save_state(s)
    s.target0[:] = s.target
    s.ramp_left0[:] = s.ramp_left


@njit(cache=True)
def back(s):
    """Back to `keep`'s state."""
    family.restore_state(s)
    s.target[:] = s.target0
    s.ramp_left[:] = s.ramp_left0


family.realisation(MotorWheelDrive, turn, move, stop, keep, back)
