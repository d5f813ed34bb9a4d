"""Two other learners behind EBRL's interface, for Section 4's question: can a learner
other than EBRL use the intrinsic behaviour, given a way to measure its confidence?

Both take ``(config, obs_dim, action_dim, fallback, *, groups=None, group_weights=None,
seed=None)`` like ebrl.Agent, and offer ``act(obs, ranges=None)``, ``learn(reward,
last=False)``, ``steps``, ``used_memory`` (True when the learner, not the fallback,
chose), ``memory_decisions`` and ``fallback_decisions``. Each act draws one exploration
number from the agent's generator (``np.random.default_rng(seed)``), then either the
learner's own draws (QTable's roulette wheel; MFEC has none) or the fallback's: the
same seed gives the same actions bit for bit.

``QTable`` ("qtable"): tabular Q-learning on discretised inputs with Boltzmann
(roulette-wheel) selection. Confidence, as Section 4 suggests, is the variance of the
action probabilities in the current state, divided by its largest possible value
(``confidence``): 0 for uniform probabilities, 1 for a certain choice. Below
``confidence_threshold`` (or on exploration) the fallback acts.

``MFEC`` ("mfec"): model-free episodic control (Blundell et al. 2016): per discrete
action a memory of (embedding, best return) pairs, Q(s, a) from the stored return of an
identical embedding or the mean of the k nearest neighbours', updated with each trial's
discounted returns at its end. The learner acts greedily when the chosen action's
neighbours are near (mean distance at most ``distance_threshold``) and its estimate
positive; otherwise (or on exploration) the fallback acts.

Both learn from the fallback's actions too, each mapped to the nearest discrete action
(``nearest_action``); the environment always gets the action that was chosen, the
fallback's own continuous one included. Discrete actions (``discrete_actions``): for
action_dim 1, ``action_levels`` values evenly spaced on [-1, 1] (5: -1, -0.5, 0, 0.5,
1); for action_dim d >= 2, the zero action and every non-zero vector of {-1, 0, 1}^d
scaled to unit length (d = 2: zero and the 8 compass directions, counter-clockwise from
+x). docs/interpretation.md ("Other learners") gives every choice and its reason.

Neither imports a simulator; everything is derived from obs_dim, action_dim and groups.
``AGENTS`` names them for the command line: ``AGENTS[name] = (ConfigClass, AgentClass)``.
"""
import dataclasses
import itertools
import math

import numpy as np
from numba import njit

from ebrl import compiled  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from ebrl.config import FALLBACK_READINGS, Config, check_reading
from ebrl.similarity import modalities

__all__ = ["QTableConfig", "QTable", "MFECConfig", "MFEC", "AGENTS", "discrete_actions",
           "nearest_action", "boltzmann", "confidence", "discounted_returns"]


# -- config checks (one-line ValueErrors naming the parameter) -------------------------
def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _check_int(cfg, name, lo):
    v = getattr(cfg, name)
    if not isinstance(v, int) or isinstance(v, bool) or v < lo:
        raise ValueError(f"{name} must be an integer of at least {lo}, got {v!r}")


