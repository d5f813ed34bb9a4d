"""QTable ("qtable"): tabular Q-learning on discretised inputs with Boltzmann
(roulette-wheel) selection, its confidence Section 4's variance of the action
probabilities (ebrl.baselines' docstring)."""
import numpy as np

from ebrl.baselines.common import _Base, action_count
from ebrl.baselines.configs import QTableConfig


def memory_bytes(config, obs_dim, action_dim, steps):
    """About the most memory (bytes) a QTable of config holds over a run of `steps`
    steps: a row of Q values (8 bytes an action, and a dict entry) for each state it
    meets (at most 3^obs_dim, at most one a step), the discrete actions, the default row
    and each act's temporaries (its probabilities, exponentials and sums), a row each.
    For the sizes a user sets (action_levels), checked before any run."""
    a = action_count(action_dim, config.action_levels)
    rows = min(3 ** min(int(obs_dim), 40), int(steps) + 1)
    return 8 * a * (rows + action_dim + 8) + 200 * rows


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
