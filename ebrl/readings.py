"""The agent's readings of the paper, one record each: the home of every reading.

A reading is a detail the paper leaves open, or states in words this replication had to
read, that a run may change: a switch (a tuple of choices, the first the default; the
kernels receive a value as its index) or a number (a Range); a protocol
(tasks.protocols) may give a reading a value other than its default. Each record holds
the reading's name, its scope, its allowed values and default, the paper's words where
the paper states the value (the quote, with its section) or OPEN where it does not, and
a one-line description. docs/interpretation.md gives every reading's reason.

The task's readings use the same record (tasks/readings.py, which also lists both for
the commands: tasks.readings.EVERY). ebrl.Config takes its reading fields' defaults
from AGENT and checks them with Reading.check; `--set`, `ebrl ablate`, `ebrl fit` and
the first-trial stage read names, values, defaults and descriptions from the registry;
tests/test_readings_registry.py checks docs/interpretation.md's table "Every reading"
against it. A new reading of the agent is an entry here, the Config field of its name
(default from its entry), its kernel and its test.

The agent names no robot: an agent reading's scope is the fallback behaviours
(ebrl.intrinsic's "eq8", "eq9-10") and the conditions ("random", "avoidance") it acts
on; a task reading's is the drives.
"""
import dataclasses
import math

#: The paper's words for a reading whose value the paper does not state.
OPEN = "open"


@dataclasses.dataclass(frozen=True)
class Range:
    """A number's allowed values: finite, of `type` (float takes ints too, never bools),
    between low and high (None: unbounded; each bound closed unless marked open), and
    None too when `none` says what None means."""
    type: type = float
    low: float = None
    high: float = None
    low_open: bool = False
    high_open: bool = False
    none: str = None       # what None means where None is allowed ("the robot file's")
    high_note: str = ""    # said after the upper bound in an error (its unit and reason)

    def problem(self, value):
        """Why value is not allowed ("must be ..."), or None."""
        if value is None and self.none is not None:
            return None
        kinds = (int,) if self.type is int else (int, float)
        if isinstance(value, bool) or not isinstance(value, kinds):
            return "must be an integer" if self.type is int else "must be a finite number"
        if not math.isfinite(value):
            return "must be a finite number"
        if self.low is not None and (value <= self.low if self.low_open else value < self.low):
            if self.low == 0:
                return "must be positive" if self.low_open else "must be non-negative"
            return f"must be {'above' if self.low_open else 'at least'} {self.low:g}"
        if self.high is not None and (value >= self.high if self.high_open else value > self.high):
            bound = "below" if self.high_open else "at most"
            return f"must be {bound} {self.high:g}{self.high_note}"
        return None

    def text(self):
        """The allowed values in words: 'a number in [0, 1]', 'a number >= 0 or None (...)'."""
        noun = "an integer" if self.type is int else "a number"
        if self.low is not None and self.high is not None:
            out = (f"{noun} in {'(' if self.low_open else '['}{self.low:g}, {self.high:g}"
                   f"{')' if self.high_open else ']'}")
        elif self.low is not None:
            out = f"{noun} {'>' if self.low_open else '>='} {self.low:g}"
        elif self.high is not None:
            out = f"{noun} {'<' if self.high_open else '<='} {self.high:g}"
        else:
            out = f"any finite {'integer' if self.type is int else 'number'}"
        return out + (f" or None ({self.none})" if self.none is not None else "")


@dataclasses.dataclass(frozen=True)
class Reading:
    """One reading: see the module's docstring."""
    name: str              # the config field that holds it (ebrl.Config, tasks.TaskConfig)
    scope: str             # "agent" or "task"
    values: object         # a switch's choices (a tuple, the default first) or a Range
    default: object
    what: str              # one line
    paper: str = OPEN      # 'Section N: "the paper's words"', or OPEN
    #: Where it acts (all when empty): the drives (a task reading's), the fallback
    #: behaviours (an agent reading's), the conditions.
    drives: tuple = ()
    behaviours: tuple = ()
    conditions: tuple = ()
    #: The fallback's reading (Section 3.4's intrinsic behaviour), not the learner's:
    #: every learner's config carries it (ebrl.baselines) and the runner builds the
    #: fallback with it.
    fallback: bool = False

    def __post_init__(self):
        if self.scope not in ("agent", "task"):
            raise ValueError(f"reading {self.name}: scope must be agent or task, "
                             f"got {self.scope!r}")
        if self.switch and (not self.values or self.values[0] != self.default):
            raise ValueError(f"reading {self.name}: a switch's default is its first value")
        self.check(self.default)

    @property
    def switch(self):
        """Whether it takes one of a tuple of choices (else a number of a Range)."""
        return isinstance(self.values, tuple)

    @property
    def type(self):
        """The type of its values (str for a switch): what `--set` parses."""
        return str if self.switch else self.values.type

    def check(self, value):
        """value if allowed, else ValueError in one line naming the reading, what it
        takes and the value."""
        if self.switch:
            if not isinstance(value, str) or value not in self.values:
                raise ValueError(f"{self.name} must be one of {', '.join(self.values)}, "
                                 f"got {value!r}")
            return value
        problem = self.values.problem(value)
        if problem is not None:
            raise ValueError(f"{self.name} {problem}, got {value!r}")
        return value

    def code(self, value):
        """A switch's value as the kernels' int: its index (0 = the default)."""
        return self.values.index(self.check(value))

    def allowed(self):
        """The allowed values in words: 'trial / continuing', or the Range's text."""
        return " / ".join(self.values) if self.switch else self.values.text()


