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
"""
import dataclasses
import hashlib
import json
import pathlib

from experiments.running import results, runner

#: The storage used when none is given: an SQLite file in the study's folder.
DEFAULT_STORAGE = "study.db"


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


def storage_url(storage, out):
    """--storage as an Optuna URL: a URL as it is; a plain path, an SQLite file."""
    storage = storage or str(pathlib.Path(out) / DEFAULT_STORAGE)
    return storage if "://" in storage else f"sqlite:///{pathlib.Path(storage).resolve()}"


def load(name, storage, out, seed=0, create=True, sampler=None):
    """The study `name` in the storage (made when missing and create), minimising; with
    the sampler given, else a seeded TPE sampler."""
    import optuna
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    if sampler is None:
        sampler = optuna.samplers.TPESampler(seed=seed, multivariate=True,
                                             constant_liar=True, n_startup_trials=20)
    url = storage_url(storage, out)
    if not create:
        return optuna.load_study(study_name=name, storage=url, sampler=sampler)
    return optuna.create_study(study_name=name, storage=url, sampler=sampler,
                               direction="minimize", load_if_exists=True)


def _rescue(study):
    """Trials left running by a kill: failed, and their settings enqueued again."""
    import optuna
    running = study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.RUNNING,))
    for t in running:
        # Optuna has no public way to mark a trial it did not start in this process:
        # its storage and trial id (private in Optuna's API) are the only handle.
        study._storage.set_trial_user_attr(t._trial_id, "error", INTERRUPTED)
        study.tell(t.number, state=optuna.trial.TrialState.FAIL)
        study.enqueue_trial(t.params, skip_if_exists=False)
    return len(running)


INTERRUPTED = "interrupted; asked again"


def _finished(study):
    """The trials that count towards n_trials: complete, or failed by their runs (not
    those a kill interrupted, whose settings were asked again)."""
    import optuna
    return [t for t in study.get_trials(deepcopy=False)
            if t.state == optuna.trial.TrialState.COMPLETE or (
                t.state == optuna.trial.TrialState.FAIL
                and t.user_attrs.get("error") != INTERRUPTED)]


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


def optimize(problem, study, out, n_trials, *, batch=4, workers=None, backend="local",
             promote=0.1, progress=True):
    """Runs trials until the study holds n_trials finished ones (complete, or failed by
    their runs); returns an Outcome."""
    import optuna
    out = pathlib.Path(out)
    _rescue(study)
    where = lambda spec: run_folder(out, spec)  # noqa: E731
    made, failed = 0, []
    bar = None
    if progress:
        from tqdm import tqdm
        done_before = len(_finished(study))
        bar = tqdm(total=n_trials, initial=min(done_before, n_trials), unit="trial",
                   dynamic_ncols=True, desc=f"study {study.study_name}")
    try:
        while len(_finished(study)) < n_trials:
            k = min(batch, n_trials - len(_finished(study)))
            if hasattr(problem, "sampler"):
                study.sampler = problem.sampler(len(study.get_trials(deepcopy=False)))
            trials = [study.ask(problem.distributions()) for _ in range(k)]
            rung_values = {t.number: [] for t in trials}
            alive = list(trials)
            errors = {}
            for depth, seeds in enumerate(problem.rungs):
                if not alive:
                    break
                specs = {t.number: problem.specs(t.params, seeds) for t in alive}
                all_specs = sorted({s for v in specs.values() for s in v}, key=lambda s: -s.steps)
                ran = runner.run(all_specs, where, workers=workers, backend=backend,
                                 progress=False)
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
            for t in trials:
                if t.number in errors:
                    t.set_user_attr("error", errors[t.number][0])
                    t.set_user_attr("failed_runs", errors[t.number])
                    study.tell(t, state=optuna.trial.TrialState.FAIL)
                    failed.append((t.number, errors[t.number][0]))
                else:
                    rungs = rung_values[t.number]
                    t.set_user_attr("rungs", rungs)
                    t.set_user_attr("folders", sorted({run_folder(out, s).name for s in
                                                       problem.specs(t.params, problem.rungs[0])}))
                    study.tell(t, rungs[0]["value"])
                made += 1
                if bar is not None:
                    bar.update(1)
                    best = best_trials(study, 1)
                    if best:
                        bar.set_postfix_str(f"best #{best[0].number}: {deepest(best[0])['value']:.3g} "
                                            f"on {len(deepest(best[0])['seeds'])} seeds"
                                            + (f", {len(failed)} failed" if failed else ""))
    finally:
        if bar is not None:
            bar.close()
    return Outcome(made, len(study.trials), failed)


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
