"""The baseline learners (ebrl.baselines): each formula against a case computed by hand,
the confidence gates, learning on a tiny problem, determinism, bad configs."""
import dataclasses
import math

import numpy as np
import pytest

from ebrl import intrinsic
from ebrl.baselines import (AGENTS, MFEC, MFECConfig, QTable, QTableConfig, boltzmann,
                            confidence, discounted_returns, discrete_actions, nearest_action)
from ebrl.baselines.mfec import knn_estimates, store_trial

R = math.sqrt(0.5)
FLOATING = dict(groups=[np.arange(8), np.arange(8, 10)], group_weights=[0.7, 0.3])


class Constant:
    """A fallback behaviour that always takes the same action (and draws nothing)."""

    def __init__(self, action):
        self.action = np.atleast_1d(np.asarray(action, dtype=np.float64))
        self.calls = 0

    def __call__(self, readings, rng):
        self.calls += 1
        return self.action.copy()


# -- shared pieces ------------------------------------------------------------------------
def test_discrete_actions_by_hand():
    assert discrete_actions(1, 5).ravel().tolist() == [-1.0, -0.5, 0.0, 0.5, 1.0]
    assert discrete_actions(1, 3).ravel().tolist() == [-1.0, 0.0, 1.0]
    # zero, then E, NE, N, NW, W, SW, S, SE at unit length.
    expected = [[0, 0], [1, 0], [R, R], [0, 1], [-R, R], [-1, 0], [-R, -R], [0, -1], [R, -R]]
    np.testing.assert_allclose(discrete_actions(2), expected, rtol=0, atol=1e-15)
    three = discrete_actions(3)
    assert three.shape == (27, 3)
    np.testing.assert_allclose(np.linalg.norm(three[1:], axis=1), 1.0, rtol=1e-15)


def test_nearest_action_by_hand():
    one = discrete_actions(1, 5)
    assert nearest_action(one, [0.3]) == 3     # 0.5 is 0.2 away, 0 is 0.3
    assert nearest_action(one, [-0.8]) == 0
    assert nearest_action(one, [0.25]) == 2    # equally far from 0 and 0.5: the first
    two = discrete_actions(2)
    # (0.6, 0.5): NE is sqrt(0.0115 + 0.0429) away, E sqrt(0.41), zero sqrt(0.61).
    assert nearest_action(two, [0.6, 0.5]) == 2
    assert nearest_action(two, [0.1, -0.05]) == 0
    assert nearest_action(two, [-0.2, -0.9]) == 7  # S


# -- QTable -------------------------------------------------------------------------------
def test_discretisation_by_hand():
    ag = QTable(QTableConfig(), 7, 1, Constant(0.0), seed=0)
    obs = [0.0, 0.1, 0.15, 0.3, 0.5, 0.9, 1.0]
    assert ag.bins(obs).tolist() == [0, 0, 1, 1, 2, 2, 2]
    assert ag.state(obs) == 1 * 81 + 1 * 27 + 2 * 9 + 2 * 3 + 2
    assert ag.state_count == 3 ** 7 == 2187
    fl = QTable(QTableConfig(), 10, 2, Constant([0.0, 0.0]), seed=0, **FLOATING)
    obs = [0.6, 0, 0, 0, 0, 0, 0, 0.2, -0.5, 0.2]   # velocity: -0.5 < -0.2, |0.2| <= 0.2
    assert fl.bins(obs).tolist() == [2, 0, 0, 0, 0, 0, 0, 1, 0, 1]
    assert fl.state(obs) == 2 * 3 ** 9 + 1 * 9 + 0 * 3 + 1
    assert fl.bins([0] * 8 + [0.25, -0.21]).tolist() == [0] * 8 + [2, 0]
    assert fl.state_count == 3 ** 10 == 59049


