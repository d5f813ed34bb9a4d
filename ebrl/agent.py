"""The episode-based reinforcement learner (Unemi 2000, Section 2).

Worked example::

    import numpy as np, ebrl
    agent = ebrl.Agent(ebrl.paper_config("T"), obs_dim=7, action_dim=1,
                       fallback=ebrl.intrinsic.fallback_for("eq8", "avoidance"), seed=0)
    obs = np.zeros(7)                      # readings scaled to [0, 1]
    for t in range(100):
        action = agent.act(obs)            # memory (eq 5) or the fallback behaviour
        obs, reward, last = np.random.rand(7), float(t == 99), t == 99   # your environment
        agent.learn(reward, last)          # store, eq 6-7, time discount; last ends the trial

Per step: act(s_t) advances the recall table (eq 1), adds the memory elements most
similar to s_t (eq 2-4), and acts as the best entry's element did (eq 5) unless no
entry exceeds the threshold or the agent explores. learn(r) stores (s_t, a_t) as the
next element of the current episode, forgetting the least reliable element when the
memory is full, then applies eq 6 and eq 7 when r != 0 and decays every reliability.
learn(r, last=True) ends the trial (end_episode).

The readings that Config makes switches (ebrl.config.READINGS) act here as follows:
episode and recall_at_trial_end at a trial's end (end_episode), eq7_scope and
forgetting in kernels.learn; eq7_scope "decided_only" also flags, in act, each element
used for a memory decision. eq9_dead_zone and random_in_avoidance belong to the
fallback (ebrl.intrinsic.fallback_for builds it from them); the agent only calls the
fallback's reset(), if it has one, when a trial ends.

The work of each step is done by two compiled kernels, ebrl.kernels.act and
ebrl.kernels.learn, on the arrays this class holds; the agent's random stream is one
exploration draw per act, then the fallback's draws when the fallback acts.
"""
import math

import numpy as np

from ebrl import kernels
from ebrl.config import Config, reading_code
from ebrl.kernels import eq1, eq5
from ebrl.similarity import modalities

__all__ = ["Agent", "DECIDERS", "eq1", "eq5"]

