"""The episode-based reinforcement learner of Unemi (2000), Section 2, with a fallback
behaviour (random walk or intrinsic avoidance, Section 3.4) for when memory does not act.

Worked example::

    import numpy as np
    import ebrl

    agent = ebrl.Agent(ebrl.paper_config("two_wheel"), obs_dim=7, action_dim=1,
                       fallback=ebrl.intrinsic.fallback_for("two_wheel", "avoidance"),
                       seed=0)
    rng = np.random.default_rng(0)
    obs = rng.random(7)                    # range readings scaled to [0, 1], leftmost first
    for t in range(1000):
        a = agent.act(obs)                 # from memory (eq 1-5) or from the fallback
        obs = rng.random(7)                # ... your environment steps with a ...
        r, last = (1.0, True) if t % 100 == 99 else (0.0, False)
        agent.learn(r, last)               # store, eq 6-7, time discount; last ends the trial

The floating robot passes its 8 readings and 2 velocities as obs (obs_dim=10, groups
[0..7], [8, 9] with group_weights 0.7, 0.3 for eq 3) and the readings alone to the
fallback: agent.act(obs, readings=obs[:8]). Without readings the fallback gets obs.

One step t:

1. act(s_t) updates the recall table (Section 2.2): each entry moves along its forward
   link (dropped at the end of its episode) and its weight follows eq 1; every element
   is also a candidate with weight S(M_j, s_t) (eq 2-4); an element that is both keeps
   the larger weight; the recall_size largest stay (ties: lowest slot).
2. act picks the entry maximising eq 5, min(W_i, U_i), and repeats its element's action,
   unless the table is empty, the best measure is <= policy_threshold, or the agent
   explores (probability exploration_rate): then the fallback acts.
3. learn(r, last) stores (s_t, a_t) after the episode's previous element, forgetting
   the least reliable element first if the memory is full.
4. If r != 0: eq 6 along the backward links from the new element; eq 7 along the
   backward links from the trial's latest element used for a decision.
5. Every reliability is multiplied by time_discount.
6. If last: the episode (trial) ends; the next act starts a new one.
"""
import math

import numpy as np

from ebrl.config import Config
from ebrl.memory import Memory

#: Largest |obs| value accepted: the similarity's float32 matrix holds x^2 (max 3.4e38).
OBS_LIMIT = 1e18


def eq1(weight, similarity, alpha):
    """eq 1: W <- W + alpha (S(M_i, s) - W), for a recall entry moved along its link.

    eq 1 is affine, so the agent applies it to distances 1 - W and 1 - S unchanged:
    1 - W' = (1 - W) + alpha ((1 - S) - (1 - W))."""
    return weight + alpha * (similarity - weight)


def eq5(weights, utilities):
    """eq 5: the policy's measure min(W_i, U_i) for each recall-table entry."""
    return np.minimum(weights, utilities)


def eq6(memory, newest, reward, discount, cutoff):
    """eq 6: U_j += r_t * gamma^(t - t_j) for the elements reached from newest (stored at
    t) along backward links, t_j being each element's stored time. Stops where
    gamma^(t - t_j) < cutoff. (The paper prints gamma^(j - t); with gamma < 1 only
    t - j, the age, makes sense.)"""
    # Each link goes back at least one step, so at most max_age + 1 links matter.
    max_age = math.log(cutoff) / math.log(discount) if cutoff > 0 else math.inf
    chain = memory.chain(newest, min(memory.capacity, max_age + 1))
    g = discount ** (memory.time[newest] - memory.time[chain]).astype(np.float64)
    chain, g = chain[g >= cutoff], g[g >= cutoff]
    memory.utility[chain] += reward * g


def eq7(memory, start, reward, rho):
    """eq 7: R_i += rho r (1 - R_i) if r > 0, R_i += rho r R_i if r < 0, for start and
    every element before it along the backward links (no discount, no cutoff)."""
    chain = memory.chain(start, memory.capacity)
    r = memory.reliability_of(chain)
    memory.set_reliability(chain, r + rho * reward * ((1.0 - r) if reward > 0 else r))


def smallest(values, k):
    """Slots of the k smallest values, ascending slots; ties at the k-th value go to
    the lowest slots."""
    part = values.argpartition(k)
    top, edge = part[:k], values[part[k]]
    if values[top].max() == edge:  # a tie across the edge
        below = np.flatnonzero(values < edge)
        top = np.concatenate((below, np.flatnonzero(values == edge)[: k - len(below)]))
    top.sort()
    return top


