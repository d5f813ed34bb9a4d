"""The protocol pipeline end to end, through the real command: in real processes where it
is killed, interrupted or given a test hook, else in the pytest worker (helpers.ebrl_here),
its runs on the pool's worker processes either way."""
import functools
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import numba
import numpy as np
import pytest

import helpers
from helpers import ROOT, ebrl_here
from experiments.ops import procs


ebrl = functools.partial(helpers.ebrl, check=True)  # a failure raises, unless check=False
here = functools.partial(ebrl_here, check=True)  # the same command in this process


def summary(out):
    return json.loads((pathlib.Path(out) / "summary.json").read_text())


def arrays(out):
    """Every run's trials.csv text and trace arrays, keyed by run folder."""
    got = {}
    for run in sorted(pathlib.Path(out).glob("*/*/seed_*")):
        if not (run / "trace.npz").exists():  # a failed run: run.json alone
            continue
        with np.load(run / "trace.npz") as z:
            got[str(run.relative_to(out))] = ((run / "trials.csv").read_text(),
                                              z["trace"].tobytes(), z["starts"].tobytes())
    return got


SMALL = ["--robot", "paper", "--condition", "all", "--seeds", "0-1", "--steps", "400", "--no-progress"]


@pytest.fixture(scope="module")
def clean_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("clean") / "results"
    here("run", *SMALL, "--workers", "1", "--out", out)
    return out


