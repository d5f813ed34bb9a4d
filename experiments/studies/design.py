"""Two-level fractional factorial designs of resolution V or better (`ebrl multiverse`).

A regular 2^(k-p) design: the first m = k - p factors (the base) take every combination
of -1 and +1 in standard (Yates) order, the first factor changing fastest; each of the
other p is a product of base columns (its generator), times a sign. Its defining
relation is every product of the generators' words (each word with its own letter); the
resolution is the shortest word's length. At resolution V no main effect or two-factor
interaction is aliased with another main effect or two-factor interaction: the ±1 columns
of the main effects and of every pairwise product are mutually orthogonal
(tests/test_multiverse.py checks it for every k this module makes).

The generators for 5 to 11 factors are the textbook's minimum-aberration designs
(Montgomery, Design and Analysis of Experiments, Table 8.14; Box, Hunter and Hunter,
Statistics for Experimenters, 2nd ed., Table 6.22), in their letters (I is skipped). Up
to 4 factors the design is the full factorial; from 12 to 17 (the most a 256-run design
of resolution V holds) the generators over a base of 8 are searched (depth first over
words of at least four base letters; resolution V, not necessarily minimum aberration).

Each generator's sign is chosen so that the row with every base factor at -1 has every
factor at -1: the fraction holds the all-minus row (`ebrl multiverse`'s literal protocol,
every factor at its plain level), as its first row.
"""
import dataclasses
import itertools

import numpy as np

#: The letters of the factors, in order (the textbooks skip I).
LETTERS = "ABCDEFGHJKLMNOPQRSTUVWXYZ"

#: k -> the generators of the textbook's 2^(k-p) design of resolution V or more, each
#: "NEW=WORD" in LETTERS (Montgomery Table 8.14).
TEXTBOOK = {
    5: ("E=ABCD",),                              # 2^(5-1)_V, 16 runs
    6: ("F=ABCDE",),                             # 2^(6-1)_VI, 32 runs
    7: ("G=ABCDEF",),                            # 2^(7-1)_VII, 64 runs
    8: ("G=ABCD", "H=ABEF"),                     # 2^(8-2)_V, 64 runs
    9: ("H=ACDFG", "J=BCEFG"),                   # 2^(9-2)_VI, 128 runs
    10: ("H=ABCG", "J=BCDE", "K=ACDF"),          # 2^(10-3)_V, 128 runs
    11: ("H=ABCG", "J=BCDE", "K=ACDF", "L=ABCDEFG"),  # 2^(11-4)_V, 128 runs
}
#: The most factors a design of this module takes: 256 runs hold at most 17 at resolution V.
MAX_FACTORS = 17


@dataclasses.dataclass(frozen=True)
class Design:
    """A 2^(k-p) design: its ±1 matrix (rows x k, int8), its generators ("G=ABCD"), its
    resolution (None for a full factorial: no word) and where its generators come from."""
    matrix: np.ndarray
    generators: tuple
    resolution: int
    source: str

    @property
    def factors(self):
        return self.matrix.shape[1]

    @property
    def runs(self):
        return self.matrix.shape[0]

    def name(self):
        """'2^(11-4)_V, 128 runs' (roman resolution; 'full' for a full factorial)."""
        k, p = self.factors, len(self.generators)
        res = "full" if self.resolution is None else roman(self.resolution)
        return f"2^({k}-{p}) {res}, {self.runs} runs"


def roman(n):
    return {3: "III", 4: "IV", 5: "V", 6: "VI", 7: "VII", 8: "VIII"}.get(n, str(n))


def _mask(word):
    """A word of base letters as a bit mask (A the lowest bit)."""
    return sum(1 << LETTERS.index(c) for c in word)


def _word(mask):
    return "".join(c for i, c in enumerate(LETTERS) if mask >> i & 1)


def base_matrix(m):
    """The full 2^m factorial in standard order (the first column fastest), ±1 int8."""
    rows = np.arange(2 ** m)[:, None]
    return np.where((rows >> np.arange(m)) & 1, 1, -1).astype(np.int8)


