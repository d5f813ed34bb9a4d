"""A study shared by several workers on a real PostgreSQL server (tests/conftest.py's
throwaway cluster): two `ebrl fit` and two `ebrl evolve` processes on one study, one
killed (SIGKILL) mid-trial and restarted, and no password in any output."""
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

from helpers import ROOT, ebrl

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
    import optuna

    from experiments.studies import study
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    return optuna.load_study(study_name=name, storage=study.storage_url(url, "."))


def check_shared(s, n, out):
    """n complete trials, numbers once each, no trial left running, no setting run by
    two trials (so no run made twice), and every run folder a trial's."""
    import optuna
    trials = s.get_trials(deepcopy=False)
    numbers = [t.number for t in trials]
    assert len(numbers) == len(set(numbers))
    complete = [t for t in trials if t.state == optuna.trial.TrialState.COMPLETE]
    assert len(complete) == n
    assert not [t for t in trials if t.state in (optuna.trial.TrialState.RUNNING,
                                                 optuna.trial.TrialState.WAITING)]
    settings = [json.dumps(t.params, sort_keys=True) for t in complete]
    assert len(settings) == len(set(settings)), "a setting was run by two trials"
    folders = {f for t in complete for f in t.user_attrs["folders"]}
    assert folders == {p.name for p in (pathlib.Path(out) / "runs").iterdir()}
    return complete


def test_two_fit_workers_share_one_study_on_a_fresh_database(postgres_url, tmp_path):
    out = tmp_path / "fit"
    a, b = start(FIT, out, postgres_url), start(FIT, out, postgres_url)  # at once: a race
    (out_a, err_a), (out_b, err_b) = finish(a), finish(b)
    assert err_a.strip() == "" and err_b.strip() == "", (err_a, err_b)
    made = [int(o.split()[0]) for o in (out_a, out_b)]
    assert sum(made) == 6 and all(made), (out_a, out_b)  # both worked, 6 trials in all
    complete = check_shared(load(postgres_url, "fit"), 6, out)
    assert complete[0].number == 0  # the defaults, enqueued once
