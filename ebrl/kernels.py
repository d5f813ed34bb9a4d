"""The agent's per-step work (Section 2) as compiled kernels, one per paper equation.

Every kernel is ``@njit(cache=True)``: compiled once, then loaded from numba's cache
(``ebrl/__pycache__``) by later processes and spawned workers. None uses ``fastmath``
or ``parallel``, so every floating-point operation runs as written, in the order
written, and a run gives the same numbers bit for bit on any machine and with any
number of workers. (The compiler may process several memory elements at once with
vector instructions; each element's value is computed by the same operations in the
same order, so this changes no value.)

The memory, as the kernels see it (M = memory_size, n = obs_dim):
    inputs[i, m]   component i of element m's input (one row per component, so that
                   eq 2-4 run along rows, over the elements)
    inputs32[i, m] the same rounded to single precision, and input_bound[i] at least
                   every stored |inputs[i, m]|: only for the act's bound (ebrl.acting)
    actions[m]     element m's action
    utility[m]     U_m (eq 5, eq 6);   rel[m]: R_m (eq 7, time discount, forgetting)
    time[m]        the step at which m was stored (eq 6's exponent)
    nxt[m], prev[m] m's forward and backward links in its episode, -1 for none
    sums[0], sums[1] running sums of x and x^2 over the stored inputs (eq 2's V_i)
    decided[m]     m was used for a memory decision in the current trial (eq 7 with
                   eq7_scope "decided_only"; kept False otherwise)
Elements 0..size-1 are stored. The recall table is table[e] (an element, -1 for an
empty entry) and table_w[e] (its weight W), best first: larger weight, then lower
element.

The readings that are switches reach the kernels as ints, their codes
(ebrl.readings.Reading.code: the value's index in the registry), and the constants here
are named by those codes (ebrl.readings.codes): learn's eq7_scope (EQ7_TO_START,
EQ7_DECIDED_ONLY) and forgetting (FORGET_LEAST_RELIABLE, FORGET_OLDEST). The episode
and recall-table switches act at a trial's end, in ebrl.Agent.end_trial.
"""
import numpy as np
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from ebrl.readings import codes

INVALID = -2  # act's answer for an observation that is not finite or whose square overflows
FALLBACK = -1  # act_memory's answer when the fallback is to choose the action
#: Who chose an action: the memory (eq 5); the fallback's intrinsic behaviour or its
#: random action; or the exploration draw, which handed to the fallback a step the
#: memory would have taken. AgentState.decider holds the index, -1 before any act.
DECIDERS = ("memory", "intrinsic", "random", "exploration")
MEMORY, INTRINSIC, RANDOM, EXPLORATION = map(DECIDERS.index, DECIDERS)
EXPLORED = -3  # act_memory's answer when its exploration step's random action is s.action
#: The switch readings' codes (ebrl.readings: each value's index in its registry entry).
EQ7_TO_START, EQ7_DECIDED_ONLY = codes("eq7_scope", "to_start", "decided_only")
FORGET_LEAST_RELIABLE, FORGET_OLDEST = codes("forgetting", "least_reliable", "oldest")
EQ7_REWARD, EQ7_SURPRISE_MEASURE, EQ7_SURPRISE_RATE = codes(
    "eq7_signal", "reward", "surprise_measure", "surprise_rate")
EQ7_WHOLE, EQ7_DISCOUNTED, EQ7_CUT = codes("eq7_walk", "whole", "discounted", "cut")
#: recall_candidates "all": no element is too recent to be a candidate.
NO_EXCLUSION = np.iinfo(np.int64).max


@njit(cache=True)
def eq1(weight, similarity, alpha):
    """eq 1: W <- W + alpha (S(M_i, s) - W), for an entry moved along its forward link."""
    return weight + alpha * (similarity - weight)


@njit(cache=True)
def eq5(weights, utilities):
    """eq 5's measure, min(W_i, U_i), for each recall-table entry (scalars or arrays)."""
    return np.minimum(weights, utilities)


@njit(cache=True)
def scales(variance, group_of, group_size):
    """eq 4's c_i = 1 / (2 n_j V_i) for each component i of group j: a radicand is
    sum_i (x_i - m_i)^2 c_i."""
    c = np.empty(variance.shape[0])
    for i in range(variance.shape[0]):
        c[i] = 1.0 / (2.0 * group_size[group_of[i]] * variance[i])
    return c


