"""Similarity between an input and memorised inputs: eq 2, and eq 3-4 for modalities.

This is the plain reference, written as the paper writes it. The agent computes the
same numbers for the whole memory at once with a float32 product (ebrl.memory); the
tests check that the two agree.
"""
import numpy as np


def eq2(x, memory, variance):
    """eq 2: S(x, y) = 1 - sqrt( 1/(2n) * sum_{i=1}^{n} (x_i - y_i)^2 / V_i ), for x
    against every row y of memory ((M, n) -> (M,)). V_i: variance of component i."""
    x = np.asarray(x, dtype=np.float64)
    memory = np.atleast_2d(np.asarray(memory, dtype=np.float64))
    variance = np.asarray(variance, dtype=np.float64)
    n = x.shape[0]
    return 1.0 - np.sqrt(((memory - x) ** 2 / variance).sum(axis=1) / (2 * n))


def similarity(x, memory, variance, groups=None, weights=None):
    """(M,) similarities of x to each row of memory.

    Without groups, eq 2 over all n components. With groups (one index array per
    modality) and weights, eq 3-4: S = sum_j w_j S'_j / sum_j w_j, where S'_j (eq 4)
    is eq 2 over group j's n_j components alone.
    """
    x = np.asarray(x, dtype=np.float64)
    memory = np.atleast_2d(np.asarray(memory, dtype=np.float64))
    variance = np.asarray(variance, dtype=np.float64)
    if groups is None:
        return eq2(x, memory, variance)
    if weights is None or len(weights) != len(groups):
        raise ValueError("weights must give one weight per group")
    total = np.zeros(memory.shape[0])
    for idx, w in zip(groups, weights):
        idx = np.asarray(idx)
        total += w * eq2(x[idx], memory[:, idx], variance[idx])  # eq 4 for this group
    return total / float(np.sum(weights))  # eq 3