def _claim_odds():
    import importlib.util
    spec = importlib.util.spec_from_file_location("claim_odds", ROOT / "examples/claim_odds.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_claim_odds_draws_seeds_with_replacement_and_judges_each_draw_as_the_report(tmp_path):
    """examples/claim_odds.py, run as a user would, and its draws: with replacement (a seed
    drawn twice counts twice), the same seeds for every group, each draw judged by the
    report's own claims; more seeds than every group has is one line and exit status 1;
    C6 has no model-based odds, only m / (m + n)."""
    from experiments.outputs import report
    from experiments.running import aggregate, results
    out = tmp_path / "results"  # long enough for a goal in both conditions on both seeds
    here("run", "--robot", "two_wheel", "--seeds", "0-1", "--steps", "8000", "--no-progress",
         "--workers", "1", "--out", out)
    odds = _claim_odds()
    runs = results.load_runs(out)
    rng = np.random.default_rng(3)
    draws = [odds.draw(runs, [0, 1], 2, rng) for _ in range(20)]
    picked = [tuple(d[("two_wheel", "random", i)]["parameters"]["seed"] for i in range(2))
              for d in draws]
    assert {(0, 0), (1, 1)} & set(picked) and {(0, 1), (1, 0)} & set(picked)  # with replacement
    for d in draws:  # every group drew the same seeds
        for i in range(2):
            assert d[("two_wheel", "avoidance", i)]["parameters"]["seed"] == \
                d[("two_wheel", "random", i)]["parameters"]["seed"]
        want = {c: bool(ok) for c, _, ok in report.claims(aggregate.summarize(d))}
        got = odds.verdicts(aggregate.summarize(d))
        assert {c: got[c] for c in want} == want
    model = odds.verdicts(aggregate.summarize(draws[0]), model=True)
    assert not any("every run reaches at least" in c or c.startswith("C6") for c in model)
    assert odds.c6_exchangeable(50) == 0.5 and odds.c6_exchangeable(100) == pytest.approx(1 / 3)
    # m / (m + n) by simulation: 100 continuous draws all above the least of 50 others
    x = np.random.default_rng(0).exponential(size=(20_000, 150))
    assert (x[:, 50:].min(axis=1) >= x[:, :50].min(axis=1)).mean() == pytest.approx(1 / 3, abs=0.015)
    script = [sys.executable, "examples/claim_odds.py", str(out)]
    proc = subprocess.run(script + ["--seeds", "2", "--draws", "3"], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0] == "3 draws of 2 seeds; share of draws on which each claim holds:"
    assert lines[1] == "| claim | our runs (2 seeds) | the paper's figures |"
    rows = [line.strip("|").split("|") for line in lines[3:]]
    got = {claim.strip(): float(ours.strip().rstrip("%")) / 100 for claim, ours, _ in rows}
    assert all(0.0 <= v <= 1.0 for v in got.values()) and len(got) >= 4
    assert any(c.endswith("(point estimate)") for c in got)
    bad = subprocess.run(script + ["--seeds", "3"], cwd=ROOT, capture_output=True, text=True)
    assert bad.returncode == 1 and "only 2 seeds" in bad.stderr


@pytest.mark.slow
def test_a_short_run_writes_every_file(clean_run):
    runs = sorted(clean_run.glob("*/*/seed_*"))
    assert len(runs) == 8
    for run in runs:
        assert {p.name for p in run.iterdir()} == {"config.json", "trials.csv", "trace.npz", "run.json"}
        config = json.loads((run / "config.json").read_text())
        assert config["steps"] == 400 and config["agent"]["recall_size"] == 7
        assert {"mujoco", "numpy", "numba", "llvmlite", "git_commit"} <= set(config["versions"])
        assert config["versions"]["numba"] == numba.__version__
        record = json.loads((run / "run.json").read_text())
        assert record["status"] == "complete"
        rows = (run / "trials.csv").read_text().splitlines()
        assert rows[0] == "trial,steps,cumulative_steps,reached"
        assert sum(int(r.split(",")[1]) for r in rows[1:]) == 400
        with np.load(run / "trace.npz") as z:
            assert z["trace"].shape == (401, 2) and z["trace"].dtype == np.int16
    s = summary(clean_run)
    assert len(s["groups"]) == 4
    g = s["groups"][0]
    assert {"robot", "condition", "steps", "seeds", "first_trial_steps", "steps_per_trial",
            "shrink", "goals"} <= set(g)
    assert {"mean", "sd", "reached", "ci95"} <= set(g["first_trial_steps"])
    assert {"min", "median", "max"} <= set(g["goals"])
    for fig in ("cumulative_reward_two_wheel.png", "cumulative_reward_floating.png",
                "traces_two_wheel.png", "traces_floating.png", "first_vs_learned.png"):
        assert (clean_run / "figures" / fig).stat().st_size > 5000
    report = (clean_run / "REPORT.md").read_text()
    assert "first-trial steps" in report and "6,087" in report


@pytest.mark.slow
def test_rerun_skips_and_report_is_reproducible(clean_run):
    before = (clean_run / "summary.json").read_bytes()
    proc = here("run", *SMALL, "--out", clean_run)
    assert "0 runs made, 8 already on disk" in proc.stdout
    here("report", clean_run)
    assert (clean_run / "summary.json").read_bytes() == before


@pytest.mark.slow
def test_worker_count_does_not_change_results(clean_run, tmp_path):
    here("run", *SMALL, "--workers", "2", "--out", tmp_path / "w2")
    assert arrays(tmp_path / "w2") == arrays(clean_run)
    assert summary(tmp_path / "w2") == summary(clean_run)


KILL_ARGS = ["run", "--robot", "two_wheel", "--condition", "all", "--seeds", "0-2",
             "--steps", "1500", "--no-progress"]


@pytest.fixture(scope="module")
def kill_clean(tmp_path_factory):
    out = tmp_path_factory.mktemp("kill_clean") / "clean"
    here(*KILL_ARGS, "--workers", "1", "--out", out)
    return out


def _default_sigint():
    # A shell's background job, like this test's own process may be, ignores SIGINT, and a
    # Python started so ignores Ctrl-C: give the command SIGINT's default, as a terminal does.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start_ebrl(*args):
    """`ebrl ARGS` in its own process group (so the group can be signalled like a
    terminal's foreground job), with SIGINT at its default."""
    return subprocess.Popen([sys.executable, "-m", "experiments", *map(str, args)], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, preexec_fn=_default_sigint)


def wait_for_runs(out, count, proc, timeout=120):
    deadline = time.time() + timeout
    while (time.time() < deadline and proc.poll() is None
           and len(list(out.glob("*/*/seed_*/run.json"))) < count):
        time.sleep(0.02)
    return len(list(out.glob("*/*/seed_*/run.json")))


@pytest.mark.parametrize("moment,workers", [
    ("starting", 2),   # while it imports and starts the pool: nothing on disk yet
    ("running", 1),    # between runs, two on disk
    ("running", 2),    # with the pool's workers busy
    ("reporting", 2),  # every run on disk, the report being built
])
@pytest.mark.slow
def test_kill_then_resume_gives_the_clean_summary(kill_clean, tmp_path, moment, workers):
    args = [*KILL_ARGS, "--workers", workers, "--out", tmp_path / "killed"]
    out = tmp_path / "killed"
    proc = start_ebrl(*args)
    if moment == "starting":
        time.sleep(0.5)
    else:
        wait_for_runs(out, 2 if moment == "running" else 6, proc)
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:  # it had finished
        pass
    proc.communicate()
    done = len(list(out.glob("*/*/seed_*/run.json")))
    if moment != "reporting":
        assert proc.returncode == -signal.SIGKILL
    if moment == "running":
        assert 2 <= done < 6, done
    proc = here(*args)
    assert proc.stdout.strip().startswith(f"{6 - done} runs made, {done} already on disk")
    assert summary(out) == summary(kill_clean)
    assert arrays(out) == arrays(kill_clean)


@pytest.mark.slow
@pytest.mark.parametrize("how", ["ctrl-c", "sigterm"])
def test_ctrl_c_stops_the_workers_in_one_line_and_the_command_resumes(kill_clean, tmp_path, how):
    """Ctrl-C at a terminal (SIGINT to the whole group), or SIGTERM to the command alone
    (`kill PID`): the workers are stopped, none is left to finish its run as an orphan."""
    out = tmp_path / "interrupted"
    args = [*KILL_ARGS, "--workers", "2", "--out", out]
    proc = start_ebrl(*args)
    wait_for_runs(out, 1, proc)
    workers = procs.pool_workers(proc.pid)
    assert workers, "no pool worker found"
    if how == "ctrl-c":
        os.killpg(proc.pid, signal.SIGINT)  # as Ctrl-C at a terminal: the whole group
    else:
        os.kill(proc.pid, signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    assert len(err.strip().splitlines()) == 1 and "interrupted" in err, err
    assert "Traceback" not in err
    deadline = time.time() + 5
    while time.time() < deadline and any(procs.alive(pid) for pid in workers):
        time.sleep(0.05)
    assert not [pid for pid in workers if procs.alive(pid)], "workers left running"
    done = len(list(out.glob("*/*/seed_*/run.json")))
    assert 1 <= done < 6, done
    # No run folder holds a failed record: an interrupted run is simply unfinished.
    assert all(json.loads(p.read_text())["status"] == "complete"
               for p in out.glob("*/*/seed_*/run.json"))
    proc = here(*args)
    assert proc.stdout.strip().startswith(f"{6 - done} runs made, {done} already on disk")
    assert summary(out) == summary(kill_clean)
    assert arrays(out) == arrays(kill_clean)


@pytest.mark.slow
def test_a_failed_run_is_recorded_named_never_averaged_and_retried(clean_run, tmp_path):
    out = tmp_path / "results"
    failing = "two_wheel/avoidance/seed_001"
    env = dict(os.environ, EBRL_TEST_FAIL="two_wheel/avoidance/1")  # test-only hook
    proc = ebrl("run", *SMALL, "--workers", "2", "--out", out, env=env, check=False)
    assert proc.returncode == 1, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and failing in lines[0] and "PhysicsError" in lines[0], proc.stderr
    assert "7 runs made, 0 already on disk" in lines[0] and "Traceback" not in proc.stderr
    # The same seed raises again: the line says so rather than "rerun to retry".
    assert lines[0].endswith("; a rerun raises the same again (same seed, same result): each "
                             "run.json holds its traceback")
    # The record: status, parameters, the error in one line and the worker's traceback.
    record = json.loads((out / failing / "run.json").read_text())
    assert record["status"] == "failed"
    assert record["parameters"]["seed"] == 1 and record["parameters"]["steps"] == 400
    assert record["error"].startswith("PhysicsError: ") and "\n" not in record["error"]
    assert "PhysicsError" in record["traceback"] and "running/worker.py\", line" in record["traceback"]
    # The other runs finished, identical to the clean run's.
    others = {k: v for k, v in arrays(clean_run).items() if k != failing}
    assert {k: v for k, v in arrays(out).items() if k != failing} == others
    # The report names it and never averages it.
    s = summary(out)
    assert s["failed"] == [{"run": failing, "error": record["error"]}]
    group = next(g for g in s["groups"] if (g["robot"], g["condition"]) == ("two_wheel", "avoidance"))
    assert group["seeds"] == 1
    proc = here("report", out, check=False)
    assert proc.returncode == 1 and failing in proc.stderr and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    report = (out / "REPORT.md").read_text()
    assert "Failed runs: 1, not averaged" in report and failing in report
    # A rerun without the hook retries it alone, and the summary is a clean run's.
    proc = here("run", *SMALL, "--workers", "2", "--out", out)
    assert "1 runs made, 7 already on disk" in proc.stdout and proc.stderr.strip() == ""
    assert summary(out) == summary(clean_run)
    assert arrays(out) == arrays(clean_run)
    assert "Failed runs" not in (out / "REPORT.md").read_text()


@pytest.mark.slow
def test_a_worker_that_dies_fails_only_its_own_run(clean_run, tmp_path):
    out = tmp_path / "results"
    dying = "two_wheel/random/seed_000"
    env = dict(os.environ, EBRL_TEST_CRASH="two_wheel/random/0")  # test-only hook
    proc = ebrl("run", *SMALL, "--workers", "2", "--out", out, env=env, check=False)
    assert proc.returncode == 1 and dying in proc.stderr and "WorkerDied" in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr
    assert proc.stderr.strip().endswith("; rerun the same command to retry the runs whose worker "
                                        "was killed or died (out of memory: fewer --workers)")
    assert json.loads((out / dying / "run.json").read_text())["status"] == "failed"
    assert {k: v for k, v in arrays(out).items() if k != dying} == {
        k: v for k, v in arrays(clean_run).items() if k != dying}
    here("run", *SMALL, "--workers", "2", "--out", out)
    assert summary(out) == summary(clean_run)


@pytest.mark.parametrize("args,message", [
    (["run", "--robot", "tricycle"], "tricycle"),
    (["run", "--condition", "lazy"], "lazy"),
    (["run", "--seeds", "9-3"], "reversed"),
    (["run", "--seeds", ""], "seed"),
    (["run", "--steps", "0"], "positive"),
    (["run", "--steps", "-5"], "positive"),
    (["run", "--workers", "0"], "positive"),
    (["report", "no_such_folder"], "no results folder"),
    (["render", "--robot", "two_wheel", "--condition", "avoidance", "--seed", "0",
      "--out", "x.gif"], "mp4"),
])
@pytest.mark.slow
def test_bad_arguments_fail_in_one_line_and_write_nothing(tmp_path, args, message):
    if args[0] == "run":
        args = args + ["--out", str(tmp_path / "out")]
    proc = ebrl_here(*args, cwd=tmp_path)
    assert proc.returncode != 0
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow
def test_a_damaged_run_is_named_skipped_and_made_again_with_the_same_bits(clean_run, tmp_path):
    """docs/failures.md, "A damaged run folder": `ebrl report` skips each damaged run with
    one line naming its folder and counts them in REPORT.md; `ebrl run` moves its files
    into damaged-<time>/ (never deleted) and makes it again, bit for bit a clean run's."""
    import math
    import shutil
    out = tmp_path / "results"
    shutil.copytree(clean_run, out)
    cut = out / "floating" / "random" / "seed_001"
    (cut / "run.json").write_text((cut / "run.json").read_text()[:40])
    short = out / "two_wheel" / "avoidance" / "seed_000"
    (short / "trace.npz").write_bytes((short / "trace.npz").read_bytes()[:200])
    nan = out / "floating" / "avoidance" / "seed_000"
    run = json.loads((nan / "run.json").read_text())
    run["metrics"]["goals"] = math.nan
    (nan / "run.json").write_text(json.dumps(run))
    damaged = {folder: {p.name: p.read_bytes() for p in folder.iterdir()}
               for folder in (cut, short, nan)}
    proc = here("report", out)
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 3 and all(line.startswith("ebrl: warning: ") for line in lines)
    for folder, said in ((cut, "run.json is not JSON"), (short, "trace.npz cannot be read"),
                         (nan, "run.json: metrics.goals is NaN")):
        assert any(f"{folder}: damaged run: {said}" in line for line in lines), "\n".join(lines)
    assert "## Damaged runs: 3, skipped" in (out / "REPORT.md").read_text()
    assert len(summary(out)["damaged"]) == 3
    proc = here("run", *SMALL, "--out", out)
    assert proc.stdout.strip().splitlines()[-1].startswith("3 runs made, 5 already on disk")
    assert arrays(out) == arrays(clean_run) and summary(out) == summary(clean_run)
    for folder, files in damaged.items():  # set aside, whole
        (aside,) = folder.glob("damaged-*")
        assert {p.name: p.read_bytes() for p in aside.iterdir()} == files


@pytest.mark.slow
def test_other_parameters_are_refused_not_overwritten(clean_run, tmp_path):
    import shutil
    out = tmp_path / "results"
    shutil.copytree(clean_run, out)
    proc = ebrl_here("run", *SMALL[:-3], "--steps", "500", "--out", out)
    assert proc.returncode != 0 and "other parameters" in proc.stderr
    assert json.loads((out / "two_wheel/random/seed_000/run.json").read_text())["parameters"]["steps"] == 400


@pytest.mark.slow
def test_sweep_table_takes_the_default_rows_from_a_baseline_run(clean_run, tmp_path):
    sweep = ["sweep", "--robot", "two_wheel", "--condition", "avoidance", "--values", "0.4",
             "--steps", "400", "--out", tmp_path / "sweeps", "--baseline", clean_run, "--no-progress"]
    here(*sweep, "--seeds", "0-1")
    table = (tmp_path / "sweeps" / "SWEEP.md").read_text()
    base = summary(clean_run)["groups"]
    goals = next(g for g in base if (g["robot"], g["condition"]) == ("two_wheel", "avoidance"))["goals"]
    from tasks.protocols import ADOPTED
    default = f"| {dict(ADOPTED.readings)['policy_threshold']} (default"   # the adopted protocol's
    row = next(line for line in table.splitlines() if line.startswith(default))
    assert row.endswith(f"| {goals['min']} / {goals['median']:.1f} |")
    assert table.index(default) < table.index("| 0.4 |")
    # Seeds the baseline lacks: refused in one line, before anything runs.
    proc = ebrl_here(*sweep, "--seeds", "0-2")
    assert proc.returncode != 0 and "lacks some of these runs" in proc.stderr
    assert "Traceback" not in proc.stderr
    sweep = tmp_path / "sweeps" / "policy_threshold_0.4"
    assert not (sweep / "two_wheel" / "avoidance" / "seed_002").exists()
