"""One act, compiled: eq 2-4 against the memory, the recall table (2.2, eq 1) and eq 5's
choice (`act`), the table made by `recall_bounded`: recall_since's table (ebrl.kernels),
bit for bit, with each similarity taken only where its element may enter it.

The bound: the N_r elements the entries reach set a floor the new table's lowest weight
cannot be below; eq 3's sum is at most the heaviest group's term plus the other groups'
weights (`prune_cut`), and that group's radicand is bounded in single precision over
every element (`group_radicands` on the agent's inputs rounded, `single_cut` widened by
every rounding), so that only the elements that may enter (about 4% on a real run) get
their double-precision similarity (`similarities_of`, the plain sums). ebrl.kernels
keeps the equations and the plain kernels this is tested against
(tests/test_recall_bounded.py); docs/speed.md has the measurements."""
import numpy as np
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from ebrl.kernels import INVALID, NO_EXCLUSION, advance, fill, policy, radicands_scaled, \
    scales, similarity_of


#: prune_cut's margin, relative: an element is left out only where its similarity's bound
#: is below the reached elements' weights by this much, far more than the bound's rounding
#: in double precision (about 1e-16), so that no element that could enter the table is
#: left out (single_cut adds the single-precision pass's own).
PRUNE_MARGIN = 1e-9


@njit(cache=True)
def prune_cut(floor, group_weight):
    """(g, cut): an element whose group-g radicand exceeds cut has a similarity below
    floor, g being the group of largest weight; cut is inf (no element left out) where no
    such bound holds (a weight not above 0, a floor too close to the largest similarity).

    S = sum_j w_j (1 - sqrt(r_j)) <= w_g (1 - sqrt(r_g)) + sum_{j != g} w_j, each
    1 - sqrt(r_j) being at most 1 and w_j >= 0; it is below floor - margin when sqrt(r_g)
    > 1 - c, c = (floor - margin - rest) / w_g, that is when r_g > (1 - c)^2 (with the
    margin, PRUNE_MARGIN, on both)."""
    g, rest = 0, 0.0
    for j in range(group_weight.shape[0]):
        if not group_weight[j] > 0.0:  # a weight 0 times an infinite radicand is nan
            return 0, np.inf
        if group_weight[j] > group_weight[g]:
            g = j
    for j in range(group_weight.shape[0]):
        if j != g:
            rest += group_weight[j]
    c = (floor - PRUNE_MARGIN * (1.0 + abs(floor)) - rest) / group_weight[g]
    base = 1.0 - c
    if not base > 0.0:
        return 0, np.inf
    return g, base * base * (1.0 + PRUNE_MARGIN)


@njit(cache=True)
def scales_finite(c):
    """Whether every c_i (scales) is finite and above 0: then no radicand is nan (that
    needs 0 * inf, a c_i of 0 or inf), and recall_bounded may leave elements out (a
    variance floor so small that c_i overflows, or variances that overflow, make it
    take every element)."""
    for i in range(c.shape[0]):
        if not 0.0 < c[i] < np.inf:
            return False
    return True


#: The largest magnitude of an input, an input bound or a c_i for which recall_bounded's
#: single-precision pass may leave elements out: with every value below it no difference
#: overflows in single precision (its largest is about 3.4e38), so the bound holds.
BOUNDED_LIMIT = 1e30
#: The most components the bounded group may have: the single-precision sum's rounding,
#: (n + 7) 2^-24 of it at most, stays below single_cut's relative 1e-5.
BOUNDED_COMPONENTS = 100