#: Who chose an action (Agent.decision): the memory (eq 5); the fallback's intrinsic
#: behaviour or its random action (its `choice`, "fallback" for one without); or the
#: exploration draw, which handed to the fallback a step the memory would have taken.
DECIDERS = ("memory", "intrinsic", "random", "exploration")


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
        # Modalities (eq 3-4): each component's group, each group's size and weight.
        group_of, self._group_size, self._group_weight = modalities(n, groups, group_weights)
        self._group_of = group_of.astype(np.int64)
        # Memory (2.1), laid out as ebrl.kernels describes.
        self._inputs = np.zeros((n, M))
        self._action = np.zeros((M, self.action_dim))
        self._utility = np.zeros(M)
        self._rel = np.zeros(M)
        self._time = np.zeros(M, dtype=np.int64)
        self._next = np.full(M, -1, dtype=np.int64)
        self._prev = np.full(M, -1, dtype=np.int64)
        self._size = 0
        self._sums = np.zeros((2, n))  # running sums of x and x^2, for eq 2's V_i
        self._var = np.full(n, float(config.variance_floor))  # eq 2's V_i
        self._sim = np.zeros(M)  # the current input's similarities (act's scratch)
        self._decided = np.zeros(M, dtype=np.bool_)  # used for a decision this trial (eq 7)
        # Recall table (2.2), the episode being recorded, the last decision.
        self._table = np.full(config.recall_size, -1, dtype=np.int64)  # -1: empty
        self._table_w = np.zeros(config.recall_size)
        self._tail = -1        # the current episode's latest element
        self._referred = -1    # the trial's latest element used for a decision (eq 7)
        # The switches acting here (ebrl.config.READINGS; the kernels get ints).
        self._continuing = config.episode == "continuing"
        self._keep_recall = config.recall_at_trial_end == "keep"
        self._flag_decisions = config.eq7_scope == "decided_only"
        self._obs = None  # the last act's input and action, until learn stores them
        self._act = None
        # The kernels' other arguments, in their order: the arrays above (updated in
        # place, never rebound) and config values as floats (so one compiled version
        # serves every config).
        c = config
        self._exploration = float(c.exploration_rate)
        self._act_args = (self._inputs, self._var, self._group_of, self._group_size,
                          self._group_weight, self._sim, self._next, self._table,
                          self._table_w, self._utility, float(c.alpha),
                          float(c.policy_threshold))
        self._learn_args = (self._inputs, self._sums, self._var, self._action,
                            self._utility, self._rel, self._time, self._next, self._prev,
                            self._table, self._table_w, float(c.variance_floor),
                            float(c.initial_utility), float(c.initial_reliability),
                            float(c.discount), float(c.utility_cutoff),
                            float(c.reliability_rate), float(c.time_discount),
                            self._decided, reading_code("eq7_scope", c.eq7_scope),
                            reading_code("forgetting", c.forgetting))
        self.steps = 0
        self.used_memory = False
        self.memory_decisions = 0
        self.fallback_decisions = 0
        #: Who chose the last act's action, one of DECIDERS (videos colour by it).
        self.decision = None

    # -- read-outs -----------------------------------------------------------------
    @property
    def size(self):
        return self._size

    @property
    def reliability(self):
        return self._rel[: self._size].copy()

    @property
    def utility(self):
        return self._utility[: self._size]

    @property
    def variance(self):
        """eq 2's V_i over the stored inputs, kept from running sums, floored."""
        return self._var.copy()

    def recall_table(self):
        """(element slots, weights W) of the recall table, best first."""
        used = self._table >= 0
        return self._table[used].copy(), self._table_w[used].copy()

    def _similarities(self, x):
        """eq 2-4 for x against every stored element, by the kernel act uses."""
        out = np.zeros(self._size)
        kernels.similarities(np.array(x, dtype=np.float64), self._inputs, self._size,
                             self._var, self._group_of, self._group_size,
                             self._group_weight, out)
        return out

    # -- acting --------------------------------------------------------------------
    def act(self, obs, readings=None):
        """The action for observation obs (1-D). The fallback gets readings, or obs."""
        x = np.array(obs, dtype=np.float64)
        if x.shape != (self.obs_dim,):
            raise ValueError(f"observation must have shape ({self.obs_dim},), got {x.shape}")
        # eq 2-4 against the memory, the recall table (eq 1), eq 5's choice.
        element = kernels.act(x, self._size, *self._act_args)
        if element == kernels.INVALID:
            if not np.isfinite(x).all():
                raise ValueError("observation contains NaN or inf")
            raise ValueError("observation too large: |x|^2 overflows")
        explore = self.rng.random() < self._exploration
        if element >= 0 and not explore:
            action = self._action[element].copy()
            self._referred = element
            if self._flag_decisions:
                self._decided[element] = True
            self.used_memory = True
            self.memory_decisions += 1
            self.decision = "memory"
        else:
            action = np.array(self.fallback(x if readings is None else readings, self.rng),
                              dtype=np.float64).reshape(self.action_dim)
            self.used_memory = False
            self.fallback_decisions += 1
            self.decision = ("exploration" if element >= 0
                             else getattr(self.fallback, "choice", "fallback"))
        self._obs, self._act = x, action
        return action

    # -- learning ------------------------------------------------------------------
    def learn(self, reward, last=False):
        """Stores the last act's experience, learns from reward, ends the trial if last."""
        if self._act is None:
            raise ValueError("learn() needs an act() first")
        reward = float(reward)
        if not math.isfinite(reward):
            raise ValueError("reward must be finite")
        # Store (forgetting one element when full), eq 6, eq 7, time discount.
        self._size, self._tail, self._referred = kernels.learn(
            self._obs, self._act, reward, self.steps, self._size, self._tail,
            self._referred, *self._learn_args)
        self.steps += 1
        self._obs = self._act = None
        if last:
            self.end_episode()

    def end_episode(self):
        """A trial ends (learn(..., last=True) calls this).

        episode "trial": the episode ends with it, so the next element has no backward
        link; "continuing": the link from this trial's last element to the next one's
        first is kept, and eq 6 and eq 7 follow it. recall_at_trial_end "empty": the
        recall table is emptied; "keep": it stays, its entries advancing at the next
        act. Either way eq 7's starting point is reset: the trial's memory decisions
        (the latest one, and the decided flags of eq7_scope "decided_only") were judged
        by its last reward. The fallback's reset(), if any, is called."""
        if not self._continuing:
            self._tail = -1
        self._referred = -1
        if self._flag_decisions:
            self._decided[:] = False
        if not self._keep_recall:
            self._table[:] = -1
        reset = getattr(self.fallback, "reset", None)
        if reset is not None:
            reset()
