"""The episode-based reinforcement learner (Unemi 2000, Section 2).

Worked example::

    import numpy as np, ebrl
    agent = ebrl.Agent(ebrl.paper_config("T"), obs_dim=7, action_dim=1,
                       fallback=ebrl.intrinsic.fallback_for("eq8", "avoidance"), seed=0)
    obs = np.zeros(7)                      # ranges scaled to [0, 1]
    for t in range(100):
        action = agent.act(obs)            # memory (eq 5) or the fallback behaviour
        obs, reward, last = np.random.rand(7), float(t == 99), t == 99   # your environment
        agent.learn(reward, last)          # store, eq 6-7, time discount; last ends the trial

Per step: act(s_t) advances the recall table (eq 1), adds the memory elements most
similar to s_t (eq 2-4), and acts as the best entry's element did (eq 5) unless no
entry exceeds the threshold or the agent explores. learn(r) stores (s_t, a_t) as the
next element of the current episode, forgetting the least reliable element when the
memory is full, then applies eq 6 and eq 7 when r != 0 and decays every reliability.
learn(r, last=True) ends the trial (end_trial).

The readings that Config makes switches (ebrl.config.READINGS) act here as follows:
episode and recall_at_trial_end at a trial's end (end_trial, through
steps.end_trial), eq7_scope and forgetting in steps.learn_step;
eq7_scope "decided_only" also flags, in steps.act_memory, each element used for a
memory decision. eq9_dead_zone and random_in_avoidance belong to the fallback
(ebrl.intrinsic.fallback_for builds it from them); the agent only calls the fallback's
reset(), if it has one, when a trial ends.

The work of each step is done by the compiled per-step kernels of ebrl.steps
(act_memory, learn_step, end_trial; act_step and end_trial below add a compiled
fallback) on the agent's record (steps.AgentRecord), which holds the arrays of this
class's memory; act_memory calls ebrl.acting.act, which chains eq 1-5, and learn_step
the kernels of eq 6, eq 7, forgetting and the time discount. The agent's random stream
is one exploration draw per act, then the fallback's draws when the fallback acts (or
the random action's, for exploration "random").
"""
from __future__ import annotations

import math
import types
import warnings
from collections.abc import Callable, Sequence

import numpy as np
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled.records import direct
from ebrl import intrinsic, kernels, steps
from ebrl.config import Config, reading_code
from ebrl.kernels import DECIDERS, EXPLORATION, FALLBACK, INVALID, eq1, eq5
from ebrl.similarity import modalities

__all__ = ["Agent", "DECIDERS", "act_step", "end_trial", "eq1", "eq5"]


@njit(cache=True)
def act_step(s, f, x, ranges):
    """One act of an agent with a compiled fallback: steps.act_memory on the agent's
    record s, then, where the memory does not choose, the fallback's step (record f,
    ebrl.intrinsic.fallback_step) on the agent's stream. Returns who chose (an index of
    DECIDERS), or INVALID with nothing changed. Agent.act calls it; so does a compiled
    loop, step after step."""
    element = steps.act_memory(s, x)
    if element == INVALID:
        return INVALID
    if element == FALLBACK:
        chose = intrinsic.fallback_step(f, ranges, s.rng, s.action)
        if s.decider != EXPLORATION:
            s.decider = chose
    return s.decider


@njit(cache=True)
def end_trial(s, f):
    """A trial's end for an agent with a compiled fallback: steps.end_trial on the
    agent's record s, then the fallback's reset (record f)."""
    steps.end_trial(s)
    intrinsic.fallback_reset(f)


def invalid_observation(x):
    """The error for an observation the act kernel refuses (kernels.INVALID)."""
    if not np.isfinite(x).all():
        return ValueError("observation contains NaN or inf")
    return ValueError("observation too large: |x|^2 overflows")


#: A fallback behaviour: (ranges, the agent's random stream) -> an action of action_dim
#: values (ebrl.intrinsic.fallback_for builds the paper's; any such callable will do).
Fallback = Callable[[np.ndarray, np.random.Generator], np.ndarray]


