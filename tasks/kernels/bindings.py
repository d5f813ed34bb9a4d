"""MuJoCo's C functions for compiled kernels, and views of the struct fields they touch.

Kernels call MuJoCo's C functions (mj_step, mj_step1, mj_step2, mj_sensorPos,
mj_forward, mj_objectVelocity, mj_geomDistance) directly on the mjModel and mjData, with no Python in
between. The functions are declared by symbol name (numba ExternalFunction), resolved in
libmujoco.so, which the mujoco package has loaded; compiled kernels stay cacheable
because they hold no addresses. Every kernel is ``@njit(cache=True)`` with no fastmath:
each floating-point operation runs as written, in the same order (same bits, tested).

What a kernel reads and writes of MuJoCo's structs:
    m, d          the mjModel and mjData addresses (`addresses`)
    flags         an int32 view of m->opt.disableflags (the sensor stage is switched on
                  only for mj_sensorPos: tasks.kernels.sensing.ranges)
    bad_qacc      an int32 view of d->warning[mjWARN_BADQACC].number
    ncon, contact the contact count and the contact array (contact_views)
    qpos, ctrl, sensordata, ...   MjData's own arrays (numpy views)
    xpos, xmat    the base body's rows of d->xpos and d->xmat

Also MuJoCo's stage timers (`stage_timers_off`) and `run`, the substeps as dm_control's
legacy step runs them, with the statuses every kernel returns.
"""
import ctypes
import glob
import os

import numpy as np
from llvmlite import binding
from numba import njit, types

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from tasks.simulator import mujoco

_LIBRARY = sorted(glob.glob(os.path.join(os.path.dirname(mujoco.__file__), "libmujoco.so*")))
if not _LIBRARY:  # pragma: no cover - every mujoco wheel for Linux ships it
    raise ImportError("libmujoco.so not found beside the mujoco package")
binding.load_library_permanently(_LIBRARY[0])

#: MuJoCo's timer callback, the C global mjcb_time of the library loaded above (one
#: handle per process: dlopen gives the mujoco package's own).
TIMER_CALLBACK = ctypes.c_void_p.in_dll(ctypes.CDLL(_LIBRARY[0]), "mjcb_time")


class stage_timers_off:  # a class named as a function: `with stage_timers_off():`
    """MuJoCo's stage timers off inside the block, the previous callback back after it.

    The mujoco package sets mjcb_time at import (a clock for mjData.timer, its profiler's
    read-out), and every mj_step then reads the clock about twenty times, once at each
    stage's start and end: a share of every step worth saving (docs/speed.md). The timers
    only fill mjData.timer, which nothing here reads, so every other value stays the
    same bit for bit (tests/test_kernels.py). A class rather than a generator: the
    Gymnasium step enters it once per step, and a class costs less to enter (docs/speed.md)."""
    __slots__ = ("_previous",)

    def __enter__(self):
        self._previous = TIMER_CALLBACK.value
        TIMER_CALLBACK.value = None

    def __exit__(self, *exc):
        TIMER_CALLBACK.value = self._previous


_P = types.uintp  # a pointer, as an integer (the C ABI passes both in one register)
mj_step = types.ExternalFunction("mj_step", types.void(_P, _P))
mj_step1 = types.ExternalFunction("mj_step1", types.void(_P, _P))
mj_step2 = types.ExternalFunction("mj_step2", types.void(_P, _P))
mj_sensorPos = types.ExternalFunction("mj_sensorPos", types.void(_P, _P))
mj_forward = types.ExternalFunction("mj_forward", types.void(_P, _P))
mj_geomDistance = types.ExternalFunction(
    "mj_geomDistance", types.float64(_P, _P, types.intc, types.intc, types.float64, _P))
mj_objectVelocity = types.ExternalFunction(
    "mj_objectVelocity", types.void(_P, _P, types.intc, types.intc, _P, types.intc))

#: A kernel's status: the step ran; MuJoCo flagged an unstable state (mjWARN_BADQACC);
#: a free-joint robot tilted past navigation.MAX_TILT_DEGREES; the action is not finite;
#: the robot's centre left the room's floor (tasks.kernels.env_step.step).
OK, UNSTABLE, TIPPED, NOT_FINITE, OUTSIDE = 0, 1, 2, 3, 4

OBJ_BODY = int(mujoco.mjtObj.mjOBJ_BODY)
SENSOR_BIT = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)


def addresses(model, data):
    """The mjModel's and mjData's addresses (mujoco.MjModel, mujoco.MjData): the one read
    of the bindings' private `_address`, which the mujoco package has as its only way to
    them (its ctypes views of the structs' arrays start inside the structs, not at
    them)."""
    return model._address, data._address


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
        raise RuntimeError("tasks.kernels.bindings: a field of MuJoCo's struct was not found")
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
        raise RuntimeError("tasks.kernels.bindings: an unexpected mjContact layout")
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
def tilted(xmat, min_cos_tilt):
    """Whether a body whose frame is xmat (row-major 3 x 3) is tilted past the angle
    whose cosine is min_cos_tilt: its z axis's vertical component is below it."""
    return xmat[8] < min_cos_tilt


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
    if free and tilted(xmat, min_cos_tilt):
        return TIPPED
    return OK
