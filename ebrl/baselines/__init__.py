"""Two other learners behind EBRL's interface, for Section 4's question: can a learner
other than EBRL use the intrinsic behaviour, given a way to measure its confidence?

Both take ``(config, obs_dim, action_dim, fallback, *, groups=None, group_weights=None,
seed=None)`` like ebrl.Agent, and offer ``act(obs, ranges=None)``, ``learn(reward,
last=False)``, ``steps``, ``used_memory`` (True when the learner, not the fallback,
chose), ``memory_decisions`` and ``fallback_decisions``. Each act draws one exploration
number from the agent's generator (``np.random.default_rng(seed)``), then either the
learner's own draws (QTable's roulette wheel; MFEC has none) or the fallback's: the
same seed gives the same actions bit for bit.

``QTable`` ("qtable"): tabular Q-learning on discretised inputs with Boltzmann
(roulette-wheel) selection. Confidence, as Section 4 suggests, is the variance of the
action probabilities in the current state, divided by its largest possible value
(``confidence``): 0 for uniform probabilities, 1 for a certain choice. Below
``confidence_threshold`` (or on exploration) the fallback acts.

``MFEC`` ("mfec"): model-free episodic control (Blundell et al. 2016): per discrete
action a memory of (embedding, best return) pairs, Q(s, a) from the stored return of an
identical embedding or the mean of the k nearest neighbours', updated with each trial's
discounted returns at its end. The learner acts greedily when the chosen action's
neighbours are near (mean distance at most ``distance_threshold``) and its estimate
positive; otherwise (or on exploration) the fallback acts.

Both learn from the fallback's actions too, each mapped to the nearest discrete action
(``nearest_action``); the environment always gets the action that was chosen, the
fallback's own continuous one included. Discrete actions (``discrete_actions``): for
action_dim 1, ``action_levels`` values evenly spaced on [-1, 1] (5: -1, -0.5, 0, 0.5,
1); for action_dim d >= 2, the zero action and every non-zero vector of {-1, 0, 1}^d
scaled to unit length (d = 2: zero and the 8 compass directions, counter-clockwise from
+x). docs/interpretation.md ("Other learners") gives every choice and its reason.

Neither imports a simulator; everything is derived from obs_dim, action_dim and groups.
``AGENTS`` names them for the command line: ``AGENTS[name]`` is a ``Learner``, its config
class and its agent class. The package imports no numba: the configs live in
ebrl.baselines.configs, and MFEC (compiled) is imported at its first use.
"""
import dataclasses
import importlib

from ebrl.baselines.common import discrete_actions, nearest_action
from ebrl.baselines.configs import MFECConfig, QTableConfig
from ebrl.baselines.qtable import QTable, boltzmann, confidence

__all__ = ["QTableConfig", "QTable", "MFECConfig", "MFEC", "AGENTS", "Learner",
           "discrete_actions", "nearest_action", "boltzmann", "confidence", "discounted_returns"]

#: The names ebrl.baselines.mfec defines, imported (with numba) at their first use.
_MFEC = ("MFEC", "discounted_returns")


@dataclasses.dataclass(frozen=True)
class Learner:
    """A learner the command line knows: its config class, and its agent class as
    "module:Class", imported at its first use (`agent`), so that the argument checks,
    which need only the config, import no numba."""
    config: type
    agent_path: str

    @property
    def agent(self) -> type:
        """The agent class (importing its module)."""
        module, name = self.agent_path.split(":")
        return getattr(importlib.import_module(module), name)


AGENTS = {"qtable": Learner(QTableConfig, "ebrl.baselines.qtable:QTable"),
          "mfec": Learner(MFECConfig, "ebrl.baselines.mfec:MFEC")}


def __getattr__(name):
    """MFEC and discounted_returns (ebrl.baselines.mfec, compiled): imported at first use."""
    if name in _MFEC:
        return getattr(importlib.import_module("ebrl.baselines.mfec"), name)
    raise AttributeError(f"module 'ebrl.baselines' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_MFEC))
