"""Each paper equation against a case computed by hand."""
import math

import numpy as np
import pytest

import ebrl
from ebrl import agent as agent_mod
from ebrl import intrinsic, kernels


def test_eq1_recall_weight_moves_alpha_of_the_way():
    # W = 0.2, S = 0.8, alpha = 0.5: 0.2 + 0.5 * (0.8 - 0.2) = 0.5
    assert agent_mod.eq1(0.2, 0.8, 0.5) == pytest.approx(0.5)
    assert agent_mod.eq1(0.9, 0.1, 0.25) == pytest.approx(0.7)


def _compiled_similarity(x, memory, variance, groups=None, weights=None):
    """ebrl.kernels.similarities (what the agent runs) with ebrl.similarity's arguments."""
    x = np.asarray(x, dtype=np.float64)
    memory = np.atleast_2d(np.asarray(memory, dtype=np.float64))
    if groups is None:
        groups, weights = [np.arange(len(x))], [1.0]
    group_of = np.zeros(len(x), dtype=np.int64)
    for j, idx in enumerate(groups):
        group_of[np.asarray(idx)] = j
    w = np.asarray(weights, dtype=np.float64)
    out = np.zeros(len(memory))
    kernels.similarities(x, np.ascontiguousarray(memory.T), len(memory),
                         np.asarray(variance, dtype=np.float64), group_of,
                         np.array([len(g) for g in groups], dtype=np.float64), w / w.sum(), out)
    return out


BOTH = pytest.mark.parametrize("similarity", [ebrl.similarity, _compiled_similarity],
                               ids=["reference", "compiled"])


@BOTH
def test_eq2_by_hand(similarity):
    # x = (1, 2), y = (0, 4), V = (1, 4): sum (1/1 + 4/4) = 2, 1/(2n) = 1/4 -> 1 - sqrt(0.5)
    s = similarity([1.0, 2.0], [[0.0, 4.0], [1.0, 2.0]], [1.0, 4.0])
    assert s[0] == pytest.approx(1 - math.sqrt(0.5))
    assert s[1] == pytest.approx(1.0)


@BOTH
def test_eq3_eq4_weighted_modalities_by_hand(similarity):
    x = np.array([0.0, 0.0, 1.0])
    y = np.array([[1.0, 1.0, 3.0]])
    v = np.array([1.0, 1.0, 2.0])
    # group A = (0, 1): sum = 2, n = 2 -> S'_A = 1 - sqrt(2/4) ;
    # group B = (2): (2^2)/2 = 2, n = 1 -> 1 - sqrt(1)
    s_a, s_b = 1 - math.sqrt(0.5), 0.0
    s = similarity(x, y, v, groups=[[0, 1], [2]], weights=[0.7, 0.3])
    assert s[0] == pytest.approx((0.7 * s_a + 0.3 * s_b) / 1.0)
    # Weights need not sum to 1: eq 3 divides by their sum.
    s = similarity(x, y, v, groups=[[0, 1], [2]], weights=[1.4, 0.6])
    assert s[0] == pytest.approx(0.7 * s_a + 0.3 * s_b)


@pytest.mark.parametrize("groups,weights", [
    (None, None), ([np.arange(8), np.arange(8, 10)], [0.7, 0.3]),
    ([[0, 5, 9], [1, 2], [3, 4, 6, 7, 8]], [2.0, 0.5, 1.0]),  # interleaved groups
])
def test_compiled_similarity_equals_float64_reference(groups, weights):
    rng = np.random.default_rng(0)
    for trial in range(20):
        memory = rng.random((257, 10)) * 10.0 ** rng.uniform(-3, 3, 10)  # mixed scales
        x = memory[rng.integers(257)] if trial % 4 == 0 else rng.random(10)  # exact matches too
        variance = np.maximum(memory.var(axis=0), 1e-6)
        want = ebrl.similarity(x, memory, variance, groups, weights)
        np.testing.assert_allclose(_compiled_similarity(x, memory, variance, groups, weights),
                                   want, rtol=0, atol=1e-12)


