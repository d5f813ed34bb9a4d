"""The tasks' per-step work as compiled kernels, around MuJoCo's own C calls.

The mirror of ebrl/kernels.py for the simulator side. An agent step of the paper's
robots (a drive's action mapping, its phases of substeps, the read-outs, the
rangefinders' encoding and noise) is one compiled call (`two_wheel_step`,
`floating_step`) that calls MuJoCo's C functions (mj_step, mj_step1, mj_step2,
mj_sensorPos, mj_objectVelocity) directly on the MjModel and MjData, with no Python
in between. The task's hooks (before_step, Physics.step, after_step, sense) call the
same kernels one piece at a time, and dm_control's Environment.step runs them; the two
paths give the same bits (tests/test_tasks.py).

Every kernel is ``@njit(cache=True)`` with no fastmath: each floating-point operation
runs as the Python it replaced wrote it, in the same order (same bits, tested against
tests/data/planar_traces_v*.npz). MuJoCo's functions are declared by symbol name
(numba ExternalFunction), resolved in libmujoco.so, which the mujoco package has
loaded; the compiled kernels stay cacheable because they hold no addresses.

What a kernel reads and writes of MuJoCo's structs:
    m, d          the mjModel and mjData addresses (MjModel._address, MjData._address)
    flags         an int32 view of m->opt.disableflags (the sensor stage is switched on
                  only for mj_sensorPos, as navigation.Physics.ranges does)
    bad_qacc      an int32 view of d->warning[mjWARN_BADQACC].number
    qpos, ctrl, sensordata   MjData's own arrays (numpy views)
    xpos, xmat    the base body's rows of d->xpos and d->xmat

The random draws stay NumPy's (the task's RandomState): the caller draws the action
noise's two uniforms and the sensor noise's normals, in the order the hooks draw them,
and passes them in.
"""
import ctypes
import glob
import math
import os

import mujoco
import numpy as np
from llvmlite import binding
from numba import njit, types
from numba.experimental import structref

_LIBRARY = sorted(glob.glob(os.path.join(os.path.dirname(mujoco.__file__), "libmujoco.so*")))
if not _LIBRARY:  # pragma: no cover - every mujoco wheel for Linux ships it
    raise ImportError("libmujoco.so not found beside the mujoco package")
binding.load_library_permanently(_LIBRARY[0])

#: MuJoCo's timer callback, the C global mjcb_time of the library loaded above (one
#: handle per process: dlopen gives the mujoco package's own).
_TIMER_CALLBACK = ctypes.c_void_p.in_dll(ctypes.CDLL(_LIBRARY[0]), "mjcb_time")


class stage_timers_off:  # noqa: N801  used as a function: `with stage_timers_off():`
    """MuJoCo's stage timers off inside the block, the previous callback back after it.

    The mujoco package sets mjcb_time at import (a clock for mjData.timer, its profiler's
    read-out), and every mj_step then reads the clock about twenty times, once at each
    stage's start and end: 10-15% of a planar robot's step (docs/speed.md). The timers
    only fill mjData.timer, which nothing here reads, so every other value stays the
    same bit for bit (tests/test_kernels.py). A class rather than a generator: the
    Gymnasium step enters it once per step (0.5 against 1.8 us)."""
    __slots__ = ("_previous",)

    def __enter__(self):
        self._previous = _TIMER_CALLBACK.value
        _TIMER_CALLBACK.value = None

    def __exit__(self, *exc):
        _TIMER_CALLBACK.value = self._previous


_P = types.uintp  # a pointer, as an integer (the C ABI passes both in one register)
mj_step = types.ExternalFunction("mj_step", types.void(_P, _P))
mj_step1 = types.ExternalFunction("mj_step1", types.void(_P, _P))
mj_step2 = types.ExternalFunction("mj_step2", types.void(_P, _P))
mj_sensorPos = types.ExternalFunction("mj_sensorPos", types.void(_P, _P))
mj_forward = types.ExternalFunction("mj_forward", types.void(_P, _P))
mj_objectVelocity = types.ExternalFunction(
    "mj_objectVelocity", types.void(_P, _P, types.intc, types.intc, _P, types.intc))

#: A kernel's status: the step ran; MuJoCo flagged an unstable state (mjWARN_BADQACC);
#: a free-joint robot tilted past navigation.MAX_TILT_DEGREES; the action is not finite.
OK, UNSTABLE, TIPPED, NOT_FINITE = 0, 1, 2, 3

