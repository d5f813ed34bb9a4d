"""The compiled loop of wheels turned through a robot file's own motors
(tasks.two_wheel.MotorWheelPhysics): a PD loop on the two wheel angles, solved for the
motors' controls at every substep, for a whole phase in one call. Kept apart from
tasks.kernels, whose steps are the paper drives'; it calls that module's `run` for the
substeps, as tasks.gait_kernels does."""
import numpy as np
from numba import njit

from tasks.kernels import OK, TIPPED, run


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
    (M, measured at load: two_wheel.motor_forces), so the motors give tau = M^T c. The
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
def wheel_phase(m, d, n, bad_qacc, xmat, free, min_cos_tilt, qpos, qvel, ctrl, qadr, dofadr,
                motors, forces, mtm, lo, hi, kp, kv, target, delta, ramp_left, tau, c):
    """n substeps of a phase: at each, while ramp_left[0] > 0 the wheels' targets move by
    delta (and ramp_left counts down); the desired wheel torques are
    tau = kp (target - q) - kv dq; the motors' controls (motor_controls) go into ctrl;
    one substep runs (tasks.kernels.run). Returns the first non-OK status of run
    (UNSTABLE), TIPPED when a free base (free) ends the phase tilted past min_cos_tilt
    (checked at the end, as navigation.Physics.step checks it), else OK."""
    for _ in range(n):
        if ramp_left[0] > 0:
            target[0] += delta[0]
            target[1] += delta[1]
            ramp_left[0] -= 1
        for j in range(2):
            tau[j] = kp * (target[j] - qpos[qadr[j]]) - kv * qvel[dofadr[j]]
        motor_controls(forces, mtm, tau, lo, hi, c)
        for k in range(motors.shape[0]):
            ctrl[motors[k]] = c[k]
        status = run(m, d, 1, bad_qacc, xmat, False, min_cos_tilt)
        if status != OK:
            return status
    if free and xmat[8] < min_cos_tilt:
        return TIPPED
    return OK