def test_boltzmann_by_hand():
    q = np.array([0.0, 0.01, 0.02, 0.0, 0.0])
    e = math.e
    expected = np.array([1, e, e * e, 1, 1]) / (3 + e + e * e)
    np.testing.assert_allclose(boltzmann(q, 0.01), expected, rtol=1e-14)
    # Shifted by 1000 (no overflow; 1000.01 itself carries a rounding error of ~1e-13).
    np.testing.assert_allclose(boltzmann(q + 1000.0, 0.01), expected, rtol=1e-10)
    np.testing.assert_allclose(boltzmann(np.array([0.0, 0.1]), 0.1), [1 / (1 + e), e / (1 + e)],
                               rtol=1e-15)


def test_confidence_by_hand():
    assert confidence(np.full(5, 0.2)) == pytest.approx(0.0, abs=1e-15)
    assert confidence(np.array([0.0, 1.0, 0.0])) == pytest.approx(1.0, rel=1e-15)
    assert confidence(boltzmann(np.full(9, 0.3), 0.01)) == 0.0   # equal Q: exactly 0
    # p = (1/2, 1/4, 1/4): var = ((1/6)^2 + 2 (1/12)^2) / 3 = 1/72; largest 2/9; 1/16.
    p = np.array([0.5, 0.25, 0.25])
    assert confidence(p) == pytest.approx(1 / 16, rel=1e-15)
    assert confidence(p) == pytest.approx(np.var(p) / (2 / 9), rel=1e-14)


def test_q_learning_updates_by_hand():
    """Two trials of two steps, A then B (the goal); the fallback always gives 0.9,
    whose nearest discrete action is 1 (index 4)."""
    cfg = QTableConfig(alpha=0.5, discount=0.9, temperature=1e-3, exploration_rate=0.0)
    ag = QTable(cfg, 2, 1, Constant(0.9), seed=0)
    A, B = [0.0, 0.0], [1.0, 0.0]
    sA, sB = ag.state(A), ag.state(B)
    assert (sA, sB) == (0, 6)
    # Trial 1: nothing known, the fallback acts; Q(A,1) += 0.5 (0 + 0.9 * 0 - 0) = 0;
    # at the goal Q(B,1) += 0.5 (1 - 0) (terminal: no bootstrap).
    assert ag.act(A).tolist() == [0.9] and not ag.used_memory
    ag.learn(0.0)
    assert ag.act(B).tolist() == [0.9] and not ag.used_memory
    ag.learn(1.0, last=True)
    assert ag.table[sA].tolist() == [0, 0, 0, 0, 0]
    assert ag.table[sB].tolist() == [0, 0, 0, 0, 0.5]
    # Trial 2: A still all zeros -> uniform -> the fallback; then Q(A,1) += 0.5 (0 + 0.9
    # * max Q(B) - 0) = 0.225; at B the table is certain (tau 1e-3) and takes 1:
    # Q(B,1) += 0.5 (1 - 0.5) = 0.75.
    ag.act(A)
    assert not ag.used_memory and ag.confidence == 0.0
    ag.learn(0.0)
    assert ag.act(B).tolist() == [1.0] and ag.used_memory
    assert ag.table[sA][4] == pytest.approx(0.5 * 0.9 * 0.5, rel=1e-15)
    ag.learn(1.0, last=True)
    assert ag.table[sB].tolist() == [0, 0, 0, 0, 0.75]
    # The next trial's first act applies no update (the trial ended at the goal).
    ag.act(A)
    assert ag.table[sA][4] == pytest.approx(0.225, rel=1e-15)
    assert (ag.memory_decisions, ag.fallback_decisions, ag.steps) == (2, 3, 4)


def test_fallback_action_is_learned_as_the_nearest_discrete_action():
    ag = QTable(QTableConfig(alpha=0.5, exploration_rate=0.0), 3, 1, Constant(-0.3), seed=0)
    assert ag.act([0.0, 0.0, 0.0]).tolist() == [-0.3]   # the environment gets -0.3
    ag.learn(1.0, last=True)
    assert ag.table[0].tolist() == [0, 0.5, 0, 0, 0]    # learned as -0.5 (index 1)
    fl = QTable(QTableConfig(alpha=0.5, exploration_rate=0.0), 10, 2,
                Constant([-0.1, 0.8]), seed=0, **FLOATING)
    fl.act(np.zeros(10))
    fl.learn(1.0, last=True)
    assert fl.table[fl.state(np.zeros(10))][3] == 0.5  # N


