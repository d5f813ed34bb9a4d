"""The episode-based reinforcement learner (Unemi 2000, Section 2).

Worked example::

    import numpy as np, ebrl
    agent = ebrl.Agent(ebrl.paper_config("T"), obs_dim=7, action_dim=1,
                       fallback=ebrl.intrinsic.fallback_for("eq8", "avoidance"), seed=0)
    obs = np.zeros(7)                      # readings scaled to [0, 1]
    for t in range(100):
        action = agent.act(obs)            # memory (eq 5) or the fallback behaviour
        obs, reward, last = np.random.rand(7), float(t == 99), t == 99   # your environment
        agent.learn(reward, last)          # store, eq 6-7, time discount; last ends the episode

Per step: act(s_t) advances the recall table (eq 1), adds the memory elements most
similar to s_t (eq 2-4), and acts as the best entry's element did (eq 5) unless no
entry exceeds the threshold or the agent explores. learn(r) stores (s_t, a_t) as the
next element of the current episode, forgetting the least reliable element when the
memory is full, then applies eq 6 and eq 7 when r != 0 and decays every reliability.
"""
import math

import numpy as np

from ebrl.config import Config

_RESCALE_BELOW = 1e-150  # the lazy reliability scale is folded into the values below this
_PAGE = 2 << 20  # a huge page on x86-64 Linux