@njit(cache=True)
def radicands(x, inputs, size, variance, group_of, group_size, groups):
    """eq 4's radicands for every stored element m < size: out[j, m] = 1/(2 n_j) sum_{i in
    j} (x_i - m_i)^2 / V_i, the sum over group j's components in index order.

    Computed as sum_i (x_i - m_i)^2 c_i with c_i = 1 / (2 n_j V_i) taken once per act:
    per element and component a multiply instead of two divisions (protocol 5;
    docs/speed.md). This rounds differently from the formula as written
    (`ebrl.similarity`) in the last bits: within 1e-12 of it
    (tests/test_ebrl_equations.py). Each element's sum still adds the components one by
    one in index order; up to four consecutive components of a group are added in one
    pass over the elements, so that each element's partial sum is read and written once
    per four components, not once per component (the same sums, bit for bit)."""
    return radicands_scaled(x, inputs, size, scales(variance, group_of, group_size), group_of,
                            groups)


@njit(cache=True)
def radicands_scaled(x, inputs, size, c, group_of, groups):
    """radicands with eq 4's c_i given (scales)."""
    radicand = np.zeros((groups, size))
    n, i = x.shape[0], 0
    while i < n:  # up to four components of one group in one pass over the elements
        j = group_of[i]
        acc = radicand[j]
        if i + 3 < n and group_of[i + 1] == j and group_of[i + 2] == j and group_of[i + 3] == j:
            r0, r1, r2, r3 = inputs[i], inputs[i + 1], inputs[i + 2], inputs[i + 3]
            x0, x1, x2, x3 = x[i], x[i + 1], x[i + 2], x[i + 3]
            c0, c1, c2, c3 = c[i], c[i + 1], c[i + 2], c[i + 3]
            for m in range(size):
                d0, d1, d2, d3 = x0 - r0[m], x1 - r1[m], x2 - r2[m], x3 - r3[m]
                a = acc[m] + d0 * d0 * c0
                a = a + d1 * d1 * c1
                a = a + d2 * d2 * c2
                acc[m] = a + d3 * d3 * c3
            i += 4
        elif i + 1 < n and group_of[i + 1] == j:
            r0, r1, x0, x1 = inputs[i], inputs[i + 1], x[i], x[i + 1]
            c0, c1 = c[i], c[i + 1]
            for m in range(size):
                d0, d1 = x0 - r0[m], x1 - r1[m]
                a = acc[m] + d0 * d0 * c0
                acc[m] = a + d1 * d1 * c1
            i += 2
        else:
            r0, x0, c0 = inputs[i], x[i], c[i]
            for m in range(size):
                d0 = x0 - r0[m]
                acc[m] += d0 * d0 * c0
            i += 1
    return radicand


@njit(cache=True)
def similarity_of(radicand, m, group_weight):
    """eq 3-4 for element m from its radicands: S = sum_j w_j S'_j, S'_j = 1 -
    sqrt(radicand[j, m]), the weights already divided by their sum, summed in group order
    from 0.0. With one group (weight 1) this is eq 2. (similarities computes the same
    sums group by group over every element.)"""
    total = 0.0
    for j in range(group_weight.shape[0]):
        total += group_weight[j] * (1.0 - np.sqrt(radicand[j, m]))
    return total


@njit(cache=True)
def similarities(x, inputs, size, variance, group_of, group_size, group_weight, out):
    """eq 2-4: out[m] = S(M_m, x) for every stored element m < size: radicands, then
    eq 4's square roots and eq 3's weighted sum for each element (similarity_of's sums,
    group by group over the elements, which vectorises)."""
    radicand = radicands(x, inputs, size, variance, group_of, group_size,
                         group_weight.shape[0])
    out[:size] = 0.0
    for j in range(group_weight.shape[0]):
        acc, w = radicand[j], group_weight[j]
        for m in range(size):
            out[m] += w * (1.0 - np.sqrt(acc[m]))


@njit(cache=True)
def recall(sim, size, nxt, table, table_w, alpha):
    """recall_since with every stored element a candidate (recall_candidates "all")."""
    recall_since(sim, size, nxt, table, table_w, alpha, nxt, NO_EXCLUSION)


@njit(cache=True)
def advance(sim, nxt, table, table_w, alpha, time, since):
    """eq 1 for the recall table's entries, in table order: each moves along its forward
    link (an entry at the end of its episode drops out), and the element it reaches,
    unless its time stamp is `since` or later, keeps the larger of its similarity
    sim[ahead] and W + alpha (S - W)."""
    exclude = since != NO_EXCLUSION
    for e in range(table.shape[0]):
        if table[e] >= 0:
            ahead = nxt[table[e]]
            if ahead >= 0 and not (exclude and time[ahead] >= since):
                sim[ahead] = max(sim[ahead], eq1(table_w[e], sim[ahead], alpha))


