"""MFEC ("mfec"): model-free episodic control (Blundell et al. 2016), its k-NN estimates
and trial returns compiled (ebrl.baselines' docstring)."""
import math

import numpy as np
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from ebrl.baselines.common import _Base, action_count
from ebrl.baselines.configs import MFECConfig


def memory_bytes(config, obs_dim, action_dim, steps):
    """About the most memory (bytes) an MFEC of config holds over a run of `steps` steps:
    per discrete action memory_size slots of an embedding (obs_dim floats), a return and
    a clock (8 bytes each), the scratch of a k-NN search (memory_size floats) and its k
    best (neighbours, 16 bytes each), and a trial's record (doubled as it grows, at most
    the run's steps). For the sizes a user sets (memory_size, neighbours, action_levels),
    checked before any run."""
    a = action_count(action_dim, config.action_levels)
    m, n, k = int(config.memory_size), int(obs_dim), int(config.neighbours)
    trial = 2 * max(64, int(steps)) * (n + 2)
    return 8 * (a * m * (n + 2) + m + 2 * k + a * (action_dim + 4) + trial)


@njit(cache=True)
def knn_estimates(query, keys, values, sizes, used, clock, k, scratch, q_out, dist_out):
    """For each action a: Q(s, a) into q_out[a] and the mean Euclidean distance of the
    neighbours used into dist_out[a]. An entry identical to the query gives its stored
    return (distance 0; the lowest such slot); otherwise the mean return of the k
    nearest (all when fewer are stored; on equal distances the lower slot). An empty
    buffer gives NaN and inf. Every entry used is marked used[a, j] = clock (least
    recently used). keys[a, i, j] is component i of slot j's embedding (one row per
    component, so the squared distances run along rows); scratch holds >= M floats."""
    n_actions, dim, _ = keys.shape
    best_d = np.empty(k)
    best_j = np.empty(k, dtype=np.int64)
    for a in range(n_actions):
        n = sizes[a]
        if n == 0:
            q_out[a] = np.nan
            dist_out[a] = np.inf
            continue
        d2 = scratch[:n]
        d2[:] = 0.0
        for i in range(dim):
            qi = query[i]
            row = keys[a, i]
            for j in range(n):
                diff = row[j] - qi
                d2[j] += diff * diff
        m = 0
        exact = -1
        for j in range(n):
            s = d2[j]
            if s == 0.0:
                exact = j
                break
            if m < k:
                pos = m
                m += 1
            elif s < best_d[k - 1]:
                pos = k - 1
            else:
                continue
            while pos > 0 and best_d[pos - 1] > s:
                best_d[pos] = best_d[pos - 1]
                best_j[pos] = best_j[pos - 1]
                pos -= 1
            best_d[pos] = s
            best_j[pos] = j
        if exact >= 0:
            q_out[a] = values[a, exact]
            dist_out[a] = 0.0
            used[a, exact] = clock
            continue
        qs = 0.0
        ds = 0.0
        for t in range(m):
            qs += values[a, best_j[t]]
            ds += math.sqrt(best_d[t])
            used[a, best_j[t]] = clock
        q_out[a] = qs / m
        dist_out[a] = ds / m


@njit(cache=True)
def discounted_returns(rewards, gamma):
    """R_t = r_t + gamma R_{t+1} (= sum_k gamma^k r_{t+k}), R_T = 0."""
    out = np.empty(len(rewards))
    r = 0.0
    for t in range(len(rewards) - 1, -1, -1):
        r = rewards[t] + gamma * r
        out[t] = r
    return out


@njit(cache=True)
def store_trial(embeddings, actions, returns, keys, values, sizes, used, clock):
    """The end-of-trial update, in time order: an entry identical to (s_t, a_t) keeps
    max(its return, R_t); otherwise (s_t, R_t) is inserted into a_t's buffer, replacing
    its least recently used entry (the lowest slot on ties) when full. Each write marks
    the entry used at a new clock value; returns the clock after the last."""
    dim = keys.shape[1]
    capacity = keys.shape[2]
    for t in range(len(actions)):
        a = actions[t]
        n = sizes[a]
        found = -1
        for j in range(n):
            same = True
            for i in range(dim):
                if keys[a, i, j] != embeddings[t, i]:
                    same = False
                    break
            if same:
                found = j
                break
        clock += 1
        if found >= 0:
            if returns[t] > values[a, found]:
                values[a, found] = returns[t]
            used[a, found] = clock
            continue
        if n < capacity:
            slot = n
            sizes[a] = n + 1
        else:
            slot = 0
            for j in range(1, capacity):
                if used[a, j] < used[a, slot]:
                    slot = j
        for i in range(dim):
            keys[a, i, slot] = embeddings[t, i]
        values[a, slot] = returns[t]
        used[a, slot] = clock
    return clock