_OBJ_BODY = int(mujoco.mjtObj.mjOBJ_BODY)
_SENSOR_BIT = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)


# -- finding the two ints of MuJoCo's structs that have no array view -----------------

def _int_field(anchor, get, set_, span=4096):
    """An int32 numpy view of the struct field that get() reads and set_(value) writes,
    found in the `span` bytes from `anchor` (the address of an array of the same struct
    that comes before it): two marker values are written in turn and the bytes searched
    for both at the same place, then the old value is put back."""
    old = get()
    hits = []
    try:
        for marker in (0x5EED1A2B, 0x2B1AED5E):
            set_(marker)
            raw = np.frombuffer(ctypes.string_at(anchor, span), dtype=np.int32)
            hits.append(set(np.flatnonzero(raw == marker).tolist()))
    finally:
        set_(old)
    both = hits[0] & hits[1]
    if len(both) != 1:  # pragma: no cover - a MuJoCo whose struct layout defeats the search
        raise RuntimeError("tasks.kernels: a field of MuJoCo's struct was not found")
    return np.ctypeslib.as_array((ctypes.c_int32 * 1).from_address(anchor + 4 * both.pop()))


def disable_flags(model):
    """An int32 view of model->opt.disableflags (model: mujoco.MjModel); it follows
    opt.gravity in mjOption."""
    opt = model.opt
    return _int_field(opt.gravity.ctypes.data, lambda: opt.disableflags,
                      lambda v: setattr(opt, "disableflags", v))


def contact_count(data):
    """An int32 view of data->ncon (data: mujoco.MjData); it follows the warnings."""
    return _int_field(data.solver_niter.ctypes.data, lambda: data.ncon,
                      lambda v: setattr(data, "ncon", v))


