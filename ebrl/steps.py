"""The agent as one named record, and its per-step entry points (Section 2), compiled:
`act_memory` (eq 5's decision, exploration), `learn_step` (the store, eq 6-7, the time
discount) and `end_trial`, on AgentRecord, the agent's whole state. ebrl.Agent's act and
learn call them, and the protocol's compiled loop (experiments.running.fused) iterates
the same functions on the same record. The equations themselves are ebrl.kernels', one
kernel each. Every function is ``@njit(cache=True)`` with no fastmath (ebrl.kernels)."""
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled import records
from compiled.clip import clip_unit
from ebrl.acting import act
from ebrl.kernels import EQ7_DECIDED_ONLY, EQ7_REWARD, EQ7_SURPRISE_RATE, EXPLORATION, \
    EXPLORED, FALLBACK, FORGET_OLDEST, INVALID, MEMORY, NO_EXCLUSION, eq5, eq6, eq7, \
    eq7_decided, forget, least_reliable, oldest, time_discount, update_variance


#: The record's fields, in the constructor's order.
AGENT_FIELDS = (
    # the stream and the config's numbers (floats, so one compiled version serves all)
    "rng", "exploration", "alpha", "threshold", "floor", "initial_utility",
    "initial_reliability", "discount", "cutoff", "rho", "decay",
    # the readings acting here, as ints / flags (ebrl.config.READINGS)
    "eq7_scope", "forgetting", "flag_decisions", "continuing", "keep_recall",
    "eq7_signal", "eq7_walk", "cut_links", "past_only", "explore_random", "random_sd",
    # eq 3's modalities
    "group_of", "group_size", "group_weight",
    # the memory (2.1) with its inputs rounded to single precision and each component's
    # largest |input| (the act's bound, acting.recall_bounded), the variance sums (eq 2),
    # the act's scratch, the recall table (2.2)
    "inputs", "inputs32", "input_bound", "sums", "variance", "sim", "actions", "utility",
    "rel", "time", "nxt", "prev", "decided", "table", "table_w",
    # the last act's input and action, whether learn has yet to store them, the reward
    # its memory decision expected (eq7_signal), the current trial's first step
    "obs", "action", "pending", "expected", "trial_start",
    # the counters: stored elements, the episode's latest element, the latest element used
    # for a decision (eq 7), steps learnt, decisions by memory and by the fallback, who
    # chose the last action (an index of DECIDERS)
    "size", "tail", "referred", "steps", "memory_decisions", "fallback_decisions", "decider",
)


@records.record(*AGENT_FIELDS)
class AgentRecord(records.Record):
    """ebrl.Agent's whole state as one record that compiled code takes as it is: the
    memory's arrays (as the module docstring lays them out), the recall table, the
    config's numbers, the agent's random stream (its numpy Generator, drawn in place),
    the last act's input and action until learn stores them, and the counters.
    Agent.act and Agent.learn call act_memory / learn_step on it, and a compiled loop
    (experiments.running.fused) iterates the same functions on the same record. Python
    reads its counters by name through `counters` (COUNTERS); its arrays are the caller's own (shared)."""


AgentRecord.constructor = njit(cache=True)(lambda *values: AgentRecord(*values))


#: The record's arrays, in order (AGENT_FIELDS from "group_of" to "action").
AGENT_ARRAYS = AGENT_FIELDS[AGENT_FIELDS.index("group_of"): AGENT_FIELDS.index("pending")]


#: The record's counters, in the order `counters` returns them.
COUNTERS = ("size", "tail", "referred", "steps", "memory_decisions", "fallback_decisions",
            "decider")


@njit(cache=True)
def counters(s):
    """The record's counters, in COUNTERS' order."""
    return (s.size, s.tail, s.referred, s.steps, s.memory_decisions, s.fallback_decisions,
            s.decider)


@njit(cache=True)
def expected_reward(s, element):
    """The reward a memory decision for `element` expects (eq7_signal): eq 5's measure
    min(W, U) of its recall entry (EQ7_SURPRISE_MEASURE; the first entry holding it), or
    its utility as a reward per step, (1 - gamma) U (EQ7_SURPRISE_RATE: a steady reward r
    each step sums by eq 6 to r / (1 - gamma))."""
    if s.eq7_signal == EQ7_SURPRISE_RATE:
        return (1.0 - s.discount) * s.utility[element]
    for e in range(s.table.shape[0]):
        if s.table[e] == element:
            return eq5(s.table_w[e], s.utility[element])
    return 0.0


@njit(cache=True)
def eq7_signal(s, reward):
    """eq 7's r for the step just taken (learn's r7): the reward itself for eq7_signal
    "reward"; else the reward less what the step's memory decision expected
    (s.expected), or the reward alone after a step the memory did not choose."""
    if s.eq7_signal != EQ7_REWARD and s.decider == MEMORY:
        return reward - s.expected
    return reward


