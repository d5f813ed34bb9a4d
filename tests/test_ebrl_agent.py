"""The agent as a whole: learning on a tiny problem, determinism, bad input."""
import numpy as np
import pytest

import ebrl
from ebrl import intrinsic

CORRIDOR = 12


def corridor_trials(seed, trials=40, exploration_rate=0.05):
    """A corridor of CORRIDOR cells; reward at the far end. The input names the cell
    (one-hot plus noise); action sign = direction. A random walk needs ~N^2 steps.
    exploration_rate=1 never uses the memory: the random-walk baseline."""
    rng = np.random.default_rng(seed + 100)
    ag = ebrl.Agent(ebrl.Config(memory_size=512, recall_size=7,
                                exploration_rate=exploration_rate), CORRIDOR, 1,
                    intrinsic.RandomWalk(1), seed=seed)
    lengths = []
    for _ in range(trials):
        pos, steps = 0, 0
        while True:
            obs = np.eye(CORRIDOR)[pos] + rng.normal(0, 0.05, CORRIDOR)
            a = ag.act(obs)[0]
            pos = min(max(pos + (1 if a > 0 else -1), 0), CORRIDOR - 1)
            steps += 1
            done = pos == CORRIDOR - 1 or steps >= 2000
            ag.learn(1.0 if pos == CORRIDOR - 1 else 0.0, done)
            if done:
                break
        lengths.append(steps)
    return np.array(lengths)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_trials_get_shorter_on_a_corridor(seed):
    lengths = corridor_trials(seed)
    baseline = corridor_trials(seed, exploration_rate=1.0)
    assert baseline.mean() > 5 * CORRIDOR  # no fixed behaviour solves it by chance
    assert lengths[-10:].mean() < 0.4 * baseline.mean(), (lengths, baseline.mean())
    assert lengths[-10:].mean() < 3 * CORRIDOR  # optimum: CORRIDOR - 1 steps


def test_same_seed_same_actions():
    a, b, c = corridor_trials(5, 8), corridor_trials(5, 8), corridor_trials(6, 8)
    assert np.array_equal(a, b) and not np.array_equal(a, c)


@pytest.mark.filterwarnings("ignore:overflow encountered")  # |x|^2 of the too-large input
def test_bad_observations_raise():
    ag = ebrl.Agent(ebrl.paper_config("T"), 7, 1, intrinsic.RandomWalk(1), seed=0)
    with pytest.raises(ValueError, match="shape"):
        ag.act(np.zeros(6))
    with pytest.raises(ValueError, match="NaN"):
        ag.act(np.array([0, 0, np.nan, 0, 0, 0, 0]))
    with pytest.raises(ValueError, match="NaN"):
        ag.act(np.array([0, 0, 0, -np.inf, 0, 0, 0]))
    with pytest.raises(ValueError, match="too large"):
        ag.act(np.full(7, 1e200))
    with pytest.raises(ValueError, match="act"):
        ag.learn(0.0)


@pytest.mark.parametrize("field,value", [
    ("alpha", 0.0), ("alpha", 1.5), ("exploration_rate", -0.1), ("discount", 1.0),
    ("time_discount", 0.0), ("reliability_rate", 2.0), ("memory_size", 0),
    ("recall_size", 2.5), ("variance_floor", 0.0), ("policy_threshold", float("nan")),
])
def test_bad_config_names_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        ebrl.Config(**{field: value})


def test_memory_smaller_than_recall_table_and_paper_config():
    with pytest.raises(ValueError, match="memory_size"):
        ebrl.Config(memory_size=5, recall_size=7)
    assert ebrl.paper_config("T").memory_size == 1024
    f = ebrl.paper_config("F")
    assert (f.memory_size, f.recall_size, f.alpha, f.exploration_rate, f.discount,
            f.time_discount, f.reliability_rate) == (4096, 7, 0.5, 0.05, 0.99, 0.99, 0.5)
    with pytest.raises(ValueError, match="Table 1 column"):
        ebrl.paper_config("hexapod")


def test_ebrl_never_imports_the_simulator():
    import subprocess
    import sys
    code = "import sys, ebrl, ebrl.benchmark; print(any(m.split('.')[0] in ('mujoco', 'dm_control', 'tasks') for m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
