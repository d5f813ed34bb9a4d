"""Every agent parameter, with Table 1's values as defaults (column T's memory)."""
import dataclasses

#: Table 1's memory size by column: (T) two wheels robot, (F) floating robot.
TABLE1_MEMORY = {"T": 1024, "F": 4096}


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


def paper_config(column, **overrides):
    """Table 1's parameters in column "T" or "F" (they differ in memory size), with
    overrides."""
    if column not in TABLE1_MEMORY:
        raise ValueError(f"unknown Table 1 column {column!r}; valid: {', '.join(TABLE1_MEMORY)}")
    return Config(**{"memory_size": TABLE1_MEMORY[column], **overrides})
