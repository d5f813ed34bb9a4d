"""The act's faster paths give the same bits as the plain ones: eq 4's radicands with up to
four components a pass against one component a pass, and recall_bounded (similarities
only where an element may enter the table, found by a bound in single precision) against
similarities + recall_since on the same memory. Random memories with many equal inputs
(ties at every weight) or inputs that single precision rounds, entries that reach the
same element or drop out, candidates cut by time (recall_candidates "past"), one to three
groups, contiguous or interleaved, inputs so far apart that similarities are -inf (or
nan, with a group of weight 0), and a variance so small that a radicand is nan; the
single-precision cut against elements exactly at the cut, and the agent's
single-precision copy of its inputs against the inputs."""
import numpy as np
import pytest

from ebrl import acting, kernels

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


def _bounded(mem, size, alpha, since, sim):
    """recall_bounded on mem's table (copies): (table, weights)."""
    t, w = mem["table"].copy(), mem["table_w"].copy()
    inputs = mem["inputs"]
    bound = np.abs(inputs[:, :size]).max(axis=1) if size else np.zeros(len(mem["x"]))
    with np.errstate(over="ignore"):  # inputs past single precision round to inf
        inputs32 = inputs.astype(np.float32)
    acting.recall_bounded(mem["x"], inputs, inputs32, bound, size,
                           mem["variance"], mem["group_of"], mem["group_size"],
                           mem["group_weight"], mem["nxt"], t, w, alpha, mem["time"], since,
                           sim)
    return t, w


@pytest.mark.parametrize("n,size,groups,interleaved", CASES)
def test_the_bounded_recall_is_recall_since_bit_for_bit(n, size, groups, interleaved):
    rng = np.random.default_rng(n * 100 + size + groups + interleaved)
    kinds = set()  # the edge similarities met
    for case in range(60):
        mem = _memory(rng, n, size, size + 5, groups, interleaved)
        since = SINCE_ALL if case % 3 else int(rng.integers(0, 2 * size))
        alpha = float(rng.random())
        if case % 4 == 1:  # inputs that single precision rounds, many nearly equal
            mem["inputs"][:, :size] += rng.normal(0.0, 1e-9, (n, size)) * (rng.random(size) < 0.5)
            mem["x"] = mem["x"] + rng.normal(0.0, 1e-9, n)
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
        c = kernels.scales(mem["variance"], mem["group_of"], mem["group_size"])
        assert acting.scales_finite(c) == (case % 11 != 10)
        got_t, got_w = _bounded(mem, size, alpha, since, np.zeros(size + 5))
        assert got_t.tolist() == want_t.tolist(), case
        assert got_w[got_t >= 0].tobytes() == want_w[want_t >= 0].tobytes(), case
        kinds |= {"-inf"} if np.isneginf(sim[:size]).any() else set()
        kinds |= {"nan"} if np.isnan(sim[:size]).any() else set()
        kinds |= {"nan radicand"} if np.isnan(radicand).any() else set()
    assert kinds == {"-inf", "nan", "nan radicand"}  # the edges were met


def test_the_bound_leaves_out_elements_when_a_table_reaches_its_entries():
    """The bound does leave elements out: on a memory of one long episode whose entries
    all reach an element, recall_bounded takes fewer similarities than there are
    elements (those it takes are written to sim, the others left as they were), and
    still makes recall_since's table."""
    rng = np.random.default_rng(5)
    n, size = 10, 2000
    inputs = rng.random((n, size)) * 2.0
    nxt = np.append(np.arange(1, size), -1)
    group_of = np.array([0] * 8 + [1] * 2)
    mem = dict(x=inputs[:, 100].copy(), inputs=inputs, variance=rng.random(n) * 0.3 + 0.1,
               group_of=group_of, group_size=np.array([8.0, 2.0]),
               group_weight=np.array([0.8, 0.2]), nxt=nxt,
               table=np.array([99, 500, 700, 900, 1100, 1300, 1500]),
               table_w=np.linspace(0.9, 0.6, 7), time=np.arange(size))
    sim = np.zeros(size)
    kernels.similarities(mem["x"], inputs, size, mem["variance"], group_of,
                         mem["group_size"], mem["group_weight"], sim)
    want_t, want_w = mem["table"].copy(), mem["table_w"].copy()
    kernels.recall_since(sim, size, nxt, want_t, want_w, 0.5, mem["time"], SINCE_ALL)
    unset = np.full(size, 7.0)  # no similarity is 7
    got_t, got_w = _bounded(mem, size, 0.5, SINCE_ALL, unset)
    assert got_t.tolist() == want_t.tolist() and got_w.tobytes() == want_w.tobytes()
    assert 0 < (unset == 7.0).sum() and (unset != 7.0).sum() < size // 4