def test_confidence_gate_and_exploration():
    """A row whose probabilities fall just below the threshold, then just above it."""
    cfg = QTableConfig(temperature=0.01, confidence_threshold=0.1, exploration_rate=0.0)
    fb = Constant(0.0)
    ag = QTable(cfg, 1, 1, fb, seed=0)
    s = ag.state([0.0])
    # Row (0, 0, 0, 0, x): p_4 = e^(x/tau) / (4 + e^(x/tau)). Confidence 0.1 at
    # sum p^2 = 1.4 / 5 = 0.28: 0.72 z^2 - 2.24 z - 0.48 = 0 for z = e^(x/tau), so
    # z = 3.3124, p_4 = 0.4530, x = 0.011977.
    for x, acts in ((0.0115, False), (0.0125, True)):
        ag.table[s] = np.array([0, 0, 0, 0, x])
        z = math.exp(x / 0.01)
        p4, p0 = z / (4 + z), 1 / (4 + z)
        expected = (5 * (p4 * p4 + 4 * p0 * p0) - 1) / 4
        ag.act([0.0])
        assert ag.confidence == pytest.approx(expected, rel=1e-12)
        assert (ag.confidence > 0.1) == acts and ag.used_memory == acts
        ag.learn(0.0, last=True)   # target 0: moves the row; reset it next time
    # Exploration 1: the fallback acts however certain the table is.
    explorer = QTable(dataclasses.replace(cfg, exploration_rate=1.0), 1, 1, fb, seed=0)
    explorer.table[s] = np.array([0, 0, 0, 0, 1.0])
    calls = fb.calls
    for _ in range(50):
        explorer.act([0.0])
        assert not explorer.used_memory and explorer.confidence == pytest.approx(1.0)
        explorer.learn(0.0, last=True)
        explorer.table[s] = np.array([0, 0, 0, 0, 1.0])
    assert explorer.fallback_decisions == 50 and fb.calls == calls + 50
    # With exploration 0.05 the fallback acts on about 5% of certain states.
    mostly = QTable(dataclasses.replace(cfg, exploration_rate=0.05), 1, 1, fb, seed=3)
    mostly.table[s] = np.array([0, 0, 0, 0, 1.0])
    for _ in range(4000):
        mostly.act([0.0])
        mostly.learn(0.0, last=True)
        mostly.table[s] = np.array([0, 0, 0, 0, 1.0])
    assert 0.04 < mostly.fallback_decisions / 4000 < 0.06


def test_roulette_follows_the_probabilities():
    cfg = QTableConfig(temperature=0.01, exploration_rate=0.0, confidence_threshold=0.0)
    ag = QTable(cfg, 1, 1, Constant(0.0), seed=1)
    row = np.array([0.0, 0.01, 0.02, 0.0, 0.0])
    counts = np.zeros(5)
    for _ in range(20000):
        ag.table[0] = row.copy()
        a = ag.act([0.0])[0]
        counts[int(round((a + 1) * 2))] += 1
        ag.learn(0.0, last=True)
    np.testing.assert_allclose(counts / 20000, boltzmann(row, 0.01), atol=0.01)


# -- MFEC ---------------------------------------------------------------------------------
def _buffers(n_actions, dim, capacity):
    return (np.zeros((n_actions, dim, capacity)), np.zeros((n_actions, capacity)),
            np.zeros(n_actions, dtype=np.int64), np.zeros((n_actions, capacity), dtype=np.int64))


