"""Section 2.1's memory: a fixed number of elements, each one sense-action pair with a
reliability and a utility, linked into episodes, plus the similarity of an input to
every element at once (eq 2-4).

Slots 0 .. size-1 hold the elements. Until the memory is full a new element takes the
next slot; afterwards the agent forgets one element and the new one takes its slot.

Everything is preallocated and nothing loops over the memory in Python:

* inputs are kept twice: float64 rows [x, x^2] (exact running sums for the variance)
  and a float32 matrix with one column per element, rows [x; x^2; 1], so that eq 2-4
  for all elements is one small matrix product (see `distances`);
* the variance V_i comes from running sums of x and x^2, updated on store and forget;
* the time discount multiplies every reliability each step; it is kept as one global
  scale (true reliability = stored value * scale), so a step costs O(1).
"""
import numpy as np

#: The reliability scale is folded back into the stored values when it falls below this.
RESCALE_BELOW = 1e-150


class Memory:
    def __init__(self, capacity, obs_dim, action_dim, groups, group_weights, variance_floor):
        M, n = int(capacity), int(obs_dim)
        self.capacity, self.obs_dim, self.variance_floor = M, n, float(variance_floor)
        self.size = 0
        # The elements.
        self.rows = np.zeros((M, 2 * n))            # [x, x^2], float64
        self.actions = np.zeros((M, int(action_dim)))
        self.utility = np.zeros(M)
        self.time = np.zeros(M, dtype=np.int64)     # the step it was stored at
        self.next = np.full(M, -1, dtype=np.int64)  # forward link, -1: none
        self.prev = np.full(M, -1, dtype=np.int64)  # backward link, -1: none
        self._rel = np.zeros(M)                     # reliability / self._rel_scale
        self._rel_scale = 1.0
        # Variance (eq 2's V_i) from running sums of [x, x^2].
        self._sums = np.zeros(2 * n)
        self._stale = True
        self._hole = -1  # the slot emptied by forget, filled by the next store
        # eq 3-4 as one product. With normalised weights w_j and group j of n_j inputs,
        #   1 - S = sum_j w_j sqrt(d_j / (2 n_j)) = sum_j sqrt(sum_{i in j} k_i (x_i - m_i)^2),
        #   k_i = w_j^2 / (2 n_j V_i),
        # and sum_i k_i (x_i - m_i)^2 = sum_i (-2 k_i x_i) m_i + k_i m_i^2 + k_i x_i^2:
        # row j of coef times column [m; m^2; 1] of self._columns.
        G = len(groups)
        member = np.zeros((G, n))
        for j, idx in enumerate(groups):
            member[j, np.asarray(idx, dtype=np.int64)] = 1.0
        w = np.asarray(group_weights, dtype=np.float64)
        w = w / w.sum()
        self._base = member * (w * w / (2.0 * member.sum(axis=1)))[:, None]  # k_i * V_i
        self._k = np.zeros((G, n))
        self._coef = np.zeros((G, 2 * n + 1), dtype=np.float32)
        self._columns = np.zeros((2 * n + 1, M), dtype=np.float32)
        self._columns[2 * n] = 1.0
        self._d = np.zeros((G, M), dtype=np.float32)
        self._dist = np.zeros(M, dtype=np.float32)

    # -- read-outs ---------------------------------------------------------------------
    @property
    def full(self):
        return self.size == self.capacity

    @property
    def inputs(self):
        """(size, n) stored inputs."""
        return self.rows[: self.size, : self.obs_dim]

    @property
    def reliability(self):
        """(size,) true reliabilities (stored values times the time-discount scale)."""
        return self._rel[: self.size] * self._rel_scale

    def reliability_of(self, j):
        return float(self._rel[j]) * self._rel_scale

    def set_reliability(self, j, value):
        self._rel[j] = value / self._rel_scale

    @property
    def variance(self):
        """(n,) V_i: population variance of each input over the stored elements (as
        np.var), from the running sums, floored at variance_floor."""
        n, k = self.obs_dim, max(self.size, 1)
        mean = self._sums * (1.0 / k)
        return np.maximum(mean[n:] - mean[:n] ** 2, self.variance_floor)

    # -- similarity --------------------------------------------------------------------
    def distances(self, x):
        """(size,) float32 1 - S(M_j, x) for every stored element j: eq 2, or eq 3-4 with
        groups, computed as one float32 product (module docstring). Agrees with
        ebrl.similarity to ~1e-6 except near S = 1, where the square root turns float32
        rounding (~1e-7 of the squared distance) into up to ~1e-3.

        The returned array is the memory's scratch buffer: valid until the next call."""
        n, size = self.obs_dim, self.size
        if self._hole >= 0:
            raise RuntimeError("a forgotten slot is still empty: store first")
        if self._stale:  # V changed since the last call: new k_i and their column.
            np.divide(self._base, self.variance, out=self._k)
            self._coef[:, n:2 * n] = self._k
            self._stale = False
        kx = self._k * x
        np.multiply(kx, -2.0, out=self._coef[:, :n])
        self._coef[:, 2 * n] = kx @ x
        if size == self.capacity:
            d, dist, columns = self._d, self._dist, self._columns
        else:
            d, dist, columns = self._d[:, :size], self._dist[:size], self._columns[:, :size]
        np.matmul(self._coef, columns, out=d)
        np.abs(d, out=d)  # rounding can leave -1e-7 where the true value is 0
        np.sqrt(d, out=d)
        if len(d) == 1:
            dist[:] = d[0]
        elif len(d) == 2:
            np.add(d[0], d[1], out=dist)
        else:
            d.sum(axis=0, out=dist)
        return dist

    def similarities(self, x):
        """(size,) float64 S(M_j, x), eq 2-4, by the fast path (for tests and reports)."""
        return 1.0 - self.distances(np.asarray(x, dtype=np.float64)).astype(np.float64)

    # -- storing and forgetting ----------------------------------------------------------
    def least_reliable(self):
        """The element of lowest reliability, lowest slot on ties (the stored values
        differ from the true ones by one common factor, so their argmin is the same)."""
        return int(np.argmin(self._rel[: self.size]))

    def forget(self, k):
        """Removes element k; its slot is left empty for the next store (the agent
        forgets only to make room, then stores at once). Its episode neighbours are
        linked to each other, so the links around it stay consistent."""
        if self._hole >= 0:
            raise RuntimeError("store an element before forgetting another")
        p, q = int(self.prev[k]), int(self.next[k])
        if p >= 0:
            self.next[p] = q
        if q >= 0:
            self.prev[q] = p
        self.prev[k] = self.next[k] = -1
        self._sums -= self.rows[k]
        self._stale = True
        self.size -= 1
        self._hole = k

    def store(self, x, action, time, prev, reliability, utility):
        """Stores a new element after prev (-1: it starts an episode) and returns its slot:
        the slot last forgotten, else the next free one. The memory must not be full."""
        if self._hole >= 0:
            slot, self._hole = self._hole, -1
        elif self.size < self.capacity:
            slot = self.size
        else:
            raise RuntimeError("memory is full: forget an element first")
        self.size += 1
        n, row = self.obs_dim, self.rows[slot]
        row[:n] = x
        np.multiply(x, x, out=row[n:])
        self._sums += row
        self._columns[: 2 * n, slot] = row
        self.actions[slot] = action
        self.utility[slot] = utility
        self.time[slot] = time
        self._rel[slot] = reliability / self._rel_scale
        self.next[slot] = -1
        self.prev[slot] = prev
        if prev >= 0:
            self.next[prev] = slot
        self._stale = True
        return slot

    # -- time discount ---------------------------------------------------------------------
    def decay(self, rate):
        """Every reliability times rate (Section 2.1's time discount), in O(1)."""
        self._rel_scale *= rate
        if self._rel_scale < RESCALE_BELOW:
            self._rel[: self.size] *= self._rel_scale
            self._rel_scale = 1.0
