"""The episode-based reinforcement learner (Unemi 2000, Section 2).

Worked example::

    import numpy as np, ebrl
    agent = ebrl.Agent(ebrl.paper_config("two_wheel"), obs_dim=7, action_dim=1,
                       fallback=ebrl.intrinsic.fallback_for("two_wheel", "avoidance"), seed=0)
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
import numpy as np

from ebrl.config import Config

_RESCALE_BELOW = 1e-150  # the lazy reliability scale is folded into the values below this


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
        # Memory (2.1): inputs (float64 for the variance sums, float32 [x; x^2] stored
        # one feature per row for the similarity product), actions, utility,
        # reliability, time stamps, links.
        self._x = np.zeros((M, n))
        self._aug = np.zeros((2 * n, M), dtype=np.float32)
        self._action = np.zeros((M, self.action_dim))
        self._utility = np.zeros(M)
        self._rel = np.zeros(M)  # true reliability = self._rel * self._rel_scale
        self._rel_scale = 1.0
        self._time = np.zeros(M, dtype=np.int64)
        self._next = np.full(M, -1, dtype=np.int64)
        self._prev = np.full(M, -1, dtype=np.int64)
        self._size = 0
        self._sum, self._sumsq = np.zeros(n), np.zeros(n)
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
        w = np.asarray(group_weights, dtype=np.float64)
        if np.any(w < 0) or w.sum() <= 0:
            raise ValueError("group_weights must be non-negative with a positive sum")
        # Row j scaled by 1 / (2 n_j): the product then gives eq 4's radicand.
        self._member = (member / (2.0 * member.sum(axis=0))).T.copy()
        self._group_w = (w / w.sum()).astype(np.float32)
        self._w = np.zeros((len(groups), 2 * n), dtype=np.float32)
        # Recall table (2.2), the episode being recorded, the last decision.
        self._table = np.zeros(0, dtype=np.int64)
        self._weights = np.zeros(0, dtype=np.float32)
        self._tail = -1        # the current episode's latest element
        self._referred = -1    # the trial's latest element used for a decision (eq 7)
        self._obs = self._act = None
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
        k = max(self._size, 1)
        mean = self._sum / k
        return np.maximum(self._sumsq / k - mean * mean, self.config.variance_floor)

    def recall_table(self):
        return self._table.copy(), self._weights.copy()

    # -- acting --------------------------------------------------------------------
    def _similarities(self, x):
        """eq 2-4 for x against every stored element, as one float32 product."""
        inv = 1.0 / self.variance
        n, w, member = self.obs_dim, self._w, self._member
        # sum_i (x_i - m_i)^2 / V_i = sum x^2/V - 2 sum x m / V + sum m^2 / V, per group.
        np.multiply(member, -2.0 * x * inv, out=w[:, :n], casting="unsafe")
        np.multiply(member, inv, out=w[:, n:], casting="unsafe")
        q = member @ (x * x * inv)
        d2 = w @ self._aug[:, : self._size]
        d2 += q.astype(np.float32)[:, None]
        np.maximum(d2, 0.0, out=d2)
        np.sqrt(d2, out=d2)
        return 1.0 - self._group_w @ d2

    def act(self, obs, readings=None):
        """The action for observation obs (1-D). The fallback gets readings, or obs."""
        x = np.asarray(obs, dtype=np.float64)
        if x.shape != (self.obs_dim,):
            raise ValueError(f"observation must have shape ({self.obs_dim},), got {x.shape}")
        if not np.isfinite(x).all():
            raise ValueError("observation contains NaN or inf")
        c = self.config
        if self._size:
            s = self._similarities(x)
            # eq 1: entries follow their forward links; those at an episode's end drop out.
            ahead = self._next[self._table]
            keep = ahead >= 0
            ahead, w = ahead[keep], self._weights[keep]
            w = eq1(w, s[ahead], c.alpha)
            # Every element is a candidate with its similarity; an advanced entry keeps
            # the larger of its eq 1 weight and its similarity.
            s[ahead] = np.maximum(s[ahead], w)
            if self._size > c.recall_size:
                top = np.argpartition(s, self._size - c.recall_size)[self._size - c.recall_size:]
            else:
                top = np.arange(self._size)
            self._table, self._weights = top, s[top]
        explore = self.rng.random() < c.exploration_rate
        action = None
        if len(self._table) and not explore:
            # eq 5: the entry maximising min(W_i, U_i), if it clears the threshold.
            measure = eq5(self._weights, self._utility[self._table])
            best = int(np.argmax(measure))
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
        self._obs, self._act = x, action
        return action

    # -- learning ------------------------------------------------------------------
    def learn(self, reward, last=False):
        """Stores the last act's experience, learns from reward, ends the episode if last."""
        if self._obs is None:
            raise ValueError("learn() needs an act() first")
        reward = float(reward)
        if reward != reward or abs(reward) == float("inf"):
            raise ValueError("reward must be finite")
        c = self.config
        if self._size == c.memory_size:
            slot = int(np.argmin(self._rel))
            self._forget(slot)
        else:
            slot = self._size
            self._size += 1
        x = self._obs
        self._x[slot] = x
        self._aug[: self.obs_dim, slot] = x
        self._aug[self.obs_dim:, slot] = x * x
        self._sum += x
        self._sumsq += x * x
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
        self._obs = self._act = None
        if last:
            self.end_episode()

    def end_episode(self):
        """The next act starts a new episode, with an empty recall table."""
        self._tail = self._referred = -1
        self._table = np.zeros(0, dtype=np.int64)
        self._weights = np.zeros(0, dtype=np.float32)

    def _utility_update(self, element, reward):
        """eq 6: U_j += r * gamma^(t - t_j) along the backward links from the newest
        element, stopping where gamma^(t - t_j) < utility_cutoff."""
        c, t, j = self.config, self._time[element], element
        while j >= 0:
            g = c.discount ** int(t - self._time[j])
            if g < c.utility_cutoff:
                break
            self._utility[j] += reward * g
            j = int(self._prev[j])

    def _reliability_update(self, element, reward):
        """eq 7 along the backward links from the element used for the last decision:
        R += rho r (1 - R) when r > 0, R += rho r R when r < 0."""
        rho, scale, j = self.config.reliability_rate, self._rel_scale, element
        while j >= 0:
            r = self._rel[j] * scale
            r += rho * reward * ((1.0 - r) if reward > 0 else r)
            self._rel[j] = r / scale
            j = int(self._prev[j])

    def _forget(self, k):
        """Removes element k, splicing its episode's links around it."""
        p, n = int(self._prev[k]), int(self._next[k])
        if p >= 0:
            self._next[p] = n
        if n >= 0:
            self._prev[n] = p
        if self._tail == k:
            self._tail = p
        if self._referred == k:
            self._referred = p
        keep = self._table != k
        self._table, self._weights = self._table[keep], self._weights[keep]
        self._sum -= self._x[k]
        self._sumsq -= self._x[k] * self._x[k]
        self._prev[k] = self._next[k] = -1