def test_agent_similarity_equals_reference():
    rng = np.random.default_rng(0)
    groups = [np.arange(8), np.arange(8, 10)]
    ag = ebrl.Agent(ebrl.Config(memory_size=64), 10, 2, intrinsic.RandomWalk(2),
                    groups=groups, group_weights=[0.7, 0.3], seed=0)
    fed = rng.random((100, 10))
    for x in fed:
        ag.act(x)
        ag.learn(0.0)
    x = rng.random(10)
    stored = ag.memory.inputs[:, : ag.size].T
    want = ebrl.similarity(x, stored, ag.variance, groups, [0.7, 0.3])
    np.testing.assert_allclose(ag.similarities(x), want, rtol=0, atol=1e-12)


def test_reciprocal_kernel_against_the_formula_as_written():
    """The compiled eq 2-4 multiplies by 1 / (2 n_j V_i) (protocol 5) where the formula
    divides: on Table 1's floating memory (4096 x 10, groups 8 + 2) and on inputs of
    widely different scales, within the stated 1e-12 of ebrl.similarity; on the
    hand-computed case of eq 2 exactly 1 - sqrt(0.5)."""
    rng = np.random.default_rng(7)
    groups = [np.arange(8), np.arange(8, 10)]
    for scale in (1e-3, 1.0, 255.0):
        memory = rng.random((4096, 10)) * scale
        variance = memory.var(axis=0) + 1e-6
        x = rng.random(10) * scale
        want = ebrl.similarity(x, memory, variance, groups, [0.7, 0.3])
        got = _compiled_similarity(x, memory, variance, groups, [0.7, 0.3])
        assert np.max(np.abs(got - want)) <= 1e-12
    s = _compiled_similarity([1.0, 2.0], [[0.0, 4.0]], [1.0, 4.0])
    assert s[0] == 1 - math.sqrt(0.5)


def test_recall_eq1_by_hand():
    """eq 1 on the entries that move along their forward links, then the N_r largest."""
    nxt = np.array([1, -1, 3, -1, -1])
    table, table_w = np.array([0, 1, 2]), np.array([0.9, 0.8, 0.2])
    sim = np.array([0.3, 0.1, 0.0, 0.6, 0.25])
    kernels.recall(sim, 5, nxt, table, table_w, 0.5)
    # entry 0 (W 0.9) -> element 1 (S 0.1): 0.9 + 0.5 (0.1 - 0.9) = 0.5;
    # entry 1 is at its episode's end: dropped (element 1 stays a candidate via entry 0);
    # entry 2 (W 0.2) -> element 3 (S 0.6): 0.4 < 0.6, the similarity is kept.
    # Candidates: 0.3, 0.5, 0.0, 0.6, 0.25 -> the 3 largest: 3, 1, 0.
    np.testing.assert_array_equal(table, [3, 1, 0])
    np.testing.assert_allclose(table_w, [0.6, 0.5, 0.3])
    # Fewer stored elements than entries: the rest stay empty (-1).
    table = np.full(3, -1)
    kernels.recall(np.array([0.2, 0.7]), 2, np.array([-1, -1]), table, np.zeros(3), 0.5)
    np.testing.assert_array_equal(table, [1, 0, -1])


def test_eq5_measure_is_min_of_weight_and_utility():
    np.testing.assert_allclose(agent_mod.eq5(np.array([0.9, 0.3, 0.5]), np.array([0.1, 0.8, 0.6])),
                               [0.1, 0.3, 0.5])
    assert agent_mod.eq5(0.4, 0.7) == 0.4


