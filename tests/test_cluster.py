"""A study shared by several workers on a real PostgreSQL server (tests/conftest.py's
throwaway cluster): two `ebrl fit` and two `ebrl evolve` processes on one study, one
killed (SIGKILL) mid-trial and restarted, no password in any output, and a database lost
mid-trial. Skipped, with the reason, where no server can be started (conftest.py)."""
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

from helpers import ROOT, ebrl_here

#: The slow tier (pyproject.toml's markers): PostgreSQL, Ray and study workers in processes.
pytestmark = pytest.mark.slow

FIT = ["fit", "--trials", "6", "--batch", "2", "--seeds", "0", "--promote-seeds", "0",
       "--space", "policy_threshold", "--steps", "200", "--workers", "1", "--no-progress"]
EVOLVE = ["evolve", "--robot", "two_wheel", "--population", "2", "--generations", "2",
          "--seeds", "0", "--steps", "200", "--space", "bias", "--workers", "1",
          "--no-progress"]


def start(args, out, storage):
    """`ebrl ARGS --out OUT --storage STORAGE` started as a real process (its own group)."""
    return subprocess.Popen([sys.executable, "-m", "experiments", *map(str, args), "--out",
                             str(out), "--storage", storage], cwd=ROOT, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)


def finish(proc, timeout=300):
    out, err = proc.communicate(timeout=timeout)
    assert proc.returncode == 0, f"exit {proc.returncode}:\n{out}\n{err}"
    return out, err


def load(url, name):
    """The study as the workers open it (under their lock: a reader that made the tables
    beside them would race them)."""
    from experiments.studies import study
    return study.load(name, url, ".", create=False)


def check_shared(s, n, out):
    """n complete trials, numbers once each, no trial left running, no setting run by
    two trials (so no run made twice), and every run folder a trial's."""
    import optuna
    trials = s.get_trials(deepcopy=False)
    numbers = [t.number for t in trials]
    assert len(numbers) == len(set(numbers))
    complete = [t for t in trials if t.state == optuna.trial.TrialState.COMPLETE]
    assert len(complete) == n, "\n".join(
        f"{t.number} {t.state.name} {t.params} {t.user_attrs.get('error')} "
        f"{t.system_attrs.get('ebrl:worker', {}).get('pid')} "
        f"gen={t.system_attrs.get('cma:generation')} {t.datetime_start} {t.datetime_complete}"
        for t in trials)
    assert not [t for t in trials if t.state in (optuna.trial.TrialState.RUNNING,
                                                 optuna.trial.TrialState.WAITING)]
    settings = [json.dumps(t.params, sort_keys=True) for t in complete]
    assert len(settings) == len(set(settings)), "a setting was run by two trials"
    folders = {f for t in complete for f in t.user_attrs["folders"]}
    assert folders == {p.name for p in (pathlib.Path(out) / "runs").iterdir()}
    return complete


def claimant(url, name, procs):
    """The process of procs that runs a trial of the study now (None: none does)."""
    import optuna

    from experiments.studies import study
    try:
        s = load(url, name)
    except KeyError:  # the study not made yet
        return None
    pids = {t.system_attrs.get(study.storage.WORKER, {}).get("pid") for t in s.get_trials(
        deepcopy=False, states=(optuna.trial.TrialState.RUNNING,))}
    return next((p for p in procs if p.pid in pids), None)


def kill_mid_trial(procs, url, name, timeout=120):
    """SIGKILLs (with its run workers) the first of procs seen running a trial of its own;
    returns it."""
    deadline = time.time() + timeout
    while (proc := claimant(url, name, procs)) is None:
        assert all(p.poll() is None for p in procs) and time.time() < deadline, \
            "no trial ever ran"
        time.sleep(0.1)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    return proc


def interrupted(s, complete):
    """The trials a kill interrupted: failed, marked so, their settings run again."""
    import optuna

    from experiments.studies import study
    cut = [t for t in s.get_trials(deepcopy=False) if t.user_attrs.get("error") == study.INTERRUPTED]
    assert cut and all(t.state == optuna.trial.TrialState.FAIL for t in cut)
    again = {json.dumps(t.params, sort_keys=True) for t in complete}
    assert all(json.dumps(t.params, sort_keys=True) in again for t in cut)
    return cut


def clean_values(problem, trials, out):
    """{settings: value} of the trials' settings from one clean worker: a fresh SQLite
    study run by the study runner, in a fresh folder."""
    from experiments.studies import study
    s = study.load("clean", None, out, sampler=None)
    for t in trials:
        s.enqueue_trial(t.params)
    study.optimize(problem, s, out, len(trials), batch=2, workers=1, progress=False)
    return {json.dumps(t.params, sort_keys=True): t.value for t in s.trials}


def test_two_fit_workers_on_a_fresh_database_one_killed_mid_trial(postgres_url, tmp_path):
    """Started at once on a fresh database (they race to make its tables); one killed
    mid-trial while the other carries on, then started again: the study ends with the
    trials asked, each number once, no setting run twice, the killed trials' settings
    asked again, and each trial's value the one a clean worker gives its settings."""
    from experiments.studies import fit
    out = tmp_path / "fit"
    workers = [start(FIT, out, postgres_url), start(FIT, out, postgres_url)]
    killed = kill_mid_trial(workers, postgres_url, "fit")
    workers[workers.index(killed)] = start(FIT, out, postgres_url)  # the same command again
    outputs = [finish(w) for w in workers]
    assert all(err.strip() == "" for _, err in outputs), outputs
    s = load(postgres_url, "fit")
    complete = check_shared(s, 6, out)
    assert min(t.number for t in s.trials) == 0 and s.trials[0].params == {
        "policy_threshold": fit.default("policy_threshold")}  # the defaults, enqueued once
    interrupted(s, complete)
    problem = fit.Problem(names=("policy_threshold",), rungs=((0,),), steps=200)
    want = clean_values(problem, complete, tmp_path / "clean")
    assert {json.dumps(t.params, sort_keys=True): t.value for t in complete} == want


