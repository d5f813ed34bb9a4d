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
    code = ("import sys, ebrl, ebrl.benchmark; "
            "print(any(m.split('.')[0] in ('mujoco', 'dm_control', 'tasks') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def _run(seed, steps=3000):
    """A floating-like agent (eq 3's groups) on a fixed random stream; its whole state."""
    rng = np.random.default_rng(seed + 7)
    ag = ebrl.Agent(ebrl.Config(memory_size=256), 10, 2, intrinsic.fallback_for("eq9-10", "avoidance"),
                    groups=[np.arange(8), np.arange(8, 10)], group_weights=[0.7, 0.3], seed=seed)
    actions = []
    for step in range(steps):
        obs = rng.random(10)
        actions.append(ag.act(obs, ranges=obs[:8]))
        last = step % 150 == 149
        ag.learn(1.0 if last else -0.1 if step % 40 == 0 else 0.0, last)
    return np.array(actions), ag


def test_act_takes_any_array_like_input_as_float64_and_refuses_ranges_not_1d():
    """act converts its inputs itself (its kernel is called without numba's typing,
    compiled.records.direct): ints, lists, strided and read-only arrays act as their
    float64 copies; ranges of two dimensions are one ValueError, nothing changed."""
    def agent():
        return ebrl.Agent(ebrl.Config(memory_size=64), 10, 2,
                          intrinsic.fallback_for("eq9-10", "avoidance"), seed=5)
    rng = np.random.default_rng(0)
    codes = rng.integers(0, 256, size=(200, 20))  # int64, every other column taken below
    plain, odd = agent(), agent()
    for step, row in enumerate(codes):
        x = row[::2] / 255.0  # a strided view
        x.flags.writeable = False
        a = plain.act(np.ascontiguousarray(x), ranges=np.array(x[:8], dtype=np.float64))
        b = odd.act(list(x), ranges=row[:16:2] / 255.0)
        assert np.array_equal(a, b), step
        for ag in (plain, odd):
            ag.learn(1.0 if step % 50 == 49 else 0.0, step % 50 == 49)
    assert plain.memory_decisions == odd.memory_decisions > 0
    before = odd.steps
    with pytest.raises(ValueError, match=r"ranges must be 1-D, got shape \(2, 4\)"):
        odd.act(codes[0, :10] / 255.0, ranges=np.zeros((2, 4)))
    with pytest.raises(ValueError, match="learn\\(\\) needs an act\\(\\) first"):
        odd.learn(0.0)  # the refused act left nothing pending
    assert odd.steps == before


def test_same_seed_same_state_bit_for_bit():
    (a1, ag1), (a2, ag2) = _run(3), _run(3)
    assert np.array_equal(a1, a2)
    for name in ("inputs", "actions", "utility", "rel", "time", "nxt", "prev", "sums",
                 "variance", "table", "table_w"):
        assert np.array_equal(getattr(ag1.memory, name), getattr(ag2.memory, name)), name
    assert ag1.memory_decisions == ag2.memory_decisions > 0



def test_a_trial_ends_by_one_name_and_the_old_one_warns():
    """end_trial is a trial's end (learn(r, last=True) calls it); end_episode, its old
    name, warns and does the same: the next act recalls from the candidates only."""
    ag = ebrl.Agent(ebrl.Config(memory_size=16, recall_size=3), 2, 1,
                    intrinsic.fallback_for("eq8", "avoidance"), seed=0)
    for _ in range(4):
        ag.act(np.array([0.1, 0.2]))
        ag.learn(0.0)
    ag.end_trial()
    assert ag.tail == -1 and ag.referred == -1
    ag.act(np.array([0.1, 0.2]))
    ag.learn(0.0)
    assert ag.tail >= 0
    with pytest.warns(DeprecationWarning, match="use Agent.end_trial"):
        ag.end_episode()
    assert ag.tail == -1


@pytest.mark.slow
def test_kernels_are_compiled_once_and_cached():
    """Every kernel carries cache=True, and a new process loads them from numba's cache
    instead of compiling: the second of two fresh processes compiles nothing."""
    import subprocess
    import sys
    from ebrl import kernels
    dispatchers = [v for v in vars(kernels).values() if hasattr(v, "py_func")]
    assert len(dispatchers) >= 10
    for d in dispatchers:
        assert d.stats.cache_path is not None, d.__name__  # numba's NullCache: None
        assert not d.targetoptions.get("fastmath") and not d.targetoptions.get("parallel")
    code = ("import numpy as np, ebrl\n"
            "from ebrl import kernels, steps\n"
            "ag = ebrl.Agent(ebrl.Config(memory_size=8, recall_size=2), 3, 1,\n"
            "                ebrl.intrinsic.RandomWalk(1), seed=0)\n"
            "for t in range(20):\n"
            "    ag.act(np.random.default_rng(t).random(3)); ag.learn(float(t % 5 == 4), t % 5 == 4)\n"
            "ds = [v for m in (kernels, steps) for v in vars(m).values() if hasattr(v, 'py_func')]\n"
            "print(sum(len(d.stats.cache_misses) for d in ds), sum(len(d.stats.cache_hits) for d in ds))\n")
    for _ in range(2):
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    misses, hits = map(int, out.stdout.split())
    assert misses == 0 and hits > 0, out.stdout
