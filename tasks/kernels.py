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

_LIBRARY = sorted(glob.glob(os.path.join(os.path.dirname(mujoco.__file__), "libmujoco.so*")))
if not _LIBRARY:  # pragma: no cover - every mujoco wheel for Linux ships it
    raise ImportError("libmujoco.so not found beside the mujoco package")
binding.load_library_permanently(_LIBRARY[0])

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
    """Rangefinder readings (m from the centre; -1 = no hit) -> units from the surface."""
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
def ranges(m, d, flags, sensordata, beams, metres_to_units, radius):
    """The sensor stage run once at the current state (MuJoCo's is disabled while
    stepping), then each beam's distance from the body surface in units (inf: no hit).
    beams = (first, end) of the rangefinders' sensordata."""
    flags[0] &= ~_SENSOR_BIT
    mj_sensorPos(m, d)
    flags[0] |= _SENSOR_BIT
    return surface_distances(sensordata[beams[0]:beams[1]], metres_to_units, radius)


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
# A drive's settings reach the kernels as two arrays, `ints` and `floats`, indexed by
# the names below: the physics fills its part when it loads (navigation.Physics), the
# task its part when an episode starts (the substeps, the noise, the drive's constants).
(I_ACT0, I_ACT1,   # the drive's two actuators: forward, turn (two-wheel); thrust x, y
 I_QYAW,           # qpos address of the base's yaw hinge, -1 for none
 I_FREE,           # 1 for a free-joint base (its tilt is checked), else 0
 I_BASE,           # the base body's id
 I_BEAM0, I_BEAM1,  # the rangefinders' sensordata: first, end
 I_N_FIRST,        # substeps of the first phase: the turn (two-wheel), the thrust (floating)
 I_N_REST,         # substeps of the rest: the move (two-wheel), the coast (floating)
 I_THRUST,         # floating: the thrust reading, an index of tasks.config.THRUSTS
 I_VELOCITY_CODE,  # floating: 1 for the velocity read through the 0-255 code, else 0
 I_BUMP,           # floating: BUMP_PHYSICS, BUMP_STOP or BUMP_BOUNCE (tasks.config.BUMPS)
 I_HULL,           # the bumper geom's id
 I_DOF_X, I_DOF_Y,  # the base's x and y velocity dofs (qvel addresses)
 I_WHEELS,         # two-wheel: 1 for wheels under servos (WheelPhysics), 0 for a planar base
 I_ACT_ADR0, I_ACT_ADR1,    # wheels: the servos' activations (act addresses), left, right
 I_WHEEL_Q0, I_WHEEL_Q1,    # wheels: the wheel hinges' qpos addresses, left, right
 I_RAMP_FIRST, I_RAMP_REST,  # wheels: substeps of each phase's ramp (WheelPhysics.RAMP)
 ) = range(22)
N_INTS = 22
THRUST_SCALED, THRUST_DEMAND, THRUST_CLIPPED = range(3)  # tasks.config.THRUSTS, in order
#: The floating bump readings as the coast runs them: the contact's physics alone
#: ("grip", "slide"), or the velocity change at a contact ("stop", "bounce").
BUMP_PHYSICS, BUMP_STOP, BUMP_BOUNCE = range(3)
(F_UNIT, F_TIMESTEP, F_METRES_TO_UNITS, F_RADIUS, F_MIN_COS_TILT,
 F_X0, F_X1, F_Y0, F_Y1,  # the goal square, units
 F_LEVELS, F_PER_UNIT,    # Section 3.2's code: 255 and -255 / sensor range
 F_ACTION_NOISE,          # Section 3.3's noise
 F_GAIN0, F_GAIN1,        # MAX_TURN, MAX_MOVE (two-wheel); MAX_ACCELERATION, - (floating)
 F_TOLERANCE,             # two-wheel: a move short by more than this was blocked
 F_VELOCITY,              # floating: m/s -> units per agent step
 F_THRUST,                # floating: the force per unit/step of velocity change
 F_VELOCITY_FULL,         # floating: the velocity code's full scale, units/step
 F_RESTITUTION,           # floating, bump "bounce": the share of the speed into the wall reflected
 F_HALF_TRACK, F_WHEEL_RADIUS,  # wheels: half the wheels' distance apart, their radius (m)
 ) = range(21)
N_FLOATS = 21


