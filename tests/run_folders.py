"""Run folders made without running (tests/test_run_folders.py, tests/test_properties.py):
results.write_run's files for a run's real parameters and a made-up result, so the
readers and their checks are tried on what the writer writes."""
import numpy as np

from experiments.running import results, runner

STEPS = 60


def spec(seed=0, condition="avoidance", steps=STEPS, **kw):
    """A real spec (its parameters are the ones a run records; the model is compiled once
    per process)."""
    return runner.plan(["two_wheel"], [condition], [seed], steps, **kw)[0]


def result(ends=(20, 45), steps=STEPS):
    """A made-up run's result as execution.execute returns it: a trace of steps + 1
    positions, a start per trial and the next one, the trial ends."""
    rng = np.random.default_rng(len(ends))
    return {"trace": rng.integers(0, 9000, (steps + 1, 2)).astype(np.int16),
            "starts": rng.integers(0, 9000, (len(ends) + 1, 2)).astype(np.int16),
            "trial_ends": np.asarray(ends, dtype=np.int64), "seconds": 0.5,
            "memory_decisions": 7, "steps_run": steps}


def make(root, s=None, ends=(20, 45)):
    """Writes a complete run folder under root; returns it."""
    s = s or spec()
    results.write_run(root, s, result(ends, s.steps), {"lock": "test"})
    return results.run_dir(root, s)