class Agent:
    def __init__(self, config: Config, obs_dim: int, action_dim: int, fallback: Fallback, *,
                 groups: Sequence[Sequence[int]] | None = None,
                 group_weights: Sequence[float] | None = None, seed: int | None = None) -> None:
        if not isinstance(config, Config):
            raise ValueError("config must be an ebrl.Config")
        if int(obs_dim) < 1 or int(action_dim) < 1:
            raise ValueError("obs_dim and action_dim must be positive")
        self.config, self.fallback = config, fallback
        self.obs_dim, self.action_dim = n, _ = int(obs_dim), int(action_dim)
        self.rng = np.random.default_rng(seed)
        M, c = config.memory_size, config
        # Modalities (eq 3-4): each component's group, each group's size and weight.
        group_of, group_size, group_weight = modalities(n, groups, group_weights)
        #: The memory as ebrl.kernels lays it out (2.1, eq 2's sums), the recall table
        #: (2.2), the act's scratch and the last act's input and action: numpy arrays,
        #: the very ones the compiled record holds.
        self.memory = types.SimpleNamespace(
            group_of=group_of.astype(np.int64), group_size=group_size,
            group_weight=group_weight, inputs=np.zeros((n, M)),
            inputs32=np.zeros((n, M), dtype=np.float32), input_bound=np.zeros(n),
            sums=np.zeros((2, n)),
            variance=np.full(n, float(c.variance_floor)), sim=np.zeros(M),
            actions=np.zeros((M, self.action_dim)), utility=np.zeros(M), rel=np.zeros(M),
            time=np.zeros(M, dtype=np.int64), nxt=np.full(M, -1, dtype=np.int64),
            prev=np.full(M, -1, dtype=np.int64), decided=np.zeros(M, dtype=np.bool_),
            table=np.full(c.recall_size, -1, dtype=np.int64), table_w=np.zeros(c.recall_size),
            obs=np.zeros(n), action=np.zeros(self.action_dim))
        #: The agent as one record for compiled code (ebrl.steps.AgentRecord): the
        #: config's numbers, the stream, the arrays above, the counters.
        self.record = steps.AgentRecord.build(
            rng=self.rng, exploration=float(c.exploration_rate), alpha=float(c.alpha),
            threshold=float(c.policy_threshold), floor=float(c.variance_floor),
            initial_utility=float(c.initial_utility),
            initial_reliability=float(c.initial_reliability), discount=float(c.discount),
            cutoff=float(c.utility_cutoff), rho=float(c.reliability_rate),
            decay=float(c.time_discount), eq7_scope=reading_code("eq7_scope", c.eq7_scope),
            forgetting=reading_code("forgetting", c.forgetting),
            flag_decisions=c.eq7_scope == "decided_only", continuing=c.episode == "continuing",
            keep_recall=c.recall_at_trial_end == "keep",
            eq7_signal=reading_code("eq7_signal", c.eq7_signal),
            eq7_walk=reading_code("eq7_walk", c.eq7_walk),
            cut_links=c.forgetting_link == "cut", past_only=c.recall_candidates == "past",
            explore_random=c.exploration == "random", random_sd=float(c.random_sd),
            **{name: getattr(self.memory, name) for name in steps.AGENT_ARRAYS},
            pending=False, expected=0.0, trial_start=0, size=0, tail=-1, referred=-1, steps=0,
            memory_decisions=0, fallback_decisions=0, decider=-1)
        # The compiled fallbacks (ebrl.intrinsic's) draw from the agent's stream.
        self.fallback_record = None
        if getattr(fallback, "record", None) is not None:
            fallback.bind(self.rng)
            self.fallback_record = fallback.record
        #: True when the fallback is compiled (ebrl.intrinsic's RandomWalk or Intrinsic with
        #: the paper's avoidance): a whole step is then compiled code (act_step, end_trial).
        self.compiled = (type(fallback) in (intrinsic.RandomWalk, intrinsic.Intrinsic)
                          and fallback.compiled)
        self._action = self.memory.action
        # The per-step kernels without numba's per-call typing of the records (about
        # 0.75 us a record; compiled.records.direct): act's x and given are always fresh
        # 1-D float64 arrays of act's own making, and learn's reward a float.
        probe = np.zeros(n)
        if self.compiled:
            self._act_step = direct(act_step, self.record, self.fallback_record, probe, probe)
        else:
            self._act_memory = direct(steps.act_memory, self.record, probe)
        self._learn_step = direct(steps.learn_step, self.record, 0.0)

    # -- read-outs -----------------------------------------------------------------
    def _counter(name, doc):
        """A read-only property of the record's counter `name` (steps.COUNTERS)."""
        index = steps.COUNTERS.index(name)
        return property(lambda self: steps.counters(self.record)[index], doc=doc)

    size = _counter("size", "Stored memory elements.")
    tail = _counter("tail", "The current episode's latest element (-1: none).")
    referred = _counter("referred", "The trial's latest element used for a memory decision "
                                    "(eq 7's start; -1: none).")
    steps = _counter("steps", "Steps learnt so far.")
    memory_decisions = _counter("memory_decisions", "Actions the memory chose (eq 5).")
    fallback_decisions = _counter("fallback_decisions", "Actions the fallback chose.")
    _decider = _counter("decider", "Who chose the last action (an index of DECIDERS; -1: none).")
    del _counter

    @property
    def decision(self) -> str | None:
        """Who chose the last act's action, one of DECIDERS (videos colour by it); a
        Python fallback without a choice reads "fallback"; None before any act."""
        code = self._decider
        return DECIDERS[code] if code >= 0 else self._python_choice

    @property
    def used_memory(self) -> bool:
        """True when the memory chose the last act's action."""
        return self._decider == kernels.MEMORY

    _python_choice = None

    @property
    def reliability(self) -> np.ndarray:
        return self.memory.rel[: self.size].copy()

    @property
    def utility(self) -> np.ndarray:
        return self.memory.utility[: self.size]

    @property
    def variance(self) -> np.ndarray:
        """eq 2's V_i over the stored inputs, kept from running sums, floored."""
        return self.memory.variance.copy()

    def recall_table(self) -> tuple[np.ndarray, np.ndarray]:
        """(element slots, weights W) of the recall table, best first."""
        m = self.memory
        used = m.table >= 0
        return m.table[used].copy(), m.table_w[used].copy()

    def similarities(self, x: np.ndarray) -> np.ndarray:
        """eq 2-4 for x against every stored element, by the kernel act uses."""
        m = self.memory
        out = np.zeros(self.size)
        kernels.similarities(np.array(x, dtype=np.float64), m.inputs, self.size, m.variance,
                             m.group_of, m.group_size, m.group_weight, out)
        return out

    # -- acting --------------------------------------------------------------------
    def act(self, obs: np.ndarray, ranges: np.ndarray | None = None) -> np.ndarray:
        """The action for observation obs (1-D). The fallback gets ranges, or obs."""
        x = np.array(obs, dtype=np.float64)
        if x.shape != (self.obs_dim,):
            raise ValueError(f"observation must have shape ({self.obs_dim},), got {x.shape}")
        given = x
        if ranges is not None:
            given = np.array(ranges, dtype=np.float64)
            if given.ndim != 1:
                raise ValueError(f"ranges must be 1-D, got shape {given.shape}")
        if self.compiled:  # eq 2-4, eq 1, eq 5, the exploration draw, the fallback
            code = self._act_step(self.record, self.fallback_record, x, given)
        else:  # the same, with a Python fallback
            code = self._act_memory(self.record, x)
            if code == FALLBACK:
                self._action[:] = np.array(self.fallback(given, self.rng),
                                           dtype=np.float64).reshape(self.action_dim)
                self._python_choice = getattr(self.fallback, "choice", "fallback")
        if code == INVALID:
            raise invalid_observation(x)
        return self._action.copy()

    # -- learning ------------------------------------------------------------------
    def learn(self, reward: float, last: bool = False) -> None:
        """Stores the last act's experience, learns from reward, ends the trial if last."""
        reward = float(reward)
        if not math.isfinite(reward):
            raise ValueError("reward must be finite")
        # Store (forgetting one element when full), eq 6, eq 7, time discount.
        if not self._learn_step(self.record, reward):
            raise ValueError("learn() needs an act() first")
        if last:
            self.end_trial()

    def end_trial(self) -> None:
        """A trial ends (learn(..., last=True) calls this).

        episode "trial": the episode ends with it, so the next element has no backward
        link; "continuing": the link from this trial's last element to the next one's
        first is kept, and eq 6 and eq 7 follow it. recall_at_trial_end "empty": the
        recall table is emptied; "keep": it stays, its entries advancing at the next
        act. Either way eq 7's starting point is reset: the trial's memory decisions
        (the latest one, and the decided flags of eq7_scope "decided_only") were judged
        by its last reward (steps.end_trial). The fallback's reset(), if any, is
        called."""
        if self.compiled:
            end_trial(self.record, self.fallback_record)
            return
        steps.end_trial(self.record)
        reset = getattr(self.fallback, "reset", None)
        if reset is not None:
            reset()

    def end_episode(self) -> None:
        """Deprecated: end_trial, the one name of a trial's end (Section 3.6's trials;
        an episode is a sequence of memory elements, Section 2.1)."""
        warnings.warn("Agent.end_episode is deprecated: use Agent.end_trial", DeprecationWarning,
                      stacklevel=2)
        self.end_trial()