#: The agent's readings (every reading field of ebrl.Config), in Config's field order.
AGENT = (
    Reading("policy_threshold", "agent", Range(float), 0.0,
            "eq 5's measure must exceed this"),
    Reading("initial_reliability", "agent", Range(float, 0.0, 1.0), 1.0,
            "a new element's reliability"),
    Reading("initial_utility", "agent", Range(float), 0.0, "a new element's utility"),
    Reading("utility_cutoff", "agent", Range(float, 0.0, 1.0), 0.0,
            "eq 6 stops where gamma^k falls below this"),
    Reading("variance_floor", "agent", Range(float, 0.0, low_open=True), 1e-6,
            "the floor of eq 2's variance V_i"),
    # 2.1: the first element of a trial has no backward link; or the link from a trial's
    # last element to the next trial's first is kept, so eq 6 and eq 7 follow it.
    Reading("episode", "agent", ("trial", "continuing"), "trial",
            "an episode is one trial, or one continuing episode across trials"),
    # 2.2: kept, its entries advance along their forward links at the next act, as on
    # any step.
    Reading("recall_at_trial_end", "agent", ("empty", "keep"), "empty",
            "the recall table at a trial's end"),
    # eq 7: from the last memory decision's element back along its links to its episode's
    # start, or only the elements used for a memory decision in the trial.
    Reading("eq7_scope", "agent", ("to_start", "decided_only"), "to_start",
            "eq 7 walks to the episode's start, or changes only deciding elements"),
    # 2.1: the least reliable element (first slot on ties), or the oldest (smallest time
    # stamp).
    Reading("forgetting", "agent", ("least_reliable", "oldest"), "least_reliable",
            "which element a full memory forgets",
            paper='Section 2.1: "it forgets a memory element of the lowest reliability when '
                  'there is no more room to store new experience"'),
    # eq 9: inside the dead zone the acceleration on that axis is 0, or the fallback's
    # previous acceleration on that axis is kept (0 again after a trial's end).
    Reading("eq9_dead_zone", "agent", ("keep", "zero"), "keep",
            "eq 9's 'not changed': the previous acceleration kept, or zero",
            behaviours=("eq9-10",), conditions=("avoidance",), fallback=True),
    # 3.4: with probability intrinsic_random_rate the random action replaces the avoidance
    # action, or is added to it (the sum clipped to [-1, 1]).
    Reading("random_in_avoidance", "agent", ("replace", "add"), "replace",
            "the 20% random action replaces, or is added to, the avoidance action",
            conditions=("avoidance",), fallback=True),
    # 3.4 / 3.3: Section 3.4's Gaussian (mean 0, sd random_sd, clipped) for every random
    # action; or uniform over Section 3.3's demand range (-1, 1) for the random walk (the
    # condition without avoidance) only; or uniform for every random action (the walk's
    # and the avoidance condition's 20%). The exploration action is the fallback's, so it
    # follows.
    Reading("random_demand", "agent", ("gaussian", "uniform_walk", "uniform_all"), "gaussian",
            "a random action's demand: Gaussian, or uniform for the walk or for all",
            paper='Section 3.4: "The demand value of random action is produced using pseudo '
                  'Gaussian distribution of which mean value is 0 and standard deviation is 0.5."',
            fallback=True),
    # eq 7's r_t: the reward (the equation as printed: it acts at a goal, from the latest
    # memory decision's element); or, after each memory decision, the difference between
    # the reward and the reward that decision expected (the sentence before eq 7): its
    # eq 5 measure min(W, U) ("surprise_measure"), or its utility as a reward per step,
    # (1 - gamma) U ("surprise_rate"); a reward after a fallback's step expected nothing.
    Reading("eq7_signal", "agent", ("reward", "surprise_measure", "surprise_rate"), "reward",
            "eq 7's r: the reward, or the reward less the decision's expected reward",
            paper='Section 2.4: "the reliability of memory element that the agent referred '
                  'for decision should be modified according to the difference between '
                  'real and expected reward values"'),
    # eq 7's walk (eq7_scope "to_start"): every element changed by the same r ("whole");
    # r times gamma^(t_ref - t_j), as eq 6 discounts ("discounted"); or stopped where
    # gamma^(t_ref - t_j) falls below utility_cutoff, where eq 6 stops ("cut").
    Reading("eq7_walk", "agent", ("whole", "discounted", "cut"), "whole",
            "eq 7's walk back: undiscounted, discounted as eq 6, or stopped at eq 6's cutoff"),
    # 2.1: a forgotten element's episode neighbours are linked to each other ("join"), or
    # the episode is cut there ("cut": the earlier part ends, the later one starts).
    Reading("forgetting_link", "agent", ("join", "cut"), "join",
            "forgetting joins the episode across the gap, or cuts it there"),
    # 2.2: every stored element is a recall candidate ("all"), or only the elements of
    # earlier trials ("past": none stored since the current trial began).
    Reading("recall_candidates", "agent", ("all", "past"), "all",
            "recall candidates: every element, or only earlier trials' elements"),
    # 2.3: the exploration step goes to the fallback (the avoidance rule, or its random
    # action 20% of the time), or is Section 3.4's random action (Gaussian, sd random_sd).
    Reading("exploration", "agent", ("fallback", "random"), "fallback",
            "an exploration step: the fallback's action, or Section 3.4's random action",
            paper='Section 2.3: "it should sometimes do a type of exploration behavior '
                  'ignoring the above decision process"'),
)
AGENT_BY_NAME = {r.name: r for r in AGENT}


def codes(name, *values):
    """The codes (Reading.code) of an agent switch's values, in the order asked: what a
    kernel module names its switch constants by (``EQ7_WHOLE, EQ7_CUT = codes("eq7_walk",
    "whole", "cut")``), so they follow the registry, never a position kept by hand."""
    reading = AGENT_BY_NAME[name]
    return reading.code(values[0]) if len(values) == 1 else tuple(map(reading.code, values))
