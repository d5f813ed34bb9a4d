"""The agent's readings, continued from test_ebrl_readings.py: random_demand's
distribution, and the readings of the ablation of the untried readings (eq 7's walk and
signal, forgetting's link, recall candidates, exploration), each on a case computed by
hand."""

import numpy as np
import pytest

import ebrl
from ebrl import intrinsic, kernels
from ebrl.config import READINGS


# -- random_demand: the random action's distribution ------------------------------------

@pytest.mark.parametrize("dim", [1, 2])
def test_random_demand_draws_what_it_names(dim):
    """By hand: the random walk's action from a fresh default_rng(5). "gaussian" is
    normal(0, 0.5) per part, clipped; "uniform_walk" and "uniform_all" are -1 + 2 u per
    part, u the stream's doubles (Generator.uniform(-1, 1)). The avoidance condition's
    random action (rate 1: every step) is uniform under "uniform_all" only."""
    behaviour = "eq8" if dim == 1 else "eq9-10"
    ranges = np.zeros(7 if dim == 1 else 8)
    u = np.random.default_rng(5).random(1 + dim)
    z = np.random.default_rng(5).normal(0.0, 0.5, dim)
    walk = {d: intrinsic.fallback_for(behaviour, "random", random_demand=d)(
        ranges, np.random.default_rng(5)) for d in READINGS["random_demand"]}
    np.testing.assert_array_equal(walk["gaussian"], np.clip(z, -1, 1))
    np.testing.assert_array_equal(walk["uniform_walk"], -1.0 + 2.0 * u[:dim])
    np.testing.assert_array_equal(walk["uniform_all"], -1.0 + 2.0 * u[:dim])
    # avoidance, random share 1: one uniform draw (below 1), then the random action's
    g = np.random.default_rng(5)
    g.random()
    z2 = g.normal(0.0, 0.5, dim)
    avoid = {d: intrinsic.fallback_for(behaviour, "avoidance", 1.0, random_demand=d)(
        ranges, np.random.default_rng(5)) for d in READINGS["random_demand"]}
    np.testing.assert_array_equal(avoid["gaussian"], np.clip(z2, -1, 1))
    np.testing.assert_array_equal(avoid["uniform_walk"], np.clip(z2, -1, 1))
    np.testing.assert_array_equal(avoid["uniform_all"], -1.0 + 2.0 * u[1:])


def test_a_uniform_walk_spreads_over_the_demand_range():
    """Uniform over (-1, 1): mean 0 and sd 1 / sqrt(3) = 0.577 (the Gaussian's, clipped:
    0.49), every value inside (-1, 1)."""
    fb = intrinsic.fallback_for("eq8", "random", random_demand="uniform_walk")
    rng = np.random.default_rng(0)
    a = np.array([fb(np.zeros(7), rng)[0] for _ in range(20000)])
    assert abs(a.mean()) < 0.01 and abs(a.std() - 1 / np.sqrt(3)) < 0.005
    assert (a >= -1).all() and (a < 1).all()


# -- the readings of issue 37, each on a case computed by hand ---------------------------

def chain(n, reliability=0.5):
    """n elements linked 0 -> 1 -> ... -> n-1, time stamps 0..n-1, reliabilities equal."""
    prev = np.arange(-1, n - 1, dtype=np.int64)
    nxt = np.append(np.arange(1, n, dtype=np.int64), -1)
    return np.full(n, reliability), prev, nxt, np.arange(n, dtype=np.int64)


@pytest.mark.parametrize("walk,expected", [
    # rho 0.5, r 1: R = 0.5 + 0.5 * g * 0.5 with g = 1 (whole), 0.5^k (discounted), or 1
    # down to where 0.5^k < 0.3 (cut: k = 0, 1 changed; k = 2 is 0.25, the walk stops).
    (kernels.EQ7_WHOLE, [0.75, 0.75, 0.75, 0.75]),
    (kernels.EQ7_DISCOUNTED, [0.53125, 0.5625, 0.625, 0.75]),
    (kernels.EQ7_CUT, [0.5, 0.5, 0.75, 0.75]),
])
def test_eq7_walks_by_hand(walk, expected):
    rel, prev, _, time = chain(4)
    kernels.eq7(rel, prev, 3, 1.0, 0.5, time, 0.5, 0.3, walk)
    assert rel.tolist() == expected
    # r < 0 (eq7_signal's surprises): R + rho r R = 0.5 - 0.5 * 0.5 * 0.5 = 0.375
    rel, prev, _, time = chain(2)
    kernels.eq7(rel, prev, 1, -0.5, 0.5, time, 0.5, 0.0, walk)
    assert rel[1] == 0.375