def test_the_single_precision_cut_keeps_every_element_at_the_cut():
    """single_cut's guarantee, at its edge: an element whose exact radicand is the cut
    itself has a single-precision radicand (group_radicands) at or below the single cut,
    over magnitudes from 1e-30 to 1e25 and scales from 1e-12 to 1e12; and no cut where
    a value passes BOUNDED_LIMIT or the cut is not finite."""
    rng = np.random.default_rng(11)
    for case in range(3000):
        n = int(rng.integers(1, 11))
        group_of = (rng.random(n) < 0.3).astype(np.int64)
        group_of[0] = 0
        size = 16
        scale = 10.0 ** rng.uniform(-30, 25)
        inputs = rng.normal(0.0, 1.0, (n, size)) * scale
        x = inputs[:, 0] + rng.normal(0.0, 1.0, n) * scale * 10.0 ** rng.uniform(-9, 0)
        c = 10.0 ** rng.uniform(-12, 12, n)
        exact = np.zeros(size)
        for i in np.flatnonzero(group_of == 0):
            exact += (x[i] - inputs[i]) ** 2 * c[i]
        single = np.zeros(size, np.float32)
        acting.group_radicands(x, inputs.astype(np.float32), size, c, group_of, 0, single)
        bound = np.abs(inputs).max(axis=1)
        for m in range(size):
            cut = acting.single_cut(exact[m], 0, c, x, bound, group_of)
            if np.isfinite(exact[m]) and exact[m] < 1e36:
                assert not single[m] > cut, (case, m, exact[m], single[m], cut)
    c = np.ones(3)
    zero = np.zeros(3, np.int64)
    assert acting.single_cut(np.inf, 0, c, np.ones(3), np.ones(3), zero) == np.inf
    assert acting.single_cut(0.5, 0, c, np.full(3, 2e30), np.ones(3), zero) == np.inf
    assert acting.single_cut(0.5, 0, c, np.ones(3), np.full(3, 2e30), zero) == np.inf
    assert acting.single_cut(0.5, 0, np.full(3, 2e30), np.ones(3), np.ones(3), zero) == np.inf
    assert acting.single_cut(2e37, 0, c, np.ones(3), np.ones(3), zero) == np.inf
    assert 0.5 < acting.single_cut(0.5, 0, c, np.ones(3), np.ones(3), zero) < 0.5001
    many = acting.BOUNDED_COMPONENTS + 1  # the sum's rounding past the relative 1e-5
    assert acting.single_cut(0.5, 0, np.ones(many), np.ones(many), np.ones(many),
                             np.zeros(many, np.int64)) == np.inf


def test_passing_takes_the_elements_not_above_the_cut_nan_included_in_order():
    rng = np.random.default_rng(3)
    for size in (0, 1, 7, 8, 9, 63, 64, 65, 1000):
        values = rng.random(size).astype(np.float32)
        values[rng.random(size) < 0.05] = np.nan
        for cut in (np.float32(0.0), np.float32(0.03), np.float32(0.5), np.float32(np.inf)):
            passed = np.full(size + 1, -1)
            count = acting.passing(values, size, cut, passed)
            want = [m for m in range(size) if not values[m] > cut]
            assert passed[:count].tolist() == want


def test_the_agents_single_precision_inputs_follow_its_inputs():
    """After stores and forgetting, the record's inputs32 is its inputs rounded to single
    precision, element by element, and input_bound at least each component's largest
    |input| (the act's bound needs both)."""
    from ebrl import Agent, Config
    rng = np.random.default_rng(2)
    agent = Agent(Config(memory_size=40), 3, 1, lambda ranges, r: np.zeros(1), seed=0)
    for step in range(300):
        agent.act(rng.normal(0.0, 10.0 ** rng.uniform(-3, 3), 3))
        agent.learn(1.0 if step % 17 == 0 else 0.0, step % 17 == 0)
    m, size = agent.memory, agent.size
    assert size == 40
    assert m.inputs32[:, :size].tobytes() == m.inputs[:, :size].astype(np.float32).tobytes()
    assert (m.input_bound >= np.abs(m.inputs[:, :size]).max(axis=1)).all()


def test_the_bound_leaves_out_only_elements_below_the_floor():
    """prune_cut's bound, at its edge: an element just past the cut is below the floor,
    and no cut is made where no bound holds."""
    weight = np.array([0.7, 0.3])
    for floor in (0.2, 0.5, 0.9, 0.999):
        g, cut = acting.prune_cut(floor, weight)
        assert g == 0 and np.isfinite(cut)
        r = np.nextafter(cut, np.inf)
        best = weight[0] * (1.0 - np.sqrt(r)) + weight[1] * 1.0  # group 1 at its best
        assert best < floor
    # at the largest similarity, 1, only elements equal to the input in group 0 stay
    assert 0.0 < acting.prune_cut(1.0, weight)[1] < 1e-15
    assert acting.prune_cut(1.5, weight)[1] == np.inf  # past 1 the bound cuts nothing
    assert acting.prune_cut(0.5, np.array([1.2, -0.2]))[1] == np.inf  # a negative weight
    assert acting.prune_cut(0.5, np.array([1.0, 0.0]))[1] == np.inf  # a weight 0
