"""Similarity between an input and memorised inputs: eq 2, and eq 3-4 for modalities."""
import numpy as np


def similarity(x, memory, variance, groups=None, weights=None):
    """(M,) similarities of x to each row of memory.

    eq 2: S(x, y) = 1 - sqrt( 1/(2n) * sum_i (x_i - y_i)^2 / V_i ).
    With groups (index arrays) and weights, eq 3-4: S = sum_j w_j S'_j / sum_j w_j,
    where S'_j is eq 2 over group j's n_j components.
    """
    x = np.asarray(x, dtype=np.float64)
    memory = np.atleast_2d(np.asarray(memory, dtype=np.float64))
    variance = np.asarray(variance, dtype=np.float64)
    if groups is None:
        groups, weights = [np.arange(x.shape[0])], [1.0]
    if weights is None or len(weights) != len(groups):
        raise ValueError("weights must give one weight per group")
    total = np.zeros(memory.shape[0])
    for idx, w in zip(groups, weights):
        idx = np.asarray(idx)
        d2 = ((memory[:, idx] - x[idx]) ** 2 / variance[idx]).sum(axis=1)
        total += w * (1.0 - np.sqrt(d2 / (2 * len(idx))))
    return total / float(np.sum(weights))


def modalities(obs_dim, groups, group_weights):
    """eq 3's modalities of an obs_dim input: (the group of each component, each group's
    size n_j, the weights w_j divided by their sum); groups None is one group of weight 1.
    ValueError unless the groups cover every component once and the weights are
    non-negative with a positive sum."""
    n = obs_dim
    if groups is None:
        groups, group_weights = [np.arange(n)], [1.0]
    if group_weights is None or len(group_weights) != len(groups):
        raise ValueError("group_weights must give one weight per group")
    member = np.zeros((n, len(groups)))
    for j, idx in enumerate(groups):
        member[np.asarray(idx), j] = 1.0
    if not np.array_equal(member.sum(axis=1), np.ones(n)):
        raise ValueError("groups must cover every observation component exactly once")
    w = np.asarray(group_weights, dtype=np.float64)
    if np.any(w < 0) or w.sum() <= 0:
        raise ValueError("group_weights must be non-negative with a positive sum")
    return member.argmax(axis=1), member.sum(axis=0), w / w.sum()