def test_eq5_policy_by_hand():
    utility = np.array([0.5, 0.9, 0.5, 0.0, 0.45])
    table, table_w = np.array([3, 0, 2, 4, 1]), np.array([0.9, 0.6, 0.6, 0.5, 0.4])
    # measures: min(0.9, 0) = 0, min(0.6, 0.5) = 0.5, 0.5, 0.45, 0.4: entries 1 and 2 tie
    # at 0.5 with equal weights; the first in table order (element 0) wins.
    assert kernels.policy(table, table_w, utility, 0.0) == 0
    assert kernels.policy(table, table_w, utility, 0.5) == -1  # must exceed the threshold
    assert kernels.policy(np.full(5, -1), table_w, utility, -1.0) == -1  # empty table


def _agent(**kw):
    """New elements start at reliability 1 in these hand-computed cases (a case may set
    another value)."""
    kw = {"initial_reliability": 1.0, **kw}
    return ebrl.Agent(ebrl.Config(**kw), 2, 1, lambda r, rng: np.array([-0.5]), seed=0)


def test_eq6_utilities_discount_along_the_episode_and_stop_at_cutoff():
    ag = _agent(memory_size=16, recall_size=2, discount=0.5, utility_cutoff=0.2)
    for t in range(4):
        ag.act(np.array([t, -t], dtype=float))
        ag.learn(1.0 if t == 3 else 0.0, last=t == 3)
    # newest 1, then 0.5, 0.25; 0.125 < cutoff 0.2 stays 0
    np.testing.assert_allclose(ag.utility, [0.0, 0.25, 0.5, 1.0])


def test_eq6_exponent_is_elapsed_time_across_a_spliced_gap():
    # Episode 0 -> 1 -> 2 stored at steps 0, 1, 5; element 1 forgotten (spliced): 2 -> 0.
    # r = 2, gamma = 0.5, cutoff 0.01: U_2 += 2 * 0.5^0, U_0 += 2 * 0.5^5 (5 steps, 1 hop).
    utility, prev, time = np.zeros(3), np.array([-1, -1, 0]), np.array([0, 1, 5])
    kernels.eq6(utility, prev, time, 2, 2.0, 0.5, 0.01)
    np.testing.assert_array_equal(utility, [2 * 0.5 ** 5, 0.0, 2.0])
    kernels.eq6(utility, prev, time, 2, 2.0, 0.5, 0.05)  # 0.5^5 = 0.031 < 0.05: stops
    np.testing.assert_array_equal(utility, [2 * 0.5 ** 5, 0.0, 4.0])


def test_eq7_reliability_along_backward_links_both_signs():
    ag = _agent(memory_size=16, recall_size=2, time_discount=0.5, reliability_rate=0.5,
                exploration_rate=0.0)
    for t in range(3):  # one episode of 3 elements, rewarded: utilities > 0
        ag.act(np.array([t, 0.0]))
        ag.learn(1.0 if t == 2 else 0.0, last=t == 2)
    before = ag.reliability.copy()  # 1 * 0.5^3, 0.5^2, 0.5^1 after the decays
    np.testing.assert_allclose(before, [0.125, 0.25, 0.5])
    # Next trial: the input equals element 1, so memory acts as element 1 did.
    ag.act(np.array([1.0, 0.0]))
    assert ag.used_memory
    referred = int(ag.referred)
    ag.learn(1.0, last=True)
    r = ag.reliability
    # element 1 and, back along its links, element 0: R + 0.5 * 1 * (1 - R), then the
    # step's decay (x 0.5). E.g. element 1: (0.25 + 0.5 * 0.75) * 0.5 = 0.3125.
    assert referred == 1
    for j, r0 in ((1, before[1]), (0, before[0])):
        assert r[j] == pytest.approx((r0 + 0.5 * (1 - r0)) * 0.5), j
    assert r[1] == pytest.approx(0.3125)
    assert r[2] == pytest.approx(before[2] * 0.5)  # not on the chain: decayed only
    # Negative reward: R + rho * r * R.
    ag2 = _agent(memory_size=16, recall_size=2, time_discount=0.5, exploration_rate=0.0)
    for t in range(2):
        ag2.act(np.array([t, 0.0]))
        ag2.learn(1.0 if t == 1 else 0.0, last=t == 1)
    ag2.act(np.array([0.0, 0.0]))
    rel = ag2.reliability.copy()
    j = int(ag2.referred)
    ag2.learn(-1.0)
    assert ag2.reliability[j] == pytest.approx(rel[j] * (1 - 0.5) * 0.5)


