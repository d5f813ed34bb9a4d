"""The target plan: two joints' targets moved over a ramp, then held, and a controller
that turns them into the actuators' controls at every substep. The wheel_motors
realisation (tasks.kernels.wheel_motors: the wheels' angles through a file's torque
motors, the MuJoCo car) and the joint_motors one (tasks.kernels.joint_motors: a forward
and a turn joint through a file's motors or servos) are this one plan on two joints.

A phase of n substeps (`aim`, then `phase`) moves the two targets by (left, right) over
its first `ramp` substeps (tasks.kernels.wheels.ramp_substeps), then lets them settle;
the halt puts the targets where the joints are (`hold_here`), so a stalled joint gives
up the rest. At every substep the controller (`controls`) turns the targets into the
actuators' controls, by the actuators' kind (tasks.actuators.ACTUATOR_KINDS):

- TORQUE (motors): the PD torques tau_j = kp_j (target_j - q_j) - kv_j dq_j, and the motors'
  controls of least norm that give them (`motor_controls`, over the motors' forces
  measured at load: tasks.actuators.motor_forces);
- POSITION (position servos): each servo's control is its length at the targets,
  length0 + sum_j gain[k, j] (target_j - rest_j) (gain: its length per unit of joint
  j, measured at load; the servo's own gains hold it there);
- VELOCITY (velocity servos): the joints' speeds v_j = kp_j (target_j - q_j), each servo's
  control its speed at those, sum_j gain[k, j] v_j.

Each control is clipped to its actuator's range.
"""
import numpy as np
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from tasks.actuators import ACTUATOR_KINDS
from tasks.kernels import bindings, two_wheel as family

#: The controllers, by the kind of the actuators on the joints (the code is the kind's
#: index in tasks.actuators.ACTUATOR_KINDS).
TORQUE, POSITION, VELOCITY = (ACTUATOR_KINDS.index(k) for k in ("torque motors", "position servos",
                                                       "velocity servos"))

#: The plan's fields of a record:
PLAN_FIELDS = (
    # the two joints' qpos and dof addresses and rest positions; the actuators, the
    # controller (TORQUE, POSITION, VELOCITY), the motors' forces on the joints and their
    # Gram matrix (TORQUE), the actuators' length per unit of each joint and their
    # lengths at rest (POSITION, VELOCITY), the controls' ranges; the gains, one per
    # joint
    "joint_q", "joint_dof", "rest", "motors", "mode", "forces", "gram", "gain", "length0",
    "ctrl_lo", "ctrl_hi", "kp", "kv",
    # the targets (rad or m), their step per ramp substep, the ramp's substeps left;
    # scratch (the torques, the controls); the targets and the ramp a refused move
    # returns to
    "target", "delta", "ramp_left", "tau", "controls", "target0", "ramp_left0")


@njit(cache=True)
def gram(forces):
    """(a, b, e, det) of M^T M = [[a, b], [b, e]] for the motors' forces M (forces[k, j]:
    motor k's generalised force on joint dof j per unit control): what motor_controls
    inverts, computed once per model (det 0: the motors cannot move the joints apart,
    tasks.actuators.require_independent)."""
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
    """The motors' controls c that give the two joint dofs the generalised forces tau.

    forces[k, j] is motor k's generalised force on dof j per unit of its control (M,
    measured at load: tasks.actuators.motor_forces), so the motors give tau = M^T c. The
    solution of least norm is c = M (M^T M)^-1 tau: for two motors, the one solution;
    for more, the smallest controls that do it. (M^T M is 2 x 2, mtm = gram(forces): its
    inverse is written out.) Each c[k] is then clipped to [lo[k], hi[k]], the motor's
    control range. With the car's motors ("forward", "turn" on tendons of coefficients
    0.5, 0.5 and -0.5, 0.5), M = [[0.5, 0.5], [-0.5, 0.5]] and c = (tau_l + tau_r,
    tau_r - tau_l)."""
    a, b, e, det = mtm[0], mtm[1], mtm[2], mtm[3]
    y0 = (e * tau[0] - b * tau[1]) / det
    y1 = (a * tau[1] - b * tau[0]) / det
    for k in range(forces.shape[0]):
        c[k] = min(max(forces[k, 0] * y0 + forces[k, 1] * y1, lo[k]), hi[k])


@njit(cache=True)
def solve(s):
    """The actuators' controls for the joints' targets, by the controller (the module's
    docstring), into s.controls."""
    target, tau, c, q, dq = s.target, s.tau, s.controls, s.joint_q, s.joint_dof
    qpos, qvel = s.qpos, s.qvel
    if s.mode == TORQUE:
        for j in range(2):
            tau[j] = s.kp[j] * (target[j] - qpos[q[j]]) - s.kv[j] * qvel[dq[j]]
        motor_controls(s.forces, s.gram, tau, s.ctrl_lo, s.ctrl_hi, c)
        return
    for j in range(2):
        if s.mode == POSITION:
            tau[j] = target[j] - s.rest[j]
        else:
            tau[j] = s.kp[j] * (target[j] - qpos[q[j]])
    for k in range(c.shape[0]):
        u = s.length0[k] if s.mode == POSITION else 0.0
        u += s.gain[k, 0] * tau[0] + s.gain[k, 1] * tau[1]
        c[k] = min(max(u, s.ctrl_lo[k]), s.ctrl_hi[k])


@njit(cache=True)
def controls(s):
    """`solve`'s controls, into ctrl."""
    solve(s)
    for k in range(s.motors.shape[0]):
        s.ctrl[s.motors[k]] = s.controls[k]


@njit(cache=True)
def aim(s, left, right, ramp):
    """The next phase's ramp: its two targets move by (left, right) over `ramp` substeps."""
    s.ramp_left[0] = ramp
    s.delta[0], s.delta[1] = left / ramp, right / ramp


@njit(cache=True)
def phase(s, n, heading, watch):
    """n substeps of a phase: at each, while ramp_left[0] > 0 the two targets move by
    delta (and ramp_left counts down); the controls for them go into ctrl (`controls`);
    one substep runs (tasks.kernels.bindings.run). With `watch` (a move), the phase ends
    where the body touches the room along `heading` (family.touching, checked before each
    substep), the joints held there (`halt`). Returns (the first non-OK status of run
    (UNSTABLE), TIPPED when a free base ends the phase tilted past min_cos_tilt (checked
    at the end, as a phase's substeps check it), else OK; the substeps run)."""
    target, delta, ramp_left = s.target, s.delta, s.ramp_left
    for k in range(n):
        if watch and family.touching(s, heading):
            halt(s)
            return bindings.OK, k
        if ramp_left[0] > 0:
            target[0] += delta[0]
            target[1] += delta[1]
            ramp_left[0] -= 1
        controls(s)
        status = bindings.run(s.m, s.d, 1, s.bad_qacc, s.xmat, False, s.min_cos_tilt)
        if status != bindings.OK:
            return status, n
    if s.free != 0 and bindings.tilted(s.xmat, s.min_cos_tilt):
        return bindings.TIPPED, n
    return bindings.OK, n


@njit(cache=True)
def hold_here(target, ramp_left, qpos, joint_q):
    """The targets where the joints are, the ramp over: a stalled joint gives up the rest."""
    target[0] = qpos[joint_q[0]]
    target[1] = qpos[joint_q[1]]
    ramp_left[0] = 0


@njit(cache=True)
def halt(s):
    """The halt: the targets where the joints are (hold_here)."""
    hold_here(s.target, s.ramp_left, s.qpos, s.joint_q)
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
