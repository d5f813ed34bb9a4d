"""Faults through the real command (in real processes where it is killed, crashed or given
a test hook; reruns in the pytest worker, helpers.ebrl_here): a worker that crashes (whatever
--workers), Ray's failures and a lost cluster, a results folder that fills up or turns
read-only. Each ends in one line, keeps every finished run, and a rerun finishes the set
with the clean run's summary."""
import functools
import json
import os
import pathlib
import re
import subprocess
import sys
import time

import numpy as np
import pytest

import helpers
from experiments.running import results, runner
from helpers import ROOT

#: The slow tier (pyproject.toml's markers): processes killed, crashed, starved of disk.
pytestmark = pytest.mark.slow

SET = ["--robot", "two_wheel", "--condition", "all", "--seeds", "0-3", "--steps", "1000",
       "--no-progress"]


ebrl = functools.partial(helpers.ebrl, check=True)  # a failure raises, unless check=False
here = functools.partial(helpers.ebrl_here, check=True)  # the same command in this process


def env(**hooks):
    e = dict(os.environ, **hooks)
    e.pop("RAY_ADDRESS", None)
    return e


def summary(out):
    return json.loads((pathlib.Path(out) / "summary.json").read_text())


def records(out):
    """Every run.json under out, by run folder."""
    return {str(p.parent.relative_to(out)): json.loads(p.read_text())
            for p in sorted(pathlib.Path(out).glob("*/*/seed_*/run.json"))}


def arrays(out):
    """Every complete run's trials.csv text and trace arrays, keyed by run folder."""
    got = {}
    for name, record in records(out).items():
        if record["status"] == "complete":
            with np.load(pathlib.Path(out) / name / "trace.npz") as z:
                got[name] = ((pathlib.Path(out) / name / "trials.csv").read_text(),
                             z["trace"].tobytes(), z["starts"].tobytes())
    return got


def leftovers(out):
    """Temporary files a write left behind."""
    return sorted(str(p) for p in pathlib.Path(out).rglob("*.tmp"))


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    out = tmp_path_factory.mktemp("clean") / "results"
    here("run", *SET, "--workers", "2", "--out", out)
    return out


# -- a worker that crashes ----------------------------------------------------------
@pytest.mark.parametrize("workers", [1, 2])
def test_a_crashed_worker_is_recorded_with_its_signal_whatever_the_workers(clean, tmp_path,
                                                                           workers):
    out = tmp_path / "results"
    crash = {"two_wheel/random/seed_000": "SIGSEGV",   # a segfault in native code
             "two_wheel/avoidance/seed_002": "SIGKILL"}  # as the out-of-memory killer does
    hooks = env(EBRL_TEST_CRASH="two_wheel/random/0:SIGSEGV,two_wheel/avoidance/2:SIGKILL")
    proc = ebrl("run", *SET, "--workers", workers, "--out", out, env=hooks, check=False)
    assert proc.returncode == 1, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert all(name in lines[0] for name in crash) and "6 runs made" in lines[0]
    assert lines[0].endswith("; " + results.advice([f"WorkerDied: {s}" for s in crash.values()]))
    assert "a crash in native code, which a rerun repeats" in lines[0]
    assert "rerun the same command to retry the runs whose worker was killed" in lines[0]
    got = records(out)
    for name, sig in crash.items():
        assert got[name]["status"] == "failed" and got[name]["signal"] == sig
        assert got[name]["error"].startswith(f"WorkerDied: the worker process running {name} "
                                             f"was killed by {sig}")
    assert {k: v for k, v in arrays(clean).items() if k not in crash} == arrays(out)
    proc = here("run", *SET, "--workers", workers, "--out", out)
    assert proc.stdout.strip().startswith("2 runs made, 6 already on disk")
    assert summary(out) == summary(clean) and arrays(out) == arrays(clean)