@njit(cache=True)
def step_phase(m, d, n, bad_qacc, xmat, ints, floats):
    """`run` with the physics' tilt check."""
    return run(m, d, n, bad_qacc, xmat, ints[I_FREE] != 0, floats[F_MIN_COS_TILT])


@njit(cache=True)
def base_pose(qpos, xpos, xmat, ints, floats):
    return pose(xpos, xmat, qpos, ints[I_QYAW], floats[F_UNIT])


@njit(cache=True)
def goal_reached(qpos, xpos, xmat, ints, floats):
    """navigation.Physics.in_goal."""
    x, y, _ = base_pose(qpos, xpos, xmat, ints, floats)
    return floats[F_X0] <= x <= floats[F_X1] and floats[F_Y0] <= y <= floats[F_Y1]


@njit(cache=True)
def readings(m, d, flags, sensordata, ints, floats, noise):
    """navigation.Navigation.sense: the encoded readings plus noise (empty: none)."""
    return encode(ranges(m, d, flags, sensordata, ints[I_BEAM0:I_BEAM1 + 1],
                         floats[F_METRES_TO_UNITS], floats[F_RADIUS]),
                  noise, floats[F_LEVELS], floats[F_PER_UNIT])


@njit(cache=True)
def factors(u, floats):
    """navigation.Navigation.noise_factors from its two uniform draws u (none are drawn,
    and both factors are 1, without noise)."""
    noise = floats[F_ACTION_NOISE]
    if noise <= 0:
        return 1.0, 1.0
    return noise_factor(noise, u[0]), noise_factor(noise, u[1])


# -- the two-wheel drive (tasks.two_wheel: Physics, a planar base; WheelPhysics, wheels) --

@njit(cache=True)
def drive(ctrl, ints, floats, speed, yaw_rate):
    """two_wheel.Physics.drive: speed in units/s along the heading, yaw rate in rad/s."""
    ctrl[ints[I_ACT0]] = speed * floats[F_UNIT]
    ctrl[ints[I_ACT1]] = yaw_rate


@njit(cache=True)
def two_wheel_phase(turn, amount, n, ramp, m, d, ctrl, xmat, bad_qacc, ints, floats):
    """A phase of n substeps that turns by `amount` rad counter-clockwise (turn) or moves
    `amount` units forward: a planar base's servos get the speed that does it in the n
    substeps (two_wheel.Physics.begin_turn, begin_move); wheels get the speeds that turn
    them by the phase's angle over the first `ramp` substeps, then zero speeds for the
    rest, their servos settling on the targets (WheelPhysics._wheel_speeds and step).
    Returns a status."""
    dt = floats[F_TIMESTEP]
    if ints[I_WHEELS] == 0:
        if turn:
            drive(ctrl, ints, floats, 0.0, amount / (n * dt))
        else:
            drive(ctrl, ints, floats, amount / (n * dt), 0.0)
        return step_phase(m, d, n, bad_qacc, xmat, ints, floats)
    if turn:
        w = amount * floats[F_HALF_TRACK] / floats[F_WHEEL_RADIUS]
        left, right = -w, w
    else:
        w = amount * floats[F_UNIT] / floats[F_WHEEL_RADIUS]
        left, right = w, w
    ctrl[ints[I_ACT0]] = left / (ramp * dt)
    ctrl[ints[I_ACT1]] = right / (ramp * dt)
    status = step_phase(m, d, ramp, bad_qacc, xmat, ints, floats)
    if status != OK:
        return status
    ctrl[ints[I_ACT0]] = 0.0
    ctrl[ints[I_ACT1]] = 0.0
    if n > ramp:
        status = step_phase(m, d, n - ramp, bad_qacc, xmat, ints, floats)
    return status


@njit(cache=True)
def two_wheel_halt(ctrl, act, qpos, ints, floats):
    """Physics.halt (both servos' speeds 0) or WheelPhysics.halt (the wheels' speeds 0
    and their targets where the wheels are: a stalled wheel gives up the rest)."""
    if ints[I_WHEELS] == 0:
        drive(ctrl, ints, floats, 0.0, 0.0)
        return
    ctrl[ints[I_ACT0]] = 0.0
    act[ints[I_ACT_ADR0]] = qpos[ints[I_WHEEL_Q0]]
    ctrl[ints[I_ACT1]] = 0.0
    act[ints[I_ACT_ADR1]] = qpos[ints[I_WHEEL_Q1]]