@njit(cache=True)
def single_cut(cut, g, c, x, input_bound, group_of):
    """The single-precision cut that keeps every element whose group-g radicand is at
    most `cut`: an element whose single-precision radicand (group_radicands) exceeds it
    has an exact radicand above cut. inf (no element left out) where no such cut holds
    (values past BOUNDED_LIMIT, more than BOUNDED_COMPONENTS components, a cut past 1e37).

    With the weighted norm |v| = sqrt(sum_{i in g} c_i v_i^2), the exact sqrt(r) = |x -
    m| >= |x' - m'| - |x - x'| - |m - m'| (x', m' rounded to single precision: each
    within 2^-24 of its value, so the last two at most 2^-24 (|x| + |B|), B the inputs'
    bound, input_bound). The single-precision sum of n positive terms, each of a
    subtraction, a product by sqrt(c_i) rounded and a square, is within (n + 7) 2^-24 of
    |x' - m'|^2, below the relative 1e-5 taken, and numbers so small that they are not
    normal in single precision within the absolute 1e-20; a sum that overflows is above
    any cut returned. So an element above the returned cut has |x' - m'| > sqrt(cut) +
    |x - x'| + |m - m'|, hence r > cut."""
    if not cut < np.inf:
        return np.float32(np.inf)
    sx, sb, sc, count = 0.0, 0.0, 0.0, 0
    for i in range(x.shape[0]):
        if group_of[i] != g:
            continue
        count += 1
        if not (c[i] <= BOUNDED_LIMIT and abs(x[i]) <= BOUNDED_LIMIT
                and input_bound[i] <= BOUNDED_LIMIT):
            return np.float32(np.inf)
        sx += c[i] * x[i] * x[i]
        sb += c[i] * input_bound[i] * input_bound[i]
        sc += c[i]
    if count > BOUNDED_COMPONENTS:
        return np.float32(np.inf)
    eps = 2.0 ** -23 * (np.sqrt(sx) + np.sqrt(sb)) + 1e-20 * (1.0 + np.sqrt(sc))
    root = np.sqrt(cut) + eps
    bound = ((1.0 + 1e-5) * root * root + 1e-20) * (1.0 + 1e-6)  # rounds up to single
    if not bound < 1e37:
        return np.float32(np.inf)
    return np.float32(bound)


@njit(cache=True)
def group_radicands(x, inputs32, size, c, group_of, g, out):
    """out[m] = group g's radicand of element m < size in single precision, from the
    inputs' single-precision copy, as sum_{i in g} (sqrt(c_i) (x_i - m_i))^2 (a square
    that overflows only where the radicand does): a bound's arithmetic (single_cut),
    never a similarity. Up to four components a pass over the elements."""
    out[:size] = 0.0
    n, i = x.shape[0], 0
    while i < n:
        if group_of[i] != g:
            i += 1
        elif i + 3 < n and group_of[i + 1] == g and group_of[i + 2] == g and group_of[i + 3] == g:
            r0, r1, r2, r3 = inputs32[i], inputs32[i + 1], inputs32[i + 2], inputs32[i + 3]
            q0, q1 = np.float32(np.sqrt(c[i])), np.float32(np.sqrt(c[i + 1]))
            q2, q3 = np.float32(np.sqrt(c[i + 2])), np.float32(np.sqrt(c[i + 3]))
            x0, x1 = np.float32(x[i]), np.float32(x[i + 1])
            x2, x3 = np.float32(x[i + 2]), np.float32(x[i + 3])
            for m in range(size):
                s0, s1 = q0 * (x0 - r0[m]), q1 * (x1 - r1[m])
                s2, s3 = q2 * (x2 - r2[m]), q3 * (x3 - r3[m])
                out[m] += (s0 * s0 + s1 * s1) + (s2 * s2 + s3 * s3)
            i += 4
        else:
            r0, q0, x0 = inputs32[i], np.float32(np.sqrt(c[i])), np.float32(x[i])
            for m in range(size):
                s0 = q0 * (x0 - r0[m])
                out[m] += s0 * s0
            i += 1


@njit(cache=True)
def passing(values, size, cut, passed):
    """passed[:count] = the m < size, ascending, with not values[m] > cut (nan passes);
    returns count. A flag per element, then only the runs of eight flags with one set
    are read one by one (most are clear where few pass). passed holds size + 1."""
    words = (size + 7) // 8
    flags = np.zeros(words * 8, np.uint8)
    for m in range(size):
        flags[m] = not values[m] > cut
    packed, count = flags.view(np.uint64), 0
    for w in range(words):
        if packed[w] != 0:
            for m in range(w * 8, w * 8 + 8):
                passed[count] = m
                count += flags[m]
    return count


@njit(cache=True)
def similarities_of(x, inputs, elements, count, c, group_of, group_weight, sim):
    """sim[elements[q]] for q < count: the elements' radicands (radicands' sums, on their
    columns gathered), then similarity_of. The same bits as similarities."""
    gathered = np.empty((inputs.shape[0], count))
    for i in range(inputs.shape[0]):
        row, column = inputs[i], gathered[i]
        for q in range(count):
            column[q] = row[elements[q]]
    radicand = radicands_scaled(x, gathered, count, c, group_of, group_weight.shape[0])
    for q in range(count):
        sim[elements[q]] = similarity_of(radicand, q, group_weight)