class _Arena:
    """The memory's arrays side by side in one 2 MiB-aligned block.

    numpy asks Linux for transparent huge pages on blocks of 4 MiB and more, so arrays
    carved from a huge page share one TLB entry; scattered, the memory's ~1 MB missed
    the TLB often enough to cost about 2 us per step at 4096 elements. Elsewhere it is
    plain memory. Values and results are the same either way."""

    def __init__(self, specs):
        counts = [int(np.prod(shape)) for shape, _ in specs]
        sizes = [-(-count * np.dtype(dtype).itemsize // 64) * 64  # 64-byte aligned
                 for count, (_, dtype) in zip(counts, specs)]
        block = np.zeros(max(sum(sizes) + _PAGE, 2 * _PAGE + 64), dtype=np.uint8)
        at = (-block.ctypes.data) % _PAGE
        self.arrays = []
        for (shape, dtype), count, size in zip(specs, counts, sizes):
            self.arrays.append(block[at: at + size].view(dtype)[:count].reshape(shape))
            at += size


def eq1(weight, similarity, alpha):
    """eq 1: W <- W + alpha (S(M_i, s) - W), for an entry moved along its forward link."""
    return weight + alpha * (similarity - weight)


def eq5(weights, utilities):
    """eq 5's measure, min(W_i, U_i), for each recall-table entry."""
    return np.minimum(weights, utilities)


class Agent:
    def __init__(self, config, obs_dim, action_dim, fallback, *, groups=None,
                 group_weights=None, seed=None):
        if not isinstance(config, Config):
            raise ValueError("config must be an ebrl.Config")
        if int(obs_dim) < 1 or int(action_dim) < 1:
            raise ValueError("obs_dim and action_dim must be positive")
        self.config, self.fallback = config, fallback
        self.obs_dim, self.action_dim = n, _ = int(obs_dim), int(action_dim)
        self.rng = np.random.default_rng(seed)
        M = config.memory_size
        # Modalities (eq 3-4): a 0/1 membership matrix, weights normalised to sum 1.
        if groups is None:
            groups, group_weights = [np.arange(n)], [1.0]
        if group_weights is None or len(group_weights) != len(groups):
            raise ValueError("group_weights must give one weight per group")
        member = np.zeros((n, len(groups)))
        for j, idx in enumerate(groups):
            member[np.asarray(idx), j] = 1.0
        if not np.array_equal(member.sum(axis=1), np.ones(n)):
            raise ValueError("groups must cover every observation component exactly once")
        # Memory (2.1): inputs (float64 [x, x^2] for the variance sums, float32
        # [x; x^2; 1] one feature per row for the similarity product), actions, utility,
        # reliability, time stamps, links (backward links and time stamps as Python lists:
        # they are read one at a time, along the chains of eq 6 and eq 7).
        (self._aug, self._xs, self._action, self._utility, self._rel, self._next, self._d2,
         self._d) = _Arena([((2 * n + 1, M), np.float32), ((M, 2 * n), np.float64),
                            ((M, self.action_dim), np.float64), (M, np.float64),
                            (M, np.float64), (M, np.int64),
                            ((len(groups), M), np.float32), (M, np.float32)]).arrays
        # _aug: [m; m^2; 1] one feature per row (see _distances); _xs: [x, x^2] per element,
        # for the running sums; _rel * _rel_scale: the true reliability.
        self._aug[:] = 1.0
        self._next[:] = -1
        self._x = self._xs[:, :n]
        self._rel_scale = 1.0
        self._time = [0] * M
        self._prev = [-1] * M
        self._size = 0
        self._stats = np.zeros(2 * n)  # running sums of x and x^2, for eq 2's V_i
        w = np.asarray(group_weights, dtype=np.float64)
        if np.any(w < 0) or w.sum() <= 0:
            raise ValueError("group_weights must be non-negative with a positive sum")
        # Group j's row of the product [m; m^2; 1] -> eq 4's radicand, for input x, is
        # (-2 x / V, 1 / V, sum x^2 / V) over its components, each scaled by 1 / (2 n_j):
        # a linear map of c / V with c = [x, x^2, 1], kept as the matrix _to_w.
        G = len(groups)
        scaled = (member / (2.0 * member.sum(axis=0))).T  # (G, n)
        to_w = np.zeros((3 * n, G, 2 * n + 1))
        for i in range(n):
            to_w[i, :, i] = -2.0 * scaled[:, i]
            to_w[2 * n + i, :, n + i] = to_w[n + i, :, 2 * n] = scaled[:, i]
        self._to_w = to_w.reshape(3 * n, -1).astype(np.float32)
        self._c = np.ones(3 * n)  # [x, x^2, 1] of the current input (see _set_input)
        self._v = np.zeros(3 * n, dtype=np.float32)
        self._group_w = (w / w.sum()).astype(np.float32)
        # Views and buffers reused every step (one allocation each, not one per step).
        self._c3, self._v3 = self._c.reshape(3, n), self._v.reshape(3, n)
        self._w = np.zeros((G, 2 * n + 1), dtype=np.float32)
        self._w_flat = self._w.reshape(-1)
        self._mean = np.zeros(2 * n)
        self._mean1, self._mean2 = self._mean[:n], self._mean[n:]
        self._var = np.full(n, float(config.variance_floor))  # eq 2's V_i, see _update_variance
        self._floor = np.array(config.variance_floor)
        self._x_now, self._xx_now = self._c[:n], self._c[n:2 * n]
        self._xs_now = self._c[:2 * n]  # [x, x^2]: what learn stores
        self._aug_x = self._aug[:2 * n]
        self._radius = np.inf  # see _nearest
        # Recall table (2.2), the episode being recorded, the last decision.
        self._table = np.zeros(0, dtype=np.int64)
        self._dist = np.zeros(0, dtype=np.float32)  # 1 - W of each entry
        self._tail = -1        # the current episode's latest element
        self._referred = -1    # the trial's latest element used for a decision (eq 7)
        self._act = None  # the last act's action, until learn stores it
        self.steps = 0
        self.used_memory = False
        self.memory_decisions = 0
        self.fallback_decisions = 0

    # -- read-outs -----------------------------------------------------------------
    @property
    def size(self):
        return self._size

    @property
    def reliability(self):
        return self._rel[: self._size] * self._rel_scale

    @property
    def utility(self):
        return self._utility[: self._size]

    @property
    def variance(self):
        """eq 2's V_i over the stored inputs, kept from running sums, floored."""
        return self._var.copy()

    def _update_variance(self):
        """V_i = mean(x_i^2) - mean(x_i)^2 from the running sums, floored; run whenever
        the sums change, so act reads it as it is."""
        var = self._var
        np.divide(self._stats, float(max(self._size, 1)), out=self._mean)
        np.multiply(self._mean1, self._mean1, out=var)
        np.subtract(self._mean2, var, out=var)
        np.maximum(var, self._floor, out=var)

    def recall_table(self):
        """(element slots, weights W) of the recall table."""
        return self._table.copy(), 1.0 - self._dist.astype(np.float64)

    # -- acting --------------------------------------------------------------------
    def _set_input(self, x):
        """Keeps [x, x^2] in self._c: the input's terms of eq 4's expansion, and what
        learn stores."""
        self._x_now[:] = x
        np.multiply(x, x, out=self._xx_now)

    def _distances(self):
        """1 - S(M_j, x) (eq 2-4) of the input x (set by _set_input) for every stored
        element, as one float32 product.

        sum_i (x_i - m_i)^2 / V_i = sum m^2/V - 2 sum x m / V + sum x^2/V per group: the
        memory holds [m; m^2; 1] one feature per row, so one product gives every radicand.
        """
        np.divide(self._c3, self._var, out=self._v3, casting="unsafe")
        np.matmul(self._v, self._to_w, out=self._w_flat)
        if self._size == self.config.memory_size:
            d2 = np.matmul(self._w, self._aug, out=self._d2)
        else:
            d2 = self._w @ self._aug[:, : self._size]
        d2[d2 < 0.0] = 0.0  # rounding can make an exact match's radicand negative
        np.sqrt(d2, out=d2)
        if len(d2) == 1:
            return d2[0]
        return np.matmul(self._group_w, d2, out=self._d[: d2.shape[1]])

    def _similarities(self, x):
        """eq 2-4 for x against every stored element."""
        self._set_input(x)
        return 1.0 - self._distances()

    def _nearest(self, d):
        """The recall_size smallest of d, ties to the lower slot.

        Sorting only the elements within self._radius is exact, as every other element is
        farther, and cheaper than a selection over the whole memory; the radius follows
        the data so that a few times recall_size elements lie within it. It changes the
        cost, never the result."""
        k = self.config.recall_size
        near = (d <= self._radius).nonzero()[0]
        if len(near) < k:  # the input moved away: widen once before a full selection
            self._radius *= 1.5
            near = (d <= self._radius).nonzero()[0]
        if not k <= len(near) <= 32 * k:
            m = min(4 * k, len(d) - 1)
            self._radius = float(d[np.argpartition(d, m)[m]])
            near = (d <= self._radius).nonzero()[0]  # all within it, ties included
        order = d[near].argsort(kind="stable")
        if len(near) > 8 * k:
            self._radius = float(d[near[order[4 * k]]])
        elif len(near) < 2 * k:
            self._radius *= 1.05
        return near[order[:k]]

    def act(self, obs, readings=None):
        """The action for observation obs (1-D). The fallback gets readings, or obs."""
        x = np.asarray(obs, dtype=np.float64)
        if x.shape != (self.obs_dim,):
            raise ValueError(f"observation must have shape ({self.obs_dim},), got {x.shape}")
        if not math.isfinite(x.dot(x)):  # one product; the exact test only when it fails
            if not np.isfinite(x).all():
                raise ValueError("observation contains NaN or inf")
            raise ValueError("observation too large: |x|^2 overflows")
        c = self.config
        self._set_input(x)
        if self._size:
            # Worked on distances 1 - W and 1 - S: eq 1 is affine, so it holds unchanged.
            d = self._distances()
            # eq 1: entries follow their forward links; those at an episode's end drop out.
            ahead = self._next[self._table]
            if -1 in ahead.tolist():
                keep = ahead >= 0
                ahead, self._dist = ahead[keep], self._dist[keep]
            # Every element is a candidate with its similarity; an advanced entry keeps
            # the larger of its eq 1 weight and its similarity.
            d_ahead = d[ahead]
            d[ahead] = np.minimum(d_ahead, eq1(self._dist, d_ahead, c.alpha))
            top = (self._nearest(d) if self._size > c.recall_size
                   else d.argsort(kind="stable"))  # ordered by weight, ties to the lower slot
            self._table, self._dist = top, d[top]
        explore = self.rng.random() < c.exploration_rate
        action = None
        if len(self._table) and not explore:
            # eq 5: the entry maximising min(W_i, U_i), if it clears the threshold.
            measure = eq5(1.0 - self._dist, self._utility[self._table])
            best = int(measure.argmax())
            if measure[best] > c.policy_threshold:
                element = int(self._table[best])
                action = self._action[element].copy()
                self._referred = element
        self.used_memory = action is not None
        if action is None:
            action = np.asarray(self.fallback(x if readings is None else readings, self.rng),
                                dtype=np.float64).reshape(self.action_dim)
            self.fallback_decisions += 1
        else:
            self.memory_decisions += 1
        self._act = action
        return action

    # -- learning ------------------------------------------------------------------
    def learn(self, reward, last=False):
        """Stores the last act's experience, learns from reward, ends the episode if last."""
        if self._act is None:
            raise ValueError("learn() needs an act() first")
        reward = float(reward)
        if not math.isfinite(reward):
            raise ValueError("reward must be finite")
        c = self.config
        if self._size == c.memory_size:
            slot = int(self._rel.argmin())
            self._forget(slot)
        else:
            slot = self._size
            self._size += 1
        xs = self._xs_now  # [x, x^2] of the last act's input
        self._xs[slot] = xs
        self._aug_x[:, slot] = xs
        self._stats += xs
        self._update_variance()
        self._action[slot] = self._act
        self._utility[slot] = c.initial_utility
        self._rel[slot] = c.initial_reliability / self._rel_scale
        self._time[slot] = self.steps
        self._next[slot] = -1
        self._prev[slot] = self._tail
        if self._tail >= 0:
            self._next[self._tail] = slot
        self._tail = slot
        if reward != 0.0:
            self._utility_update(slot, reward)
            if self._referred >= 0:
                self._reliability_update(self._referred, reward)
        # Time discount: every reliability times time_discount, as one lazy scale.
        self._rel_scale *= c.time_discount
        if self._rel_scale < _RESCALE_BELOW:
            self._rel *= self._rel_scale
            self._rel_scale = 1.0
        self.steps += 1
        self._act = None
        if last:
            self.end_episode()

    def end_episode(self):
        """The next act starts a new episode, with an empty recall table."""
        self._tail = self._referred = -1
        self._table = np.zeros(0, dtype=np.int64)
        self._dist = np.zeros(0, dtype=np.float32)

    def _utility_update(self, element, reward):
        """eq 6: U_j += r * gamma^(t - t_j) along the backward links from the newest
        element, stopping where gamma^(t - t_j) < utility_cutoff."""
        c, time, prev = self.config, self._time, self._prev
        t, j, chain, gains = time[element], element, [], []
        while j >= 0:
            g = c.discount ** (t - time[j])
            if g < c.utility_cutoff:
                break
            chain.append(j)
            gains.append(g)
            j = prev[j]
        self._utility[chain] += reward * np.array(gains)

    def _reliability_update(self, element, reward):
        """eq 7 along the backward links from the element used for the last decision:
        R += rho r (1 - R) when r > 0, R += rho r R when r < 0."""
        prev, chain, j = self._prev, [], element
        while j >= 0:
            chain.append(j)
            j = prev[j]
        r = self._rel[chain] * self._rel_scale
        r += self.config.reliability_rate * reward * ((1.0 - r) if reward > 0 else r)
        self._rel[chain] = r / self._rel_scale

    def _forget(self, k):
        """Removes element k, splicing its episode's links around it."""
        p, n = self._prev[k], int(self._next[k])
        if p >= 0:
            self._next[p] = n
        if n >= 0:
            self._prev[n] = p
        if self._tail == k:
            self._tail = p
        if self._referred == k:
            self._referred = p
        if k in self._table.tolist():
            keep = self._table != k
            self._table, self._dist = self._table[keep], self._dist[keep]
        self._stats -= self._xs[k]
        self._prev[k] = -1
        self._next[k] = -1
