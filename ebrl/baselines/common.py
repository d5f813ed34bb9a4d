"""What both baselines share (ebrl.baselines): their configs' one-line checks, the
fallback's fields every learner's config carries, the discrete actions, and the base
class of construction, input checks and decision counters."""
import dataclasses
import itertools
import math

import numpy as np

from ebrl.config import FALLBACK_READINGS, Config, check_reading
from ebrl.similarity import modalities


# -- config checks (one-line ValueErrors naming the parameter) -------------------------
def _is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _check_int(cfg, name, lo):
    v = getattr(cfg, name)
    if not isinstance(v, int) or isinstance(v, bool) or v < lo:
        raise ValueError(f"{name} must be an integer of at least {lo}, got {v!r}")


def _check_range(cfg, name, lo, hi, lo_open=False, hi_open=False):
    v = getattr(cfg, name)
    ok = _is_number(v) and (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        interval = f"{'(' if lo_open else '['}{lo}, {hi}{')' if hi_open else ']'}"
        raise ValueError(f"{name} must be in {interval}, got {v!r}")


def _check_positive(cfg, name):
    v = getattr(cfg, name)
    if not (_is_number(v) and v > 0):
        raise ValueError(f"{name} must be a positive finite number, got {v!r}")


def _check_finite(cfg, name):
    if not _is_number(getattr(cfg, name)):
        raise ValueError(f"{name} must be a finite number, got {getattr(cfg, name)!r}")


def _check_shared(cfg):
    """The fields both configs share."""
    _check_range(cfg, "discount", 0.0, 1.0)
    _check_range(cfg, "exploration_rate", 0.0, 1.0)
    _check_int(cfg, "action_levels", 2)
    _check_range(cfg, "intrinsic_random_rate", 0.0, 1.0)
    _check_positive(cfg, "random_sd")
    for name in FALLBACK_READINGS:
        check_reading(name, getattr(cfg, name))


def _fallback_fields():
    """ebrl.Config's fields that the fallback is built with (Section 3.4's random share
    and spread, then its readings, ebrl.readings' fallback=True), as Config has them:
    name, type and default."""
    config = {f.name: f for f in dataclasses.fields(Config)}
    return [(n, config[n].type, dataclasses.field(default=config[n].default))
            for n in ("intrinsic_random_rate", "random_sd") + FALLBACK_READINGS]


#: Section 3.4's intrinsic behaviour, for the fallback the caller builds
#: (intrinsic.fallback_for), with ebrl.Config's fields and defaults: every learner gets
#: the same behaviour, a drive's readings of it included (tasks.robots). Made from
#: Config's fields, so a new fallback reading reaches every learner with its entry.
_Fallback = dataclasses.make_dataclass("_Fallback", _fallback_fields(), frozen=True,
                                       namespace={"__module__": __name__})


# -- pieces shared by both learners ---------------------------------------------------
def discrete_actions(action_dim, levels=5):
    """The discrete action set, one action per row (see the module docstring)."""
    if action_dim == 1:
        return np.linspace(-1.0, 1.0, levels).reshape(levels, 1)
    rows = [np.zeros(action_dim)]
    grid = [v for v in itertools.product((-1.0, 0.0, 1.0), repeat=action_dim) if any(v)]
    grid.sort(key=lambda v: math.atan2(v[1], v[0]) % (2 * math.pi) if action_dim == 2 else 0)
    rows += [np.array(v) / np.linalg.norm(v) for v in grid]
    return np.array(rows)


def action_count(action_dim, levels=5):
    """How many discrete actions discrete_actions gives (levels for action_dim 1, 3^d
    otherwise), without making them."""
    return int(levels) if action_dim == 1 else 3 ** int(action_dim)


def nearest_action(actions, action):
    """Index of the discrete action nearest (Euclidean) to `action`; the first on ties."""
    diff = actions - np.asarray(action, dtype=np.float64).reshape(1, -1)
    return int(np.argmin(np.einsum("ij,ij->i", diff, diff)))


class _Base:
    """Construction, input checks and the decision counters both learners share."""

    config_class = None

    def __init__(self, config, obs_dim, action_dim, fallback, *, groups=None,
                 group_weights=None, seed=None):
        if not isinstance(config, self.config_class):
            raise ValueError(f"config must be an ebrl.baselines.{self.config_class.__name__}")
        if int(obs_dim) < 1 or int(action_dim) < 1:
            raise ValueError("obs_dim and action_dim must be positive")
        self.config, self.fallback = config, fallback
        self.obs_dim, self.action_dim = int(obs_dim), int(action_dim)
        self.rng = np.random.default_rng(seed)
        self._group_of, self._group_size, self._group_weight = modalities(
            self.obs_dim, groups, group_weights)
        self.actions = discrete_actions(self.action_dim, config.action_levels)
        self._exploration = float(config.exploration_rate)
        self._action_index = None  # the last act's discrete action, until learn
        self.steps = 0
        self.used_memory = False
        self.memory_decisions = 0
        self.fallback_decisions = 0

    @property
    def n_actions(self):
        return len(self.actions)

    def _input(self, obs):
        x = np.array(obs, dtype=np.float64)
        if x.shape != (self.obs_dim,):
            raise ValueError(f"observation must have shape ({self.obs_dim},), got {x.shape}")
        if not np.isfinite(x).all():
            raise ValueError("observation contains NaN or inf")
        return x

    def _reward(self, reward):
        if self._action_index is None:
            raise ValueError("learn() needs an act() first")
        reward = float(reward)
        if not math.isfinite(reward):
            raise ValueError("reward must be finite")
        return reward

    def _decide(self, x, ranges, learner_action):
        """Exploration draw first; then learner_action() -> discrete index or None (the
        learner declines), else the fallback, whose action is mapped for learning."""
        explore = self.rng.random() < self._exploration
        index = None if explore else learner_action()
        if index is not None:
            action = self.actions[index].copy()
            self.used_memory = True
            self.memory_decisions += 1
        else:
            action = np.array(self.fallback(x if ranges is None else ranges, self.rng),
                              dtype=np.float64).reshape(self.action_dim)
            index = nearest_action(self.actions, action)
            self.used_memory = False
            self.fallback_decisions += 1
        self._action_index = index
        return action


# -- tabular Q-learning -----------------------------------------------------------------
