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
``AGENTS`` names them for the command line: ``AGENTS[name] = (ConfigClass, AgentClass)``.
"""
from ebrl.baselines.common import discrete_actions, nearest_action
from ebrl.baselines.mfec import MFEC, MFECConfig, discounted_returns
from ebrl.baselines.qtable import QTable, QTableConfig, boltzmann, confidence

__all__ = ["QTableConfig", "QTable", "MFECConfig", "MFEC", "AGENTS", "discrete_actions",
           "nearest_action", "boltzmann", "confidence", "discounted_returns"]

AGENTS = {"qtable": (QTableConfig, QTable), "mfec": (MFECConfig, MFEC)}
