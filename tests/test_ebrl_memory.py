"""The memory's invariants under many stores and forgettings."""
import numpy as np
import pytest

import ebrl
from ebrl import intrinsic


def chains_are_consistent(ag):
    nxt, prv = ag._next, ag._prev
    for k in range(ag.size):
        if nxt[k] >= 0:
            assert prv[nxt[k]] == k
        if prv[k] >= 0:
            assert nxt[prv[k]] == k
    # No cycles: walking back from any element ends.
    for k in range(ag.size):
        seen, j = 0, k
        while j >= 0:
            j = prv[j]
            seen += 1
            assert seen <= ag.size


@pytest.mark.parametrize("groups", [None, [np.arange(3), np.arange(3, 5)]])
def test_invariants_under_random_episodes(groups):
    rng = np.random.default_rng(1)
    cfg = ebrl.Config(memory_size=32, recall_size=4, exploration_rate=0.3)
    ag = ebrl.Agent(cfg, 5, 1, intrinsic.RandomWalk(1), groups=groups,
                    group_weights=None if groups is None else [0.7, 0.3], seed=2)
    for step in range(3000):
        ag.act(rng.random(5) * [1, 1, 1, 3, 0.1])
        last = rng.random() < 0.03
        ag.learn(1.0 if last else 0.0, last)
        assert ag.size <= cfg.memory_size
        if step % 97 == 0:
            chains_are_consistent(ag)
            stored = ag._x[: ag.size]
            np.testing.assert_allclose(ag.variance, np.maximum(stored.var(axis=0), 1e-6), rtol=1e-6)
            np.testing.assert_allclose(ag._aug[:5, : ag.size].T, stored, rtol=1e-6)
            table, _ = ag.recall_table()
            assert len(set(table.tolist())) == len(table) <= cfg.recall_size
            assert np.all(ag.reliability > 0) and np.all(ag.reliability <= 1.0)
    assert ag.size == cfg.memory_size


def test_forgetting_takes_the_least_reliable_and_splices_links():
    cfg = ebrl.Config(memory_size=4, recall_size=1, time_discount=0.5, exploration_rate=0.0)
    ag = ebrl.Agent(cfg, 1, 1, lambda r, rng: np.zeros(1), seed=0)
    for t in range(4):
        ag.act(np.array([float(t)]))
        ag.learn(0.0)
    # one episode 0 -> 1 -> 2 -> 3; element 0 is oldest, least reliable.
    ag.act(np.array([9.0]))
    ag.learn(0.0)
    assert ag._x[0, 0] == 9.0  # slot 0 reused for the new element
    assert ag._prev[1] == -1 and ag._next[3] == 0 and ag._prev[0] == 3
    np.testing.assert_allclose(ag.variance, np.var([9.0, 1, 2, 3]))


def test_cost_is_flat_and_memory_capped_over_long_runs():
    ag = ebrl.Agent(ebrl.Config(memory_size=64, recall_size=7), 3, 1, intrinsic.RandomWalk(1), seed=0)
    rng = np.random.default_rng(0)
    for step in range(20000):
        ag.act(rng.random(3))
        ag.learn(1.0 if step % 300 == 299 else 0.0, step % 300 == 299)
    assert ag.size == 64 and ag.steps == 20000
    assert np.isfinite(ag.reliability).all() and (ag.reliability > 0).all()


def test_recall_selection_is_the_stable_top_n_r_whatever_the_radius():
    """_nearest, which sorts only elements within an adaptive radius, must give exactly the
    N_r smallest distances, ties to the lower slot, on data with and without ties."""
    rng = np.random.default_rng(3)
    ag = ebrl.Agent(ebrl.Config(memory_size=512, recall_size=7), 2, 1, intrinsic.RandomWalk(1), seed=0)
    for trial in range(400):
        kind = trial % 4
        if kind == 0:
            d = rng.random(512).astype(np.float32)
        elif kind == 1:  # many ties, including at the cut
            d = rng.integers(0, 5, 512).astype(np.float32)
        elif kind == 2:  # spread over orders of magnitude: the radius is often wrong
            d = (10.0 ** rng.uniform(-6, 2, 512)).astype(np.float32)
        else:  # all equal
            d = np.full(512, 0.5, dtype=np.float32)
        want = np.argsort(d, kind="stable")[:7]
        got = ag._nearest(d)
        np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("memory_size,obs_dim,groups", [(7, 3, None), (33, 5, [[0, 1, 2], [3, 4]]),
                                                         (4096, 10, [range(8), range(8, 10)])])
def test_memory_arrays_are_disjoint_aligned_and_initialised(memory_size, obs_dim, groups):
    cfg = ebrl.Config(memory_size=memory_size, recall_size=7)
    ag = ebrl.Agent(cfg, obs_dim, 2, intrinsic.RandomWalk(2), seed=0,
                    groups=groups, group_weights=None if groups is None else [0.7, 0.3])
    arrays = [ag._aug, ag._xs, ag._action, ag._utility, ag._rel, ag._next, ag._d2, ag._d]
    for i, a in enumerate(arrays):
        assert a.ctypes.data % 64 == 0
        assert not any(np.shares_memory(a, b) for b in arrays[i + 1:])
    assert (ag._aug == 1).all() and (ag._next == -1).all() and not ag._xs.any()
    assert ag._aug.shape == (2 * obs_dim + 1, memory_size) and ag._d2.shape[1] == memory_size
