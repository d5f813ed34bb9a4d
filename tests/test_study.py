"""experiments.studies.study on a real SQLite storage, in this process: a trial whose
worker is on another machine is failed by its stale heartbeat (Optuna's own check) and its
settings asked again; one whose process is gone from this machine is failed at once; one
whose worker lives is left alone. No attribute is added to Optuna's Study."""
import os
import subprocess
import sys
import time

import pytest

optuna = pytest.importorskip("optuna")
pytestmark = [pytest.mark.filterwarnings("ignore:Heartbeat of storage:UserWarning"),
              pytest.mark.slow]  # the slow tier: study workers and their heartbeats


@pytest.fixture
def quick(monkeypatch):
    """The study module with a one-second heartbeat and grace (Optuna's least: its
    storage's, experiments.studies.storage)."""
    from experiments.studies import storage, study
    monkeypatch.setattr(storage, "HEARTBEAT", 1)
    monkeypatch.setattr(storage, "GRACE", 1)
    return study


def running(study, s, worker):
    """A trial asked and claimed as worker (host and pid) with a heartbeat now."""
    t = s.ask({"x": optuna.distributions.FloatDistribution(0.0, 1.0)})
    o = study.opened(s)
    o.storage.set_trial_system_attr(o.trial_id(t), study.storage.WORKER, worker)
    o.storage.record_heartbeat(o.trial_id(t))
    return t


def test_a_lost_machines_trial_is_failed_by_its_stale_heartbeat_and_asked_again(quick, tmp_path):
    study = quick
    s = study.load("lost", None, tmp_path)
    assert set(vars(s)) == set(vars(optuna.load_study(study_name="lost", storage=study.storage_url(
        None, tmp_path))))  # nothing of ours on Optuna's object
    elsewhere = running(study, s, {"host": "elsewhere/boot", "pid": 1})
    here = running(study, s, {"host": study.machine(), "pid": os.getpid()})
    assert study.rescue(s) == [] and len(s.get_trials(states=(optuna.trial.TrialState.RUNNING,))) == 2
    time.sleep(2.5)  # the other machine's heartbeat goes stale (SQLite's clock: seconds)
    o = study.opened(s)
    o.storage.record_heartbeat(o.trial_id(here))  # this worker's trial still beats
    assert study.rescue(s) == []  # failed by Optuna's heartbeat check, not this module's
    trials = {t.number: t for t in s.get_trials()}
    assert trials[elsewhere.number].state == optuna.trial.TrialState.FAIL
    assert study.interrupted(trials[elsewhere.number])
    assert trials[here.number].state == optuna.trial.TrialState.RUNNING
    waiting = [t for t in trials.values() if t.state == optuna.trial.TrialState.WAITING]
    assert [t.system_attrs["fixed_params"] for t in waiting] == [elsewhere.params]


def test_a_trial_whose_process_is_gone_is_failed_marked_and_asked_again(quick, tmp_path):
    study = quick
    s = study.load("killed", None, tmp_path)
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    t = running(study, s, {"host": study.machine(), "pid": int(gone)})
    assert study.rescue(s) == [t.number]
    cut = s.get_trials()[t.number]
    assert cut.state == optuna.trial.TrialState.FAIL and cut.user_attrs["error"] == study.INTERRUPTED
    assert study.interrupted(cut)
    assert s.get_trials()[-1].system_attrs["fixed_params"] == t.params


def test_a_study_not_opened_by_load_is_refused_in_one_line(tmp_path):
    from experiments.studies import study
    s = optuna.create_study()
    with pytest.raises(ValueError, match="not opened by experiments.studies.study.load"):
        study.opened(s)