def test_discounted_returns_by_hand():
    np.testing.assert_allclose(discounted_returns(np.array([0.0, 0.0, 1.0]), 0.9),
                               [0.81, 0.9, 1.0], rtol=1e-15)
    # R2 = 2, R1 = 0 + 0.9 * 2 = 1.8, R0 = 1 + 0.9 * 1.8 = 2.62.
    np.testing.assert_allclose(discounted_returns(np.array([1.0, 0.0, 2.0]), 0.9),
                               [2.62, 1.8, 2.0], rtol=1e-15)


def test_knn_estimate_by_hand():
    keys, values, sizes, used = _buffers(2, 2, 8)
    emb = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 2.0], [3.0, 0.0]])
    clock = store_trial(emb, np.zeros(4, dtype=np.int64), np.array([1.0, 2.0, 3.0, 4.0]),
                        keys, values, sizes, used, 0)
    assert clock == 4 and sizes.tolist() == [4, 0]
    q, d, scratch = np.zeros(2), np.zeros(2), np.zeros(8)
    # Query (0.5, 0): distances 0.5, 0.5, sqrt(4.25), 2.5.
    knn_estimates(np.array([0.5, 0.0]), keys, values, sizes, used, 5, 2, scratch, q, d)
    assert q[0] == 1.5 and d[0] == 0.5
    assert math.isnan(q[1]) and d[1] == math.inf     # action 1 has no memory
    assert used[0].tolist()[:4] == [5, 5, 3, 4]       # the two neighbours marked used
    knn_estimates(np.array([0.5, 0.0]), keys, values, sizes, used, 6, 3, scratch, q, d)
    assert q[0] == pytest.approx(2.0, rel=1e-15)
    assert d[0] == pytest.approx((0.5 + 0.5 + math.sqrt(4.25)) / 3, rel=1e-15)
    knn_estimates(np.array([0.5, 0.0]), keys, values, sizes, used, 7, 11, scratch, q, d)
    assert q[0] == 2.5                                # fewer than k stored: all of them
    # An identical embedding gives its own return, at distance 0.
    knn_estimates(np.array([0.0, 2.0]), keys, values, sizes, used, 8, 2, scratch, q, d)
    assert (q[0], d[0]) == (3.0, 0.0)


def test_existing_entry_keeps_the_larger_return():
    keys, values, sizes, used = _buffers(1, 2, 4)
    e = np.array([[0.3, 0.4]])
    a = np.zeros(1, dtype=np.int64)
    clock = 0
    for ret, kept in ((0.5, 0.5), (0.3, 0.5), (0.7, 0.7)):
        clock = store_trial(e, a, np.array([ret]), keys, values, sizes, used, clock)
        assert sizes[0] == 1 and values[0, 0] == kept
    assert used[0, 0] == clock == 3


def test_least_recently_used_entry_is_replaced_when_full():
    keys, values, sizes, used = _buffers(1, 1, 2)
    a = np.zeros(1, dtype=np.int64)
    clock = store_trial(np.array([[1.0], [2.0]]), np.zeros(2, dtype=np.int64),
                        np.array([0.1, 0.2]), keys, values, sizes, used, 0)
    assert used[0].tolist() == [1, 2]
    # A lookup near 1.0 (k = 1) uses slot 0, so slot 1 (2.0) is now the least recent.
    q, d = np.zeros(1), np.zeros(1)
    knn_estimates(np.array([1.1]), keys, values, sizes, used, 3, 1, np.zeros(2), q, d)
    assert used[0].tolist() == [3, 2]
    clock = store_trial(np.array([[5.0]]), a, np.array([0.5]), keys, values, sizes, used, 3)
    assert keys[0, 0].tolist() == [1.0, 5.0] and values[0].tolist() == [0.1, 0.5]
    # Then 1.0 (used at 3) goes before 5.0 (written at 4).
    store_trial(np.array([[7.0]]), a, np.array([0.7]), keys, values, sizes, used, clock)
    assert keys[0, 0].tolist() == [7.0, 5.0] and sizes[0] == 2


