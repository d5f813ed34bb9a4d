"""The intrinsic behaviours of Section 3.4 and the random walk they are compared with.

Inputs are the range codes (0..255) scaled to [0, 1], the "ranges". A fallback behaviour is a
callable fallback(ranges, rng) -> action array; one with a reset() method is reset
by the agent when a trial ends.

Three readings are switches (ebrl.config.READINGS), passed to fallback_for:
eq9_dead_zone ("zero": eq 9's "not changed" is zero acceleration; "keep": the
fallback's previous acceleration on that axis), random_in_avoidance ("replace":
the random action replaces the avoidance action; "add": it is added to it, clipped)
and random_demand ("gaussian": every random action Section 3.4's Gaussian;
"uniform_walk": the random walk's uniform over (-1, 1); "uniform_all": every random
action's).
"""
import ctypes.util

import numpy as np
from llvmlite import binding
from numba import njit, types

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled import records
from compiled.clip import clip_unit
from ebrl.config import CONDITIONS, READINGS, check_reading
from ebrl.kernels import INTRINSIC, RANDOM

THETA = 0.25  # eq 9's sensitivity threshold for the floating robot

# The C library's fma (a * b + c rounded once), for eq 8's sum as numpy's dot makes it.
binding.load_library_permanently(ctypes.util.find_library("m"))
_fma = types.ExternalFunction("fma", types.float64(types.float64, types.float64, types.float64))

_NOTHING = np.zeros(0)


@njit(cache=True)
def eq8(s):
    """eq 8: a = sum_{i=1}^{n//2} i (s_i - s_{n+1-i}) / sum_{i=1}^{n//2} i.

    s: the ranges, leftmost first; a > 0 turns right, away from something on the left.
    The sum is numpy's dot of the ranks and the differences as it runs on this project's
    machines (BLAS on an FMA CPU): the first product, then each next one fused with the
    sum, one rounding each, so a run keeps the bits it had when this was np.dot."""
    n = s.shape[0]
    half = n // 2
    total = 0.0
    for i in range(half):
        d = s[i] - s[n - 1 - i]
        total = (i + 1) * d if i == 0 else _fma(float(i + 1), d, total)
    return total / (half * (half + 1) // 2)


@njit(cache=True)
def eq9(b, theta, unchanged):
    """eq 9: the dead-zoned acceleration for one axis; `unchanged` inside the dead zone
    (0 for eq9_dead_zone "zero", the previous acceleration for "keep")."""
    if b <= -theta:
        return (b + theta) / (1.0 - theta)
    if b >= theta:
        return (b - theta) / (1.0 - theta)
    return unchanged


@njit(cache=True)
def eq10(s):
    """eq 10 for the ranges E, NE, N, NW, W, SW, S, SE (counter-clockwise):
    b_h = 0.5 (s_W - s_E) + 0.25 (s_NW + s_SW - s_NE - s_SE), and symmetrically
    b_v = 0.5 (s_S - s_N) + 0.25 (s_SW + s_SE - s_NW - s_NE): away from obstacles."""
    e, ne, n, nw, w, sw, so, se = s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7]
    b_h = 0.5 * (w - e) + 0.25 * (nw + sw - ne - se)
    b_v = 0.5 * (so - n) + 0.25 * (sw + se - nw - ne)
    return b_h, b_v


def _ranges(ranges):
    return np.ascontiguousarray(ranges, dtype=np.float64)


def avoid_by_turning(ranges):
    """eq 8 (`eq8`) for the ranges, leftmost first: the turn, a > 0 to the right."""
    return float(eq8(_ranges(ranges)))


def avoid_by_accelerating(ranges, theta=THETA, previous=None):
    """eq 9-10 for both axes. ranges: E, NE, N, NW, W, SW, S, SE (counter-clockwise).

    eq 10 (`eq10`) gives each axis's b, away from obstacles; eq 9 (`eq9`) its dead-zoned
    acceleration: 0 on an axis inside the dead zone, or previous[axis] when previous
    (the last acceleration, eq9_dead_zone "keep") is given.
    """
    b_h, b_v = eq10(_ranges(ranges))
    if previous is None:
        return np.array([eq9(b_h, theta, 0.0), eq9(b_v, theta, 0.0)])
    return np.array([eq9(b_h, theta, float(previous[0])), eq9(b_v, theta, float(previous[1]))])


