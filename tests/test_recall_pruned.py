"""The act's faster paths give the same bits as the plain ones: eq 4's radicands with up to
four components a pass against one component a pass, and recall_pruned (square roots
only where an element may enter the table) against similarities + recall_since on the
same memory. Random memories with many equal inputs (ties at every weight), entries
that reach the same element or drop out, candidates cut by time (recall_candidates
"past"), one to three groups, contiguous or interleaved, inputs so far apart that
similarities are -inf (or nan, with a group of weight 0), and a variance so small that a
radicand is nan."""
import numpy as np
import pytest

from ebrl import kernels

SINCE_ALL = kernels.NO_EXCLUSION


def _plain_radicands(x, inputs, size, variance, group_of, group_size, groups):
    """eq 4's radicands one component a pass, in index order (the kernel before it
    took up to four at once)."""
    radicand = np.zeros((groups, size))
    for i in range(len(x)):
        j = group_of[i]
        c = 1.0 / (2.0 * group_size[j] * variance[i])
        for m in range(size):
            d = x[i] - inputs[i, m]
            radicand[j, m] = radicand[j, m] + d * d * c
    return radicand


def _memory(rng, n, size, capacity, groups, interleaved):
    """A memory of `size` elements (of `capacity`) whose inputs take few values, so that
    many elements are equal to each other and some to the input; its episodes' links,
    time stamps and a recall table of entries (one at an episode's end)."""
    group_of = (np.arange(n) % groups if interleaved else
                np.minimum(np.arange(n) * groups // n, groups - 1)).astype(np.int64)
    group_size = np.bincount(group_of, minlength=groups).astype(np.float64)
    weight = rng.random(groups) + 0.1
    inputs = np.zeros((n, capacity))
    inputs[:, :size] = rng.integers(0, 4, (n, size)) / 4.0
    x = rng.integers(0, 4, n) / 4.0
    variance = rng.random(n) * 0.3 + 0.01
    nxt, prev = np.full(capacity, -1), np.full(capacity, -1)
    for m in range(size - 1):
        if rng.random() < 0.9:  # episodes of about ten elements
            nxt[m], prev[m + 1] = m + 1, m
    k = 7
    table = np.full(k, -1)
    filled = rng.integers(0, k + 1)
    table[:filled] = rng.choice(size, filled, replace=False)
    if filled and rng.random() < 0.3:
        table[0] = size - 1  # an entry at its episode's end drops out
    table_w = np.sort(rng.random(k))[::-1].copy()
    table_w[rng.random(k) < 0.3] = 1.0  # weights equal to the largest similarity
    time = rng.permutation(size * 2)[:capacity].astype(np.int64)
    return dict(x=x, inputs=inputs, variance=variance, group_of=group_of,
                group_size=group_size, group_weight=weight / weight.sum(), nxt=nxt,
                table=table, table_w=table_w, time=time)


CASES = [(n, size, groups, interleaved) for n, size, groups, interleaved in
         [(1, 30, 1, False), (7, 200, 1, False), (10, 300, 2, False), (10, 300, 2, True),
          (9, 150, 3, False), (5, 64, 3, True)]]


@pytest.mark.parametrize("n,size,groups,interleaved", CASES)
def test_the_radicands_are_one_component_a_pass_bit_for_bit(n, size, groups, interleaved):
    rng = np.random.default_rng(n * 1000 + size + groups)
    for _ in range(20):
        mem = _memory(rng, n, size, size + 5, groups, interleaved)
        mem["x"] = rng.normal(0.0, 2.0, n)  # inputs of every size
        args = (mem["x"], mem["inputs"], size, mem["variance"], mem["group_of"],
                mem["group_size"], groups)
        got, want = kernels.radicands(*args), _plain_radicands(*args)
        assert got.tobytes() == want.tobytes()


@pytest.mark.parametrize("n,size,groups,interleaved", CASES)
def test_the_pruned_recall_is_recall_since_bit_for_bit(n, size, groups, interleaved):
    rng = np.random.default_rng(n * 100 + size + groups + interleaved)
    kinds = set()  # the edge similarities met
    for case in range(60):
        mem = _memory(rng, n, size, size + 5, groups, interleaved)
        since = SINCE_ALL if case % 3 else int(rng.integers(0, 2 * size))
        alpha = float(rng.random())
        if case % 5 == 4:  # inputs far apart: squares overflow, similarities -inf
            mem["x"] *= 1e155
            mem["inputs"][:, ::2] *= -1e155
        if case % 7 == 6 and groups > 1:  # a group of weight 0: 0 * -inf is nan
            mem["group_weight"][-1] = 0.0
        if case % 11 == 10:  # a variance so small that 1 / (2 n V) is inf: 0 * inf is nan
            mem["variance"][0] = 1e-320
        radicand = kernels.radicands(mem["x"], mem["inputs"], size, mem["variance"],
                                     mem["group_of"], mem["group_size"], groups)
        sim = np.zeros(size + 5)
        kernels.similarities(mem["x"], mem["inputs"], size, mem["variance"],
                             mem["group_of"], mem["group_size"], mem["group_weight"], sim)
        want_t, want_w = mem["table"].copy(), mem["table_w"].copy()
        kernels.recall_since(sim, size, mem["nxt"], want_t, want_w, alpha, mem["time"],
                             since)
        got_t, got_w = mem["table"].copy(), mem["table_w"].copy()
        prune = kernels.scales_finite(mem["variance"], mem["group_of"], mem["group_size"])
        assert prune == (case % 11 != 10)
        kernels.recall_pruned(radicand, mem["group_weight"], size, mem["nxt"], got_t,
                              got_w, alpha, mem["time"], since, np.zeros(size + 5), prune)
        assert got_t.tolist() == want_t.tolist(), case
        assert got_w[got_t >= 0].tobytes() == want_w[want_t >= 0].tobytes(), case
        kinds |= {"-inf"} if np.isneginf(sim[:size]).any() else set()
        kinds |= {"nan"} if np.isnan(sim[:size]).any() else set()
        kinds |= {"nan radicand"} if np.isnan(radicand).any() else set()
    assert kinds == {"-inf", "nan", "nan radicand"}  # the edges were met


def test_the_bound_leaves_out_only_elements_below_the_floor():
    """prune_cut's bound, at its edge: an element just past the cut is below the floor,
    and no cut is made where no bound holds."""
    weight = np.array([0.7, 0.3])
    for floor in (0.2, 0.5, 0.9, 0.999):
        g, cut = kernels.prune_cut(floor, weight)
        assert g == 0 and np.isfinite(cut)
        r = np.nextafter(cut, np.inf)
        best = weight[0] * (1.0 - np.sqrt(r)) + weight[1] * 1.0  # group 1 at its best
        assert best < floor
    # at the largest similarity, 1, only elements equal to the input in group 0 stay
    assert 0.0 < kernels.prune_cut(1.0, weight)[1] < 1e-15
    assert kernels.prune_cut(1.5, weight)[1] == np.inf  # past 1 the bound cuts nothing
    assert kernels.prune_cut(0.5, np.array([1.2, -0.2]))[1] == np.inf  # a negative weight
    assert kernels.prune_cut(0.5, np.array([1.0, 0.0]))[1] == np.inf  # a weight 0