@njit(cache=True)
def fill(table, table_w, candidates, count, weight):
    """The recall table from scratch: the N_r = len(table) of candidates[:count]
    (ascending elements) of largest weight[m], best first, equal weights to the lower
    element (each goes after every entry of equal or larger weight; a full table takes
    one only above its lowest weight)."""
    table[:] = -1
    k, filled = table.shape[0], 0
    lowest = -np.inf  # once the table is full: the weight a candidate must exceed
    for c in range(count):
        m = candidates[c]
        w = weight[m]
        if filled == k:
            if not w > lowest:
                continue
        else:
            filled += 1
        e = filled - 1
        while e > 0 and table_w[e - 1] < w:
            table[e], table_w[e] = table[e - 1], table_w[e - 1]
            e -= 1
        table[e], table_w[e] = m, w
        if filled == k:
            lowest = table_w[k - 1]


@njit(cache=True)
def recall_since(sim, size, nxt, table, table_w, alpha, time, since):
    """The recall table (2.2) for the new input, whose similarities are sim[:size].

    eq 1: each entry moves along its forward link (advance). Every stored element is a
    candidate with its similarity S; an element reached by an entry keeps the larger of
    the two. The N_r = len(table) candidates of largest weight form the new table, best
    first, equal weights to the lower element (fill). sim is overwritten with the
    candidates' weights.

    An element whose time stamp is `since` or later is no candidate, nor reached by an
    entry (recall_candidates "past": since = the current trial's first step;
    NO_EXCLUSION: none is excluded, and `time` is not read).
    """
    exclude = since != NO_EXCLUSION
    advance(sim, nxt, table, table_w, alpha, time, since)
    candidates = np.empty(size, np.int64)
    count = 0
    for m in range(size):
        if not (exclude and time[m] >= since):
            candidates[count] = m
            count += 1
    fill(table, table_w, candidates, count, sim)


@njit(cache=True)
def policy(table, table_w, utility, threshold):
    """eq 5: the element of the entry maximising min(W_i, U_i), the first in table
    order on ties (larger weight, then lower element); -1 when no entry's measure
    exceeds threshold."""
    best, best_measure = -1, -np.inf
    for e in range(table.shape[0]):
        if table[e] >= 0:
            measure = eq5(table_w[e], utility[table[e]])
            if measure > best_measure:
                best, best_measure = table[e], measure
    return best if best_measure > threshold else -1


#: least_reliable's block: its least key is taken over this many elements at a time.
LEAST_BLOCK = 64
#: The bits of a float64 below its sign, as an int64 (ordered_key's mask).
_MAGNITUDE = 0x7FFFFFFFFFFFFFFF
#: The largest int64: no key is above it.
_LARGEST_KEY = np.iinfo(np.int64).max