def _clip(a):
    """a clipped to [-1, 1] in place (np.clip, with less overhead)."""
    return np.minimum(np.maximum(a, -1.0, out=a), 1.0, out=a)


def random_action(rng, action_dim, sd=0.5):
    """Section 3.4's random action: Gaussian, mean 0, sd 0.5, clipped to [-1, 1]."""
    return _clip(rng.normal(0.0, sd, size=action_dim))


#: What a fallback's avoidance is: eq 8 (TURNING), eq 9-10 (ACCELERATING), computed by
#: the caller into the action before the fallback's step (GIVEN: an evolved genome's
#: avoid, ebrl.behaviour); WALK: the random walk, no avoidance.
TURNING, ACCELERATING, GIVEN, WALK = range(4)


@njit(cache=True)
def avoid_into(kind, ranges, theta, last, out):
    """out = eq 8's turn (TURNING) or eq 9-10's accelerations (ACCELERATING), holding
    `last` inside eq 9's dead zone when it is not empty; GIVEN leaves out as it is."""
    if kind == TURNING:
        out[0] = eq8(ranges)
        return
    if kind == GIVEN:
        return
    b_h, b_v = eq10(ranges)
    hold = last.shape[0] > 0
    out[0] = eq9(b_h, theta, last[0] if hold else 0.0)
    out[1] = eq9(b_v, theta, last[1] if hold else 0.0)


@njit(cache=True)
def fallback_act(kind, ranges, random, add, theta, last, out):
    """Intrinsic's action once its draws are made: `random` the random action's
    Gaussians (clipped here, in place; empty: the uniform draw was not below the
    rate), so out = the avoidance
    (avoid_into), or the random action clipped, or with add the two summed and clipped;
    `last`, when not empty, becomes the action. Returns True for the random action."""
    if random.shape[0] == 0:
        avoid_into(kind, ranges, theta, last, out)
    elif add:
        clip_unit(random)  # random_action's clip, then the sum's
        avoid_into(kind, ranges, theta, last, out)
        out += random
        clip_unit(out)
    else:
        out[:] = clip_unit(random)
    if last.shape[0]:
        last[:] = out
    return random.shape[0] > 0


# -- a fallback as one named record ------------------------------------------------------

FALLBACK_FIELDS = ("kind", "rate", "sd", "uniform", "add", "theta", "last", "random", "choice",
                   "rng")


@records.record(*FALLBACK_FIELDS)
class FallbackRecord(records.Record):
    """A fallback (RandomWalk or Intrinsic) as the record fallback_step works on: its
    kind (WALK, TURNING, ACCELERATING, GIVEN), random share and spread, whether its
    random action is uniform over (-1, 1) instead (random_demand), the
    random_in_avoidance reading (add), eq 9's theta, the held action (`last`, empty
    without hold), scratch for the random action, who chose its last action (RANDOM or
    INTRINSIC, -1 before any), and the random stream its Python calls draw from."""


FallbackRecord.constructor = njit(cache=True)(lambda *values: FallbackRecord(*values))


@njit(cache=True)
def choice_of(f):
    """The record's choice (RANDOM, INTRINSIC, -1 before any)."""
    return f.choice


@njit(cache=True)
def random_demand(f, rng, out):
    """A random action's draws into out, one per part: Gaussian (mean 0, sd f.sd; the
    caller clips), or with f.uniform uniform over (-1, 1) (-1 + 2 u, u = rng.random()'s
    double: Generator.uniform(-1, 1)'s formula)."""
    for i in range(out.shape[0]):
        out[i] = rng.uniform(-1.0, 1.0) if f.uniform else rng.normal(0.0, f.sd)


