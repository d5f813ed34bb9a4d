"""Every agent parameter, with Table 1's values as defaults (column T's memory) and, for
what the paper leaves open, the literal protocol's readings (ebrl.readings)."""
import dataclasses

from ebrl import readings

#: Section 3.6's two conditions: the fallback acts at random, or by the intrinsic
#: behaviour (ebrl.intrinsic.fallback_for builds either).
CONDITIONS = ("random", "avoidance")

#: Table 1's memory size by column: (T) two wheels robot, (F) floating robot.
TABLE1_MEMORY = {"T": 1024, "F": 4096}

#: The agent's switches, {name: values}, the first being the registry's default (Config's;
#: a protocol may give another, tasks.protocols): a view of the registry
#: (ebrl.readings.AGENT, where each reading's scope, default, the paper's words and
#: description live); the kernels receive a value as its index in this tuple.
READINGS = {r.name: r.values for r in readings.AGENT if r.switch}

#: The readings that belong to the fallback (Section 3.4's intrinsic behaviour), not to
#: the learner: every learner's config has them (ebrl.Config; ebrl.baselines.common._Fallback),
#: and the runner builds the fallback with them (execution.make_agent).
FALLBACK_READINGS = tuple(r.name for r in readings.AGENT if r.fallback)


def check_reading(name, value):
    """value if it is one of READINGS[name]'s values, else ValueError naming both."""
    return readings.AGENT_BY_NAME[name].check(value)


def reading_code(name, value):
    """The kernels' int for a reading: its index in READINGS[name] (0 = the default)."""
    return readings.AGENT_BY_NAME[name].code(value)


def _default(name):
    """A reading field's default: its registry entry's (ebrl.readings)."""
    return readings.AGENT_BY_NAME[name].default


@dataclasses.dataclass(frozen=True)
class Config:
    # Table 1.
    memory_size: int = 1024
    recall_size: int = 7          # N_r
    alpha: float = 0.5            # eq 1
    exploration_rate: float = 0.05
    discount: float = 0.99        # gamma, eq 6
    time_discount: float = 0.99   # reliability decay per step
    reliability_rate: float = 0.5  # rho, eq 7
    # Readings the paper leaves open (ebrl.readings: each one's values, scope and
    # description; docs/interpretation.md: its reason).
    policy_threshold: float = _default("policy_threshold")
    initial_reliability: float = _default("initial_reliability")
    initial_utility: float = _default("initial_utility")
    utility_cutoff: float = _default("utility_cutoff")
    variance_floor: float = _default("variance_floor")
    # Section 3.4.
    intrinsic_random_rate: float = 0.2
    random_sd: float = 0.5
    # Readings with a credible alternative, as switches (ebrl.readings; default first).
    episode: str = _default("episode")
    recall_at_trial_end: str = _default("recall_at_trial_end")
    eq7_scope: str = _default("eq7_scope")
    forgetting: str = _default("forgetting")
    eq9_dead_zone: str = _default("eq9_dead_zone")  # the fallback's (intrinsic.fallback_for)
    random_in_avoidance: str = _default("random_in_avoidance")  # likewise
    random_demand: str = _default("random_demand")  # likewise
    eq7_signal: str = _default("eq7_signal")
    eq7_walk: str = _default("eq7_walk")
    forgetting_link: str = _default("forgetting_link")
    recall_candidates: str = _default("recall_candidates")
    exploration: str = _default("exploration")

    def __post_init__(self):
        for name in ("memory_size", "recall_size"):
            v = getattr(self, name)
            if not isinstance(v, int) or isinstance(v, bool) or v < 1:
                raise ValueError(f"{name} must be a positive integer, got {v!r}")
        if self.memory_size < self.recall_size:
            raise ValueError(f"memory_size ({self.memory_size}) must be at least "
                             f"recall_size ({self.recall_size})")
        for name in ("alpha", "discount", "time_discount", "reliability_rate"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and 0.0 < v < 1.0):
                raise ValueError(f"{name} must be in (0, 1), got {v!r}")
        for name in ("exploration_rate", "intrinsic_random_rate"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and 0.0 <= v <= 1.0):
                raise ValueError(f"{name} must be in [0, 1], got {v!r}")
        if not (isinstance(self.random_sd, (int, float)) and self.random_sd > 0):
            raise ValueError(f"random_sd must be positive, got {self.random_sd!r}")
        for reading in readings.AGENT:
            reading.check(getattr(self, reading.name))


def paper_config(column: str, **overrides: object) -> Config:
    """Table 1's parameters in column "T" or "F" (they differ in memory size) and the
    readings' defaults, which are the literal protocol's (the paper as written:
    tasks.protocols.LITERAL), with overrides. The adopted protocol's learner is this with
    its readings as overrides (experiments.running.execution)."""
    if column not in TABLE1_MEMORY:
        raise ValueError(f"unknown Table 1 column {column!r}; valid: {', '.join(TABLE1_MEMORY)}")
    return Config(**{"memory_size": TABLE1_MEMORY[column], **overrides})