@pytest.mark.parametrize("cut", [False, True])
def test_forgetting_joins_or_cuts_the_episode(cut):
    _, prev, nxt, _ = chain(3)
    inputs, sums = np.zeros((1, 3)), np.zeros((2, 1))
    table, table_w = np.array([1, 2, -1]), np.array([0.9, 0.8, 0.0])
    kernels.forget(1, inputs, sums, nxt, prev, table, table_w, 2, -1, cut)
    assert (nxt[0], prev[2]) == ((-1, -1) if cut else (2, 0))
    assert (nxt[1], prev[1]) == (-1, -1) and table.tolist() == [2, -1, -1]


def test_recall_candidates_past_only_by_hand():
    """Elements 0..3 stored at steps 0..3, the current trial from step 2: elements 2 and
    3 are no candidates, nor reached by an entry; the table keeps 0 and 1."""
    sim = np.array([0.6, 0.7, 0.95, 0.9])
    nxt = np.array([1, 2, 3, -1])
    table, table_w = np.array([1, -1, -1]), np.array([0.5, 0.0, 0.0])
    kernels.recall_since(sim.copy(), 4, nxt, table, table_w, 0.5, np.arange(4), 2)
    assert table.tolist() == [1, 0, -1] and table_w.tolist() == [0.7, 0.6, 0.0]
    table, table_w = np.array([1, -1, -1]), np.array([0.5, 0.0, 0.0])
    kernels.recall(sim.copy(), 4, nxt, table, table_w, 0.5)  # "all": 2 reached and kept
    assert table.tolist() == [2, 3, 1] and table_w.tolist() == [0.95, 0.9, 0.7]


def two_trials(signal, second_reward=0.0):
    """An agent (memory only, no exploration) on input 0 then 1, rewarded at its second
    step (trial 1), then input 0 again: eq 5 picks element 0 (W = 1, U = 0.99)."""
    cfg = ebrl.Config(exploration_rate=0.0, eq7_signal=signal)
    ag = ebrl.Agent(cfg, 1, 1, intrinsic.fallback_for("eq8", "random"), seed=0)
    for x, r in ((0.0, 0.0), (1.0, 1.0)):
        ag.act(np.array([x]))
        assert ag.decision != "memory"
        ag.learn(r, last=r > 0)
    ag.act(np.array([0.0]))
    assert ag.decision == "memory" and ag.referred == 0
    ag.learn(second_reward)
    return ag


@pytest.mark.parametrize("signal,factor", [
    # after trial 1: R0 = 0.99^2 = 0.9801; U0 = 0.99 (eq 6), W0 = 1 (input 0 again).
    ("reward", 1.0),                               # r = 0: eq 7 does not act
    ("surprise_measure", 1 - 0.5 * 0.99),          # r = 0 - min(1, 0.99): R (1 + rho r)
    ("surprise_rate", 1 - 0.5 * (0.01 * 0.99)),    # r = 0 - (1 - 0.99) 0.99
])
def test_eq7_signal_by_hand(signal, factor):
    ag = two_trials(signal)
    # eq 7 on element 0 (the episode's start), then the time discount
    assert ag.reliability[0] == pytest.approx(0.9801 * factor * 0.99, rel=1e-12)
    assert ag.reliability[1] == pytest.approx(0.99 ** 2, rel=1e-12)   # not on the walk
    # a reward of 1 on the decision's step: r = 1 - 0.99 for the measure (R + rho r (1 - R))
    if signal == "surprise_measure":
        R = 0.9801
        assert two_trials(signal, 1.0).reliability[0] == pytest.approx(
            (R + 0.5 * 0.01 * (1 - R)) * 0.99, rel=1e-12)


@pytest.mark.parametrize("exploration", ["fallback", "random"])
def test_exploration_reading_by_hand(exploration):
    """exploration_rate 1: every step the memory would take is explored; "fallback" acts
    as eq 8 (its random action off: intrinsic_random_rate 0), "random" as Section 3.4's
    random action, N(0, 0.5) clipped, drawn after the exploration draw."""
    cfg = ebrl.Config(exploration_rate=1.0, intrinsic_random_rate=0.0, exploration=exploration)
    fb = intrinsic.fallback_for("eq8", "avoidance", 0.0)
    ag = ebrl.Agent(cfg, 7, 1, fb, seed=5)
    twin = np.random.default_rng(5)
    obs = np.linspace(0.1, 0.7, 7)
    for r in (0.0, 1.0):  # trial 1: the fallback (an exploration draw, then the rate's)
        ag.act(obs)
        twin.random(), twin.random()
        ag.learn(r, last=r > 0)
    action = ag.act(obs)
    assert ag.decision == "exploration"
    twin.random()
    if exploration == "random":
        assert action[0] == np.clip(twin.normal(0.0, 0.5), -1, 1)
    else:
        assert action[0] == intrinsic.eq8(obs)