@njit(cache=True)
def fallback_step(f, ranges, rng, out):
    """The fallback's action into out, its draws from rng in their order: the random
    walk's draws (WALK, random_demand); or Intrinsic's uniform draw, then the random
    action's draws when it is below the rate, then fallback_act (a GIVEN avoidance is
    in out already). Returns, and keeps as f.choice, RANDOM or INTRINSIC."""
    dim = out.shape[0]
    if f.kind == WALK:
        random_demand(f, rng, out)
        clip_unit(out)
        f.choice = RANDOM
        return RANDOM
    random = f.random[:0]
    if rng.random() < f.rate:
        random = f.random[:dim]
        random_demand(f, rng, random)
    chose = fallback_act(f.kind, ranges, random, f.add, f.theta, f.last, out)
    f.choice = RANDOM if chose else INTRINSIC
    return f.choice


@njit(cache=True)
def fallback_reset(f):
    """A trial ends: the held acceleration (eq9_dead_zone "keep") returns to 0."""
    if f.last.shape[0]:
        f.last[:] = 0.0


@njit(cache=True)
def fallback_call(f, ranges, out):
    """fallback_step drawing from the record's own stream (a fallback called from Python)."""
    return fallback_step(f, ranges, f.rng, out)


class _Fallback:
    """What RandomWalk and Intrinsic share: their record (`record`, bound to the random
    stream of the latest call), and the call itself, which is one compiled
    fallback_step."""

    _kind = WALK
    _choices = (None, "intrinsic", "random")

    def _record(self, rate, sd, add, last, uniform=False):
        self._fields = dict(kind=self._kind, rate=float(rate), sd=float(sd),
                            uniform=bool(uniform), add=bool(add), theta=THETA,
                            last=_NOTHING if last is None else last,
                            random=np.zeros(self.action_dim), choice=-1)
        self.bind(np.random.default_rng(0))

    def bind(self, rng):
        """Binds the record to rng, the stream its Python calls draw from (a new record
        only for a new stream; the agent binds its own at construction)."""
        if getattr(self, "_bound", None) is not rng:
            self.record = FallbackRecord.build(**self._fields, rng=rng)
            self._bound = rng

    @property
    def choice(self):
        """Who chose the last action: "intrinsic" or "random" (None before any)."""
        code = choice_of(self.record)
        return self._choices[code] if code >= 0 else None

    def _given(self, ranges, out):
        """For a GIVEN avoidance: out = the avoidance of ranges (none here)."""

    def __call__(self, ranges, rng):
        self.bind(rng)
        ranges = _ranges(ranges)
        out = np.empty(self.action_dim)
        self._given(ranges, out)
        fallback_call(self.record, ranges, out)
        return out


class RandomWalk(_Fallback):
    """The paper's condition without avoidance: the random action every time; with
    uniform=True uniform over (-1, 1) (random_demand "uniform_walk", "uniform_all")
    instead of Gaussian of sd `sd`."""

    compiled = True

    def __init__(self, action_dim, sd=0.5, *, uniform=False):
        self.action_dim, self.sd, self.uniform = action_dim, sd, uniform
        self._record(0.0, sd, False, None, uniform)

    @property
    def choice(self):
        return "random"


