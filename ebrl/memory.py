"""Section 2.1's memory: a fixed number of elements, each one sense-action pair with a
reliability and a utility, linked into episodes; and the similarity of an input to the
stored inputs (eq 2-4).

Slots 0 .. size-1 hold the elements. Until the memory is full a new element takes the
next slot; afterwards the agent forgets one element and the new one takes its slot.
Everything is preallocated and nothing loops over the memory in Python:

* The variance V_i of eq 2 comes from float64 running sums of x and x^2, updated on
  store and forget (never recomputed from the whole memory).
* The time discount multiplies every reliability each step. It is one global scale
  (true reliability = stored value * scale), so a step costs O(1).
* Similarity. With the groups' weights normalised (sum w_j = 1), eq 3-4 read

      1 - S(x, m) = sum_j w_j sqrt(d_j / (2 n_j)) = sum_j sqrt(rho_j),
      rho_j = sum_{i in group j} k_i (x_i - m_i)^2,     k_i = w_j^2 / (2 n_j V_i)
            = sum_{i in j} (k_i x_i) (-2 m_i) + k_i m_i^2  +  q_j,   q_j = sum_{i in j} k_i x_i^2,

  so rho for every element and group is one float32 product of a (groups, 2n + 1)
  coefficient matrix with a (2n + 1, M) matrix holding one column [-2m; m^2; 1] per
  element (`distances`). Without groups there is one group of all n inputs, weight 1,
  and this is eq 2.

The hot path keeps every small array contiguous and of one dtype: numpy's cost for a
call on a few values is mostly its fixed overhead, which mixed dtypes, strided views and
Python scalars raise.
"""
import numpy as np

#: The reliability scale is folded back into the stored values when it falls below this.
RESCALE_BELOW = 1e-150