def test_mfec_embedding_weights_the_modalities():
    ag = MFEC(MFECConfig(), 10, 2, Constant([0.0, 0.0]), seed=0, **FLOATING)
    x = np.arange(10, dtype=np.float64)
    # Ranges: sqrt(0.7 / 8); velocity: sqrt(0.3 / 2).
    np.testing.assert_allclose(ag.embed(x), x * np.r_[[math.sqrt(0.7 / 8)] * 8,
                                                      [math.sqrt(0.3 / 2)] * 2], rtol=1e-15)
    one = MFEC(MFECConfig(), 4, 1, Constant(0.0), seed=0)
    np.testing.assert_allclose(one.embed(np.ones(4)), np.full(4, 0.5), rtol=1e-15)


def test_mfec_trial_is_stored_with_its_discounted_returns():
    cfg = MFECConfig(discount=0.9, exploration_rate=0.0)
    ag = MFEC(cfg, 4, 1, Constant(0.6), seed=0)   # 0.6 -> 0.5, index 3
    obs = [np.eye(4)[i] for i in range(3)]
    for i, x in enumerate(obs):
        ag.act(x)
        ag.learn(float(i == 2), last=i == 2)
    keys, returns = ag.buffer(3)
    np.testing.assert_allclose(keys, 0.5 * np.eye(4)[:3], rtol=0)
    np.testing.assert_allclose(returns, [0.81, 0.9, 1.0], rtol=1e-15)
    assert ag.sizes.tolist() == [0, 0, 0, 3, 0]


def test_mfec_gate():
    cfg = MFECConfig(exploration_rate=0.0, distance_threshold=0.2, neighbours=1,
                     action_levels=2)
    fb = Constant(0.7)   # -> action 1 (index 1)
    ag = MFEC(cfg, 2, 1, fb, seed=0)
    here, near, far = np.array([0.2, 0.2]), np.array([0.4, 0.2]), np.array([0.9, 0.9])
    ag.act(here)                                  # no memory at all: the fallback
    assert not ag.used_memory and ag.distance == math.inf
    ag.learn(1.0, last=True)                      # stores (here, 1) with return 1
    assert ag.act(here).tolist() == [1.0] and ag.used_memory and ag.distance == 0.0
    ag.learn(0.0)
    # near: embedding distance sqrt(0.2^2 / 2) = 0.1414 <= 0.2: memory acts.
    assert ag.act(near).tolist() == [1.0] and ag.used_memory
    assert ag.distance == pytest.approx(math.sqrt(0.02), rel=1e-14)
    ag.learn(0.0)
    # far: sqrt((0.7^2 + 0.7^2) / 2) = 0.7 > 0.2: the fallback.
    assert ag.act(far).tolist() == [0.7] and not ag.used_memory
    assert ag.distance == pytest.approx(0.7, rel=1e-14)
    ag.learn(0.0, last=True)   # that trial earned nothing: its entries hold return 0
    # here now holds max(1, 0) = 1; far holds 0, not above value_threshold 0.
    ag.act(far)
    assert not ag.used_memory and ag.estimates[1] == 0.0 and ag.distance == 0.0
    ag.learn(0.0)
    ag.act(here)
    assert ag.used_memory and ag.estimates[1] == 1.0
    ag.learn(0.0)
    # Exploration 1: the fallback always.
    explorer = MFEC(dataclasses.replace(cfg, exploration_rate=1.0), 2, 1, fb, seed=0)
    explorer.act(here)
    explorer.learn(1.0, last=True)
    for _ in range(20):
        explorer.act(here)
        assert not explorer.used_memory and explorer.estimates[1] == 1.0
        explorer.learn(0.0)


# -- both: learning, determinism, configs --------------------------------------------------
N = 10


