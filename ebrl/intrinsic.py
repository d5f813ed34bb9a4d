"""The intrinsic behaviours of Section 3.4 and the random walk they are compared with.

Inputs are the encoded 0..255 readings scaled to [0, 1]. A fallback behaviour is a
callable fallback(readings, rng) -> action array; one with a reset() method is reset
by the agent when a trial ends.

Two readings are switches (ebrl.config.READINGS), passed to fallback_for:
eq9_dead_zone ("zero": eq 9's "not changed" is zero acceleration; "keep": the
fallback's previous acceleration on that axis) and random_in_avoidance ("replace":
the random action replaces the avoidance action; "add": it is added to it, clipped).
"""
import functools

import numpy as np

from ebrl.config import READINGS, check_reading

THETA = 0.25  # eq 9's sensitivity threshold for the floating robot


@functools.cache
def _ranks(half):
    """eq 8's i = 1..half, made once per sensor count."""
    return np.arange(1, half + 1)


def avoid_by_turning(readings):
    """eq 8: a = sum_{i=1}^{n//2} i (s_i - s_{n+1-i}) / sum_{i=1}^{n//2} i.

    readings leftmost first; a > 0 turns right, away from something on the left.
    """
    s = np.asarray(readings, dtype=np.float64)
    half = len(s) // 2
    return float(np.dot(_ranks(half), s[:half] - s[: -half - 1: -1]) / (half * (half + 1) // 2))


def _eq9(b, theta, unchanged=0.0):
    """eq 9: the dead-zoned acceleration for one axis; `unchanged` inside the dead zone
    (0 for eq9_dead_zone "zero", the previous acceleration for "keep")."""
    if b <= -theta:
        return (b + theta) / (1.0 - theta)
    if b >= theta:
        return (b - theta) / (1.0 - theta)
    return unchanged


def avoid_by_accelerating(readings, theta=THETA, previous=None):
    """eq 9-10 for both axes. readings: E, NE, N, NW, W, SW, S, SE (counter-clockwise).

    eq 10: b_h = 0.5 (s_W - s_E) + 0.25 (s_NW + s_SW - s_NE - s_SE), and symmetrically
    b_v = 0.5 (s_S - s_N) + 0.25 (s_SW + s_SE - s_NW - s_NE): away from obstacles.
    eq 9's dead zone ("not changed") gives 0 on that axis, or previous[axis] when
    previous (the last acceleration, eq9_dead_zone "keep") is given.
    """
    e, ne, n, nw, w, sw, s, se = np.asarray(readings, dtype=np.float64).tolist()
    b_h = 0.5 * (w - e) + 0.25 * (nw + sw - ne - se)
    b_v = 0.5 * (s - n) + 0.25 * (sw + se - nw - ne)
    if previous is None:
        return np.array([_eq9(b_h, theta), _eq9(b_v, theta)])
    return np.array([_eq9(b_h, theta, float(previous[0])), _eq9(b_v, theta, float(previous[1]))])


def _clip(a):
    """a clipped to [-1, 1] in place (np.clip, with less overhead)."""
    return np.minimum(np.maximum(a, -1.0, out=a), 1.0, out=a)


def random_action(rng, action_dim, sd=0.5):
    """Section 3.4's random action: Gaussian, mean 0, sd 0.5, clipped to [-1, 1]."""
    return _clip(rng.normal(0.0, sd, size=action_dim))


class RandomWalk:
    """The paper's condition without avoidance: the random action every time."""

    choice = "random"  # who chose the last action (ebrl.agent.DECIDERS)

    def __init__(self, action_dim, sd=0.5):
        self.action_dim, self.sd = action_dim, sd

    def __call__(self, readings, rng):
        return random_action(rng, self.action_dim, self.sd)


class Intrinsic:
    """The avoidance behaviour with the random action at probability random_rate (0.2).

    random_in_avoidance (Section 3.4, "introduce some probability of random action"):
    "replace": the random action replaces the avoidance action; "add": the random
    action is added to the avoidance action and the sum clipped to [-1, 1]. Either way
    one uniform draw decides, then the Gaussian draws only when it is below
    random_rate: the same draws in the same order, so the two differ in the action
    only. (Adding a random action every step would leave the paper's 20% unused.)

    hold=True (eq9_dead_zone "keep", for eq 9-10): avoid(readings, previous=last) gets
    the last action this fallback returned (avoidance, random or their clipped sum),
    which eq 9 keeps on an axis inside its dead zone; 0 at first and after reset(),
    which the agent calls when a trial ends (the robot restarts at rest). Actions the
    memory takes in between are not seen: the fallback holds its own output.
    """

    def __init__(self, avoid, action_dim, random_rate=0.2, sd=0.5, *,
                 random_in_avoidance="replace", hold=False):
        self.avoid, self.action_dim = avoid, action_dim
        self.random_rate, self.sd = random_rate, sd
        self.random_in_avoidance = check_reading("random_in_avoidance", random_in_avoidance)
        self._add = random_in_avoidance == "add"
        self.last = np.zeros(action_dim) if hold else None  # eq 9's "not changed"
        self.choice = None  # who chose the last action: "intrinsic" or "random"

    def _avoid(self, readings):
        if self.last is None:
            return np.array(self.avoid(readings), dtype=np.float64, ndmin=1)
        return np.array(self.avoid(readings, previous=self.last), dtype=np.float64, ndmin=1)

    def __call__(self, readings, rng):
        if rng.random() < self.random_rate:
            self.choice = "random"
            action = random_action(rng, self.action_dim, self.sd)
            if self._add:
                action = _clip(self._avoid(readings) + action)
        else:
            self.choice = "intrinsic"
            action = self._avoid(readings)
        if self.last is not None:
            self.last = action.copy()
        return action

    def reset(self):
        """A trial ends: eq 9's held acceleration (hold=True) returns to 0."""
        if self.last is not None:
            self.last = np.zeros(self.action_dim)


#: Section 3.4's intrinsic behaviours by equation: (behaviour, action dimension).
BEHAVIOURS = {"eq8": (avoid_by_turning, 1), "eq9-10": (avoid_by_accelerating, 2)}
CONDITIONS = ("random", "avoidance")


#: The behaviours with eq 9's dead zone, where eq9_dead_zone applies.
DEAD_ZONE = ("eq9-10",)


def fallback_for(behaviour, condition, random_rate=0.2, sd=0.5, *,
                 eq9_dead_zone=READINGS["eq9_dead_zone"][0],
                 random_in_avoidance=READINGS["random_in_avoidance"][0]):
    """The fallback of Section 3.6's condition ("random": the random walk only,
    "avoidance": the intrinsic behaviour `behaviour`, a key of BEHAVIOURS, with the
    random action at random_rate), acting in the behaviour's action dimension.

    eq9_dead_zone and random_in_avoidance are the Config switches of those names (see
    Intrinsic); they change the avoidance condition only, and eq9_dead_zone only eq
    9-10 (eq 8 has no dead zone). Defaults: the readings of docs/interpretation.md."""
    check_reading("eq9_dead_zone", eq9_dead_zone)
    check_reading("random_in_avoidance", random_in_avoidance)
    if behaviour not in BEHAVIOURS:
        raise ValueError(f"unknown intrinsic behaviour {behaviour!r}; valid: "
                         f"{', '.join(BEHAVIOURS)}")
    avoid, dim = BEHAVIOURS[behaviour]
    if condition == "random":
        return RandomWalk(dim, sd)
    if condition == "avoidance":
        return Intrinsic(avoid, dim, random_rate, sd, random_in_avoidance=random_in_avoidance,
                         hold=eq9_dead_zone == "keep" and behaviour in DEAD_ZONE)
    raise ValueError(f"unknown condition {condition!r}; valid: {', '.join(CONDITIONS)}")