@njit(cache=True)
def recall_bounded(x, inputs, inputs32, input_bound, size, variance, group_of, group_size,
                   group_weight, nxt, table, table_w, alpha, time, since, sim):
    """recall_since on the similarities of x to the memory, bit for bit, with each
    similarity taken only where its element may enter the table.

    The elements the entries reach get their similarity, then eq 1 (advance). When the
    entries reach N_r elements, the new table's lowest weight is at least the least of
    theirs (it holds the N_r largest weights of a set that includes them), so an element
    whose similarity is bound below that cannot enter: it is no candidate (with every
    group weight above 0 and the reached weights finite, no similarity is nan, so the
    table is the stable top N_r that recall_since's scan makes). The bound: prune_cut's
    on the heaviest group's radicand, tested in single precision over every element
    (group_radicands on `inputs32`, the inputs rounded; single_cut, with `input_bound`
    at least each component's largest |input|). The others and the reached ones are the
    candidates, in element order, as recall_since's (fill); their similarities are the
    plain sums (similarities_of). sim holds their weights afterwards; the rest of sim is
    left as it was. Where no bound holds (fewer elements reached, a reached weight not
    finite, a c_i of 0 or inf, values past BOUNDED_LIMIT) every element is a candidate."""
    exclude = since != NO_EXCLUSION
    c, k = scales(variance, group_of, group_size), table.shape[0]
    reached = np.empty(k + 1, np.int64)  # the elements reached by an entry, ascending
    n_reached = 0
    for e in range(k):
        if table[e] >= 0:
            ahead = nxt[table[e]]
            if ahead < 0 or (exclude and time[ahead] >= since):
                continue
            q = n_reached
            while q > 0 and reached[q - 1] > ahead:
                q -= 1
            if q > 0 and reached[q - 1] == ahead:
                continue
            for r in range(n_reached, q, -1):
                reached[r] = reached[r - 1]
            reached[q] = ahead
            n_reached += 1
    similarities_of(x, inputs, reached, n_reached, c, group_of, group_weight, sim)
    advance(sim, nxt, table, table_w, alpha, time, since)
    g, cut = 0, np.float32(np.inf)
    if scales_finite(c) and n_reached == k:  # a floor from finite weights (eq 1: nan)
        floor, finite = np.inf, True
        for q in range(k):
            w = sim[reached[q]]
            finite = finite and -np.inf < w < np.inf
            floor = min(floor, w)
        if finite:
            g, cut64 = prune_cut(floor, group_weight)
            cut = single_cut(cut64, g, c, x, input_bound, group_of)
    passed = np.empty(size + 1, np.int64)
    if cut < np.inf:
        bounded = np.empty(size, np.float32)
        group_radicands(x, inputs32, size, c, group_of, g, bounded)
        n_passed = passing(bounded, size, cut, passed)
    else:
        passed[:size] = np.arange(size)
        n_passed = size
    passed[n_passed] = reached[n_reached] = size  # the ends, past every element
    # merged with the reached elements, in element order; the others' similarities after
    candidates, count, a, b = np.empty(n_passed + n_reached, np.int64), 0, 0, 0
    fresh, n_fresh = np.empty(n_passed, np.int64), 0
    while passed[a] < size or reached[b] < size:
        if reached[b] <= passed[a]:
            m = reached[b]
            a += passed[a] == m
            b += 1
        else:
            m = passed[a]
            a += 1
            if exclude and time[m] >= since:
                continue
            fresh[n_fresh] = m
            n_fresh += 1
        candidates[count] = m
        count += 1
    if cut < np.inf:
        similarities_of(x, inputs, fresh, n_fresh, c, group_of, group_weight, sim)
    else:  # every element: the memory's radicands as they are, no columns gathered
        radicand = radicands_scaled(x, inputs, size, c, group_of, group_weight.shape[0])
        for q in range(n_fresh):
            sim[fresh[q]] = similarity_of(radicand, fresh[q], group_weight)
    fill(table, table_w, candidates, count, sim)


@njit(cache=True)
def act(x, size, inputs, inputs32, input_bound, variance, group_of, group_size,
        group_weight, sim, nxt, table, table_w, utility, alpha, threshold, time, since):
    """One act: eq 2-4 against the memory, the recall table (eq 1; candidates stored
    before `since` only; recall_bounded: recall_since's table, each similarity taken only
    where it may enter), eq 5's choice.

    Returns the element whose action eq 5 picks, -1 for none, or INVALID (with nothing
    changed) when x is not finite or its square overflows (the variance sums need x^2).
    """
    square = 0.0
    for i in range(x.shape[0]):
        square += x[i] * x[i]
    if not np.isfinite(square):
        return INVALID
    recall_bounded(x, inputs, inputs32, input_bound, size, variance, group_of, group_size,
                   group_weight, nxt, table, table_w, alpha, time, since, sim)
    return policy(table, table_w, utility, threshold)