class MFEC(_Base):
    """Model-free episodic control (Blundell et al. 2016), gated by familiarity.

    Embedding: the observation with each component of group j multiplied by
    sqrt(w_j / n_j) (eq 3's normalised weight over the group's size), so the squared
    Euclidean distance is sum_j w_j mean_{i in j} (x_i - y_i)^2: eq 3's weighted
    modalities, each its mean squared difference (no variance division: the embedding
    stays fixed, as Blundell et al.'s). One group: the root-mean-square difference.

    Memory: for each discrete action, ``memory_size`` slots of (embedding, return,
    last use). act() estimates every action (``knn_estimates``), takes the greedy action
    (the first of equal estimates) among actions with memory, and lets the fallback act
    when no action has memory, the chosen action's mean neighbour distance exceeds
    distance_threshold, or its estimate is not above value_threshold. learn() records
    (embedding, discrete action, reward); at last=True the trial's discounted returns
    are stored (``store_trial``) and the record is cleared.
    """

    config_class = MFECConfig

    def __init__(self, config, obs_dim, action_dim, fallback, *, groups=None,
                 group_weights=None, seed=None):
        super().__init__(config, obs_dim, action_dim, fallback, groups=groups,
                         group_weights=group_weights, seed=seed)
        c = config
        w = self._group_weight[self._group_of] / self._group_size[self._group_of]
        self._scale = np.sqrt(w)
        a, m, n = self.n_actions, c.memory_size, self.obs_dim
        self._keys = np.zeros((a, n, m))  # component-major, as knn_estimates reads it
        self._scratch = np.zeros(m)
        self._values = np.zeros((a, m))
        self._used = np.zeros((a, m), dtype=np.int64)
        self._sizes = np.zeros(a, dtype=np.int64)
        self._clock = 0
        self._k = int(c.neighbours)
        self._gamma = float(c.discount)
        self._dist_threshold = float(c.distance_threshold)
        self._value_threshold = float(c.value_threshold)
        self.estimates = np.zeros(a)  # the last act's Q(s, a) (NaN: no memory)
        self.distances = np.zeros(a)  # ... and mean neighbour distances (inf: none)
        self.distance = math.inf      # ... the chosen action's
        # The trial being recorded, grown by doubling.
        self._trial_emb = np.zeros((64, n))
        self._trial_act = np.zeros(64, dtype=np.int64)
        self._trial_rew = np.zeros(64)
        self._trial_len = 0
        self._emb = None

    @property
    def sizes(self):
        """Entries stored per discrete action."""
        return self._sizes.copy()

    def buffer(self, action):
        """(embeddings, returns) stored for discrete action `action`, slot order."""
        n = self._sizes[action]
        return self._keys[action, :, :n].T.copy(), self._values[action, :n].copy()

    def embed(self, obs):
        """The embedding of an observation (+ 0.0 makes -0.0 equal to 0.0 bitwise)."""
        return np.asarray(obs, dtype=np.float64) * self._scale + 0.0

    def act(self, obs, ranges=None):
        x = self._input(obs)
        e = self._emb = self.embed(x)
        self._clock += 1
        knn_estimates(e, self._keys, self._values, self._sizes, self._used, self._clock,
                      self._k, self._scratch, self.estimates, self.distances)

        def greedy():
            if not self._sizes.any():
                self.distance = math.inf
                return None
            q = np.where(self._sizes > 0, self.estimates, -np.inf)
            best = int(np.argmax(q))
            self.distance = float(self.distances[best])
            if self.distance > self._dist_threshold or q[best] <= self._value_threshold:
                return None
            return best

        return self._decide(x, ranges, greedy)

    def learn(self, reward, last=False):
        reward = self._reward(reward)
        t = self._trial_len
        if t == len(self._trial_act):
            self._trial_emb = np.concatenate([self._trial_emb, np.zeros_like(self._trial_emb)])
            self._trial_act = np.concatenate([self._trial_act, np.zeros_like(self._trial_act)])
            self._trial_rew = np.concatenate([self._trial_rew, np.zeros_like(self._trial_rew)])
        self._trial_emb[t] = self._emb
        self._trial_act[t] = self._action_index
        self._trial_rew[t] = reward
        self._trial_len = t + 1
        self.steps += 1
        self._action_index = None
        if last:
            self.end_trial()

    def end_trial(self):
        """Stores the trial's discounted returns (done by learn(r, last=True))."""
        n = self._trial_len
        if n:
            returns = discounted_returns(self._trial_rew[:n], self._gamma)
            self._clock = store_trial(self._trial_emb[:n], self._trial_act[:n], returns,
                                      self._keys, self._values, self._sizes, self._used,
                                      self._clock)
        self._trial_len = 0


#: The learners by command-line name: (config class, agent class).