@njit(cache=True)
def least_reliable(rel, size):
    """The element of lowest reliability, the first on ties (forgetting, 2.1): the answer
    of the plain scan (found = 0, then m wherever rel[m] < rel[found]), which is the first
    m holding the least value that is not NaN, or 0 when rel[0] is NaN.

    Over a full memory the scan's compare-and-branch per element was most of a learn
    step. Here the least value is taken per block of LEAST_BLOCK elements on the values'
    ordered integer keys (ordered_key: an integer minimum is vectorised, a float minimum
    is not without fast-math), then searched for in the first block holding it. -0.0 and
    0.0 have two keys and one value: the search compares values. A NaN of negative sign
    (its key below -inf's) sends it back to the plain scan."""
    if size < 2 * LEAST_BLOCK or not rel[0] == rel[0]:
        return _least_by_scan(rel, size)
    bits = rel[:size].view(np.int64)
    blocks = -(-size // LEAST_BLOCK)
    lows = np.empty(blocks, dtype=np.int64)
    best, best_key = 0, _LARGEST_KEY  # the first block of the least key
    for b in range(blocks):
        low = _LARGEST_KEY
        for m in range(b * LEAST_BLOCK, min(size, (b + 1) * LEAST_BLOCK)):
            key = ordered_key(bits[m])
            low = key if key < low else low
        lows[b] = ordered_key(low)  # a key is its own inverse: the block's least bits
        if low < best_key:
            best, best_key = b, low
    least = lows.view(np.float64)
    value = least[best]
    if value != value:  # a NaN of negative sign
        return _least_by_scan(rel, size)
    for b in range(best + 1):
        if least[b] == value:  # the first block holding it
            for m in range(b * LEAST_BLOCK, min(size, (b + 1) * LEAST_BLOCK)):
                if rel[m] == value:
                    return m
    return 0  # not reached: block `best` holds the value


@njit(cache=True)
def ordered_key(bits):
    """A float64's bits (as an int64) turned into an int64 that orders as the values do,
    -inf < ... < -0.0 < 0.0 < ... < inf (a NaN of negative sign below -inf, of positive
    sign above inf): a negative value's magnitude bits are flipped. Its own inverse."""
    return bits ^ ((bits >> 63) & _MAGNITUDE)


@njit(cache=True)
def _least_by_scan(rel, size):
    """least_reliable's answer by the plain scan."""
    found = 0
    for m in range(1, size):
        if rel[m] < rel[found]:
            found = m
    return found


@njit(cache=True)
def oldest(time, size):
    """The element of oldest time stamp, the first on ties (forgetting "oldest", 2.1:
    the memory as a queue; time stamps are unique, one element stored per step)."""
    found = 0
    for m in range(1, size):
        if time[m] < time[found]:
            found = m
    return found


@njit(cache=True)
def forget(k, inputs, sums, nxt, prev, table, table_w, tail, referred, cut):
    """Removes element k (2.1): its episode's neighbours are linked to each other (or,
    with cut, forgetting_link "cut", unlinked: the episode ends at k's predecessor and
    a new one starts at its successor), a recall entry pointing at it is dropped, its
    input leaves the variance sums. Returns (tail, referred), moved back to k's
    predecessor if either was k."""
    p, n = prev[k], nxt[k]
    if p >= 0:
        nxt[p] = -1 if cut else n
    if n >= 0:
        prev[n] = -1 if cut else p
    nxt[k] = prev[k] = -1
    if tail == k:
        tail = p
    if referred == k:
        referred = p
    kept = 0
    for e in range(table.shape[0]):
        if table[e] >= 0 and table[e] != k:
            table[kept], table_w[kept] = table[e], table_w[e]
            kept += 1
    table[kept:] = -1
    for i in range(inputs.shape[0]):
        xi = inputs[i, k]
        sums[0, i] -= xi
        sums[1, i] -= xi * xi
    return tail, referred


@njit(cache=True)
def update_variance(sums, size, floor, variance):
    """eq 2's V_i = mean(x_i^2) - mean(x_i)^2 over the stored inputs, from the running
    sums, floored at floor."""
    for i in range(variance.shape[0]):
        mean = sums[0, i] / size
        v = sums[1, i] / size - mean * mean
        variance[i] = v if v > floor else floor


@njit(cache=True)
def eq6(utility, prev, time, newest, reward, discount, cutoff):
    """eq 6: U_j += r gamma^(t - t_j) along the backward links from the newest element
    (time t), t_j being element j's time stamp; stops where gamma^(t - t_j) < cutoff.

    gamma^k is computed by repeated squaring (numba's float ** int): IEEE products
    only, the same on every machine."""
    t, j = time[newest], newest
    while j >= 0:
        gain = discount ** (t - time[j])
        if gain < cutoff:
            break
        utility[j] += reward * gain
        j = prev[j]


@njit(cache=True)
def eq7_change(r, reward, rho):
    """eq 7 for one element: R + rho r (1 - R) when r > 0, R + rho r R when r < 0."""
    return r + rho * reward * ((1.0 - r) if reward > 0 else r)


@njit(cache=True)
def eq7(rel, prev, referred, reward, rho, time, discount, cutoff, walk):
    """eq 7, eq7_scope "to_start": along the backward links from the element used for
    the last memory decision to its episode's start: R += rho r (1 - R) when r > 0,
    R += rho r R when r < 0.

    walk (eq7_walk): EQ7_WHOLE, every element by the same r; EQ7_DISCOUNTED, element j
    by r gamma^(t_ref - t_j) (gamma = discount, t_ref the referred element's time
    stamp), as eq 6 discounts; EQ7_CUT, by r, stopping where gamma^(t_ref - t_j) falls
    below cutoff, where eq 6 stops."""
    j = referred
    if walk == EQ7_WHOLE:
        while j >= 0:
            rel[j] = eq7_change(rel[j], reward, rho)
            j = prev[j]
        return
    t = time[referred]
    while j >= 0:
        gain = discount ** (t - time[j])
        if walk == EQ7_CUT:
            if gain < cutoff:
                break
            rel[j] = eq7_change(rel[j], reward, rho)
        else:
            rel[j] = eq7_change(rel[j], reward * gain, rho)
        j = prev[j]


@njit(cache=True)
def eq7_decided(rel, decided, size, reward, rho):
    """eq 7, eq7_scope "decided_only": once on each element used for a memory decision
    in the current trial (decided[m]), however often it was used; no other element
    changes."""
    for m in range(size):
        if decided[m]:
            rel[m] = eq7_change(rel[m], reward, rho)


@njit(cache=True)
def time_discount(rel, size, rate):
    """2.1: every stored element's reliability times the time discount rate."""
    for m in range(size):
        rel[m] *= rate
