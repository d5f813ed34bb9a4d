"""The memory's invariants under many stores and forgettings."""
import numpy as np
import pytest

import ebrl
from ebrl import intrinsic, kernels


def chains_are_consistent(ag):
    nxt, prv = ag.memory.nxt, ag.memory.prev
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
    fed = set()
    for step in range(3000):
        x = rng.random(5) * [1, 1, 1, 3, 0.1]
        fed.add(tuple(x))
        ag.act(x)
        last = rng.random() < 0.03
        ag.learn(1.0 if last else 0.0, last)
        assert ag.size <= cfg.memory_size
        if step % 97 == 0:
            chains_are_consistent(ag)
            stored = ag.memory.inputs[:, : ag.size].T
            assert all(tuple(m) in fed for m in stored)  # inputs stored exactly as given
            np.testing.assert_allclose(ag.variance, np.maximum(stored.var(axis=0), 1e-6), rtol=1e-6)
            table, weights = ag.recall_table()
            assert len(set(table.tolist())) == len(table) <= cfg.recall_size
            assert np.all(table < ag.size) and np.all(np.diff(weights) <= 0)  # best first
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
    assert ag.memory.inputs[0, 0] == 9.0  # slot 0 reused for the new element
    assert ag.memory.prev[1] == -1 and ag.memory.nxt[3] == 0 and ag.memory.prev[0] == 3
    np.testing.assert_allclose(ag.variance, np.var([9.0, 1, 2, 3]))


def test_cost_is_flat_and_memory_capped_over_long_runs():
    ag = ebrl.Agent(ebrl.Config(memory_size=64, recall_size=7), 3, 1, intrinsic.RandomWalk(1), seed=0)
    rng = np.random.default_rng(0)
    for step in range(20000):
        ag.act(rng.random(3))
        ag.learn(1.0 if step % 300 == 299 else 0.0, step % 300 == 299)
    assert ag.size == 64 and ag.steps == 20000
    assert np.isfinite(ag.reliability).all() and (ag.reliability > 0).all()


def test_recall_selection_is_the_stable_top_n_r():
    """The recall kernel keeps exactly the N_r largest weights, best first, ties to the
    lower slot, on data with and without ties."""
    rng = np.random.default_rng(3)
    no_links = np.full(512, -1, dtype=np.int64)
    for trial in range(400):
        kind = trial % 4
        if kind == 0:
            w = rng.random(512)
        elif kind == 1:  # many ties, including at the cut
            w = rng.integers(0, 5, 512).astype(np.float64)
        elif kind == 2:  # spread over orders of magnitude, either sign
            w = (10.0 ** rng.uniform(-6, 2, 512)) * rng.choice([-1, 1], 512)
        else:  # all equal
            w = np.full(512, 0.5)
        size = 512 if trial % 5 else int(rng.integers(1, 12))  # fewer than N_r at times
        table, table_w = np.full(7, -1, dtype=np.int64), np.zeros(7)
        kernels.recall(w.copy(), size, no_links, table, table_w, 0.5)
        want = np.argsort(-w[:size], kind="stable")[:7]
        np.testing.assert_array_equal(table[: len(want)], want)
        np.testing.assert_array_equal(table_w[: len(want)], w[want])
        assert (table[len(want):] == -1).all()


def test_forgetting_takes_the_first_of_equal_reliabilities():
    rel = np.array([0.5, 0.25, 0.75, 0.25, 0.25])
    assert kernels.least_reliable(rel, 5) == 1
    assert kernels.least_reliable(rel, 1) == 0


def _first_least(rel, size):
    """Forgetting's choice by its definition (2.1, the first on ties), as the plain scan
    made it: the first element holding the least value that is not NaN; 0 when the
    first element is NaN (the scan compares the others with it and none is less)."""
    values = rel[:size]
    if np.isnan(values[0]):
        return 0
    return int(np.flatnonzero(values == np.nanmin(values))[0])


def test_least_reliable_by_blocks_is_the_plain_scan_at_every_edge():
    """least_reliable takes the least value per block of integer keys: the same element
    as the plain scan on memories of ties, of -0.0 beside 0.0, of infinities, subnormals
    and NaNs of either sign (rel[0] one of them too), at sizes across the blocks' edges."""
    rng = np.random.default_rng(11)
    special = np.array([0.5, 0.25, -0.125, -0.0, 0.0, 1.0, np.inf, -np.inf, 5e-324, -5e-324])
    negative_nan = -np.abs(np.nan)  # a NaN with its sign bit set
    assert np.signbit(negative_nan) and np.isnan(negative_nan)
    block = kernels.LEAST_BLOCK
    sizes = [1, 2, 2 * block - 1, 2 * block, 2 * block + 1, 3 * block, 4096]
    for trial in range(3000):
        size = sizes[trial % len(sizes)] if trial % 2 else int(rng.integers(1, 8 * block))
        rel = rng.choice(special, size + 3) if trial % 3 else rng.random(size + 3)
        if trial % 4 == 0:
            rel[rng.integers(0, size)] = np.nan
        if trial % 9 == 0:
            rel[rng.integers(0, size)] = negative_nan
        if trial % 13 == 0:
            rel[0] = np.nan
        if trial % 5 == 0:  # the least at a block's end, then at its start
            rel[:] = 0.5
            rel[min(size - 1, block - 1 + block * int(rng.integers(0, 4)))] = 0.25
        if trial % 10 in (3, 6):  # zeros of both signs, either first
            rel[:] = 0.5
            first, later = sorted(rng.choice(size, 2, replace=False)) if size > 1 else (0, 0)
            rel[first], rel[later] = (0.0, -0.0) if trial % 10 == 3 else (-0.0, 0.0)
        rel[size:] = -1.0  # past size: never the answer
        assert kernels.least_reliable(rel, size) == _first_least(rel, size), (trial, size)
    keys = [kernels.ordered_key(np.array([v]).view(np.int64)[0]) for v in
            (-np.inf, -1.0, -5e-324, -0.0, 0.0, 5e-324, 1.0, np.inf)]
    assert keys == sorted(keys) and len(set(keys)) == len(keys)


@pytest.mark.parametrize("memory_size,obs_dim,groups", [(7, 3, None), (33, 5, [[0, 1, 2], [3, 4]]),
                                                         (4096, 10, [range(8), range(8, 10)])])
def test_memory_arrays_are_disjoint_and_initialised(memory_size, obs_dim, groups):
    cfg = ebrl.Config(memory_size=memory_size, recall_size=7)
    ag = ebrl.Agent(cfg, obs_dim, 2, intrinsic.RandomWalk(2), seed=0,
                    groups=groups, group_weights=None if groups is None else [0.7, 0.3])
    st = ag.memory
    arrays = [st.inputs, st.actions, st.utility, st.rel, st.time, st.nxt, st.prev,
              st.sums, st.variance, st.sim, st.table, st.table_w, st.decided, st.obs, st.action]
    for i, a in enumerate(arrays):
        assert a.flags.c_contiguous and a.flags.writeable
        assert not any(np.shares_memory(a, b) for b in arrays[i + 1:])
    assert (st.nxt == -1).all() and (st.prev == -1).all() and (st.table == -1).all()
    assert not st.inputs.any() and not st.sums.any() and not st.decided.any()
    assert st.inputs.shape == (obs_dim, memory_size) and st.actions.shape == (memory_size, 2)
    # The record holds these very arrays: a read-out from Python shares their memory.
    assert np.shares_memory(st.inputs, ag.memory.inputs) and ag.action_dim == 2