# -- a results folder that fills up or turns read-only --------------------------------
def test_a_disk_that_fills_mid_run_is_one_line_and_the_rerun_finishes(clean, tmp_path):
    out = tmp_path / "results"
    # Test-only: the third run.json write fails halfway with ENOSPC, as do all after it.
    proc = ebrl("run", *SET, "--workers", "2", "--out", out, env=env(EBRL_TEST_DISK_FULL="2"),
                check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert "No space left on device" in lines[0] and f"in {out}/two_wheel/" in lines[0]
    got = records(out)  # every run.json there parses and is a complete record
    assert len(got) == 2 and all(r["status"] == "complete" for r in got.values())
    assert len(list(out.glob("*/*/seed_*"))) > 2  # the third run's folder: no run.json
    assert leftovers(out) == []
    proc = here("run", *SET, "--workers", "2", "--out", out)
    assert proc.stdout.strip().startswith("6 runs made, 2 already on disk")
    assert summary(out) == summary(clean) and arrays(out) == arrays(clean)


@pytest.fixture
def small_disk(tmp_path):
    """A tmpfs of 48 KiB at tmp_path/disk (skipped where mounting is not allowed)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    made = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=48k", "tmpfs", str(disk)],
                          capture_output=True, text=True)
    if made.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {made.stderr.strip()}")
    try:
        yield disk
    finally:
        subprocess.run(["umount", "-l", str(disk)], capture_output=True)


def remount(disk, options):
    subprocess.run(["mount", "-o", f"remount,{options}", str(disk)], check=True)


def test_a_small_filesystem_that_fills_up_then_is_freed(clean, tmp_path, small_disk):
    out = small_disk / "results"
    proc = here("run", *SET, "--workers", "2", "--out", out, check=False)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert "No space left on device" in lines[0] and str(out) in lines[0]
    done = records(out)
    assert 1 <= len(done) < 8 and all(r["status"] == "complete" for r in done.values())
    assert leftovers(out) == []
    remount(small_disk, "size=16m")  # space freed
    proc = here("run", *SET, "--workers", "2", "--out", out)
    assert proc.stdout.strip().startswith(f"{8 - len(done)} runs made, {len(done)} already on disk")
    assert summary(out) == summary(clean) and arrays(out) == arrays(clean)


def test_a_folder_turned_read_only_mid_run_then_writable(clean, tmp_path, small_disk):
    remount(small_disk, "size=16m")
    out = small_disk / "results"
    proc = subprocess.Popen([sys.executable, "-m", "experiments", "run", *SET, "--workers", "1",
                             "--out", str(out)], cwd=ROOT, env=env(), text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.time() + 120
    while time.time() < deadline and not list(out.glob("*/*/seed_*/run.json")):
        time.sleep(0.01)
    while subprocess.run(["mount", "-o", "remount,ro", str(small_disk)],
                         capture_output=True).returncode != 0:  # busy while a file is written
        time.sleep(0.01)
    _, err = proc.communicate(timeout=120)
    remount(small_disk, "rw")
    assert proc.returncode == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Read-only file system" in lines[0] and str(out) in lines[0]
    done = records(out)
    assert 1 <= len(done) < 8 and all(r["status"] == "complete" for r in done.values())
    assert leftovers(out) == []
    proc = here("run", *SET, "--workers", "2", "--out", out)
    assert proc.stdout.strip().startswith(f"{8 - len(done)} runs made, {len(done)} already on disk")
    assert summary(out) == summary(clean) and arrays(out) == arrays(clean)


# -- Ray ---------------------------------------------------------------------------------
def start_cluster(tries=3, cpus=2):
    """A local Ray cluster of one head node (2 CPUs), its processes this test's own. Ray
    waits at most 30 s for its raylet, too little on a heavily loaded machine: tried
    again then."""
    ray_cluster = pytest.importorskip("ray.cluster_utils")
    for attempt in range(tries):
        cluster = ray_cluster.Cluster()
        try:
            cluster.add_node(num_cpus=cpus, include_dashboard=False)
            return cluster
        except Exception:
            cluster.shutdown()
            _stop_ray_children()  # the half-started node's, which the cluster never kept
            if attempt == tries - 1:
                raise


def _stop_ray_children():
    """SIGKILLs this process's own child processes that run Ray's services."""
    for entry in pathlib.Path("/proc").iterdir():
        try:
            ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            if ppid == os.getpid() and b"ray" in (entry / "cmdline").read_bytes():
                os.kill(int(entry.name), 9)
        except (OSError, ValueError, IndexError):
            continue


#: A line of Ray's own log: its C++ core's, or its Python logger's (date, level, file:line).
RAY_LOG = re.compile(r"^(\[\d{4}-\d\d-\d\d [\d:,]+ [A-Z] \d+ \d+\] \S+\.(cc|h):\d+: "
                     r"|\d{4}-\d\d-\d\d [\d:,]+\s+[A-Z]+ \S+\.py:\d+ -- )")


def test_ray_records_a_raised_run_and_a_dead_worker_as_the_local_pool_does(clean, tmp_path):
    """Without RAY_ADDRESS the command starts its own Ray (two CPUs) and stops it; the
    test hooks reach its workers (the across-nodes test below joins a cluster). Its six
    finished runs are the local pool's, bit for bit, and a rerun completes the set."""
    pytest.importorskip("ray")
    out = tmp_path / "results"
    raised, died = "two_wheel/avoidance/seed_001", "two_wheel/random/seed_002"
    hooks = env(EBRL_TEST_FAIL="two_wheel/avoidance/1",
                EBRL_TEST_CRASH="two_wheel/random/2:SIGKILL")
    proc = ebrl("run", *SET, "--backend", "ray", "--workers", "2", "--out", out, env=hooks,
                check=False)
    assert proc.returncode == 1, proc.stderr
    # Ray's own log may add its lines (the Ray it starts says how it authenticates)
    lines = [line for line in proc.stderr.strip().splitlines() if not RAY_LOG.match(line)]
    assert len(lines) == 1 and raised in lines[0] and died in lines[0], proc.stderr
    assert lines[0].endswith("; a rerun raises the same again (same seed, same result): each "
                             "run.json holds its traceback")  # the killed one's advice before
    assert "rerun the same command to retry the runs whose worker was killed" in lines[0]
    got = records(out)
    assert got[raised]["status"] == "failed" and got[raised]["error"] == (
        f"PhysicsError: failure injected by EBRL_TEST_FAIL (test only) in {raised}")
    assert "PhysicsError" in got[raised]["traceback"]
    assert got[died]["status"] == "failed"
    assert got[died]["error"].startswith(f"WorkerDied: the Ray worker running {died} died")
    assert {k: v for k, v in arrays(clean).items() if k not in (raised, died)} == arrays(out)
    # The rerun here on the local pool: Ray's runs and the pool's make one set (a whole set
    # on Ray, bit for bit the pool's: the across-nodes test).
    proc = here("run", *SET, "--workers", "2", "--out", out)
    assert proc.stdout.strip().startswith("2 runs made, 6 already on disk")
    assert summary(out) == summary(clean) and arrays(out) == arrays(clean)


def test_a_lost_ray_cluster_is_one_line_and_keeps_the_finished_runs(clean, tmp_path):
    out = tmp_path / "results"
    doomed = start_cluster()
    # Runs long enough (about a quarter of a second each on an idle machine, two at a time)
    # that the cluster dies, killed within milliseconds of the first run's record, with most
    # of them unfinished: with SET's 1,000 steps the whole set could end first.
    longer = [a if a != "1000" else "5000" for a in SET]
    try:
        proc = subprocess.Popen(
            [sys.executable, "-m", "experiments", "run", *longer, "--backend", "ray", "--out",
             str(out)], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            env=dict(env(EBRL_TEST_CLUSTER_TIMEOUT="3"), RAY_ADDRESS=doomed.address))
        # The cluster dies once the first run is written (a machine busy with other jobs
        # may take minutes to start Ray and finish one run: the deadline only bounds a hang).
        deadline = time.time() + 600
        while (time.time() < deadline and proc.poll() is None
               and not list(out.glob("*/*/seed_*/run.json"))):
            time.sleep(0.01)
        doomed.head_node.kill_all_processes(check_alive=False, allow_graceful=False)
        _, err = proc.communicate(timeout=120)
    finally:
        doomed.shutdown()
    assert proc.returncode == 2, err
    # Ray's own C++ log may add a line per task lost; ours is the only other one.
    lines = [line for line in err.strip().splitlines() if not RAY_LOG.match(line)]
    assert len(lines) == 1 and "lost the connection to the Ray cluster" in lines[0], err
    done = records(out)
    assert 1 <= len(done) < 8 and all(r["status"] == "complete" for r in done.values())
    assert f"the {len(done)} runs written are on disk" in lines[0]
    # The rerun here on the local pool (a rerun on Ray: the test above).
    proc = here("run", *longer, "--workers", "2", "--out", out)
    assert proc.stdout.strip().startswith(f"{8 - len(done)} runs made, {len(done)} already")
    again = records(out)
    assert len(again) == 8 and all(r["status"] == "complete" for r in again.values())
    assert all(again[k] == v for k, v in done.items())  # the finished runs kept as they were


def _held(hold, node):
    """The runs that wait on the file hold on the Ray node (EBRL_TEST_HOLD's markers)."""
    return sorted(p.name.rsplit(".", 1)[1] for p in hold.parent.glob(f"{hold.name}.{node.node_id}.*"))


def _until(condition, proc, what, seconds=300):
    """Waits until condition() (a loaded machine may take minutes to start a Ray node)."""
    deadline = time.time() + seconds
    while not condition():
        assert proc.poll() is None and time.time() < deadline, (what, proc.communicate())
        time.sleep(0.05)


def test_ray_across_nodes_a_lost_node_costs_its_runs_in_flight_and_a_new_node_takes_work(
        clean, tmp_path):
    """A head and two worker nodes, of one CPU each, on this machine: one worker node is
    there from the start, the other added once a run is in flight on each of the first
    two, and takes a run; then the first worker node is killed (all its processes,
    SIGKILL) with its run in flight. The command makes every run, bit for bit the local
    pool's."""
    out, hold = tmp_path / "results", tmp_path / "hold"
    hold.touch()  # every run waits, announced, until the file goes
    cluster = start_cluster(cpus=1)
    try:
        lost = cluster.add_node(num_cpus=1)
        proc = subprocess.Popen(
            [sys.executable, "-m", "experiments", "run", *SET, "--backend", "ray", "--out",
             str(out)], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            env=dict(env(EBRL_TEST_HOLD=str(hold)), RAY_ADDRESS=cluster.address))
        _until(lambda: _held(hold, cluster.head_node) and _held(hold, lost), proc,
               "a run in flight on each node")
        added = cluster.add_node(num_cpus=1)
        _until(lambda: _held(hold, added), proc, "a run on the added node")
        cluster.remove_node(lost, allow_graceful=False)
        hold.unlink()
        stdout, stderr = proc.communicate(timeout=300)
    finally:
        cluster.shutdown()
    assert proc.returncode == 0, stderr
    # Ray's driver prints the lost node's raylet's end ("(raylet) Raylet is terminated...")
    assert stdout.strip().splitlines()[-1].startswith("8 runs made, 0 already on disk"), stdout
    assert summary(out) == summary(clean) and arrays(out) == arrays(clean)


# -- what a failure line advises ------------------------------------------------------
def _missing_library():
    import ctypes
    ctypes.CDLL("libebrl_no_such_library.so.1")


def _damaged_install():
    import importlib
    importlib.import_module("ebrl_no_such_module")


def _bad_robot_file():
    import mujoco
    mujoco.MjModel.from_xml_string("<mujoco><worldbody><body><geom type='sphere'/>"
                                   "</body></worldbody><no_such_element/></mujoco>")


def _out_of_memory():
    np.empty(2 ** 62, dtype=np.uint8)


def _unstable_simulation():
    from dm_control.rl.control import PhysicsError
    raise PhysicsError("Physics state is invalid. Warning(s) raised: mjWARN_BADQACC")


#: Real errors of each kind a rerun cannot mend alone, raised here as a worker raises
#: them (the runner records whatever the run raised): what the line says instead.
CANNOT_RERUN = {
    "library": (_missing_library, "a system library is missing (the error names it): "
                                  "install it, then rerun"),
    "install": (_damaged_install, "the install is damaged or incomplete: reinstall it "
                                  "(pip install -e .), then rerun"),
    "robot": (_bad_robot_file, "the robot file is bad (the error says where): fix it, then rerun"),
    "memory": (_out_of_memory, "out of memory: rerun the same command with fewer --workers"),
    "raised": (_unstable_simulation, "a rerun raises the same again (same seed, same result)"),
}


@pytest.mark.parametrize("kind", sorted(CANNOT_RERUN))
def test_a_failure_that_a_rerun_cannot_mend_says_what_will(kind, tmp_path):
    cause, said = CANNOT_RERUN[kind]
    spec = runner.plan(["two_wheel"], ["avoidance"], [0], 200)[0]
    with pytest.raises(BaseException) as raised:
        cause()
    line = results.write_failure(tmp_path, spec, raised.value)  # the record, as the runner's
    assert results.failed_runs(tmp_path) == {"two_wheel/avoidance/seed_000": line}
    assert results.failure_kind(line) == kind, line
    assert results.failure_kind(f"{spec.name}: {line}") == kind  # as a study's trial holds it
    assert results.advice([line]).startswith(said)
    assert "to retry" not in results.advice([line])


def test_the_rerun_advice_by_kind_through_the_commands(tmp_path):
    """`ebrl report` on runs that failed each way: one line with each kind's advice once;
    killed and crashed workers come from the crash test above, a raised run from
    test_experiments, through `ebrl run`."""
    for seed, kind in enumerate(sorted(CANNOT_RERUN)):
        with pytest.raises(BaseException) as raised:
            CANNOT_RERUN[kind][0]()
        results.write_failure(tmp_path, runner.plan(["two_wheel"], ["avoidance"], [seed], 200)[0],
                              raised.value)
    proc = here("report", tmp_path, check=False)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, proc.stderr
    assert lines[0].startswith(f"ebrl: error: no complete runs under {tmp_path} (5 failed: ")
    for kind, (_, said) in CANNOT_RERUN.items():
        assert lines[0].count(said.replace("rerun the same command", "rerun `ebrl run`")
                              .replace("then rerun", "then rerun `ebrl run`")) == 1, (kind, lines)


# -- studies (`ebrl fit`) --------------------------------------------------------------
FIT = ["fit", "--trials", "8", "--batch", "2", "--seeds", "0", "--promote-seeds", "0",
       "--space", "policy_threshold", "--steps", "200", "--workers", "2", "--no-progress"]


def trials(out):
    import optuna
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    return optuna.load_study(study_name="fit", storage=f"sqlite:///{out}/study.db").trials


def running(out):
    """Whether the study's SQLite storage holds a running trial (read as it is written)."""
    import sqlite3
    if not (out / "study.db").exists():
        return False
    try:
        with sqlite3.connect(f"file:{out / 'study.db'}?mode=ro", uri=True, timeout=1) as db:
            return db.execute("SELECT COUNT(*) FROM trials WHERE state = 'RUNNING'").fetchone()[0] > 0
    except sqlite3.Error:  # the tables not made yet
        return False


def test_a_study_killed_at_random_moments_is_continued_by_the_same_command(tmp_path):
    pytest.importorskip("optuna")
    import random

    import optuna

    from experiments.studies import fit, study
    from experiments.running import results
    out = tmp_path / "fit"
    rng = random.Random(21)  # the moments: random, the same on every run of the test
    kills = 0
    for attempt in range(3):
        proc = subprocess.Popen([sys.executable, "-m", "experiments", *FIT, "--out", str(out)],
                                cwd=ROOT, env=env(), stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, start_new_session=True)
        try:
            if attempt == 0:  # the first kill while trials run, so that some are left running
                deadline = time.time() + 120
                while time.time() < deadline and proc.poll() is None and not running(out):
                    time.sleep(0.1)
                proc.wait(timeout=rng.uniform(0.0, 1.0))
            else:  # then at any moment, the start included
                proc.wait(timeout=rng.uniform(1.0, 8.0))
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, 9)  # SIGKILL, the command and its workers
            proc.wait()
            kills += 1
        else:
            break
    assert kills >= 1
    proc = here(*FIT, "--out", out)  # the same command continues
    assert "trials made now" in proc.stdout and proc.stderr.strip() == ""
    got = trials(out)
    states = [t.state for t in got]
    assert optuna.trial.TrialState.RUNNING not in states
    interrupted = [t for t in got if t.user_attrs.get("error") == study.INTERRUPTED]
    assert interrupted and all(t.state == optuna.trial.TrialState.FAIL for t in interrupted)
    complete = [t for t in got if t.state == optuna.trial.TrialState.COMPLETE]
    assert len(complete) == 8 and len(got) == 8 + len(interrupted)
    # Every score is the one its runs on disk give: nothing half-written was scored.
    problem = fit.Problem(names=("policy_threshold",), rungs=((0,),), steps=200)
    for t in complete:
        runs = {}
        for spec in problem.specs(t.params, (0,)):
            runs.update(results.load_runs(study.run_folder(out, spec), [spec]))
        assert t.value == problem.score(t.params, runs)[0]
    assert leftovers(out) == []


def test_a_trial_whose_runs_failed_is_marked_failed_not_scored(tmp_path):
    pytest.importorskip("optuna")
    import optuna
    out = tmp_path / "fit"
    args = [*FIT[:2], "2", *FIT[3:], "--out", out]  # two trials
    proc = ebrl(*args, env=env(EBRL_TEST_FAIL="floating/random/0"), check=False)
    assert proc.returncode == 1, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "trial 0" in lines[0] and "PhysicsError" in lines[0], proc.stderr
    assert lines[0].endswith("; a rerun raises the same again (same seed, same result): each "
                             "run.json holds its traceback")
    got = trials(out)
    assert [t.state for t in got] == [optuna.trial.TrialState.FAIL] * 2
    for t in got:
        assert t.value is None and "rungs" not in t.user_attrs
        assert "floating/random/seed_000: PhysicsError" in t.user_attrs["error"]
    # One more trial, without the failure: scored.
    proc = here(*FIT[:2], "3", *FIT[3:], "--out", out)
    got = trials(out)
    assert got[2].state == optuna.trial.TrialState.COMPLETE and got[2].value is not None
