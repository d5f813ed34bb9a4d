"""Each baseline's config (ebrl.baselines): its parameters, their defaults and their
checks. Kept apart from the learners so that the command line checks `--set` without
importing numba (MFEC compiles with it)."""
import dataclasses

from ebrl.baselines.common import _check_finite, _check_int, _check_positive, _check_range, \
    _check_shared, _Fallback, _is_number


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