def test_two_evolve_workers_keep_cma_generations_through_a_kill(postgres_url, tmp_path):
    from experiments.studies import evolve
    from tasks.robots import ROBOTS
    out = tmp_path / "evolve"
    name = "evolve-two_wheel"
    workers = [start(EVOLVE, out, postgres_url), start(EVOLVE, out, postgres_url)]
    killed = kill_mid_trial(workers, postgres_url, name)
    workers[workers.index(killed)] = start(EVOLVE, out, postgres_url)
    for w in workers:
        finish(w)
    s = load(postgres_url, name)
    complete = check_shared(s, 5, out)
    interrupted(s, complete)
    # Generations stay generations: the starting genome alone, then two of 2 trials each,
    # every trial of a generation sampled from the one before it (CMA-ES's own record).
    by_generation = {}
    for t in complete:
        by_generation.setdefault(evolve.generation(t), []).append(t.number)
    assert {g: len(v) for g, v in by_generation.items()} == {0: 1, 1: 2, 2: 2}, [
        (t.number, t.state.name, t.user_attrs.get("error"), t.system_attrs.get("ebrl:worker"),
         t.system_attrs.get("cma:generation"), t.datetime_start.time(), t.datetime_complete)
        for t in s.get_trials(deepcopy=False)]
    assert max(by_generation[1]) < min(by_generation[2])
    start_genome = evolve.paper_genome(ROBOTS["two_wheel"])
    problem = evolve.Problem("two_wheel", start_genome, ("bias",), (0,), 200, population=2)
    first = next(t for t in complete if t.number == by_generation[0][0])
    assert first.params == problem.x0()  # generation 0: the starting genome (maybe asked again)
    want = clean_values(problem, complete, tmp_path / "clean")
    assert {json.dumps(t.params, sort_keys=True): t.value for t in complete} == want
    assert (out / f"{name}.md").exists()


SECRET = "S3cret-pw"


def with_password(url):
    """The URL with a password (the test server trusts its socket: any is accepted)."""
    return url.replace("postgresql://postgres@", f"postgresql://postgres:{SECRET}@")


def test_no_password_in_any_output_of_a_study(postgres_url, tmp_path):
    out = tmp_path / "fit"
    url = with_password(postgres_url)
    args = [a for a in FIT if a != "--no-progress"] + ["--trials", "2"]  # the progress bar too
    proc = start(args, out, url)
    stdout, stderr = finish(proc)
    assert "postgres:***@" in stdout
    from experiments.studies import study
    s = load(postgres_url, "fit")
    o = study.opened(s)
    stored = json.dumps([[t.user_attrs, t.system_attrs] for t in s.trials]
                        + [s.user_attrs, o.storage.get_study_system_attrs(o.study_id)])
    files = [p.read_bytes() for p in out.rglob("*") if p.is_file()]
    for text in [stdout, stderr, stored] + files:
        assert SECRET not in (text.decode(errors="replace") if isinstance(text, bytes) else text)
    # A server that cannot be reached: one line, the password hidden.
    bad = ebrl_here("fit", "--storage", f"postgresql://ebrl:{SECRET}@127.0.0.1:1/db", "--out",
                    tmp_path / "bad", "--no-progress")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1, bad.stderr
    assert "cannot open the study storage postgresql+psycopg://ebrl:***@127.0.0.1:1/db" \
        in bad.stderr and SECRET not in bad.stderr + bad.stdout


def test_a_lost_database_is_one_line_and_the_same_command_resumes(postgres_url, postgres_server,
                                                                   tmp_path):
    import psycopg
    out = tmp_path / "fit"
    db = postgres_url.split("?")[0].rsplit("/", 1)[1]
    url = with_password(postgres_url)
    args = [x if x != "6" else "4" for x in FIT]  # 4 trials
    proc = start(args, out, url)
    deadline = time.time() + 120
    while claimant(postgres_url, "fit", [proc]) is None:
        assert proc.poll() is None and time.time() < deadline
        time.sleep(0.1)
    with psycopg.connect(host=str(postgres_server), user="postgres", dbname="postgres",
                         autocommit=True) as c:  # the database goes away mid-trial
        c.execute(f"ALTER DATABASE {db} ALLOW_CONNECTIONS false")
        c.execute("SELECT pg_terminate_backend(pid) FROM pg_stat_activity WHERE datname = %s",
                  (db,))
    stdout, stderr = proc.communicate(timeout=120)
    lines = stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1, stderr
    assert lines[0].startswith("ebrl: error: lost the study storage postgresql+psycopg://"
                               "postgres:***@/") and "rerun the same command" in lines[0]
    assert SECRET not in stdout + stderr
    with psycopg.connect(host=str(postgres_server), user="postgres", dbname="postgres",
                         autocommit=True) as c:
        c.execute(f"ALTER DATABASE {db} ALLOW_CONNECTIONS true")
    finish(start(args, out, url))  # the same command resumes
    check_shared(load(postgres_url, "fit"), 4, out)
