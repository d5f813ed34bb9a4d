"""One study runner for `ebrl fit` (the readings against the paper's table) and `ebrl
evolve`: an Optuna study in a storage URL (SQLite by default), asked and told in batches,
every trial's runs made by experiments.running.runner (so --workers and --backend ray work) and
written to disk as `ebrl run` writes them.

A problem (experiments.studies.fit.Problem, say) gives four things: its search space (Optuna
distributions), the runs of a trial's settings on some seeds, a score of those runs (the
value to minimise, and the figures to record), and the rungs of seeds. A trial runs on the
first rung's seeds; a trial whose value is among the best `promote` share of the study so
far runs again on the next rung's seeds too (the runs it already has are kept), and its
value and figures are then the larger rung's. The value told to the sampler is the first
rung's, so that every trial is judged on the same seeds; the deeper rungs are recorded as
user attributes ("rungs"), from which the best trials are ranked.

Runs live under OUT/runs/<key>/, one folder per setting of a robot (its overrides), so a
run that two trials share (the two-wheel robot's when only a floating reading differs, a
repeated setting, a promotion's first seeds) is made once. Each trial records its figures,
its claims and its runs' folders as user attributes, so any other objective can be
recomputed from the storage without running again.

A problem may also give sampler(n): a fresh Optuna sampler for a batch that starts when
the study holds n trials (`ebrl evolve`'s CMA-ES), so a study resumed at a batch's
boundary samples as one that never stopped; without it the study keeps load()'s seeded
TPE sampler (`ebrl fit`). A spec's genome (RunSpec.behaviour) is part of its folder key.

Resume: the same command continues the study. Trials left running by a kill or Ctrl-C are
marked failed and their settings asked again first, so their finished runs are reused. A
trial whose runs failed is marked failed (not scored) with the errors in its attributes.

Several workers (the same command on several machines, one storage URL, PostgreSQL say)
share a study. Each records who runs a trial (host and process) and a heartbeat every
storage.HEARTBEAT seconds while it runs; a trial left running is taken as dead, and asked again,
when its process is gone from this machine or no worker claimed it (one killed between
asking and claiming): failed, marked INTERRUPTED; or when its heartbeat is older than GRACE
seconds (a machine that died): failed by Optuna's own heartbeat check
(optuna.storages.fail_stale_trials, RDBStorage's heartbeat_stale_trial_callback). The
steps that must not interleave (making the storage's tables,
the first trial, rescuing, asking a batch) run under one lock: a PostgreSQL advisory lock,
or a file lock beside an SQLite file. A worker asks no more trials than the study lacks
beside those the others run, and waits for theirs before it ends; a problem with its own
sampler (`ebrl evolve`'s CMA-ES generations) has a batch asked only when no trial runs,
so that a generation is asked whole, by one worker, from the trials before it.

A storage that fails while a study runs (a lost database connection) is StorageError: one
line, the finished trials kept, the same command resumes. A URL is shown with its password
hidden (shown()); keep it out of the command line with libpq's ~/.pgpass or PGPASSWORD.

Optuna through its public API only (checked on Optuna 5.0.0): its Study, and the
RDBStorage this module makes and keeps in its own Opened record beside the Study (found
with opened(study); nothing is added to Optuna's objects): trial ids from
get_trial_id_from_study_id_trial_number, the trials as stored from get_all_trials, trial
attributes from set_trial_user_attr and set_trial_system_attr, heartbeats from
record_heartbeat, stale ones failed by fail_stale_trials.
"""
import contextlib
import dataclasses
import hashlib
import json
import os
import pathlib
import socket
import threading
import time
import warnings

from experiments.running import results, runner
from experiments.studies import storage
from experiments.studies.storage import (  # noqa: F401  the storage's names, as study's
    DEFAULT_STORAGE, StorageError, hide, load, opened, shown, storage_errors, storage_url, tpe)

@dataclasses.dataclass
class Outcome:
    """What a study did in one call."""
    made: int      # trials finished now (complete or failed)
    total: int     # trials in the study now
    failed: list   # (trial number, first error) of trials failed now


def folder_key(overrides, behaviour=None):
    """A run setting's folder name: a digest of its overrides (sorted pairs) and, when
    it has one, its genome (ebrl.behaviour)."""
    text = json.dumps([list(kv) for kv in overrides], sort_keys=True)
    if behaviour is not None:
        from ebrl.behaviour import to_dict
        text += json.dumps(to_dict(behaviour), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:12]


def run_folder(out, spec):
    return pathlib.Path(out) / "runs" / folder_key(spec.overrides, spec.behaviour)


def machine():
    """This machine: its name and boot (a process id means something only on it)."""
    try:
        boot = pathlib.Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    except OSError:
        boot = ""
    return f"{socket.gethostname()}/{boot}"