def build(m, words):
    """The design of base m with generated columns from base-letter bit masks, each
    signed so that the all-minus base row is all minus."""
    base = base_matrix(m)
    cols = [base]
    for w in words:
        bits = [i for i in range(m) if w >> i & 1]
        sign = -((-1) ** len(bits))
        cols.append((sign * np.prod(base[:, bits], axis=1, dtype=np.int64))[:, None])
    return np.hstack(cols).astype(np.int8)


def defining_words(m, words):
    """Every word of the defining relation (as a mask over all k factors: the base's m
    bits, then one bit per generator) of a design of base m and generator masks."""
    gens = [w | 1 << (m + j) for j, w in enumerate(words)]
    out = []
    for r in range(1, len(gens) + 1):
        for combo in itertools.combinations(gens, r):
            acc = 0
            for g in combo:
                acc ^= g
            out.append(acc)
    return out


def resolution(m, words):
    """The shortest defining word's length; None without generators (a full factorial)."""
    lengths = [bin(w).count("1") for w in defining_words(m, words)]
    return min(lengths) if lengths else None


def _search(m, p, minimum=5):
    """p generator masks over m base letters giving resolution >= minimum, or None: a
    depth-first search over words of at least minimum - 1 letters, the longest first."""
    candidates = sorted((w for w in range(1, 2 ** m) if bin(w).count("1") >= minimum - 1),
                        key=lambda w: (-bin(w).count("1"), w))
    chosen, group = [], [0]  # group: the defining relation's elements (masks over m + p)

    def extend(start):
        if len(chosen) == p:
            return True
        j = len(chosen)
        for i in range(start, len(candidates)):
            g = candidates[i] | 1 << (m + j)
            new = [e ^ g for e in group]
            if all(bin(e).count("1") >= minimum for e in new):
                chosen.append(candidates[i])
                group.extend(new)
                if extend(i + 1):
                    return True
                chosen.pop()
                del group[len(group) - len(new):]
        return False

    return list(chosen) if extend(0) else None


@dataclasses.dataclass(frozen=True)
class _Plan:
    m: int
    words: tuple
    source: str


def _plan(k):
    if not 1 <= k <= MAX_FACTORS:
        raise ValueError(f"a design takes 1 to {MAX_FACTORS} factors, got {k}")
    if k <= 4:
        return _Plan(k, (), "full factorial")
    if k in TEXTBOOK:
        gens = [g.split("=") for g in TEXTBOOK[k]]
        m = k - len(gens)
        assert [LETTERS.index(new) for new, _ in gens] == list(range(m, k))
        return _Plan(m, tuple(_mask(w) for _, w in gens),
                     "textbook (Montgomery Table 8.14; Box, Hunter and Hunter Table 6.22)")
    words = _search(8, k - 8)  # found for every k up to 17 (tests/test_multiverse.py)
    return _Plan(8, tuple(words), "searched (resolution V, depth first)")


def fractional_factorial(k):
    """The design for k two-level factors (module docstring)."""
    plan = _plan(k)
    matrix = build(plan.m, plan.words)
    gens = tuple(f"{LETTERS[plan.m + j]}={_word(w)}" for j, w in enumerate(plan.words))
    return Design(matrix, gens, resolution(plan.m, plan.words), plan.source)


def model_matrix(matrix, interactions=True):
    """The ±1 model matrix: a column of ones, the main effects and (with interactions)
    every two-factor product, in itertools.combinations order; and the column names
    (indices: (), (i,), (i, j))."""
    x = np.asarray(matrix, dtype=np.float64)
    k = x.shape[1]
    names = [()] + [(i,) for i in range(k)]
    cols = [np.ones(len(x))] + [x[:, i] for i in range(k)]
    if interactions:
        for i, j in itertools.combinations(range(k), 2):
            names.append((i, j))
            cols.append(x[:, i] * x[:, j])
    return np.column_stack(cols), names