def contact_views(data):
    """Views of mjData's contact array for the kernels: (float64 view, int32 view, the
    layout), where layout holds, in 8-byte and 4-byte words, the struct's size, the
    offset of its frame (the normal is its first row) and of geom1 and geom2. The array
    is d->contact, which MuJoCo keeps at the start of the arena (mj_clearEfc), so the
    views cover the arena and never move; the offsets are the bindings' own fields'."""
    c = data.contact
    size = c.frame.strides[0]
    start = c.dist.ctypes.data
    offsets = [c.frame.ctypes.data - start, c.geom1.ctypes.data - start,
               c.geom2.ctypes.data - start]
    if size % 8 or offsets[0] % 8 or offsets[1] % 4 or offsets[2] % 4:  # pragma: no cover
        raise RuntimeError("tasks.kernels: an unexpected mjContact layout")
    words = data.narena // 8
    floats = np.ctypeslib.as_array((ctypes.c_double * words).from_address(start))
    ints = np.ctypeslib.as_array((ctypes.c_int32 * (2 * words)).from_address(start))
    layout = np.array([size // 8, offsets[0] // 8, size // 4, offsets[1] // 4, offsets[2] // 4,
                       data.narena // size], dtype=np.int64)
    return floats, ints, layout


def warning_count(data, warning):
    """An int32 view of data->warning[warning].number (data: mujoco.MjData); mjData's
    warnings follow its solver_niter."""
    stat = data.warning[warning]
    return _int_field(data.solver_niter.ctypes.data, lambda: stat.number,
                      lambda v: setattr(stat, "number", v))


# -- physics ------------------------------------------------------------------------

@njit(cache=True)
def run(m, d, n, bad_qacc, xmat, free, min_cos_tilt):
    """n substeps as dm_control's legacy step runs them (mj_step2, mj_step n-1 times,
    mj_step1: contacts and kinematics then describe the new state). Returns OK, UNSTABLE
    when MuJoCo flagged a bad acceleration meanwhile, or TIPPED when a free-joint robot
    (free) ends tilted past min_cos_tilt (the cosine of the largest tilt)."""
    before = bad_qacc[0]
    mj_step2(m, d)
    for _ in range(n - 1):
        mj_step(m, d)
    mj_step1(m, d)
    if bad_qacc[0] != before:
        return UNSTABLE
    if free and xmat[8] < min_cos_tilt:
        return TIPPED
    return OK


@njit(cache=True)
def pose(xpos, xmat, qpos, qyaw, unit):
    """(x, y, heading) in units and radians (navigation.Physics.robot_pose): the
    heading is the yaw hinge's angle (qyaw >= 0), else the frame's x axis in the plane."""
    x = xpos[0] / unit
    y = xpos[1] / unit
    heading = qpos[qyaw] if qyaw >= 0 else math.atan2(xmat[3], xmat[0])
    return x, y, heading


# -- sensing (Section 3.2) ----------------------------------------------------------

@njit(cache=True)
def surface_distances(raw, metres_to_units, radius):
    """Rangefinder values (m from the centre; -1 = no hit) -> units from the surface."""
    out = np.empty(raw.shape[0])
    for i in range(raw.shape[0]):
        out[i] = np.inf if raw[i] < 0.0 else raw[i] * metres_to_units - radius
    return out


@njit(cache=True)
def encode(distance, noise, levels, per_unit):
    """Section 3.2's code of each distance, plus noise (if any) clipped to [0, levels].
    max/min as numpy's maximum/minimum (the second argument unless the first is larger:
    max(-0.0, 0.0) is 0.0)."""
    out = np.empty(distance.shape[0])
    for i in range(distance.shape[0]):
        d = distance[i]
        c = d if d > 0.0 else 0.0
        c = c * per_unit
        c = c + levels
        c = np.rint(c)
        c = c if c > 0.0 else 0.0
        if noise.shape[0]:
            c = c + noise[i]
            c = c if c > 0.0 else 0.0
            c = c if c < levels else levels
        out[i] = c
    return out


@njit(cache=True)
def ranges(m, d, flags, sensordata, first, end, metres_to_units, radius):
    """The sensor stage run once at the current state (MuJoCo's is disabled while
    stepping), then each beam's distance from the body surface in units (inf: no hit).
    first, end: the rangefinders' span of sensordata."""
    flags[0] &= ~_SENSOR_BIT
    mj_sensorPos(m, d)
    flags[0] |= _SENSOR_BIT
    return surface_distances(sensordata[first:end], metres_to_units, radius)


@njit(cache=True)
def velocity(m, d, base, scale, out6):
    """(vx, vy) of the base body's frame times scale (units per agent step over m/s)."""
    mj_objectVelocity(m, d, _OBJ_BODY, base, out6.ctypes.data, 0)
    out = np.empty(2)
    out[0] = out6[3] * scale
    out[1] = out6[4] * scale
    return out


# -- actions (Section 3.3) ----------------------------------------------------------

@njit(cache=True)
def clip_unit(a):
    """Each part clipped to [-1, 1] as Python's min(max(v, -1), 1); NaN and inf are
    refused (returns False)."""
    for i in range(a.shape[0]):
        if not math.isfinite(a[i]):
            return False
    for i in range(a.shape[0]):
        v = a[i]
        v = -1.0 if -1.0 > v else v
        a[i] = 1.0 if 1.0 < v else v
    return True


@njit(cache=True)
def noise_factor(noise, u):
    """Section 3.3's factor from a uniform draw u in [0, 1): low + (1 - low) u with
    low = 1 - noise, i.e. uniform in [1 - noise, 1] (RandomState.uniform's formula)."""
    low = 1.0 - noise
    return low + (1.0 - low) * u


# -- the drives -------------------------------------------------------------------
# A drive's kernels work on one named record (`Drive`): the MuJoCo handles, the robot's
# parts and the drive's settings for the episode. navigation.Physics.drive_record builds
# it, each drive's task giving its settings (two_wheel.TwoWheel, floating.Floating).

THRUST_SCALED, THRUST_DEMAND, THRUST_CLIPPED = range(3)  # tasks.config.THRUSTS, in order
#: The floating bump readings as the coast runs them: the contact's physics alone
#: ("grip", "slide"), or the velocity change at a contact ("stop", "bounce").
BUMP_PHYSICS, BUMP_STOP, BUMP_BOUNCE = range(3)
#: The drives a Drive record serves (its `kind`).
TWO_WHEEL, FLOATING = range(2)
#: The two-wheel blocked-move readings (tasks.config.BLOCKED_MOVES, LEFTOVER_TURNS, in
#: order): a blocked move stops at contact and its rest is turned (STOP), or is refused
#: whole, undone, and all of it turned (REFUSE); the rest turns the commanded turn's
#: way (COMMANDED) or away from the side whose beams read nearer (AWAY).
BLOCKED_STOP, BLOCKED_REFUSE = range(2)
LEFTOVER_COMMANDED, LEFTOVER_AWAY = range(2)


@structref.register
class DriveType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class Drive(structref.StructRefProxy):
    """One drive's kernels' record: what they read and write of MuJoCo (HANDLES), the
    robot's parts and the drive's settings (SETTINGS, ints then floats). Built by
    navigation.Physics.drive_record; the fields are documented in SETTINGS."""

    def __new__(cls, *args):
        # numba's own constructor (StructRefProxy.__new__) compiles in every
        # process; this one is cached on disk, as the kernels are
        return _new_drive(*args)


#: MuJoCo's structs and arrays the kernels touch: the model and data addresses, the
#: disable flags and the bad-acceleration warning count (int32 views), MuJoCo's own
#: arrays, the base body's rows of xpos and xmat, scratch for mj_objectVelocity; the
#: contact count and the contact array (contact_views) with scratch for the bump
#: readings' coast (and the two-wheel state a refused move returns to: qpos0, qvel0,
#: act_saved); the two-wheel step's plan (move, turn sign, x, y, cos, sin).
HANDLES = ("m", "d", "flags", "bad_qacc", "ctrl", "qpos", "qvel", "act", "sensordata",
           "xpos", "xmat", "velocity6", "ncon", "contact_f", "contact_i", "layout", "qpos0",
           "qvel0", "act_saved", "normal", "plan")
#: The settings, by name, with what each is (ints first, then floats).
SETTINGS = {
    "kind": "TWO_WHEEL or FLOATING",
    "act0": "the drive's first actuator: forward (planar two-wheel), left wheel, thrust x",
    "act1": "the drive's second actuator: turn, right wheel, thrust y",
    "qyaw": "qpos address of the base's yaw hinge, -1 for none",
    "free": "1 for a free-joint base (its tilt is checked), else 0",
    "base": "the base body's id",
    "beam0": "the rangefinders' sensordata: first",
    "beam1": "the rangefinders' sensordata: end",
    "n_first": "substeps of the first phase: the turn (two-wheel), the thrust (floating)",
    "n_rest": "substeps of the rest: the move (two-wheel), the coast (floating)",
    "thrust": "floating: the thrust reading, an index of tasks.config.THRUSTS",
    "velocity_code": "floating: 1 for the velocity read through the 0-255 code, else 0",
    "bump": "floating: BUMP_PHYSICS, BUMP_STOP or BUMP_BOUNCE (tasks.config.BUMPS)",
    "hull": "the bumper geom's id",
    "dof_x": "the base's x velocity dof (qvel address)",
    "dof_y": "the base's y velocity dof",
    "wheels": "two-wheel: 1 for wheels under servos (WheelPhysics), 0 for a planar base",
    "act_adr0": "wheels: the left servo's activation (act address)",
    "act_adr1": "wheels: the right servo's activation",
    "wheel_q0": "wheels: the left wheel hinge's qpos address",
    "wheel_q1": "wheels: the right wheel hinge's qpos address",
    "ramp_first": "wheels: substeps of the first phase's ramp (WheelPhysics.RAMP)",
    "ramp_rest": "wheels: substeps of the rest's ramp",
    "blocked_move": "two-wheel: BLOCKED_STOP or BLOCKED_REFUSE (tasks.config.BLOCKED_MOVES)",
    "leftover_turn": "two-wheel: LEFTOVER_COMMANDED or LEFTOVER_AWAY (LEFTOVER_TURNS)",
    # floats
    "unit": "metres per paper unit",
    "timestep": "the model's timestep, s",
    "metres_to_units": "1 / unit",
    "radius": "the robot's radius, units",
    "min_cos_tilt": "the cosine of the largest tilt (navigation.MAX_TILT_DEGREES)",
    "x0": "the goal square: left", "x1": "right", "y0": "bottom", "y1": "top",
    "levels": "Section 3.2's code: 255",
    "per_unit": "Section 3.2's code: -255 / sensor range",
    "action_noise": "Section 3.3's noise",
    "gain0": "MAX_TURN (two-wheel), MAX_ACCELERATION (floating)",
    "gain1": "MAX_MOVE (two-wheel)",
    "tolerance": "two-wheel: a move short by more than this was blocked",
    "velocity": "floating: m/s -> units per agent step",
    "thrust_force": "floating: the force per unit/step of velocity change",
    "velocity_full": "floating: the velocity code's full scale, units/step",
    "restitution": "floating, bump \"bounce\": the share of the speed into the wall reflected",
    "half_track": "wheels: half the wheels' distance apart (m)",
    "wheel_radius": "wheels: their radius (m)",
}
#: The settings that are ints (the rest are floats).
INT_SETTINGS = tuple(SETTINGS)[:tuple(SETTINGS).index("unit")]
structref.define_proxy(Drive, DriveType, list(HANDLES) + list(SETTINGS))


@njit(cache=True)
def _new_drive(*args):
    """Drive(*args), compiled once and cached (its __new__)."""
    return Drive(*args)


def drive_record(handles, settings):
    """The Drive record of the handles (a dict of HANDLES) and the settings (a dict of
    SETTINGS; a missing one is 0); ValueError naming a setting it does not know."""
    unknown = set(settings) - set(SETTINGS)
    if unknown:
        raise ValueError(f"unknown drive settings: {', '.join(sorted(unknown))}")
    values = [int(settings.get(k, 0)) if k in INT_SETTINGS else float(settings.get(k, 0.0))
              for k in SETTINGS]
    return Drive(*(handles[k] for k in HANDLES), *values)


@njit(cache=True)
def step_phase(s, n):
    """`run` with the robot's tilt check."""
    return run(s.m, s.d, n, s.bad_qacc, s.xmat, s.free != 0, s.min_cos_tilt)


@njit(cache=True)
def base_pose(s):
    """navigation.Physics.robot_pose."""
    return pose(s.xpos, s.xmat, s.qpos, s.qyaw, s.unit)


@njit(cache=True)
def goal_reached(s):
    """navigation.Physics.in_goal."""
    x, y, _ = base_pose(s)
    return s.x0 <= x <= s.x1 and s.y0 <= y <= s.y1


@njit(cache=True)
def sense(s, noise):
    """navigation.Navigation.sense: the range codes plus noise (empty: none)."""
    return encode(ranges(s.m, s.d, s.flags, s.sensordata, s.beam0, s.beam1,
                         s.metres_to_units, s.radius), noise, s.levels, s.per_unit)


@njit(cache=True)
def factors(s, u):
    """navigation.Navigation.noise_factors from its two uniform draws u (none are drawn,
    and both factors are 1, without noise)."""
    noise = s.action_noise
    if noise <= 0:
        return 1.0, 1.0
    return noise_factor(noise, u[0]), noise_factor(noise, u[1])


# -- the two-wheel drive (tasks.two_wheel: Physics, a planar base; WheelPhysics, wheels) --

@njit(cache=True)
def drive(s, speed, yaw_rate):
    """two_wheel.Physics.drive: speed in units/s along the heading, yaw rate in rad/s."""
    s.ctrl[s.act0] = speed * s.unit
    s.ctrl[s.act1] = yaw_rate


@njit(cache=True)
def two_wheel_phase(s, turn, amount, n, ramp):
    """A phase of n substeps that turns by `amount` rad counter-clockwise (turn) or moves
    `amount` units forward: a planar base's servos get the speed that does it in the n
    substeps (two_wheel.Physics.begin_turn, begin_move); wheels get the speeds that turn
    them by the phase's angle over the first `ramp` substeps, then zero speeds for the
    rest, their servos settling on the targets (WheelPhysics._wheel_speeds and step).
    Returns a status."""
    dt = s.timestep
    if s.wheels == 0:
        if turn:
            drive(s, 0.0, amount / (n * dt))
        else:
            drive(s, amount / (n * dt), 0.0)
        return step_phase(s, n)
    if turn:
        w = amount * s.half_track / s.wheel_radius
        left, right = -w, w
    else:
        w = amount * s.unit / s.wheel_radius
        left, right = w, w
    s.ctrl[s.act0] = left / (ramp * dt)
    s.ctrl[s.act1] = right / (ramp * dt)
    status = step_phase(s, ramp)
    if status != OK:
        return status
    s.ctrl[s.act0] = 0.0
    s.ctrl[s.act1] = 0.0
    if n > ramp:
        status = step_phase(s, n - ramp)
    return status


@njit(cache=True)
def two_wheel_halt(s):
    """Physics.halt (both servos' speeds 0) or WheelPhysics.halt (the wheels' speeds 0
    and their targets where the wheels are: a stalled wheel gives up the rest)."""
    if s.wheels == 0:
        drive(s, 0.0, 0.0)
        return
    s.ctrl[s.act0] = 0.0
    s.act[s.act_adr0] = s.qpos[s.wheel_q0]
    s.ctrl[s.act1] = 0.0
    s.act[s.act_adr1] = s.qpos[s.wheel_q1]


@njit(cache=True)
def two_wheel_turn(s, a, u):
    """two_wheel.TwoWheel.before_step for the clipped action a and the noise's uniforms
    u: the turn phase. s.plan gets (move, turn sign, x, y, cos, sin of the heading after
    the turn) for the move phase and two_wheel_finish. Returns a status."""
    noise_turn, noise_move = factors(s, u)
    turn = -a * s.gain0 * noise_turn  # counter-clockwise positive
    move = s.gain1 * (1.0 - abs(a)) * noise_move
    status = two_wheel_phase(s, True, turn, s.n_first, s.ramp_first)
    if s.blocked_move == BLOCKED_REFUSE:  # the state a refused move returns to
        s.qpos0[:] = s.qpos
        s.qvel0[:] = s.qvel
        s.act_saved[:] = s.act
    x, y, heading = base_pose(s)
    plan = s.plan
    plan[0] = move
    plan[1] = 1.0 if turn > 0 else -1.0
    plan[2], plan[3], plan[4], plan[5] = x, y, math.cos(heading), math.sin(heading)
    return status


@njit(cache=True)
def away_sign(distances, commanded):
    """The leftover turn's sign (counter-clockwise +1) under LEFTOVER_AWAY, from the
    beams' surface distances, leftmost first: away from the half whose nearest beam
    reads nearer (the left half nearer: -1, a right turn; the right: +1), the middle
    beam of an odd count in neither; `commanded` on a tie (nothing seen on either side
    included)."""
    n = distances.shape[0]
    half = n // 2
    left, right = np.inf, np.inf
    for i in range(half):
        left = min(left, distances[i])
        right = min(right, distances[n - 1 - i])
    if left < right:
        return -1.0
    if right < left:
        return 1.0
    return commanded


@njit(cache=True)
def two_wheel_finish(s):
    """two_wheel.TwoWheel.after_step: a move stopped short by more than the tolerance
    turns the rest, at MAX_TURN per MAX_MOVE, in the commanded turn's direction
    (LEFTOVER_AWAY: away from the nearer side, at the blocked pose, `away_sign`); under
    BLOCKED_REFUSE the move is undone first (the state after the turn, then
    mj_forward) and all of it is turned. Then the drive halts. Returns (status,
    substeps run, in the goal)."""
    x, y, _ = base_pose(s)
    plan = s.plan
    rest = plan[0] - ((x - plan[2]) * plan[4] + (y - plan[3]) * plan[5])
    status, n = OK, 0
    if rest > s.tolerance:
        sign = plan[1]
        if s.leftover_turn == LEFTOVER_AWAY:
            sign = away_sign(ranges(s.m, s.d, s.flags, s.sensordata, s.beam0, s.beam1,
                                    s.metres_to_units, s.radius), sign)
        if s.blocked_move == BLOCKED_REFUSE:
            s.qpos[:] = s.qpos0
            s.qvel[:] = s.qvel0
            s.act[:] = s.act_saved
            before = s.bad_qacc[0]
            mj_forward(s.m, s.d)
            if s.bad_qacc[0] != before:
                return UNSTABLE, 0, False
            rest = plan[0]
        leftover = sign * rest * s.gain0 / s.gain1
        n = s.n_first
        status = two_wheel_phase(s, True, leftover, n, s.ramp_first)
        if status != OK:
            return status, n, False
    two_wheel_halt(s)
    return status, n, goal_reached(s)


@njit(cache=True)
def two_wheel_step(s, action, u, noise):
    """One agent step of the two-wheel drive, the hooks' work in their order: the turn,
    the move, a blocked move's leftover turn, the halt, the goal test and the
    range codes. Returns (status, substeps run, in the goal, codes)."""
    nothing = np.empty(0)
    if not clip_unit(action):
        return NOT_FINITE, 0, False, nothing
    status = two_wheel_turn(s, action[0], u)
    n = s.n_first
    if status != OK:
        return status, n, False, nothing
    status = two_wheel_phase(s, False, s.plan[0], s.n_rest, s.ramp_rest)
    n += s.n_rest
    if status != OK:
        return status, n, False, nothing
    status, more, goal = two_wheel_finish(s)
    n += more
    if status != OK:
        return status, n, False, nothing
    return OK, n, goal, sense(s, noise)


# -- the floating drive (tasks.floating.Physics) -------------------------------------

@njit(cache=True)
def demand(s, a):
    """floating.Floating.demand: the velocity change (units/step) for a demand a, by the
    thrust reading: "scaled" MAX_ACCELERATION a, "demand" a, "clipped" a clipped to
    [-MAX_ACCELERATION, MAX_ACCELERATION] (Python's min(max(a, -g), g))."""
    gain = s.gain0
    reading = s.thrust
    if reading == THRUST_SCALED:
        return gain * a
    if reading == THRUST_DEMAND:
        return a
    v = -gain if -gain > a else a
    return gain if gain < v else v


@njit(cache=True)
def hull_normal(ncon, contact_f, contact_i, layout, hull, normal):
    """floating.Physics's bumper contact: the first contact of geom `hull`, its normal
    (the frame's first row, x and y) written into `normal` pointing from the wall into
    the robot. Returns False when the bumper touches nothing. layout: contact_views'."""
    for k in range(ncon[0]):
        f = k * layout[0] + layout[1]
        i = k * layout[2]
        if contact_i[i + layout[3]] == hull:
            normal[0] = -contact_f[f]
            normal[1] = -contact_f[f + 1]
            return True
        if contact_i[i + layout[4]] == hull:
            normal[0] = contact_f[f]
            normal[1] = contact_f[f + 1]
            return True
    return False


@njit(cache=True)
def bump_phase(s, n):
    """floating.Physics.step: n substeps; with the bump readings "stop" and "bounce", a
    substep that brings the bumper into a wall while moving towards it is undone (qpos
    back, so no contact force acts), the velocity becomes 0 ("stop") or its mirror image
    off the wall, the part into it scaled by the restitution ("bounce"), and mj_forward
    recomputes the state."""
    if s.bump == BUMP_PHYSICS:
        return step_phase(s, n)
    qpos, qvel, qpos0, qvel0, normal = s.qpos, s.qvel, s.qpos0, s.qvel0, s.normal
    dx, dy = s.dof_x, s.dof_y
    for _ in range(n):
        qpos0[:] = qpos
        qvel0[:] = qvel
        status = step_phase(s, 1)
        if status != OK:
            return status
        if not hull_normal(s.ncon, s.contact_f, s.contact_i, s.layout, s.hull, normal):
            continue
        vx, vy = qvel0[dx], qvel0[dy]
        into = vx * normal[0] + vy * normal[1]
        if into >= 0:  # touching while moving away: the contact's physics alone
            continue
        qpos[:] = qpos0
        qvel[:] = 0.0
        if s.bump == BUMP_BOUNCE:
            back = (1.0 + s.restitution) * into
            qvel[dx] = vx - back * normal[0]
            qvel[dy] = vy - back * normal[1]
        before = s.bad_qacc[0]
        mj_forward(s.m, s.d)
        if s.bad_qacc[0] != before:
            return UNSTABLE
    return OK


@njit(cache=True)
def floating_thrust(s, a, u):
    """floating.Floating.before_step for the clipped action a and the noise's uniforms
    u: the thrust during one substep, then none. Returns a status."""
    nh, nv = factors(s, u)
    scale = s.thrust_force
    s.ctrl[s.act0] = demand(s, a[0]) * nh * scale
    s.ctrl[s.act1] = demand(s, a[1]) * nv * scale
    status = bump_phase(s, s.n_first)
    s.ctrl[s.act0] = 0.0 * scale
    s.ctrl[s.act1] = 0.0 * scale
    return status


@njit(cache=True)
def velocity_reading(s, v, noise):
    """floating.Floating.sense_velocity on the velocity v (changed in place): plus the
    noise (an empty array: none), then, with the velocity code, the 0-255 code over
    +-full scale and back (np.clip as numpy's maximum then minimum)."""
    if noise.shape[0]:
        for i in range(v.shape[0]):
            v[i] = v[i] + noise[i]
    if s.velocity_code:
        half, full = s.levels / 2, s.velocity_full
        for i in range(v.shape[0]):
            x = v[i] / full
            x = x if x > -1.0 else -1.0
            x = x if x < 1.0 else 1.0
            code = np.rint(x * half + half)
            v[i] = (code - half) / half * full
    return v


@njit(cache=True)
def floating_step(s, action, u, noise, velocity_noise):
    """One agent step of the floating drive, the hooks' work in their order: the thrust,
    the coast (with the bump reading's velocity change), the goal test, the range codes
    and the velocity. Returns (status, substeps run, in the goal, codes, velocity)."""
    nothing = np.empty(0)
    if not clip_unit(action):
        return NOT_FINITE, 0, False, nothing, nothing
    status = floating_thrust(s, action, u)
    n = s.n_first
    if status != OK:
        return status, n, False, nothing, nothing
    status = bump_phase(s, s.n_rest)
    n += s.n_rest
    if status != OK:
        return status, n, False, nothing, nothing
    goal = goal_reached(s)
    codes = sense(s, noise)
    v = velocity(s.m, s.d, s.base, s.velocity, s.velocity6)
    return OK, n, goal, codes, velocity_reading(s, v, velocity_noise)


@njit(cache=True)
def step(s, action, u, noise, velocity_noise, codes, vel):
    """One agent step of the record's drive (two_wheel_step or floating_step) on a
    finite action (clipped in place): the range codes into codes and, floating, the
    velocity into vel. Returns (status, substeps run, in the goal)."""
    if s.kind == FLOATING:
        status, n, goal, c, v = floating_step(s, action, u, noise, velocity_noise)
        if status == OK:
            vel[:] = v
    else:
        status, n, goal, c = two_wheel_step(s, action, u, noise)
    if status == OK:
        codes[:] = c
    return status, n, goal


# -- the task's random stream ---------------------------------------------------------
# dm_control's tasks draw from a legacy RandomState (MT19937), which numba cannot take.
# Its draws are doubles from one stream (random_sample; the legacy normal's polar method
# takes its pairs from the same doubles), so the task's draws come from a buffer of the
# stream's next doubles (`Stream`), used by the legacy algorithms (`gauss`); the
# RandomState is wound to just past what was used whenever Python reads it
# (navigation.TaskStream).

#: A buffer's doubles; a step uses about a dozen.
BUFFER = 8192
#: Draws stop before a step when fewer doubles than this are left (a step's draws: 2
#: uniforms and 2 per attempt of each pair of normals, whose attempts repeat with
#: probability 1 - pi / 4).
RESERVE = 64


@structref.register
class StreamType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(typ)) for name, typ in fields)


