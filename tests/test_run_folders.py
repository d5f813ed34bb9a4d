"""Run folders as the commands read them (issue 50): run.json checked against its schema,
a complete run's other files readable, a damaged folder named and skipped by a report
and set aside (never deleted) by a rerun, and a resume into a folder of other
parameters refused with the parameters that differ."""
import json
import math
import shutil

import numpy as np
import pytest

import run_folders
from experiments.running import results, runner, schema
from helpers import ebrl_here
from tasks.protocols import ADOPTED


def _edit(folder, change):
    path = folder / "run.json"
    run = json.loads(path.read_text())
    change(run)
    path.write_text(json.dumps(run))  # NaN written as NaN, as a hand or a tool might


def _cut(path, keep=100):
    path.write_bytes(path.read_bytes()[:keep])


#: Damage done to a complete run folder, and a piece of the line that names it.
DAMAGE = {
    "run.json cut short": (lambda f: _cut(f / "run.json", 40), "run.json is not JSON"),
    "goals NaN": (lambda f: _edit(f, lambda r: r["metrics"].update(goals=math.nan)),
                  "metrics.goals is NaN, not a finite number"),
    "seed a string": (lambda f: _edit(f, lambda r: r["parameters"].update(seed="0")),
                      "parameters.seed is a string, not an integer"),
    "robot missing": (lambda f: _edit(f, lambda r: r["parameters"].pop("robot")),
                      "parameters.robot is missing"),
    "status unknown": (lambda f: _edit(f, lambda r: r.update(status="done")),
                       "status is 'done'"),
    "metrics disagree": (lambda f: _edit(f, lambda r: r["metrics"].update(goals=0)),
                         "metrics disagree"),
    "trace cut short": (lambda f: _cut(f / "trace.npz"), "trace.npz cannot be read (BadZipFile"),
    "trace missing": (lambda f: (f / "trace.npz").unlink(), "trace.npz is missing"),
    "trace of other goals": (lambda f: _edit(f, lambda r: r["metrics"].update(
        goals=1, first_trial_steps=20, steps_per_trial=20.0)), "1 goals"),
    "trials.csv emptied": (lambda f: (f / "trials.csv").write_text(""), "trials.csv does not start"),
    "config.json a list": (lambda f: (f / "config.json").write_text("[]"),
                           "config.json holds a list"),
    "another folder's": (lambda f: _edit(f, lambda r: r["parameters"].update(seed=7)),
                         "names the folder two_wheel/avoidance/seed_007"),
}


def test_a_written_run_reads_back_whole(tmp_path):
    folder = run_folders.make(tmp_path)
    run = results.read_run(folder, tmp_path)
    assert run["status"] == "complete" and run["metrics"]["goals"] == 2
    assert results.existing(tmp_path, run_folders.spec()) == "done"
    failed = run_folders.spec(seed=1)
    results.write_failure(tmp_path, failed, RuntimeError("boom"))
    assert results.read_run(results.run_dir(tmp_path, failed), tmp_path)["status"] == "failed"


@pytest.mark.parametrize("name", sorted(DAMAGE))
def test_a_damaged_run_folder_is_named_with_what_is_wrong(tmp_path, name):
    damage, said = DAMAGE[name]
    folder = run_folders.make(tmp_path)
    damage(folder)
    with pytest.raises(results.DamagedRun) as e:
        results.read_run(folder, tmp_path)
    line = str(e.value)
    assert line.startswith(f"{folder}: damaged run: ") and said in line, line
    assert "\n" not in line
    assert results.existing(tmp_path, run_folders.spec()) == "damaged"


def test_load_runs_skips_a_damaged_run_with_one_line(tmp_path, capsys):
    run_folders.make(tmp_path)
    bad = run_folders.make(tmp_path, run_folders.spec(seed=1))
    _cut(bad / "trace.npz")
    damaged = {}
    runs = results.load_runs(tmp_path, damaged=damaged)
    assert list(runs) == [("two_wheel", "avoidance", 0)]
    assert list(damaged) == ["two_wheel/avoidance/seed_001"]
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"ebrl: warning: {bad}: damaged run: trace.npz")
    shutil.rmtree(tmp_path / "two_wheel" / "avoidance" / "seed_000")
    with pytest.raises(results.ResultsError, match=r"no complete runs .*\(1 damaged, skipped\)"):
        results.load_runs(tmp_path)