class Agent:
    def __init__(self, config, obs_dim, action_dim, fallback, *, groups=None,
                 group_weights=None, seed=None):
        if not isinstance(config, Config):
            raise TypeError(f"config must be an ebrl.Config, got {type(config).__name__}")
        for name, v in (("obs_dim", obs_dim), ("action_dim", action_dim)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
        if not callable(fallback):
            raise TypeError("fallback must be callable as fallback(readings, rng)")
        n = int(obs_dim)
        groups, group_weights = _check_groups(groups, group_weights, n)
        self.config, self.fallback = config, fallback
        self.obs_dim, self.action_dim = n, int(action_dim)
        self.rng = np.random.default_rng(seed)
        self.memory = Memory(config.memory_size, n, self.action_dim, groups, group_weights,
                             config.variance_floor)
        # Recall table (Section 2.2): element slots, ascending, and their distances
        # 1 - W (the agent works with 1 - S throughout; see eq1).
        self._table = np.zeros(0, dtype=np.int64)
        self._table_dist = np.zeros(0, dtype=np.float32)
        self._table_list = []
        self._radius = np.inf  # see _recall: set from the recall table's distances
        self._tail = -1      # the current episode's latest element (-1: a new episode)
        self._referred = -1  # the trial's latest element used for a decision (eq 7)
        # The experience of the last act, stored by learn.
        self._x = np.zeros(n)
        self._action = np.zeros(self.action_dim)
        self._pending = False
        self._steps = 0
        self._used_memory = False
        self._memory_decisions = 0
        self._fallback_decisions = 0

    # -- read-outs -----------------------------------------------------------------------
    size = property(lambda self: self.memory.size, doc="elements stored")
    steps = property(lambda self: self._steps, doc="completed act + learn steps")
    used_memory = property(lambda self: self._used_memory,
                           doc="whether the last action came from memory (eq 5)")
    memory_decisions = property(lambda self: self._memory_decisions)
    fallback_decisions = property(lambda self: self._fallback_decisions)
    reliability = property(lambda self: self.memory.reliability, doc="(size,) true values")
    utility = property(lambda self: self.memory.utility[: self.memory.size].copy())
    variance = property(lambda self: self.memory.variance, doc="eq 2's V_i")

    def recall_table(self):
        """(element slots, weights W) of the recall table."""
        return self._table.copy(), 1.0 - self._table_dist.astype(np.float64)

    # -- acting ----------------------------------------------------------------------------
    def act(self, obs, readings=None):
        """The action (float64, (action_dim,)) for observation obs, a 1-D float array
        of obs_dim values. The fallback gets readings, or obs when readings is None."""
        obs = np.asarray(obs)
        if obs.shape != self._x.shape:
            raise ValueError(f"obs must be a 1-D array of shape ({self.obs_dim},), "
                             f"got shape {obs.shape}")
        if self._pending:
            raise RuntimeError("act() called twice: call learn() after each act()")
        x = self._x
        x[:] = obs
        if not x.dot(x) < OBS_LIMIT ** 2:  # also false for NaN
            bad = np.flatnonzero(~(np.abs(x) < OBS_LIMIT)).tolist()
            raise ValueError(f"obs must be finite and within +-{OBS_LIMIT:g} (the memory "
                             f"stores x^2 in float32); bad values at indices {bad}")
        cfg, mem = self.config, self.memory
        # 1. The recall table follows the input (eq 1-4).
        if mem.size:
            self._recall(x)
        # 2. The policy (eq 5), unless the agent explores; else the fallback.
        explore = self.rng.random() < cfg.exploration_rate
        element = -1
        if self._table_list and not explore:
            measure = eq5(1.0 - self._table_dist, mem.utility[self._table])
            best = int(measure.argmax())  # ties: the lowest slot
            if measure[best] > cfg.policy_threshold:
                element = self._table_list[best]
        if element >= 0:
            action = mem.actions[element].copy()
            self._referred = element
            self._memory_decisions += 1
        else:
            action = np.asarray(self.fallback(obs if readings is None else readings, self.rng),
                                dtype=np.float64)
            if action.shape != self._action.shape:
                if action.size != self.action_dim:
                    raise ValueError(f"fallback returned {action.size} values, expected "
                                     f"action_dim={self.action_dim}")
                action = action.reshape(self.action_dim)
            self._fallback_decisions += 1
        self._used_memory = element >= 0
        self._action[:] = action
        self._pending = True
        return action

    def _recall(self, x):
        """Section 2.2: the new recall table for input x, worked on distances 1 - W."""
        mem, k = self.memory, self.config.recall_size
        dist = mem.distances(x)  # every element is a candidate with 1 - S(M_j, x)
        if self._table_list:
            # Entries move along their forward links; a link of -1 (the end of an
            # episode) reads dist[-1] = inf, so those entries drop out.
            ahead = mem.next[self._table]
            d_ahead = dist[ahead]
            # eq 1; an entry that is also a candidate keeps the larger weight.
            dist[ahead] = np.minimum(d_ahead, eq1(self._table_dist, d_ahead,
                                                  self.config.alpha))
        size = mem.size
        if size <= k:
            top = np.arange(size)
        else:
            # The k smallest distances, ties to the lowest slot. Usually a few times k
            # elements lie within self._radius: sorting those is exact (all the others
            # are farther) and cheaper than a selection over the whole memory.
            scored = dist[:size]
            near = (scored <= self._radius).nonzero()[0]
            if k <= len(near) <= 64 * k:
                d_near = scored[near]
                order = d_near.argsort(kind="stable")[:k]
                edge = float(d_near[order[-1]])
                self._radius = max(0.98 * self._radius, 1.2 * edge)
                order.sort()
                top = near[order]
            else:
                top = smallest(scored, k)
                self._radius = 1.2 * float(scored[top].max())
        self._table, self._table_dist = top, dist[top]
        self._table_list = top.tolist()

    # -- learning ----------------------------------------------------------------------------
    def learn(self, reward, last=False):
        """Stores the last act's experience, learns from reward (eq 6-7) when it is not
        0, applies the time discount, and ends the episode when last is true."""
        if not self._pending:
            raise RuntimeError("learn() must follow an act()")
        reward = float(reward)
        if not math.isfinite(reward):
            raise ValueError(f"reward must be finite, got {reward!r}")
        cfg, mem = self.config, self.memory
        # 3. Store (s_t, a_t) after the episode's previous element.
        if mem.full:
            self._forget(mem.least_reliable())
        self._tail = mem.store(self._x, self._action, self._steps, self._tail,
                               cfg.initial_reliability, cfg.initial_utility)
        # 4. Learning from reward (Section 2.4).
        if reward != 0.0:
            eq6(mem, self._tail, reward, cfg.discount, cfg.utility_cutoff)
            if self._referred >= 0:
                eq7(mem, self._referred, reward, cfg.reliability_rate)
        # 5. Time discount (Section 2.1).
        mem.decay(cfg.time_discount)
        self._steps += 1
        self._pending = False
        # 6. The end of the trial ends the episode.
        if last:
            self.end_episode()

    def _forget(self, k):
        """Forgets element k; pointers to it move to its predecessor or go."""
        p = self.memory.prev[k]
        self.memory.forget(k)
        if self._tail == k:
            self._tail = p
        if self._referred == k:
            self._referred = p
        if k in self._table_list:
            keep = self._table != k
            self._table, self._table_dist = self._table[keep], self._table_dist[keep]
            self._table_list = self._table.tolist()

    def end_episode(self):
        """The next act starts a new episode, with an empty recall table."""
        self._tail = self._referred = -1
        self._table = np.zeros(0, dtype=np.int64)
        self._table_dist = np.zeros(0, dtype=np.float32)
        self._table_list = []


def _check_groups(groups, weights, n):
    """eq 3's modalities: index arrays splitting 0..n-1, one weight >= 0 each."""
    if groups is None:
        if weights is not None:
            raise ValueError("group_weights given without groups")
        return [np.arange(n)], [1.0]
    groups = [np.asarray(g, dtype=np.int64).ravel() for g in groups]
    if weights is None or len(weights) != len(groups):
        raise ValueError(f"group_weights must give one weight per group ({len(groups)})")
    if any(len(g) == 0 for g in groups) or \
            not np.array_equal(np.sort(np.concatenate(groups)), np.arange(n)):
        raise ValueError(f"groups must split the observation's components 0..{n - 1}, "
                         f"each in exactly one group")
    w = np.asarray(weights, dtype=np.float64)
    if not np.isfinite(w).all() or np.any(w < 0) or w.sum() <= 0:
        raise ValueError(f"group_weights must be >= 0 with a positive sum, got {weights!r}")
    return groups, list(w)