@njit(cache=True)
def act_memory(s, x):
    """One act's memory part on record s: eq 2-4 against the memory, the recall table
    (eq 1), eq 5's choice, then the exploration draw. x is kept as the act's input.
    Returns the element whose action s.action now holds (decider MEMORY), FALLBACK when
    the fallback is to fill s.action (decider EXPLORATION when the draw overruled the
    memory, else left for the fallback's choice), EXPLORED when the draw overruled the
    memory and exploration is "random" (s.action then holds Section 3.4's random action,
    Gaussian with sd s.random_sd, clipped; decider EXPLORATION), or INVALID, with
    nothing changed, for an x that is not finite or whose square overflows. With
    recall_candidates "past" the candidates are the elements of earlier trials."""
    since = s.trial_start if s.past_only else NO_EXCLUSION
    element = act(x, s.size, s.inputs, s.inputs32, s.input_bound, s.variance, s.group_of,
                  s.group_size, s.group_weight, s.sim, s.nxt, s.table, s.table_w, s.utility,
                  s.alpha, s.threshold, s.time, since)
    if element == INVALID:
        return INVALID
    s.obs[:] = x
    s.pending = True
    explore = s.rng.random() < s.exploration
    if element >= 0 and not explore:
        s.action[:] = s.actions[element]
        s.referred = element
        if s.flag_decisions:
            s.decided[element] = True
        s.memory_decisions += 1
        s.decider = MEMORY
        if s.eq7_signal != EQ7_REWARD:
            s.expected = expected_reward(s, element)
        return element
    s.fallback_decisions += 1
    s.decider = EXPLORATION if element >= 0 else -1
    if element >= 0 and s.explore_random:
        for i in range(s.action.shape[0]):
            s.action[i] = s.rng.normal(0.0, s.random_sd)
        clip_unit(s.action)
        return EXPLORED
    return FALLBACK


@njit(cache=True)
def learn_step(s, reward):
    """One learn on record s: stores the last act's (input, action) as the episode's next
    element, in a free slot or, when the memory is full, in a forgotten element's; then
    eq 6 if reward != 0, eq 7 if its r (eq7_signal's: the reward itself by default) != 0,
    then the time discount. False, with nothing changed, when no act is pending.

    forgetting (2.1): FORGET_LEAST_RELIABLE forgets the least reliable element,
    FORGET_OLDEST the oldest; cut_links: the episode is cut at it (forget). eq7_scope:
    EQ7_TO_START applies eq 7 from `referred` back to its episode's start (when
    referred >= 0) with its walk (eq7), EQ7_DECIDED_ONLY to the elements flagged in
    `decided`. A reused slot's decided flag is cleared."""
    if not s.pending:
        return False
    r7 = eq7_signal(s, reward)
    # the record's fields read once, as kernels take them (arrays hoisted out of the loops)
    size, tail, referred = s.size, s.tail, s.referred
    x, inputs, sums, rel, time, nxt, prev = s.obs, s.inputs, s.sums, s.rel, s.time, s.nxt, s.prev
    utility, decided, inputs32, input_bound = s.utility, s.decided, s.inputs32, s.input_bound
    if size == rel.shape[0]:
        if s.forgetting == FORGET_OLDEST:
            slot = oldest(time, size)
        else:
            slot = least_reliable(rel, size)
        tail, referred = forget(slot, inputs, sums, nxt, prev, s.table, s.table_w, tail,
                                referred, s.cut_links)
        decided[slot] = False
    else:
        slot = size
        size += 1
    for i in range(x.shape[0]):
        inputs[i, slot] = x[i]
        inputs32[i, slot] = x[i]  # rounded to nearest
        input_bound[i] = max(input_bound[i], abs(x[i]))  # never lowered: a bound
        sums[0, i] += x[i]
        sums[1, i] += x[i] * x[i]
    update_variance(sums, size, s.floor, s.variance)
    s.actions[slot] = s.action
    utility[slot] = s.initial_utility
    rel[slot] = s.initial_reliability
    time[slot] = s.steps
    nxt[slot] = -1
    prev[slot] = tail
    if tail >= 0:
        nxt[tail] = slot
    tail = slot
    if reward != 0.0:
        eq6(utility, prev, time, slot, reward, s.discount, s.cutoff)
    if r7 != 0.0:
        if s.eq7_scope == EQ7_DECIDED_ONLY:
            eq7_decided(rel, decided, size, r7, s.rho)
        elif referred >= 0:
            eq7(rel, prev, referred, r7, s.rho, time, s.discount, s.cutoff, s.eq7_walk)
    time_discount(rel, size, s.decay)
    s.size, s.tail, s.referred = size, tail, referred
    s.steps += 1
    s.pending = False
    return True


@njit(cache=True)
def end_trial(s):
    """A trial ends (ebrl.Agent.end_trial has the readings' meaning): the episode's
    link is cut unless continuing, eq 7's starting point and its decided flags reset,
    the recall table emptied unless kept; the next trial's first step noted
    (recall_candidates "past")."""
    if not s.continuing:
        s.tail = -1
    s.referred = -1
    s.trial_start = s.steps
    if s.flag_decisions:
        s.decided[:] = False
    if not s.keep_recall:
        s.table[:] = -1