def corridor(name, seed, trials, **overrides):
    """A corridor of N cells; reward at the right end. The readings name the cell (one-hot
    plus noise, clipped to [0, 1]); action > 0 moves right. exploration_rate=1 never
    lets the learner act: the random walk (about (N-1)^2 = 81 steps a trial)."""
    config_class, agent_class = AGENTS[name].config, AGENTS[name].agent
    rng = np.random.default_rng(seed + 100)
    ag = agent_class(config_class(**overrides), N, 1, intrinsic.RandomWalk(1), seed=seed)
    lengths, actions = [], []
    for _ in range(trials):
        pos, steps = 0, 0
        while True:
            obs = np.clip(np.eye(N)[pos] + rng.normal(0, 0.03, N), 0, 1)
            a = ag.act(obs)
            actions.append(a)
            pos = min(max(pos + (1 if a[0] > 0 else -1), 0), N - 1)
            steps += 1
            done = pos == N - 1 or steps >= 2000
            ag.learn(1.0 if pos == N - 1 else 0.0, done)
            if done:
                break
        lengths.append(steps)
    return np.array(lengths), np.concatenate(actions)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("name", ["qtable", "mfec"])
def test_trials_get_shorter_on_a_corridor(name, seed):
    lengths, _ = corridor(name, seed, 150)
    walk, _ = corridor(name, seed, 40, exploration_rate=1.0)
    assert walk.mean() > 5 * N
    late = lengths[-25:].mean()
    assert late < 0.6 * walk.mean() and late < 0.5 * lengths[:10].mean(), (lengths, walk.mean())
    if name == "qtable":  # the discretised corridor is solved: N - 1 steps but for exploration
        assert late < 1.5 * (N - 1)


@pytest.mark.parametrize("name", ["qtable", "mfec"])
def test_same_seed_same_actions(name):
    (la, a), (lb, b), (lc, c) = (corridor(name, s, 15) for s in (5, 5, 6))
    assert np.array_equal(la, lb) and a.tobytes() == b.tobytes()
    assert not np.array_equal(a[: min(len(a), len(c))], c[: min(len(a), len(c))])


@pytest.mark.parametrize("name", ["qtable", "mfec"])
def test_same_seed_same_actions_floating_like(name):
    """10 inputs in eq 3's groups, 2-D actions, the eq 9-10 avoidance fallback."""
    def run(seed):
        config_class, agent_class = AGENTS[name].config, AGENTS[name].agent
        ag = agent_class(config_class(), 10, 2, intrinsic.fallback_for("eq9-10", "avoidance"),
                         seed=seed, **FLOATING)
        rng = np.random.default_rng(11)
        places = np.c_[rng.random((4, 8)), rng.normal(0, 1, (4, 2))]  # a few situations
        out = []
        for t in range(600):
            obs = places[rng.integers(4)] + rng.normal(0, 0.01, 10)
            out.append(ag.act(obs, ranges=obs[:8]))
            ag.learn(float(t % 50 == 49), t % 50 == 49)
        return np.concatenate(out), ag.memory_decisions
    (a, ma), (b, mb), (c, _) = run(1), run(1), run(2)
    assert a.tobytes() == b.tobytes() and ma == mb and ma > 0
    assert a.tobytes() != c.tobytes()


@pytest.mark.parametrize("name", ["qtable", "mfec"])
def test_configs_are_numbers_for_set(name):
    """Every field is an int or a float with a default, as `--set NAME=VALUE` needs, or
    one of the fallback's switches (ebrl.config.READINGS, a string as in ebrl.Config)."""
    from ebrl.config import READINGS
    config_class = AGENTS[name].config
    default = config_class()
    for f in dataclasses.fields(config_class):
        v = getattr(default, f.name)
        assert type(v) in (int, float) or v == READINGS[f.name][0], f.name
    with pytest.raises(dataclasses.FrozenInstanceError):
        default.discount = 0.5
    with pytest.raises(ValueError, match="random_demand must be one of"):
        config_class(random_demand="wide")