def test_a_rerun_sets_the_damaged_files_aside_and_never_deletes_them(tmp_path, capsys):
    s = run_folders.spec()
    folder = run_folders.make(tmp_path, s)
    _cut(folder / "trace.npz")
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    assert runner.pending(tmp_path, [s], mend=False) == [s]
    assert sorted(p.name for p in folder.iterdir()) == sorted(before)  # untouched
    assert runner.pending(tmp_path, [s]) == [s]
    aside = [p for p in folder.iterdir() if p.is_dir()]
    assert len(aside) == 1 and aside[0].name.startswith(schema.DAMAGED_PREFIX)
    assert {p.name: p.read_bytes() for p in aside[0].iterdir()} == before  # moved whole
    assert [p for p in folder.iterdir() if p.is_file()] == []
    line = capsys.readouterr().err.strip()
    assert line.startswith(f"ebrl: warning: {folder}: damaged run: trace.npz cannot be read")
    assert f"its files moved to {aside[0]}" in line and "\n" not in line
    assert results.existing(tmp_path, s) == "missing"
    run_folders.make(tmp_path, s)  # the run made again beside them
    assert results.existing(tmp_path, s) == "done"
    results.load_runs(tmp_path)  # the damaged-*/ subfolder is never read as a run


def test_ebrl_report_skips_damaged_runs_and_counts_them(tmp_path):
    run_folders.make(tmp_path)
    bad = run_folders.make(tmp_path, run_folders.spec(seed=1))
    _edit(bad, lambda r: r["metrics"].update(goals=math.nan))
    proc = ebrl_here("report", tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.strip().splitlines() == [
        f"ebrl: warning: {bad}: damaged run: run.json: metrics.goals is NaN, not a finite "
        "number; skipped (`ebrl run` moves its files aside and makes it again)"]
    report = (tmp_path / "REPORT.md").read_text()
    assert "## Damaged runs: 1, skipped" in report
    assert "- `two_wheel/avoidance/seed_001`: run.json: metrics.goals is NaN" in report
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["damaged"] == [{"run": "two_wheel/avoidance/seed_001",
                                   "reason": "run.json: metrics.goals is NaN, not a finite number"}]
    assert summary["groups"][0]["seeds"] == 1


@pytest.mark.parametrize("args, said", [
    (["--protocol", "literal"], "(protocol: adopted on disk, literal asked; agent."),
    (["--set", "radius=2"], "(task.radius: {} on disk, 2.0 asked)".format(
        dict(ADOPTED.robots["two_wheel"])["radius"])),
    (["--set", "policy_threshold=0.1"], "(agent.policy_threshold: {} on disk, 0.1 asked)".format(
        dict(ADOPTED.readings)["policy_threshold"])),
])
def test_a_resume_into_other_parameters_names_them(tmp_path, args, said):
    run_folders.make(tmp_path)
    before = (tmp_path / "two_wheel/avoidance/seed_000/run.json").read_bytes()
    proc = ebrl_here("run", "--robot", "two_wheel", "--condition", "avoidance", "--seeds", "0",
                     "--steps", run_folders.STEPS, "--out", tmp_path, *args)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "holds a run made with other parameters" in lines[0]
    assert said in lines[0], lines[0]
    assert (tmp_path / "two_wheel/avoidance/seed_000/run.json").read_bytes() == before


def test_the_differences_name_steps_room_and_the_model_last():
    p = {"steps": 50, "task": {"radius": 1.0}, "model_sha256": "a"}
    assert schema.differences(p, dict(p, steps=100)) == "steps: 50 on disk, 100 asked"
    assert schema.differences(p, dict(p, room="b/m.txt")) == "room: sutton on disk, b/m.txt asked"
    assert schema.differences(p, dict(p, model_sha256="b")) == "model_sha256: a on disk, b asked"
    both = dict(p, task={"radius": 2.0}, model_sha256="b")
    assert schema.differences(p, both) == "task.radius: 1.0 on disk, 2.0 asked"
    many = {f"k{i}": i for i in range(8)}
    assert schema.differences({}, many, limit=2).endswith("; and 6 more")


def test_a_trace_changed_after_its_check_is_named_too(tmp_path):
    folder = run_folders.make(tmp_path)
    trace, _, ends = results.load_trace(tmp_path, "two_wheel", "avoidance", 0)
    assert list(ends) == [20, 45] and np.isfinite(trace).all()
    _cut(folder / "trace.npz")
    with pytest.raises(results.DamagedRun, match="trace.npz cannot be read"):
        results.load_trace(tmp_path, "two_wheel", "avoidance", 0)
