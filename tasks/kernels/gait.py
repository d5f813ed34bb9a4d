"""The gait realisation of the two-wheel family, compiled: the family's action
(tasks.kernels.two_wheel.act) walked by a trotting central pattern generator with heading
feedback (tasks.realisations.gait's docstring).

`walk` runs n control ticks of the CPG and the PD loops; `turn` and `move` close the
heading and distance feedback around it; `halt`, the family's last phase
(tasks.kernels.two_wheel.act), is one substep at the last controls, kept so that the
gait's runs keep their bits (tests/test_step_digests.py).
"""
import math

import numpy as np

from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled import records
from tasks.kernels import bindings
from tasks.kernels.body import BODY_FIELDS, base_pose, step_phase
from tasks.kernels import two_wheel as family


@records.record(
    *BODY_FIELDS, *family.FAMILY_FIELDS,
    # per listed joint (tasks.realisations.gait.GaitPhysics: each leg's swing, lift and held joints):
    # its leg, its role (SWING, LIFT, HELD), the sign that raises the foot (a lift
    # joint's), its qpos and dof addresses and rest angle; its torque motor (-1: none)
    # and that motor's control range and sense (1, or -1 for a motor whose force
    # opposes its control: a negative gear or gain); per leg: the swing's forward and turning shares,
    # the phase offset (cycles); the position servos: their actuators, their controls'
    # change per radian of each listed joint (servos x joints), their controls at rest
    # and ranges
    "leg", "role", "lift_sign", "q", "dq", "rest", "acts", "ctrl_lo", "ctrl_hi", "motor_sign",
    "forward_share", "turn_share", "offset", "servos", "servo_gain", "servo_rest",
    "servo_lo", "servo_hi",
    # the gait's parameters (tasks.realisations.gait.PARAMETERS): PD gains, seconds per control tick,
    # the CPG's amplitude, lift and frequency, the heading feedback, the move's
    # slow-down and coast, the phases' time limits, the feedback's ticks per update and
    # the settling's
    "kp", "kd", "tick", "control_substeps", "amplitude", "lift", "frequency",
    "heading_gain", "turn_tolerance", "slow_down", "coast", "max_turn_seconds",
    "max_move_seconds", "feedback_seconds", "n_feedback", "n_settle",
    # the CPG's state: its phase (cycles), the joints' targets; scratch: the hips' shares
    "phase", "target", "share")
class GaitRecord(records.Record):
    """The gait's record (the fields' comments)."""


GaitRecord.constructor = njit(cache=True)(lambda *values: GaitRecord(*values))


@njit(cache=True)
def remainder(x, y):
    """math.remainder(x, y) for y > 0, exactly (numba has no math.remainder): fmod is
    exact, r - y and r + y for |r| > y / 2 are exact (Sterbenz's lemma), and a tie
    |r| = y / 2 goes to the even quotient (its parity from fmod(x, 2 y), also exact)."""
    r = np.fmod(x, y)
    half = 0.5 * y
    if r > half or (r == half and abs(np.fmod(x, 2.0 * y)) >= y):
        return r - y
    if r < -half or (r == -half and abs(np.fmod(x, 2.0 * y)) >= y):
        return r + y
    return r


#: A listed joint's role in its leg (tasks.realisations.gait.GaitPhysics): the swing that moves the foot
#: fore and aft, a lift that raises it, a joint held at rest (an optional yaw).
SWING, LIFT, HELD = 0, 1, 2


@njit(cache=True)
def walk(s, n, amp, lift, freq):
    """n ticks of the trot: each sets the listed joints' targets from the phase (the
    legs' shares in s.share), the torque motors' controls by PD and the position servos'
    to their targets (clipped to their ranges), runs control_substeps substeps and
    advances the phase by frequency * tick seconds.
    Returns (the first non-OK status of tasks.kernels.bindings.run (UNSTABLE), else OK; the
    substeps run). The tilt is not checked here: a fall is judged at a phase's end
    (`ended`), as the car's motors judge it (tasks.kernels.plan.phase)."""
    kp, kd, tick = s.kp, s.kd, s.tick
    k = s.control_substeps
    phase, target, share, rest, qpos, qvel = s.phase, s.target, s.share, s.rest, s.qpos, s.qvel
    joints = len(target)
    for t in range(n):
        for j in range(joints):
            i = s.leg[j]
            phi = 2.0 * math.pi * (phase[0] + s.offset[i])
            if s.role[j] == SWING:
                target[j] = rest[j] + amp * share[i] * -math.cos(phi)
            elif s.role[j] == LIFT:
                v = -math.sin(phi)
                target[j] = rest[j] + lift * s.lift_sign[j] * (v if v > 0.0 else 0.0)
            else:
                target[j] = rest[j]
        for j in range(joints):
            if s.acts[j] >= 0:
                u = (kp * (target[j] - qpos[s.q[j]]) - kd * qvel[s.dq[j]]) * s.motor_sign[j]
                s.ctrl[s.acts[j]] = min(max(u, s.ctrl_lo[j]), s.ctrl_hi[j])
        for a in range(len(s.servos)):
            u = s.servo_rest[a]
            for j in range(joints):
                u += s.servo_gain[a, j] * (target[j] - rest[j])
            s.ctrl[s.servos[a]] = min(max(u, s.servo_lo[a]), s.servo_hi[a])
        status = bindings.run(s.m, s.d, k, s.bad_qacc, s.xmat, False, s.min_cos_tilt)
        if status != bindings.OK:
            return status, n * k
        phase[0] = (phase[0] + freq * tick) % 1.0
    return bindings.OK, n * k