class Intrinsic(_Fallback):
    """The avoidance behaviour with the random action at probability random_rate (0.2).

    random_in_avoidance (Section 3.4, "introduce some probability of random action"):
    "replace": the random action replaces the avoidance action; "add": the random
    action is added to the avoidance action and the sum clipped to [-1, 1]. Either way
    one uniform draw decides, then the Gaussian draws only when it is below
    random_rate: the same draws in the same order, so the two differ in the action
    only. (Adding a random action every step would leave the paper's 20% unused.)

    hold=True (eq9_dead_zone "keep", for eq 9-10): avoid(ranges, previous=last) gets
    the last action this fallback returned (avoidance, random or their clipped sum),
    which eq 9 keeps on an axis inside its dead zone; 0 at first and after reset(),
    which the agent calls when a trial ends (the robot restarts at rest). Actions the
    memory takes in between are not seen: the fallback holds its own output.

    With the paper's avoid functions (avoid_by_turning, avoid_by_accelerating) the
    whole step is compiled (fallback_step); any other avoid (an evolved genome's) is
    computed in Python first, then the same fallback_step makes the draws and the rest
    (kind GIVEN; tests/test_ebrl_readings.py checks the two alike).
    """

    def __init__(self, avoid, action_dim, random_rate=0.2, sd=0.5, *,
                 random_in_avoidance="replace", hold=False, uniform=False):
        self.avoid, self.action_dim = avoid, action_dim
        self.random_rate, self.sd = random_rate, sd
        self.random_in_avoidance = check_reading("random_in_avoidance", random_in_avoidance)
        self.last = np.zeros(action_dim) if hold else None  # eq 9's "not changed"
        self._kind = {avoid_by_turning: TURNING,
                      avoid_by_accelerating: ACCELERATING}.get(avoid, GIVEN)
        self.uniform = uniform  # the random action uniform over (-1, 1) ("uniform_all")
        self._record(random_rate, sd, random_in_avoidance == "add", self.last, uniform)

    @property
    def compiled(self):
        """True when the avoidance itself is compiled (the paper's eq 8 or eq 9-10)."""
        return self._kind != GIVEN

    def _given(self, ranges, out):
        if self._kind != GIVEN:
            return
        if self.last is None:
            out[:] = np.array(self.avoid(ranges), dtype=np.float64, ndmin=1)
        else:
            out[:] = np.array(self.avoid(ranges, previous=self.last), dtype=np.float64,
                              ndmin=1)

    def reset(self):
        """A trial ends: eq 9's held acceleration (hold=True) returns to 0."""
        fallback_reset(self.record)


#: Section 3.4's intrinsic behaviours by equation: (behaviour, action dimension).
BEHAVIOURS = {"eq8": (avoid_by_turning, 1), "eq9-10": (avoid_by_accelerating, 2)}


#: The behaviours with eq 9's dead zone, where eq9_dead_zone applies.
DEAD_ZONE = ("eq9-10",)


def fallback_for(behaviour, condition, random_rate=0.2, sd=0.5, *,
                 eq9_dead_zone=READINGS["eq9_dead_zone"][0],
                 random_in_avoidance=READINGS["random_in_avoidance"][0],
                 random_demand=READINGS["random_demand"][0]):
    """The fallback of Section 3.6's condition ("random": the random walk only,
    "avoidance": the intrinsic behaviour `behaviour`, a key of BEHAVIOURS, with the
    random action at random_rate), acting in the behaviour's action dimension.

    eq9_dead_zone and random_in_avoidance are the Config switches of those names (see
    Intrinsic); they change the avoidance condition only, and eq9_dead_zone only eq
    9-10 (eq 8 has no dead zone). random_demand: "gaussian" (Section 3.4's, sd `sd`,
    for every random action), "uniform_walk" (the random walk uniform over (-1, 1), the
    avoidance condition's random action Gaussian), "uniform_all" (both uniform).
    Defaults: the readings of docs/interpretation.md."""
    check_reading("eq9_dead_zone", eq9_dead_zone)
    check_reading("random_in_avoidance", random_in_avoidance)
    check_reading("random_demand", random_demand)
    if behaviour not in BEHAVIOURS:
        raise ValueError(f"unknown intrinsic behaviour {behaviour!r}; valid: "
                         f"{', '.join(BEHAVIOURS)}")
    avoid, dim = BEHAVIOURS[behaviour]
    if condition == "random":
        return RandomWalk(dim, sd, uniform=random_demand != "gaussian")
    if condition == "avoidance":
        return Intrinsic(avoid, dim, random_rate, sd, random_in_avoidance=random_in_avoidance,
                         hold=eq9_dead_zone == "keep" and behaviour in DEAD_ZONE,
                         uniform=random_demand == "uniform_all")
    raise ValueError(f"unknown condition {condition!r}; valid: {', '.join(CONDITIONS)}")