@pytest.mark.parametrize("name", ["qtable", "mfec"])
def test_a_baseline_runs_the_drives_intrinsic_behaviour(name):
    """The fallback's readings of a drive (tasks.robots) reach every learner: a baseline's
    first trial, before any reward, is EBRL's on the same seed, bit for bit."""
    from experiments.running import execution
    # seeds whose first goal comes early (tests/test_first_trial.py)
    for robot, condition, seed in (("floating", "avoidance", 319), ("two_wheel", "random", 8007)):
        ebrl_spec = execution.RunSpec(robot, condition, seed, 1000, first_trial=True)
        mine = execution.RunSpec(robot, condition, seed, 1000, agent=name, first_trial=True)
        a, b = ebrl_spec.agent_config(), mine.agent_config()
        for k in ("eq9_dead_zone", "random_in_avoidance", "random_demand"):
            assert getattr(a, k) == getattr(b, k), k
        ours, theirs = execution.execute(ebrl_spec), execution.execute(mine)
        assert ours["trial_ends"].tolist() == theirs["trial_ends"].tolist() != []
        assert ours["trace"].tobytes() == theirs["trace"].tobytes()


@pytest.mark.parametrize("name,field,value", [
    ("qtable", "alpha", 0.0), ("qtable", "alpha", 1.5), ("qtable", "discount", 1.1),
    ("qtable", "temperature", 0.0), ("qtable", "temperature", float("inf")),
    ("qtable", "confidence_threshold", -0.1), ("qtable", "exploration_rate", 2.0),
    ("qtable", "initial_q", float("nan")), ("qtable", "far_edge", 0.0),
    ("qtable", "near_edge", 1.5), ("qtable", "far_edge", 0.6),
    ("qtable", "velocity_edge", -1.0), ("qtable", "action_levels", 1),
    ("qtable", "action_levels", 2.5), ("qtable", "intrinsic_random_rate", -0.5),
    ("qtable", "random_sd", 0.0),
    ("mfec", "memory_size", 0), ("mfec", "memory_size", 1.5), ("mfec", "neighbours", 0),
    ("mfec", "neighbours", True), ("mfec", "discount", -0.1),
    ("mfec", "distance_threshold", -1.0), ("mfec", "distance_threshold", float("nan")),
    ("mfec", "value_threshold", float("inf")), ("mfec", "exploration_rate", -0.01),
    ("mfec", "action_levels", 0), ("mfec", "random_sd", float("nan")),
])
def test_bad_config_names_the_field(name, field, value):
    config_class = AGENTS[name].config
    with pytest.raises(ValueError, match=field) as err:
        config_class(**{field: value})
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("name", ["qtable", "mfec"])
def test_bad_inputs_raise(name):
    config_class, agent_class = AGENTS[name].config, AGENTS[name].agent
    with pytest.raises(ValueError, match="config"):
        agent_class(QTableConfig() if name == "mfec" else MFECConfig(), 7, 1, Constant(0.0))
    with pytest.raises(ValueError, match="group"):
        agent_class(config_class(), 10, 2, Constant([0, 0]), groups=[np.arange(8)],
                    group_weights=[1.0])
    ag = agent_class(config_class(), 7, 1, Constant(0.0), seed=0)
    with pytest.raises(ValueError, match="shape"):
        ag.act(np.zeros(6))
    with pytest.raises(ValueError, match="NaN"):
        ag.act(np.array([0, 0, np.nan, 0, 0, 0, 0]))
    with pytest.raises(ValueError, match="act"):
        ag.learn(0.0)
    ag.act(np.zeros(7))
    with pytest.raises(ValueError, match="finite"):
        ag.learn(float("inf"))


@pytest.mark.slow
def test_baselines_import_nothing_heavy():
    import subprocess
    import sys
    code = ("import sys, ebrl.baselines; print(any(m.split('.')[0] in ('mujoco', 'dm_control', "
            "'tasks', 'experiments', 'torch', 'jax') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_qtable_refuses_more_inputs_than_its_state_index_holds():
    QTable(QTableConfig(), 39, 1, Constant(0.0))
    with pytest.raises(ValueError, match="obs_dim"):
        QTable(QTableConfig(), 40, 1, Constant(0.0))
