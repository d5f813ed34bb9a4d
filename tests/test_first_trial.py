"""First-trial runs (execution.RunSpec.first_trial, `ebrl run --first-trial`): the one trial
loop (execution.Trials) stops at the first goal; the trial is a full run's, bit for bit."""
import csv
import dataclasses
import json

import pytest

from experiments.running import aggregate, execution, results, runner

# Seeds whose first trial ends well inside a short budget (first trials of protocol 7 and 8:
# the ablation's seeds 300-349 for the avoidance condition; protocol 8's fit seeds 8000-8099
# and protocol 7's 7000-7099 for the Gaussian random walks): two_wheel avoidance seed 310
# at step 90, random seed 8007 at 424; floating avoidance seed 319 at 673, random seed 7080
# at 812.
CASES = [("two_wheel", "avoidance", 310, 1500), ("two_wheel", "random", 8007, 1500),
         ("floating", "avoidance", 319, 1000), ("floating", "random", 7080, 1000)]


@pytest.mark.parametrize("robot,condition,seed,steps", CASES)
def test_a_first_trial_run_is_a_full_runs_first_trial(robot, condition, seed, steps):
    full = execution.execute(execution.RunSpec(robot, condition, seed, steps))
    first = execution.execute(execution.RunSpec(robot, condition, seed, steps, first_trial=True))
    end = int(full["trial_ends"][0])
    assert end < steps  # the full run goes on after it; the first-trial run stops
    assert first["trial_ends"].tolist() == [end]
    assert first["steps_run"] == end and full["steps_run"] == steps
    assert first["trace"].shape == (end + 1, 2)
    assert first["trace"].tobytes() == full["trace"][:end + 1].tobytes()
    # the reset after the goal is the full run's too: the next start is the same
    assert first["starts"].tobytes() == full["starts"][:2].tobytes()
    assert execution.metrics(first["trial_ends"])["first_trial_steps"] == \
        execution.metrics(full["trial_ends"])["first_trial_steps"]


def test_the_step_by_step_loop_stops_at_the_same_step():
    """fused=False (Agent.act, Environment.step, Agent.learn) stops where the compiled
    stretches stop, with the same trace."""
    spec = execution.RunSpec("two_wheel", "avoidance", 310, 1500, first_trial=True)
    stepwise, compiled = execution.execute(spec, fused=False), execution.execute(spec)
    assert stepwise["trial_ends"].tolist() == compiled["trial_ends"].tolist() == [90]
    assert stepwise["trace"].tobytes() == compiled["trace"].tobytes()


def test_a_first_trial_without_a_goal_runs_its_budget():
    """two_wheel random seed 2 reaches no goal in 300 steps: the run is the full run."""
    full = execution.execute(execution.RunSpec("two_wheel", "random", 2, 300))
    first = execution.execute(execution.RunSpec("two_wheel", "random", 2, 300, first_trial=True))
    assert full["trial_ends"].tolist() == first["trial_ends"].tolist() == []
    assert first["steps_run"] == 300
    assert first["trace"].tobytes() == full["trace"].tobytes()


def test_a_first_trial_run_has_its_own_folder_and_parameters(tmp_path):
    spec = execution.RunSpec("floating", "avoidance", 319, 1000, first_trial=True)
    full_spec = dataclasses.replace(spec, first_trial=False)
    assert spec.label == "floating.first_trial" and full_spec.label == "floating"
    assert spec.parameters()["first_trial"] is True
    assert "first_trial" not in full_spec.parameters()  # full runs' parameters as before
    assert results.run_dir(tmp_path, spec) != results.run_dir(tmp_path, full_spec)
    results.write_run(tmp_path, spec, execution.execute(spec), {})
    assert results.existing(tmp_path, spec) == "done"
    assert results.existing(tmp_path, full_spec) == "missing"
    folder = results.run_dir(tmp_path, spec)
    with open(folder / "trials.csv") as f:
        rows = list(csv.reader(f))
    assert rows == [["trial", "steps", "cumulative_steps", "reached"], ["0", "673", "673", "1"]]
    run = json.loads((folder / "run.json").read_text())
    assert run["metrics"]["goals"] == 1 and run["metrics"]["first_trial_steps"] == 673
    trace, starts, ends = results.load_trace(tmp_path, spec.label, "avoidance", 319)
    assert trace.shape == (674, 2) and ends.tolist() == [673]
    summary = aggregate.summarize(results.load_runs(tmp_path))
    assert summary["groups"][0]["robot"] == "floating.first_trial"
    assert summary["groups"][0]["first_trial_steps"]["mean"] == 673


def test_plan_makes_first_trial_specs():
    specs = runner.plan(("two_wheel",), ("random",), [0, 1], 100, first_trial=True)
    assert [s.first_trial for s in specs] == [True, True]
    assert runner.plan(("two_wheel",), ("random",), [0], 100)[0].first_trial is False