def test_policy_threshold_and_empty_table_use_the_fallback():
    ag = _agent(memory_size=8, recall_size=2, exploration_rate=0.0, policy_threshold=10.0)
    a = ag.act(np.array([0.0, 0.0]))  # empty memory: fallback
    assert not ag.used_memory and a[0] == -0.5
    ag.learn(1.0, last=True)  # utility 1 stored
    ag.act(np.array([0.0, 0.0]))
    assert not ag.used_memory  # measure 1 < threshold 10


def test_eq8_two_wheel_avoidance_by_hand():
    assert intrinsic.avoid_by_turning([1, 0, 0, 0, 0, 0, 0]) == pytest.approx(1 / 6)
    assert intrinsic.avoid_by_turning([0, 0, 1, 0, 0, 0, 0]) == pytest.approx(3 / 6)
    assert intrinsic.avoid_by_turning([0, 0, 0, 0, 0, 0.5, 0]) == pytest.approx(-2 * 0.5 / 6)
    assert intrinsic.avoid_by_turning([0.3, 0.2, 0.9, 1, 0.9, 0.2, 0.3]) == pytest.approx(0.0)


def test_eq9_eq10_floating_avoidance_by_hand():
    # Obstacle west only: b_h = 0.5 * 1 = 0.5 -> (0.5 - 0.25) / 0.75 = 1/3; b_v = 0
    np.testing.assert_allclose(intrinsic.avoid_by_accelerating([0, 0, 0, 0, 1, 0, 0, 0]), [1 / 3, 0])
    # North and north-east: b_h = 0.25 * (-1) = -0.25 -> (-0.25 + 0.25)/0.75 = 0 (edge of the dead zone)
    # b_v = 0.5 * (0 - 1) + 0.25 * (0 - 1) = -0.75 -> (-0.75 + 0.25) / 0.75 = -2/3
    np.testing.assert_allclose(intrinsic.avoid_by_accelerating([0, 1, 1, 0, 0, 0, 0, 0]), [0, -2 / 3])
    # Inside the dead zone: "not changed" = zero acceleration.
    np.testing.assert_allclose(intrinsic.avoid_by_accelerating([0.2, 0, 0, 0, 0, 0, 0, 0]), [0, 0])
    # Full push from the south-west corner.
    np.testing.assert_allclose(intrinsic.avoid_by_accelerating([0, 0, 0, 1, 1, 1, 1, 1]),
                               [(0.5 + 0.25 * 1 - 0.25) / 0.75, (0.5 + 0.25 * 1 - 0.25) / 0.75])


def test_random_action_is_clipped_gaussian_sd_half():
    rng = np.random.default_rng(0)
    a = np.array([intrinsic.random_action(rng, 1)[0] for _ in range(20000)])
    assert a.min() >= -1 and a.max() <= 1 and (np.abs(a) == 1).mean() > 0.03  # ~4.6% clipped
    assert abs(a.mean()) < 0.02 and 0.45 < a.std() < 0.5
    fb = intrinsic.fallback_for("eq8", "avoidance")
    near_left = np.array([1, 1, 1, 0, 0, 0, 0.0])
    acts = np.array([fb(near_left, rng)[0] for _ in range(5000)])
    assert 0.75 < np.isclose(acts, 1.0).mean() < 0.85  # eq 8 gives 1.0 80% of the time
    with pytest.raises(ValueError, match="condition"):
        intrinsic.fallback_for("eq8", "fuzzy")