def _check_range(cfg, name, lo, hi, lo_open=False, hi_open=False):
    v = getattr(cfg, name)
    ok = _is_number(v) and (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        interval = f"{'(' if lo_open else '['}{lo}, {hi}{')' if hi_open else ']'}"
        raise ValueError(f"{name} must be in {interval}, got {v!r}")


def _check_positive(cfg, name):
    v = getattr(cfg, name)
    if not (_is_number(v) and v > 0):
        raise ValueError(f"{name} must be a positive finite number, got {v!r}")


def _check_finite(cfg, name):
    if not _is_number(getattr(cfg, name)):
        raise ValueError(f"{name} must be a finite number, got {getattr(cfg, name)!r}")


def _check_shared(cfg):
    """The fields both configs share."""
    _check_range(cfg, "discount", 0.0, 1.0)
    _check_range(cfg, "exploration_rate", 0.0, 1.0)
    _check_int(cfg, "action_levels", 2)
    _check_range(cfg, "intrinsic_random_rate", 0.0, 1.0)
    _check_positive(cfg, "random_sd")
    for name in FALLBACK_READINGS:
        check_reading(name, getattr(cfg, name))


def _fallback_fields():
    """ebrl.Config's fields that the fallback is built with (Section 3.4's random share
    and spread, then its readings, ebrl.readings' fallback=True), as Config has them:
    name, type and default."""
    config = {f.name: f for f in dataclasses.fields(Config)}
    return [(n, config[n].type, dataclasses.field(default=config[n].default))
            for n in ("intrinsic_random_rate", "random_sd") + FALLBACK_READINGS]


#: Section 3.4's intrinsic behaviour, for the fallback the caller builds
#: (intrinsic.fallback_for), with ebrl.Config's fields and defaults: every learner gets
#: the same behaviour, a drive's readings of it included (tasks.robots). Made from
#: Config's fields, so a new fallback reading reaches every learner with its entry.
_Fallback = dataclasses.make_dataclass("_Fallback", _fallback_fields(), frozen=True,
                                       namespace={"__module__": __name__})


@dataclasses.dataclass(frozen=True)
class QTableConfig(_Fallback):
    alpha: float = 0.1             # Q-learning step size
    discount: float = 0.99         # gamma, as Table 1's
    temperature: float = 0.01      # Boltzmann tau, in units of Q (reward 1 at the goal)
    confidence_threshold: float = 0.1  # the table acts when confidence exceeds this
    exploration_rate: float = 0.05  # the fallback acts anyway, as Table 1's
    initial_q: float = 0.0         # every Q(s, a) before its first update
    far_edge: float = 0.15         # a reading below this is "nothing" (3 noise sd above 0)
    near_edge: float = 0.5         # at or above this "near" (under half the sensor range)
    velocity_edge: float = 0.2     # |v| at most this is "still", per axis (later groups)
    action_levels: int = 5         # discrete actions for action_dim 1

    def __post_init__(self):
        _check_range(self, "alpha", 0.0, 1.0, lo_open=True)
        _check_positive(self, "temperature")
        _check_range(self, "confidence_threshold", 0.0, 1.0)
        _check_finite(self, "initial_q")
        _check_range(self, "far_edge", 0.0, 1.0, lo_open=True)
        _check_range(self, "near_edge", 0.0, 1.0, lo_open=True)
        if not self.far_edge < self.near_edge:
            raise ValueError(f"far_edge ({self.far_edge}) must be below near_edge "
                             f"({self.near_edge})")
        _check_positive(self, "velocity_edge")
        _check_shared(self)


@dataclasses.dataclass(frozen=True)
class MFECConfig(_Fallback):
    memory_size: int = 1024        # entries per discrete action (least recently used go)
    neighbours: int = 11           # k of the k-NN estimate, as Blundell et al.
    discount: float = 0.99         # gamma of the trial's returns, as Table 1's
    distance_threshold: float = 0.2  # the memory acts when the mean k-NN distance <= this
    value_threshold: float = 0.0   # ... and the chosen action's estimate exceeds this
    exploration_rate: float = 0.05  # the fallback acts anyway, as Table 1's
    action_levels: int = 5         # discrete actions for action_dim 1

    def __post_init__(self):
        _check_int(self, "memory_size", 1)
        _check_int(self, "neighbours", 1)
        v = self.distance_threshold
        if not (_is_number(v) and v >= 0):
            raise ValueError(f"distance_threshold must be a non-negative finite number, "
                             f"got {v!r}")
        _check_finite(self, "value_threshold")
        _check_shared(self)


# -- pieces shared by both learners ---------------------------------------------------
def discrete_actions(action_dim, levels=5):
    """The discrete action set, one action per row (see the module docstring)."""
    if action_dim == 1:
        return np.linspace(-1.0, 1.0, levels).reshape(levels, 1)
    rows = [np.zeros(action_dim)]
    grid = [v for v in itertools.product((-1.0, 0.0, 1.0), repeat=action_dim) if any(v)]
    grid.sort(key=lambda v: math.atan2(v[1], v[0]) % (2 * math.pi) if action_dim == 2 else 0)
    rows += [np.array(v) / np.linalg.norm(v) for v in grid]
    return np.array(rows)


def nearest_action(actions, action):
    """Index of the discrete action nearest (Euclidean) to `action`; the first on ties."""
    diff = actions - np.asarray(action, dtype=np.float64).reshape(1, -1)
    return int(np.argmin(np.einsum("ij,ij->i", diff, diff)))


def boltzmann(q, temperature):
    """Roulette-wheel probabilities: exp(Q/tau) / sum exp(Q/tau) (shifted by max Q)."""
    e = np.exp((q - q.max()) / temperature)
    return e / e.sum()


def confidence(p):
    """Section 4's variance of the action probabilities over its maximum: with A
    actions, var(p) = sum (p - 1/A)^2 / A, largest ((A-1)/A^2) for a certain choice,
    so var / max = A sum (p - 1/A)^2 / (A - 1) (= (A sum p^2 - 1) / (A - 1)): 0 for
    uniform probabilities (exactly: equal Q values give p = 1/A), 1 for a certain choice."""
    a = len(p)
    d = p - 1.0 / a
    return a * float(np.dot(d, d)) / (a - 1)


class _Base:
    """Construction, input checks and the decision counters both learners share."""

    config_class = None

    def __init__(self, config, obs_dim, action_dim, fallback, *, groups=None,
                 group_weights=None, seed=None):
        if not isinstance(config, self.config_class):
            raise ValueError(f"config must be an ebrl.baselines.{self.config_class.__name__}")
        if int(obs_dim) < 1 or int(action_dim) < 1:
            raise ValueError("obs_dim and action_dim must be positive")
        self.config, self.fallback = config, fallback
        self.obs_dim, self.action_dim = int(obs_dim), int(action_dim)
        self.rng = np.random.default_rng(seed)
        self._group_of, self._group_size, self._group_weight = modalities(
            self.obs_dim, groups, group_weights)
        self.actions = discrete_actions(self.action_dim, config.action_levels)
        self._exploration = float(config.exploration_rate)
        self._action_index = None  # the last act's discrete action, until learn
        self.steps = 0
        self.used_memory = False
        self.memory_decisions = 0
        self.fallback_decisions = 0

    @property
    def n_actions(self):
        return len(self.actions)

    def _input(self, obs):
        x = np.array(obs, dtype=np.float64)
        if x.shape != (self.obs_dim,):
            raise ValueError(f"observation must have shape ({self.obs_dim},), got {x.shape}")
        if not np.isfinite(x).all():
            raise ValueError("observation contains NaN or inf")
        return x

    def _reward(self, reward):
        if self._action_index is None:
            raise ValueError("learn() needs an act() first")
        reward = float(reward)
        if not math.isfinite(reward):
            raise ValueError("reward must be finite")
        return reward

    def _decide(self, x, ranges, learner_action):
        """Exploration draw first; then learner_action() -> discrete index or None (the
        learner declines), else the fallback, whose action is mapped for learning."""
        explore = self.rng.random() < self._exploration
        index = None if explore else learner_action()
        if index is not None:
            action = self.actions[index].copy()
            self.used_memory = True
            self.memory_decisions += 1
        else:
            action = np.array(self.fallback(x if ranges is None else ranges, self.rng),
                              dtype=np.float64).reshape(self.action_dim)
            index = nearest_action(self.actions, action)
            self.used_memory = False
            self.fallback_decisions += 1
        self._action_index = index
        return action


# -- tabular Q-learning -----------------------------------------------------------------
class QTable(_Base):
    """Tabular Q-learning with Boltzmann selection, gated by its confidence.

    State: each component of the first group listed (the range readings, on [0, 1];
    every component when no groups are given) in 3 bins,
    0 nothing (x < far_edge), 1 far (far_edge <= x < near_edge), 2 near (x >= near_edge);
    each component of any later group (the velocity) in 3 bins, 0 (v < -velocity_edge),
    1 (|v| <= velocity_edge), 2 (v > velocity_edge). The state index is the bins read as a
    base-3 number, the first component most significant: 3^obs_dim states in all
    (``state_count``; 2,187 for 7 readings, 59,049 for 8 readings and 2 velocities). The
    table is a dict from state index to its row of Q values, holding only states that
    have been updated (``len(agent.table)``); others read ``initial_q``.

    The update for step t waits for s_{t+1}: the next act applies
    Q(s_t, a_t) += alpha (r_t + gamma max_a Q(s_{t+1}, a) - Q(s_t, a_t)) before choosing;
    learn(r, last=True) applies it at once with target r (terminal).
    """

    config_class = QTableConfig

    def __init__(self, config, obs_dim, action_dim, fallback, *, groups=None,
                 group_weights=None, seed=None):
        super().__init__(config, obs_dim, action_dim, fallback, groups=groups,
                         group_weights=group_weights, seed=seed)
        c = config
        if self.obs_dim > 39:  # 3^40 overflows the int64 state index
            raise ValueError(f"QTable discretises at most 39 inputs, got obs_dim {self.obs_dim}")
        first = self._group_of == 0
        self._ranges = np.flatnonzero(first)
        self._signed = np.flatnonzero(~first)
        self._radix = 3 ** np.arange(self.obs_dim - 1, -1, -1, dtype=np.int64)
        self.state_count = 3 ** self.obs_dim
        self._edges = (float(c.far_edge), float(c.near_edge), float(c.velocity_edge))
        self._alpha, self._gamma = float(c.alpha), float(c.discount)
        self._tau, self._threshold = float(c.temperature), float(c.confidence_threshold)
        self.table = {}
        self._default = np.full(self.n_actions, float(c.initial_q))
        self._state = None      # the last act's state
        self._pending = None    # (s_t, a_t, r_t) awaiting s_{t+1}
        self.confidence = 0.0   # the last act's confidence
        self.probabilities = None  # the last act's Boltzmann probabilities

    def bins(self, obs):
        """Each component's bin (0, 1, 2), as the class docstring describes."""
        x = np.asarray(obs, dtype=np.float64)
        far, near, vel = self._edges
        b = np.empty(self.obs_dim, dtype=np.int64)
        r = x[self._ranges]
        b[self._ranges] = (r >= far).astype(np.int64) + (r >= near)
        v = x[self._signed]
        b[self._signed] = 1 + (v > vel).astype(np.int64) - (v < -vel)
        return b

    def state(self, obs):
        """The state index: bins as a base-3 number, first component most significant."""
        return int(self.bins(obs) @ self._radix)

    def q(self, state):
        """The row of Q values of a state (initial_q where never updated); read-only use."""
        return self.table.get(state, self._default)

    def _update(self, state, action, target):
        row = self.table.get(state)
        if row is None:
            row = self.table[state] = self._default.copy()
        row[action] += self._alpha * (target - row[action])

    def act(self, obs, ranges=None):
        x = self._input(obs)
        s = self.state(x)
        if self._pending is not None:
            ps, pa, pr = self._pending
            self._update(ps, pa, pr + self._gamma * float(self.q(s).max()))
            self._pending = None
        p = boltzmann(self.q(s), self._tau)
        self.probabilities, self.confidence = p, confidence(p)

        def roulette():
            if self.confidence <= self._threshold:
                return None
            # The wheel: the first action whose cumulative probability exceeds u.
            return min(int(np.searchsorted(np.cumsum(p), self.rng.random(), side="right")),
                       self.n_actions - 1)

        action = self._decide(x, ranges, roulette)
        self._state = s
        return action

    def learn(self, reward, last=False):
        reward = self._reward(reward)
        if last:
            self._update(self._state, self._action_index, reward)
        else:
            self._pending = (self._state, self._action_index, reward)
        self.steps += 1
        self._action_index = None


# -- model-free episodic control ----------------------------------------------------------
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
AGENTS = {"qtable": (QTableConfig, QTable), "mfec": (MFECConfig, MFEC)}
