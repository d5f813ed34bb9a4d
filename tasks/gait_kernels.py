"""The gait drive's compiled loop (tasks.gait): the CPG and the PD loops of n control
ticks, each followed by its substeps, in one call. Kept apart from tasks.kernels, whose
steps are the paper drives'; it calls that module's `run` for the substeps."""
import math

from numba import njit

from tasks.kernels import OK, run

# The floats of `walk`'s settings array, by index.
(P_AMPLITUDE, P_LIFT, P_FREQUENCY, P_KP, P_KD, P_TICK, P_MIN_COS_TILT) = range(7)
N_PARAMS = 7


@njit(cache=True)
def walk(m, d, n, k, bad_qacc, xmat, qpos, qvel, ctrl, qadr, dofadr, acts, rest, share,
         lift_sign, offset, lo, hi, params, phase, target):
    """n ticks of the trot (tasks.gait's docstring): each sets the 4 hips' and 4 ankles'
    targets from the phase, the motors' controls by PD (clipped to [lo, hi]), runs k
    substeps and advances the phase by frequency * tick seconds. Returns the first
    non-OK status of tasks.kernels.run (a fall: TIPPED), else OK."""
    amp, lift, freq = params[P_AMPLITUDE], params[P_LIFT], params[P_FREQUENCY]
    kp, kd, tick = params[P_KP], params[P_KD], params[P_TICK]
    legs = len(share)
    for _ in range(n):
        for i in range(legs):
            phi = 2.0 * math.pi * (phase[0] + offset[i])
            target[i] = rest[i] + amp * share[i] * -math.cos(phi)
            s = -math.sin(phi)
            target[legs + i] = rest[legs + i] + lift * lift_sign[i] * (s if s > 0.0 else 0.0)
        for j in range(2 * legs):
            u = kp * (target[j] - qpos[qadr[j]]) - kd * qvel[dofadr[j]]
            ctrl[acts[j]] = min(max(u, lo[j]), hi[j])
        status = run(m, d, k, bad_qacc, xmat, True, params[P_MIN_COS_TILT])
        if status != OK:
            return status
        phase[0] = (phase[0] + freq * tick) % 1.0
    return OK