@njit(cache=True)
def two_wheel_turn(a, u, m, d, ctrl, qpos, xpos, xmat, bad_qacc, ints, floats, plan):
    """two_wheel.TwoWheel.before_step for the clipped action a and the noise's uniforms
    u: the turn phase. plan gets (move, turn sign, x, y, cos, sin of the heading after
    the turn) for the move phase and two_wheel_finish. Returns a status."""
    noise_turn, noise_move = factors(u, floats)
    turn = -a * floats[F_GAIN0] * noise_turn  # counter-clockwise positive
    move = floats[F_GAIN1] * (1.0 - abs(a)) * noise_move
    status = two_wheel_phase(True, turn, ints[I_N_FIRST], ints[I_RAMP_FIRST], m, d, ctrl,
                             xmat, bad_qacc, ints, floats)
    x, y, heading = base_pose(qpos, xpos, xmat, ints, floats)
    plan[0] = move
    plan[1] = 1.0 if turn > 0 else -1.0
    plan[2], plan[3], plan[4], plan[5] = x, y, math.cos(heading), math.sin(heading)
    return status


@njit(cache=True)
def two_wheel_finish(m, d, ctrl, act, qpos, xpos, xmat, bad_qacc, ints, floats, plan):
    """two_wheel.TwoWheel.after_step: a move stopped short by more than the tolerance
    turns the rest, at MAX_TURN per MAX_MOVE, in the commanded turn's direction; then
    the drive halts. Returns (status, substeps run, in the goal)."""
    x, y, _ = base_pose(qpos, xpos, xmat, ints, floats)
    rest = plan[0] - ((x - plan[2]) * plan[4] + (y - plan[3]) * plan[5])
    status, n = OK, 0
    if rest > floats[F_TOLERANCE]:
        leftover = plan[1] * rest * floats[F_GAIN0] / floats[F_GAIN1]
        n = ints[I_N_FIRST]
        status = two_wheel_phase(True, leftover, n, ints[I_RAMP_FIRST], m, d, ctrl, xmat,
                                 bad_qacc, ints, floats)
        if status != OK:
            return status, n, False
    two_wheel_halt(ctrl, act, qpos, ints, floats)
    return status, n, goal_reached(qpos, xpos, xmat, ints, floats)


@njit(cache=True)
def two_wheel_step(action, u, noise, m, d, flags, ctrl, qpos, xpos, xmat, sensordata,
                   bad_qacc, ints, floats, plan, act):
    """One agent step of the two-wheel drive, the hooks' work in their order: the turn,
    the move, a blocked move's leftover turn, the halt, the goal test and the encoded
    readings. Returns (status, substeps run, in the goal, readings)."""
    nothing = np.empty(0)
    if not clip_unit(action):
        return NOT_FINITE, 0, False, nothing
    status = two_wheel_turn(action[0], u, m, d, ctrl, qpos, xpos, xmat, bad_qacc, ints,
                            floats, plan)
    n = ints[I_N_FIRST]
    if status != OK:
        return status, n, False, nothing
    status = two_wheel_phase(False, plan[0], ints[I_N_REST], ints[I_RAMP_REST], m, d, ctrl,
                             xmat, bad_qacc, ints, floats)
    n += ints[I_N_REST]
    if status != OK:
        return status, n, False, nothing
    status, more, goal = two_wheel_finish(m, d, ctrl, act, qpos, xpos, xmat, bad_qacc, ints,
                                          floats, plan)
    n += more
    if status != OK:
        return status, n, False, nothing
    return OK, n, goal, readings(m, d, flags, sensordata, ints, floats, noise)


# -- the floating drive (tasks.floating.Physics) -------------------------------------

