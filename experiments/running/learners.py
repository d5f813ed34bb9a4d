"""The learners `ebrl run --agent` knows, by name: the paper's (EBRL), then Section 4's
baselines (ebrl.baselines.AGENTS), each an ebrl.baselines.Learner (its config class, its
agent class imported at its first use). Imports no numba, so the command line checks
`--agent` and `--set` against the names and the config classes alone."""
from ebrl.baselines import AGENTS as BASELINES
from ebrl.baselines import Learner
from ebrl.config import Config

#: {name: Learner}: EBRL first, then the baselines.
LEARNERS = {"ebrl": Learner(Config, "ebrl.agent:Agent"), **BASELINES}
#: The learners' names, in LEARNERS' order.
AGENTS = tuple(LEARNERS)


def learner(name) -> Learner:
    """The learner of that name, or ValueError naming the valid ones."""
    if name not in LEARNERS:
        raise ValueError(f"unknown agent {name!r}; valid: {', '.join(AGENTS)}")
    return LEARNERS[name]