class Stream(structref.StructRefProxy):
    """A stretch of the task's RandomState as doubles: the buffer, the next double's
    index, and legacy_gauss's cached value (has_gauss, gauss)."""

    def __new__(cls, *args):
        # numba's own constructor (StructRefProxy.__new__) compiles in every
        # process; this one is cached on disk, as the kernels are
        return _new_stream(*args)


structref.define_proxy(Stream, StreamType, ["buffer", "cursor", "has_gauss", "gauss"])


@njit(cache=True)
def _new_stream(*args):
    """Stream(*args), compiled once and cached (its __new__)."""
    return Stream(*args)


@njit(cache=True)
def stream_state(st):
    """(cursor, has_gauss, gauss) of a Stream, for Python."""
    return st.cursor, st.has_gauss, st.gauss


@njit(cache=True)
def stream_refill(st, buffer, has_gauss, value):
    """The Stream starts over on `buffer` with legacy_gauss's cache (has_gauss, value)."""
    st.buffer = buffer
    st.cursor = 0
    st.has_gauss = has_gauss
    st.gauss = value


@njit(cache=True)
def gauss(st):
    """numpy's legacy_gauss on the buffered doubles: the cached value if there is one,
    else the polar method on pairs of doubles, keeping the second value."""
    if st.has_gauss:
        value = st.gauss
        st.has_gauss = 0
        st.gauss = 0.0
        return value
    buf = st.buffer
    while True:
        p = st.cursor
        x1 = 2.0 * buf[p] - 1.0
        x2 = 2.0 * buf[p + 1] - 1.0
        st.cursor = p + 2
        r2 = x1 * x1 + x2 * x2
        if not (r2 >= 1.0 or r2 == 0.0):
            break
    f = math.sqrt(-2.0 * math.log(r2) / r2)
    st.gauss = f * x1
    st.has_gauss = 1
    return f * x2


@njit(cache=True)
def task_draws(st, u, z, sensor_noise, vz, velocity_noise):
    """One step's draws of the task, in its order: the action noise's two uniforms (u),
    the sensor noise's normals (z: RandomState.normal(0, sd, size)), the floating
    velocity noise's normals (vz); an array is empty where its noise is off. Returns
    False, with the stream as it was, when the buffer might run out meanwhile."""
    start, had, value = st.cursor, st.has_gauss, st.gauss
    if start + u.shape[0] + 4 * (z.shape[0] + vz.shape[0]) + RESERVE > st.buffer.shape[0]:
        return False
    for i in range(u.shape[0]):
        u[i] = st.buffer[st.cursor]
        st.cursor += 1
    for i in range(z.shape[0]):
        z[i] = 0.0 + sensor_noise * gauss(st)
    for i in range(vz.shape[0]):
        vz[i] = 0.0 + velocity_noise * gauss(st)
    if st.cursor > st.buffer.shape[0] - RESERVE:  # pragma: no cover - many rejections in a row
        st.cursor, st.has_gauss, st.gauss = start, had, value
        return False
    return True