@njit(cache=True)
def demand(a, ints, floats):
    """floating.Floating.demand: the velocity change (units/step) for a demand a, by the
    thrust reading: "scaled" MAX_ACCELERATION a, "demand" a, "clipped" a clipped to
    [-MAX_ACCELERATION, MAX_ACCELERATION] (Python's min(max(a, -g), g))."""
    gain = floats[F_GAIN0]
    reading = ints[I_THRUST]
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
def bump_phase(m, d, n, bad_qacc, xmat, qpos, qvel, ints, floats, bump):
    """floating.Physics.step: n substeps; with the bump readings "stop" and "bounce", a
    substep that brings the bumper into a wall while moving towards it is undone (qpos
    back, so no contact force acts), the velocity becomes 0 ("stop") or its mirror image
    off the wall, the part into it scaled by the restitution ("bounce"), and mj_forward
    recomputes the state. bump: (ncon, contact floats, contact ints, layout, qpos0,
    qvel0, normal) from contact_count, contact_views and scratch arrays."""
    if ints[I_BUMP] == BUMP_PHYSICS:
        return step_phase(m, d, n, bad_qacc, xmat, ints, floats)
    ncon, contact_f, contact_i, layout, qpos0, qvel0, normal = bump
    dx, dy = ints[I_DOF_X], ints[I_DOF_Y]
    for _ in range(n):
        qpos0[:] = qpos
        qvel0[:] = qvel
        status = step_phase(m, d, 1, bad_qacc, xmat, ints, floats)
        if status != OK:
            return status
        if not hull_normal(ncon, contact_f, contact_i, layout, ints[I_HULL], normal):
            continue
        vx, vy = qvel0[dx], qvel0[dy]
        into = vx * normal[0] + vy * normal[1]
        if into >= 0:  # touching while moving away: the contact's physics alone
            continue
        qpos[:] = qpos0
        qvel[:] = 0.0
        if ints[I_BUMP] == BUMP_BOUNCE:
            back = (1.0 + floats[F_RESTITUTION]) * into
            qvel[dx] = vx - back * normal[0]
            qvel[dy] = vy - back * normal[1]
        before = bad_qacc[0]
        mj_forward(m, d)
        if bad_qacc[0] != before:
            return UNSTABLE
    return OK


@njit(cache=True)
def floating_thrust(a, u, m, d, ctrl, qpos, xmat, bad_qacc, ints, floats, qvel, bump):
    """floating.Floating.before_step for the clipped action a and the noise's uniforms
    u: the thrust during one substep, then none. Returns a status."""
    nh, nv = factors(u, floats)
    scale = floats[F_THRUST]
    ctrl[ints[I_ACT0]] = demand(a[0], ints, floats) * nh * scale
    ctrl[ints[I_ACT1]] = demand(a[1], ints, floats) * nv * scale
    status = bump_phase(m, d, ints[I_N_FIRST], bad_qacc, xmat, qpos, qvel, ints, floats, bump)
    ctrl[ints[I_ACT0]] = 0.0 * scale
    ctrl[ints[I_ACT1]] = 0.0 * scale
    return status


@njit(cache=True)
def velocity_reading(v, noise, ints, floats):
    """floating.Floating.sense_velocity on the velocity v (changed in place): plus the
    noise (an empty array: none), then, with the velocity code, the 0-255 code over
    +-full scale and back (np.clip as numpy's maximum then minimum)."""
    if noise.shape[0]:
        for i in range(v.shape[0]):
            v[i] = v[i] + noise[i]
    if ints[I_VELOCITY_CODE]:
        half, full = floats[F_LEVELS] / 2, floats[F_VELOCITY_FULL]
        for i in range(v.shape[0]):
            x = v[i] / full
            x = x if x > -1.0 else -1.0
            x = x if x < 1.0 else 1.0
            code = np.rint(x * half + half)
            v[i] = (code - half) / half * full
    return v


@njit(cache=True)
def floating_step(action, u, noise, velocity_noise, m, d, flags, ctrl, qpos, xpos, xmat,
                  sensordata, bad_qacc, ints, floats, velocity6, qvel, bump):
    """One agent step of the floating drive, the hooks' work in their order: the thrust,
    the coast (with the bump reading's velocity change), the goal test, the encoded
    readings and the velocity reading. Returns (status, substeps run, in the goal,
    readings, velocity)."""
    nothing = np.empty(0)
    if not clip_unit(action):
        return NOT_FINITE, 0, False, nothing, nothing
    status = floating_thrust(action, u, m, d, ctrl, qpos, xmat, bad_qacc, ints, floats,
                             qvel, bump)
    n = ints[I_N_FIRST]
    if status != OK:
        return status, n, False, nothing, nothing
    status = bump_phase(m, d, ints[I_N_REST], bad_qacc, xmat, qpos, qvel, ints, floats, bump)
    n += ints[I_N_REST]
    if status != OK:
        return status, n, False, nothing, nothing
    goal = goal_reached(qpos, xpos, xmat, ints, floats)
    codes = readings(m, d, flags, sensordata, ints, floats, noise)
    v = velocity(m, d, ints[I_BASE], floats[F_VELOCITY], velocity6)
    return OK, n, goal, codes, velocity_reading(v, velocity_noise, ints, floats)
