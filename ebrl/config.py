"""Every agent parameter in one dataclass, Table 1's values as defaults (two_wheel's memory).

    cfg = ebrl.paper_config("floating")                  # Table 1, (F) memory of 4096
    cfg = ebrl.paper_config("two_wheel", alpha=0.3)     # with an override
    cfg.to_dict()                                         # plain dict, for results files
"""
import dataclasses
import math

#: Table 1, "memory size": (T) 1024 for the two wheels robot, (F) 4096 for the floating one.
ROBOT_MEMORY = {"two_wheel": 1024, "floating": 4096}


@dataclasses.dataclass(frozen=True)
class Config:
    # Table 1.
    memory_size: int = 1024        # (T); paper_config("floating") gives (F) 4096
    recall_size: int = 7           # N_r, the recall table's capacity (Section 2.2)
    alpha: float = 0.5             # eq 1
    exploration_rate: float = 0.05  # Section 2.3: the fallback acts whatever memory says
    discount: float = 0.99         # gamma, eq 6
    time_discount: float = 0.99    # every reliability times this, every step (Section 2.1)
    reliability_rate: float = 0.5  # rho, eq 7
    # Values the paper leaves open (docs/interpretation_agent.md).
    policy_threshold: float = 0.0  # memory acts only if the best min(W, U) of eq 5 exceeds it
    initial_reliability: float = 1.0
    initial_utility: float = 0.0
    utility_cutoff: float = 1e-4   # eq 6 stops walking back once gamma^(t - t_j) < this
    variance_floor: float = 1e-6   # lower bound of V_i in eq 2 (a constant input has V = 0)
    # Section 3.4: the intrinsic behaviour's share of random actions, and their spread.
    intrinsic_random_rate: float = 0.2
    random_sd: float = 0.5

    def __post_init__(self):
        self.validate()

    def validate(self):
        """Raises ValueError naming the first field out of its range."""
        def number(name):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"{name} must be a finite number, got {v!r}")
            return v

        def between(name, lo, hi, open_ends):
            v = number(name)
            ok = (lo < v < hi) if open_ends else (lo <= v <= hi)
            if not ok:
                ends = f"({lo}, {hi})" if open_ends else f"[{lo}, {hi}]"
                raise ValueError(f"{name} must be in {ends}, got {v!r}")

        for name in ("memory_size", "recall_size"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name} must be an integer >= 1, got {v!r}")
        if self.memory_size < self.recall_size:
            raise ValueError(f"memory_size ({self.memory_size}) must be at least "
                             f"recall_size ({self.recall_size})")
        for name in ("alpha", "discount", "time_discount", "reliability_rate"):
            between(name, 0.0, 1.0, open_ends=True)
        for name in ("exploration_rate", "intrinsic_random_rate", "initial_reliability",
                     "utility_cutoff"):
            between(name, 0.0, 1.0, open_ends=False)
        for name in ("variance_floor", "random_sd"):
            if number(name) <= 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        for name in ("policy_threshold", "initial_utility"):
            number(name)

    def to_dict(self):
        return dataclasses.asdict(self)


def paper_config(robot, **overrides):
    """Table 1's parameters for robot ("two_wheel" or "floating"), with keyword overrides."""
    if robot not in ROBOT_MEMORY:
        raise ValueError(f"unknown robot {robot!r}; valid robots: {', '.join(ROBOT_MEMORY)}")
    unknown = set(overrides) - {f.name for f in dataclasses.fields(Config)}
    if unknown:
        raise ValueError(f"unknown Config field(s): {', '.join(sorted(unknown))}")
    return Config(**{"memory_size": ROBOT_MEMORY[robot], **overrides})