@njit(cache=True)
def control(s, forward, turn):
    """One feedback interval of walking at the commands (forward in [0, 1], turn in
    [-1, 1], counter-clockwise positive): the hips' shares forward * forward_share +
    turn * turn_share, scaled down so none exceeds 1."""
    share = s.share
    top = 0.0
    for i in range(share.shape[0]):
        share[i] = forward * s.forward_share[i] + turn * s.turn_share[i]
        top = max(top, abs(share[i]))
    scale = max(1.0, top)
    for i in range(share.shape[0]):
        share[i] = share[i] / scale
    return walk(s, s.n_feedback, s.amplitude, s.lift, s.frequency)


@njit(cache=True)
def hold(s):
    """The legs back to rest for the settling seconds (the phase held)."""
    s.share[:] = 0.0
    return walk(s, s.n_settle, 0.0, 0.0, 0.0)


@njit(cache=True)
def heading(s):
    """The robot's heading: its frame's x axis in the plane (the base's, or the frame a
    mount adds: tasks.mount.frame)."""
    return math.atan2(s.xmat[3], s.xmat[0])


@njit(cache=True)
def clip_command(v):
    """v clipped to [-1, 1] as Python's max(-1, min(1, v))."""
    v = v if v < 1.0 else 1.0
    return v if v > -1.0 else -1.0


@njit(cache=True)
def ended(s, status, n):
    """A phase's end, the legs back at rest: (TIPPED, n) when the base ends it tilted
    past min_cos_tilt (a fall; a tilt within the phase that the robot recovers from is
    none), else (status, n)."""
    if status == bindings.OK and bindings.tilted(s.xmat, s.min_cos_tilt):
        return bindings.TIPPED, n
    return status, n


@njit(cache=True)
def turn(s, angle, leftover):
    """Turns by `angle` rad (counter-clockwise) with heading feedback until within the
    tolerance or the time limit, then settles. The step's own turn is walked only when
    larger than the tolerance; a leftover turn always."""
    if not leftover and not abs(angle) > s.turn_tolerance:
        return bindings.OK, 0
    target = heading(s) + angle
    chunk = s.feedback_seconds
    t = 0.0
    n = 0
    while t < s.max_turn_seconds:
        err = remainder(target - heading(s), 2 * math.pi)
        if abs(err) < s.turn_tolerance:
            break
        status, k = control(s, 0.0, clip_command(s.heading_gain * err))
        n += k
        if status != bindings.OK:
            return status, n
        t += chunk
    status, k = hold(s)
    return ended(s, status, n + k)


@njit(cache=True)
def move(s, distance):
    """Walks `distance` units along the heading the move starts with: forward 1 (less
    over the last slow_down units), heading feedback, until within `coast` of the
    target or the time limit; then settles."""
    x0, y0, h0 = base_pose(s)
    c, sn = math.cos(h0), math.sin(h0)
    chunk = s.feedback_seconds
    t, done = 0.0, 0.0
    n = 0
    watch = not family.clear_ahead(s, h0, distance)
    while distance - done > s.coast and t < s.max_move_seconds:
        if watch and family.touching(s, h0):  # Section 3.3: the move ends at the touch
            break
        err = remainder(h0 - heading(s), 2 * math.pi)
        r = (distance - done) / s.slow_down
        r = r if r > 0.3 else 0.3
        forward = r if r < 1.0 else 1.0
        status, k = control(s, forward, clip_command(s.heading_gain * err))
        n += k
        if status != bindings.OK:
            return status, n
        t += chunk
        x, y, _ = base_pose(s)
        done = (x - x0) * c + (y - y0) * sn
    if distance > s.coast:
        status, k = hold(s)
        return ended(s, status, n + k)
    return bindings.OK, n


@njit(cache=True)
def halt(s):
    """One substep at the last controls."""
    return step_phase(s, 1), 1


#: The two-wheel family's step on this body (tasks.kernels.two_wheel.act, through
#: tasks.kernels.env_step.action): the turn, move and halt phases, then how a refused
#: move's state is kept and given back.
PHASES = (turn, move, halt, family.save_state, family.restore_state)