class Memory:
    def __init__(self, capacity, obs_dim, action_dim, groups, group_weights, variance_floor):
        M, n, G = int(capacity), int(obs_dim), len(groups)
        self.capacity, self.obs_dim, self.variance_floor = M, n, float(variance_floor)
        self.size = 0
        # The elements.
        self.rows = np.zeros((M, 2 * n))            # [-2x, x^2], float64
        self.actions = np.zeros((M, int(action_dim)))
        self.utility = np.zeros(M)
        self.time = np.zeros(M, dtype=np.int64)     # the step it was stored at
        self.next = np.full(M, -1, dtype=np.int64)  # forward link, -1: none
        self.prev = [-1] * M  # backward link, -1: none (a list: it is walked one by one)
        self._rel = np.zeros(M)                     # reliability / self._rel_scale
        self._rel_scale = 1.0
        self._hole = -1  # the slot emptied by forget, filled by the next store
        # Variance: E[x] and E[x^2] are the running sums of the rows times _scale.
        self._sums = np.zeros(2 * n)
        self._unit_scale = np.repeat([-0.5, 1.0], n)
        self._scale, self._scale_size = np.zeros(2 * n), -1
        self._mean = np.zeros(2 * n)
        self._var = np.zeros(n)
        self._var_column = self._var[:, None]
        self._floor = np.full(n, self.variance_floor)
        self._minus_two = np.full(n, -2.0)
        self._stale = True  # the sums changed since the coefficients were computed
        # The coefficients, transposed so that each block is contiguous:
        # rows [0, n) k_i x_i, [n, 2n) k_i, 2n q_j; column j: group j (k_i = 0 outside it).
        member = np.zeros((n, G))
        for j, idx in enumerate(groups):
            member[np.asarray(idx, dtype=np.int64), j] = 1.0
        w = np.asarray(group_weights, dtype=np.float64)
        w = w / w.sum()
        self._k_times_v = member * (w * w / (2.0 * member.sum(axis=0)))  # (n, G): k_i V_i
        self._coef_t = np.zeros((2 * n + 1, G))
        self._kx, self._k, self._q = self._coef_t[:n], self._coef_t[n:2 * n], self._coef_t[2 * n]
        self._coef = np.zeros((G, 2 * n + 1), dtype=np.float32)
        self._columns = np.zeros((2 * n + 1, M), dtype=np.float32)
        self._columns[2 * n] = 1.0
        self._rho = np.zeros((G, M), dtype=np.float32)
        # 1 - S, with one more slot past the end holding +inf: a link of -1 ("none")
        # reads it, so a recall entry without a successor gets distance inf.
        self._dist = np.zeros(M + 1, dtype=np.float32)
        self._dist[M] = np.inf
        self._full_views = (self._columns, self._rho, list(self._rho), self._dist[:M])

    # -- read-outs ---------------------------------------------------------------------
    @property
    def full(self):
        return self.size == self.capacity

    @property
    def inputs(self):
        """(size, n) stored inputs."""
        return self.rows[: self.size, : self.obs_dim] * -0.5

    @property
    def reliability(self):
        """(size,) true reliabilities (stored values times the time-discount scale)."""
        return self._rel[: self.size] * self._rel_scale

    def reliability_of(self, j):
        """True reliability of element(s) j."""
        return self._rel[j] * self._rel_scale

    def set_reliability(self, j, value):
        self._rel[j] = value / self._rel_scale

    @property
    def variance(self):
        """(n,) V_i: population variance of each input over the stored elements (as
        np.var), from the running sums, floored at variance_floor."""
        n = self.obs_dim
        mean = self._sums * self._unit_scale / max(self.size, 1)
        return np.maximum(mean[n:] - mean[:n] ** 2, self.variance_floor)

    # -- similarity (eq 2-4) -------------------------------------------------------------
    def distances(self, x):
        """1 - S(M_j, x) for every element j: eq 2, or eq 3-4 with groups, as one
        float32 product (module docstring). Returns the memory's float32 scratch buffer of
        capacity + 1 values, valid until the next call: [0, size) the elements, [-1] inf.

        Agrees with ebrl.similarity to ~1e-6, except within ~1e-3 of S = 1, where the
        square root turns float32 rounding of rho (~1e-7) into up to ~1e-3."""
        if self._hole >= 0:
            raise RuntimeError("a forgotten slot is still empty: store first")
        size, n = self.size, self.obs_dim
        if self._stale:  # V changed: k_i = (k_i V_i) / V_i
            mean, var = self._mean, self._var
            if self._scale_size != size:
                np.multiply(self._unit_scale, 1.0 / size, out=self._scale)
                self._scale_size = size
            np.multiply(self._sums, self._scale, out=mean)  # E[x], E[x^2]
            np.multiply(mean[:n], mean[:n], out=var)
            np.subtract(mean[n:], var, out=var)  # V = E[x^2] - E[x]^2
            np.maximum(var, self._floor, out=var)
            np.divide(self._k_times_v, self._var_column, out=self._k)
            self._stale = False
        np.multiply(self._k, x[:, None], out=self._kx)
        np.matmul(x, self._kx, out=self._q)
        self._coef[...] = self._coef_t.T
        if size == self.capacity:
            columns, rho, groups, dist = self._full_views
            np.dot(self._coef, columns, out=rho)
        else:
            columns, rho, dist = self._columns[:, :size], self._rho[:, :size], self._dist[:size]
            groups = list(rho)
            np.matmul(self._coef, columns, out=rho)
        np.abs(rho, out=rho)  # float32 rounding can leave -1e-7 where rho is 0
        if len(groups) == 1:
            np.sqrt(groups[0], out=dist)
        else:
            np.sqrt(rho, out=rho)
            if len(groups) == 2:
                np.add(groups[0], groups[1], out=dist)
            else:
                rho.sum(axis=0, out=dist)
        return self._dist

    def similarities(self, x):
        """(size,) float64 S(M_j, x) for every element, by the fast path."""
        d = self.distances(np.asarray(x, dtype=np.float64))
        return 1.0 - d[: self.size].astype(np.float64)

    # -- storing and forgetting ----------------------------------------------------------
    def least_reliable(self):
        """The element of lowest reliability, lowest slot on ties (the stored values
        differ from the true ones by one common factor, so their argmin is the same)."""
        rel = self._rel if self.size == self.capacity else self._rel[: self.size]
        return int(rel.argmin())

    def forget(self, k):
        """Removes element k; its slot is left empty for the next store (the agent
        forgets only to make room, then stores at once). Its episode neighbours are
        linked to each other, so the links around it stay consistent."""
        if self._hole >= 0:
            raise RuntimeError("store an element before forgetting another")
        p, q = self.prev[k], int(self.next[k])
        if p >= 0:
            self.next[p] = q
        if q >= 0:
            self.prev[q] = p
        self.prev[k] = -1
        self.next[k] = -1
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
        np.multiply(x, self._minus_two, out=row[:n])
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

    def chain(self, start, limit):
        """Slots from start back along the backward links: start, its predecessor, ...,
        at most limit of them (the walk eq 6 and eq 7 take)."""
        prev, out, j = self.prev, [], start
        while j >= 0 and len(out) < limit:
            out.append(j)
            j = prev[j]
        return np.array(out, dtype=np.int64)

    # -- time discount ---------------------------------------------------------------------
    def decay(self, rate):
        """Every reliability times rate (Section 2.1's time discount), in O(1)."""
        self._rel_scale *= rate
        if self._rel_scale < RESCALE_BELOW:
            self._rel[: self.size] *= self._rel_scale
            self._rel_scale = 1.0
