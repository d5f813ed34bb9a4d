"""The intrinsic behaviours of Section 3.4 and the random walk they are compared with.

Inputs are the encoded 0..255 readings scaled to [0, 1]. A fallback behaviour is a
callable fallback(readings, rng) -> action array.
"""
import functools

import numpy as np

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


def _eq9(b, theta):
    """eq 9: the dead-zoned acceleration for one axis; 0 ("not changed") inside it."""
    if b <= -theta:
        return (b + theta) / (1.0 - theta)
    if b >= theta:
        return (b - theta) / (1.0 - theta)
    return 0.0


def avoid_by_accelerating(readings, theta=THETA):
    """eq 9-10 for both axes. readings: E, NE, N, NW, W, SW, S, SE (counter-clockwise).

    eq 10: b_h = 0.5 (s_W - s_E) + 0.25 (s_NW + s_SW - s_NE - s_SE), and symmetrically
    b_v = 0.5 (s_S - s_N) + 0.25 (s_SW + s_SE - s_NW - s_NE): away from obstacles.
    """
    e, ne, n, nw, w, sw, s, se = np.asarray(readings, dtype=np.float64).tolist()
    b_h = 0.5 * (w - e) + 0.25 * (nw + sw - ne - se)
    b_v = 0.5 * (s - n) + 0.25 * (sw + se - nw - ne)
    return np.array([_eq9(b_h, theta), _eq9(b_v, theta)])


def random_action(rng, action_dim, sd=0.5):
    """Section 3.4's random action: Gaussian, mean 0, sd 0.5, clipped to [-1, 1]."""
    a = rng.normal(0.0, sd, size=action_dim)
    return np.minimum(np.maximum(a, -1.0, out=a), 1.0, out=a)  # np.clip, with less overhead


class RandomWalk:
    """The paper's condition without avoidance: the random action every time."""

    def __init__(self, action_dim, sd=0.5):
        self.action_dim, self.sd = action_dim, sd

    def __call__(self, readings, rng):
        return random_action(rng, self.action_dim, self.sd)


class Intrinsic:
    """The avoidance behaviour, replaced by the random action with probability 0.2."""

    def __init__(self, avoid, action_dim, random_rate=0.2, sd=0.5):
        self.avoid, self.action_dim = avoid, action_dim
        self.random_rate, self.sd = random_rate, sd

    def __call__(self, readings, rng):
        if rng.random() < self.random_rate:
            return random_action(rng, self.action_dim, self.sd)
        return np.array(self.avoid(readings), dtype=np.float64, ndmin=1)


#: Section 3.4's intrinsic behaviours by equation: (behaviour, action dimension).
BEHAVIOURS = {"eq8": (avoid_by_turning, 1), "eq9-10": (avoid_by_accelerating, 2)}
CONDITIONS = ("random", "avoidance")


def fallback_for(behaviour, condition, random_rate=0.2, sd=0.5):
    """The fallback of Section 3.6's condition ("random": the random walk only,
    "avoidance": the intrinsic behaviour `behaviour`, a key of BEHAVIOURS, with the
    random action at random_rate), acting in the behaviour's action dimension."""
    if behaviour not in BEHAVIOURS:
        raise ValueError(f"unknown intrinsic behaviour {behaviour!r}; valid: "
                         f"{', '.join(BEHAVIOURS)}")
    avoid, dim = BEHAVIOURS[behaviour]
    if condition == "random":
        return RandomWalk(dim, sd)
    if condition == "avoidance":
        return Intrinsic(avoid, dim, random_rate, sd)
    raise ValueError(f"unknown condition {condition!r}; valid: {', '.join(CONDITIONS)}")