def _alive(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _dead(t, host):
    """Whether a running trial's worker is gone as this machine can tell: its process gone
    from this machine, or no worker claimed it."""
    who = t.system_attrs.get(storage.WORKER)
    if who and who.get("host") == host:
        return who.get("pid") != os.getpid() and not _alive(who.get("pid"))
    # Unclaimed: its worker died between asking and claiming it under the lock (or it was
    # asked by something else, an older version, say): no one runs it.
    return not who


def rescue(study):
    """Trials whose worker is gone (a kill, a lost machine): failed, and their settings
    enqueued again; the numbers of those failed here (those of a machine that died are
    failed by their stale heartbeat, in Optuna's fail_stale_trials). Call under the lock."""
    import optuna
    o = opened(study)
    host = machine()
    dead = [t for t in _now(study, (optuna.trial.TrialState.RUNNING,)) if _dead(t, host)]
    for t in dead:
        o.storage.set_trial_user_attr(o.trial_id(t), "error", INTERRUPTED)
        study.tell(t.number, state=optuna.trial.TrialState.FAIL)
        study.enqueue_trial(t.params, skip_if_exists=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        optuna.storages.fail_stale_trials(study)  # their settings: _ask_again
    return [t.number for t in dead]


def _claim(study, trials):
    """Records this worker (host and process) and a first heartbeat for each trial."""
    o = opened(study)
    me = {"host": machine(), "pid": os.getpid()}
    for trial_id in map(o.trial_id, trials):
        o.storage.set_trial_system_attr(trial_id, storage.WORKER, me)
        o.storage.record_heartbeat(trial_id)


@contextlib.contextmanager
def _heartbeats(study, trials):
    """Records a heartbeat for each trial every HEARTBEAT seconds while the block runs."""
    o = opened(study)
    ids = [o.trial_id(t) for t in trials]
    stop = threading.Event()

    def beat():
        while not stop.wait(storage.HEARTBEAT):
            for trial_id in ids:
                try:
                    o.storage.record_heartbeat(trial_id)
                except Exception:  # a lost connection: the main thread's next call says so
                    pass
    thread = threading.Thread(target=beat, daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()


INTERRUPTED = "interrupted; asked again"


def _now(study, states=None):
    """The study's trials as the storage holds them now (not through Optuna's cache of
    them, which another worker's trials can pass by), in the given states."""
    o = opened(study)
    return o.storage.get_all_trials(o.study_id, deepcopy=False, states=states)


def interrupted(trial):
    """Whether a trial was cut by a kill (its settings asked again): failed, and marked
    INTERRUPTED by rescue(), or failed by its stale heartbeat before any score or error
    was recorded (fail_stale_trials can mark nothing: Optuna refuses to edit a finished
    trial)."""
    import optuna
    error = trial.user_attrs.get("error")
    return trial.state == optuna.trial.TrialState.FAIL and (
        error == INTERRUPTED or (error is None and "rungs" not in trial.user_attrs))


def _finished(study, trials=None):
    """The trials that count towards n_trials: complete, or failed but not interrupted
    (their runs failed, or Optuna failed a value it refuses, NaN say)."""
    import optuna
    return [t for t in (_now(study) if trials is None else trials)
            if t.state == optuna.trial.TrialState.COMPLETE or (
                t.state == optuna.trial.TrialState.FAIL and not interrupted(t))]


def _promoted(value, study, share):
    """Whether a first-rung value is among the best `share` of the complete trials (at
    least eight of them needed before any promotion)."""
    import optuna
    values = sorted(t.value for t in study.get_trials(
        deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,)))
    if len(values) < 8:
        return False
    cut = values[max(0, int(len(values) * share) - 1)]
    return value <= cut


def _next_batch(problem, study, n_trials, batch):
    """Under the lock: rescues dead workers' trials, then asks this worker's next batch.
    None when the study holds n_trials finished trials; [] when this worker must wait
    (the rest of the study is being run by others, or, for a problem with its own
    sampler, a generation is)."""
    import optuna
    o = opened(study)
    with storage.lock(o.url):
        rescue(study)
        trials = _now(study)
        finished = len(_finished(study, trials))
        if finished >= n_trials:
            return None
        running = sum(t.state == optuna.trial.TrialState.RUNNING for t in trials)
        if hasattr(problem, "sampler"):  # a batch is a generation: asked whole, in turn
            k = 0 if running else ((n_trials - finished) % batch or batch)
            if k:
                study.sampler = problem.sampler(finished)
        else:
            k = min(batch, n_trials - finished - running)
            if k > 0 and o.reseed is not None:
                study.sampler = o.reseed(len(trials))
        with warnings.catch_warnings():  # the heartbeats are this module's, not optimize's
            warnings.filterwarnings("ignore", "Heartbeat of storage", UserWarning)
            # cmaes at --population 2 (one parent: no rank-mu update, cmu = 0) divides by
            # cmu in two of the three bounds it takes the least of (its eq 50-52); the
            # third is finite, so the inf is never used: not the user's concern.
            warnings.filterwarnings("ignore", "divide by zero", RuntimeWarning, "cmaes")
            trials = [study.ask(problem.distributions()) for _ in range(max(k, 0))]
        _claim(study, trials)  # before the lock is let go: no one sees them unclaimed
        return trials


def optimize(problem, study, out, n_trials, *, batch=4, workers=None, backend="local",
             promote=0.1, progress=True):
    """Runs trials until the study holds n_trials finished ones (complete, or failed by
    their runs), with any other workers on the same study; returns an Outcome. A storage
    that fails is StorageError."""
    out = pathlib.Path(out)
    made, failed = 0, []
    bar = None
    with storage_errors(study):
        if progress:
            from tqdm import tqdm
            done_before = len(_finished(study))
            bar = tqdm(total=n_trials, initial=min(done_before, n_trials), unit="trial",
                       dynamic_ncols=True, desc=f"study {study.study_name}")
        try:
            while True:
                trials = _next_batch(problem, study, n_trials, batch)
                if trials is None:
                    break
                if not trials:
                    time.sleep(storage.POLL)
                    if bar is not None:
                        bar.n = min(len(_finished(study)), n_trials)
                        bar.refresh()
                    continue
                with _heartbeats(study, trials):
                    told = _run_batch(problem, study, out, trials, workers, backend, promote)
                for number, error in told:
                    made += 1
                    if error is not None:
                        failed.append((number, error))
                if bar is not None:
                    bar.n = min(len(_finished(study)), n_trials)
                    best = best_trials(study, 1)
                    if best:
                        bar.set_postfix_str(f"best #{best[0].number}: {deepest(best[0])['value']:.3g} "
                                            f"on {len(deepest(best[0])['seeds'])} seeds"
                                            + (f", {len(failed)} failed" if failed else ""))
                    bar.refresh()
        finally:
            if bar is not None:
                bar.close()
        return Outcome(made, len(study.trials), failed)


def _run_batch(problem, study, out, trials, workers, backend, promote):
    """Runs a batch's trials (rung by rung) and tells them; [(number, first error or None)]."""
    import optuna
    where = lambda spec: run_folder(out, spec)  # noqa: E731
    rung_values = {t.number: [] for t in trials}
    alive = list(trials)
    errors = {}
    for depth, seeds in enumerate(problem.rungs):
        if not alive:
            break
        specs = {t.number: problem.specs(t.params, seeds) for t in alive}
        all_specs = sorted({s for v in specs.values() for s in v}, key=lambda s: -s.steps)
        ran = runner.run(all_specs, where, workers=workers, backend=backend, progress=False)
        bad = {s: e for s, e in ran.failed}
        nxt = []
        for t in alive:
            lost = [f"{s.name}: {bad[s]}" for s in specs[t.number] if s in bad]
            if lost:
                errors[t.number] = lost
                continue
            runs = {}
            for s in specs[t.number]:
                runs.update(results.load_runs(where(s), [s]))
            value, attrs = problem.score(t.params, runs)
            rung_values[t.number].append(dict(attrs, value=value, seeds=list(seeds)))
            if depth + 1 < len(problem.rungs) and _promoted(
                    rung_values[t.number][0]["value"], study, promote):
                nxt.append(t)
        alive = nxt
    told = []
    for t in trials:
        if t.number in errors:
            t.set_user_attr("error", errors[t.number][0])
            t.set_user_attr("failed_runs", errors[t.number])
            study.tell(t, state=optuna.trial.TrialState.FAIL)
            told.append((t.number, errors[t.number][0]))
        else:
            rungs = rung_values[t.number]
            t.set_user_attr("rungs", rungs)
            t.set_user_attr("folders", sorted({run_folder(out, s).name for s in
                                               problem.specs(t.params, problem.rungs[0])}))
            study.tell(t, rungs[0]["value"])
            told.append((t.number, None))
    return told


def deepest(trial):
    """A complete trial's record on its largest rung."""
    return trial.user_attrs["rungs"][-1]


def best_trials(study, n=5):
    """The complete trials, the deepest rung first, then by that rung's value."""
    import optuna
    done = [t for t in study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
            if "rungs" in t.user_attrs]
    return sorted(done, key=lambda t: (-len(t.user_attrs["rungs"]), deepest(t)["value"],
                                       t.number))[:n]
