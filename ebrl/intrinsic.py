"""The intrinsic behaviours of Section 3.4 and the random walk they are compared with.

A fallback behaviour acts whenever memory does not (Section 2.3). It is a callable
fallback(readings, rng) -> action array, where readings are the range sensors'
values scaled to [0, 1] and rng is the agent's numpy Generator.

    fallback = ebrl.intrinsic.fallback_for("two_wheel", "avoidance")
    action = fallback(np.array([0.9, 0.5, 0, 0, 0, 0, 0]), np.random.default_rng(0))
"""
import numpy as np

from ebrl.config import Config

#: eq 9's sensitivity threshold theta for the floating robot (Section 3.4: 0.25).
THETA = 0.25


def avoid_two_wheel(readings):
    """eq 8: a = sum_{i=1}^{floor(n/2)} i (s_i - s_{n+1-i}) / sum_{i=1}^{floor(n/2)} i.

    readings leftmost first (s_1 is the leftmost sensor). a > 0 turns right, away from
    something on the left. Any n >= 2; the middle sensor of an odd n is not used.
    """
    s = np.asarray(readings, dtype=np.float64)
    half = s.shape[0] // 2
    if half < 1:
        raise ValueError(f"eq 8 needs at least 2 readings, got {s.shape[0]}")
    i = np.arange(1, half + 1)
    return float(np.dot(i, s[:half] - s[::-1][:half]) / i.sum())


def eq9(b, theta=THETA):
    """eq 9, one axis: (b + theta)/(1 - theta) if b <= -theta, (b - theta)/(1 - theta)
    if b >= theta, otherwise "not changed", read as zero acceleration."""
    if b <= -theta:
        return (b + theta) / (1.0 - theta)
    if b >= theta:
        return (b - theta) / (1.0 - theta)
    return 0.0


def eq10(readings):
    """eq 10 and its vertical mirror: (b_h, b_v) from 8 readings ordered E, NE, N, NW,
    W, SW, S, SE (counter-clockwise from +x, "up" = N = +y).

    b_h = 0.5 (s_W - s_E) + 0.25 (s_NW + s_SW - s_NE - s_SE)   (left minus right)
    b_v = 0.5 (s_S - s_N) + 0.25 (s_SW + s_SE - s_NW - s_NE)   (below minus above)
    so both push away from obstacles: something on the left gives b_h > 0.
    """
    s = np.asarray(readings, dtype=np.float64)
    if s.shape != (8,):
        raise ValueError(f"eq 10 needs 8 readings (E, NE, N, NW, W, SW, S, SE), got {s.shape}")
    e, ne, n, nw, w, sw, so, se = s
    b_h = 0.5 * (w - e) + 0.25 * (nw + sw - ne - se)
    b_v = 0.5 * (so - n) + 0.25 * (sw + se - nw - ne)
    return b_h, b_v


def avoid_floating(readings, theta=THETA):
    """The floating robot's avoidance: eq 10 then eq 9 on each axis -> array (a_h, a_v)."""
    b_h, b_v = eq10(readings)
    return np.array([eq9(b_h, theta), eq9(b_v, theta)])


def random_action(rng, action_dim, sd=Config.random_sd):
    """Section 3.4's random action: Gaussian, mean 0, sd 0.5, clipped to the action
    range [-1, 1]."""
    return np.clip(rng.normal(0.0, sd, size=action_dim), -1.0, 1.0)


class RandomWalk:
    """The paper's condition without avoidance: the random action every time."""

    def __init__(self, action_dim, sd=Config.random_sd):
        self.action_dim, self.sd = int(action_dim), sd

    def __call__(self, readings, rng):
        return random_action(rng, self.action_dim, self.sd)


class Intrinsic:
    """An avoidance behaviour avoid_fn(readings), replaced by the random action with
    probability random_rate (Section 3.4: 20%). The random action has avoid_fn's size."""

    def __init__(self, avoid_fn, random_rate=Config.intrinsic_random_rate, sd=Config.random_sd):
        self.avoid_fn, self.random_rate, self.sd = avoid_fn, random_rate, sd

    def __call__(self, readings, rng):
        action = np.atleast_1d(np.asarray(self.avoid_fn(readings), dtype=np.float64))
        if rng.random() < self.random_rate:
            return random_action(rng, action.shape[0], self.sd)
        return action


#: robot -> its avoidance behaviour (Section 3.4).
AVOID = {"two_wheel": avoid_two_wheel, "floating": avoid_floating}
#: robot -> its action size (Section 3.3).
ACTION_DIM = {"two_wheel": 1, "floating": 2}


def fallback_for(robot, condition, config=None):
    """The fallback of robot ("two_wheel", "floating") under condition ("random": the
    random walk; "avoidance": the intrinsic behaviour). config (an ebrl.Config, default
    Table 1) supplies intrinsic_random_rate and random_sd."""
    if robot not in AVOID:
        raise ValueError(f"unknown robot {robot!r}; valid robots: {', '.join(AVOID)}")
    config = Config() if config is None else config
    if condition == "random":
        return RandomWalk(ACTION_DIM[robot], config.random_sd)
    if condition == "avoidance":
        return Intrinsic(AVOID[robot], config.intrinsic_random_rate, config.random_sd)
    raise ValueError(f"unknown condition {condition!r}; valid conditions: random, avoidance")
