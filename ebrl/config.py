"""Every agent parameter, with Table 1's values as defaults (column T's memory)."""
import dataclasses

#: Table 1's memory size by column: (T) two wheels robot, (F) floating robot.
TABLE1_MEMORY = {"T": 1024, "F": 4096}

#: The agent-side readings of the paper with a credible alternative, as switches: each
#: Config field named here takes one of its values, the first being this replication's
#: reading (the default). docs/interpretation.md gives each reading and its reason;
#: the kernels receive a value as its index in this tuple.
READINGS = {
    # 2.1: an episode is one trial (the first element of a trial has no backward link),
    # or one episode continues across trials (the link from a trial's last element to
    # the next trial's first is kept, so eq 6 and eq 7 follow it).
    "episode": ("trial", "continuing"),
    # 2.2: the recall table is emptied when a trial ends, or kept (its entries then
    # advance along their forward links at the next act, as on any step).
    "recall_at_trial_end": ("empty", "keep"),
    # eq 7: from the last memory decision's element back along its links to its
    # episode's start, or only the elements used for a memory decision in the trial.
    "eq7_scope": ("to_start", "decided_only"),
    # 2.1: when the memory is full, forget the least reliable element (first slot on
    # ties), or the oldest (smallest time stamp).
    "forgetting": ("least_reliable", "oldest"),
    # eq 9: inside the dead zone the acceleration on that axis is 0, or the fallback's
    # previous acceleration on that axis is kept (0 again after a trial's end).
    "eq9_dead_zone": ("zero", "keep"),
    # 3.4: with probability intrinsic_random_rate the random action replaces the
    # avoidance action, or is added to it (the sum clipped to [-1, 1]).
    "random_in_avoidance": ("replace", "add"),
    # 3.4 / 3.3: a random action's demand is Section 3.4's Gaussian (mean 0, sd random_sd,
    # clipped) for every random action; or uniform over Section 3.3's demand range
    # (-1, 1) for the random walk (the condition without avoidance) only; or uniform for
    # every random action (the walk's and the avoidance condition's 20%). The exploration
    # action is the fallback's, so it follows.
    "random_demand": ("gaussian", "uniform_walk", "uniform_all"),
}


#: The readings that belong to the fallback (Section 3.4's intrinsic behaviour), not to
#: the learner: every learner's config has them (ebrl.Config; ebrl.baselines._Fallback),
#: and the runner builds the fallback with them (protocol.make_agent).
FALLBACK_READINGS = ("eq9_dead_zone", "random_in_avoidance", "random_demand")


def check_reading(name, value):
    """value if it is one of READINGS[name]'s values, else ValueError naming both."""
    valid = READINGS[name]
    if not isinstance(value, str) or value not in valid:
        raise ValueError(f"{name} must be one of {', '.join(valid)}; got {value!r}")
    return value


def reading_code(name, value):
    """The kernels' int for a reading: its index in READINGS[name] (0 = the default)."""
    return READINGS[name].index(check_reading(name, value))


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
    # Readings the paper leaves open (docs/interpretation.md).
    policy_threshold: float = 0.0  # eq 5's measure must exceed this for memory to act
    initial_reliability: float = 1.0
    initial_utility: float = 0.0
    utility_cutoff: float = 1e-4   # eq 6 stops where gamma^k falls below this
    variance_floor: float = 1e-6   # V_i floor in eq 2
    # Section 3.4.
    intrinsic_random_rate: float = 0.2
    random_sd: float = 0.5
    # Readings with a credible alternative, as switches (READINGS above; default first).
    episode: str = READINGS["episode"][0]
    recall_at_trial_end: str = READINGS["recall_at_trial_end"][0]
    eq7_scope: str = READINGS["eq7_scope"][0]
    forgetting: str = READINGS["forgetting"][0]
    eq9_dead_zone: str = READINGS["eq9_dead_zone"][0]  # the fallback's (intrinsic.fallback_for)
    random_in_avoidance: str = READINGS["random_in_avoidance"][0]  # likewise
    random_demand: str = READINGS["random_demand"][0]  # likewise

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
        for name in ("exploration_rate", "intrinsic_random_rate", "utility_cutoff",
                     "initial_reliability"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and 0.0 <= v <= 1.0):
                raise ValueError(f"{name} must be in [0, 1], got {v!r}")
        for name in ("variance_floor", "random_sd"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and v > 0):
                raise ValueError(f"{name} must be positive, got {v!r}")
        for name in ("policy_threshold", "initial_utility"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and v == v and abs(v) != float("inf")):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
        for name in READINGS:
            check_reading(name, getattr(self, name))


def paper_config(column: str, **overrides: object) -> Config:
    """Table 1's parameters in column "T" or "F" (they differ in memory size), with
    overrides."""
    if column not in TABLE1_MEMORY:
        raise ValueError(f"unknown Table 1 column {column!r}; valid: {', '.join(TABLE1_MEMORY)}")
    return Config(**{"memory_size": TABLE1_MEMORY[column], **overrides})
