"""A soak of a study shared by several workers (a benchmark, not a test):

    python -m experiments.ops.studysoak [--storage URL] [--trials 60] [--workers 2]
                                           [--every 2-6] [--steps 200] [--seed 1]

`ebrl fit` (tiny trials: one reading, one seed, --steps steps a run) run by --workers
processes on one PostgreSQL study (--storage, or a database on a throwaway server,
experiments.ops.pgserver) while one worker, picked at random, is killed (SIGKILL, its
run workers with it) every few seconds and started again at once; a worker that ends
with exit 0 stays ended. Then every complete trial's settings are run again by one clean
worker in an SQLite study of their own. It prints the figures and exits 1 unless the
shared study holds --trials complete trials, each number once, no setting twice, none
left running, every interrupted trial's settings asked again, and the clean worker's
values equal the shared study's, trial by trial.
"""
import argparse
import json
import os
import pathlib
import random
import signal
import subprocess
import sys
import tempfile
import time
from experiments import ROOT
from experiments.ops import pgserver



def _command(args, out, url):
    return [sys.executable, "-m", "experiments", "fit", "--trials", str(args.trials),
            "--batch", "2", "--seeds", "0", "--promote-seeds", "0", "--space",
            "policy_threshold", "--steps", str(args.steps), "--workers", "1",
            "--no-progress", "--out", str(out), "--storage", url]


def _start(args, out, url):
    return subprocess.Popen(_command(args, out, url), cwd=ROOT, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def shared(args, out, url, rng):
    """The workers, killed at random until every one has ended with exit 0; returns
    (kills, restarts after an error exit, seconds)."""
    t0 = time.monotonic()
    procs = [_start(args, out, url) for _ in range(args.workers)]
    done = [False] * len(procs)
    kills = errors = 0
    lo, hi = args.every
    next_kill = time.monotonic() + rng.uniform(lo, hi)
    while not all(done):
        time.sleep(0.05)
        for i, p in enumerate(procs):
            if done[i] or p.poll() is None:
                continue
            if p.returncode == 0:
                done[i] = True
            else:  # an error exit (not our kill): say so, and start it again
                errors += 1
                err = p.stderr.read().strip().splitlines()
                print(f"worker {i} exit {p.returncode}: {err[-1] if err else ''}", flush=True)
                procs[i] = _start(args, out, url)
        if time.monotonic() >= next_kill:
            live = [i for i, p in enumerate(procs) if not done[i] and p.poll() is None]
            if live:
                i = rng.choice(live)
                try:
                    os.killpg(procs[i].pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                procs[i].wait()
                kills += 1
                procs[i] = _start(args, out, url)
            next_kill = time.monotonic() + rng.uniform(lo, hi)
    return kills, errors, time.monotonic() - t0


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--storage", default=None, help="a PostgreSQL URL (default: a throwaway server)")
    p.add_argument("--trials", type=int, default=60)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--steps", type=int, default=200)
    p.add_argument("--every", type=lambda t: tuple(map(float, t.split("-"))), default=(2.0, 6.0),
                   help="seconds between kills, LO-HI (default 2-6)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--keep", type=pathlib.Path, default=None, help="a folder for the runs")
    args = p.parse_args(argv)
    import contextlib

    with contextlib.ExitStack() as stack:
        url = args.storage
        if url is None:
            url = pgserver.database(stack.enter_context(pgserver.server()), "soak")
        root = args.keep or pathlib.Path(stack.enter_context(tempfile.TemporaryDirectory()))
        return _soak(args, url, root)


def _soak(args, url, root):
    import optuna

    from experiments.studies import fit, study
    rng = random.Random(args.seed)
    kills, errors, seconds = shared(args, root / "shared", url, rng)
    s = study.load("fit", url, root / "shared", create=False)
    trials = s.get_trials(deepcopy=False)
    complete = [t for t in trials if t.state == optuna.trial.TrialState.COMPLETE]
    cut = [t for t in trials if t.user_attrs.get("error") == study.INTERRUPTED]
    left = [t for t in trials if t.state in (optuna.trial.TrialState.RUNNING,
                                             optuna.trial.TrialState.WAITING)]
    key = lambda t: json.dumps(t.params, sort_keys=True)  # noqa: E731
    settings = [key(t) for t in complete]
    asked_again = all(key(t) in set(settings) for t in cut)
    t0 = time.monotonic()
    clean = study.load("clean", None, root / "clean")
    for t in complete:
        clean.enqueue_trial(t.params)
    problem = fit.Problem(names=("policy_threshold",), rungs=((0,),), steps=args.steps)
    study.optimize(problem, clean, root / "clean", len(complete), batch=2, workers=1,
                   progress=False)
    clean_seconds = time.monotonic() - t0
    want = {key(t): t.value for t in clean.trials}
    differ = [t.number for t in complete if want.get(key(t)) != t.value]
    print(f"shared study: {args.workers} workers, {len(complete)} complete trials of "
          f"{args.trials}, {len(trials)} asked, {len(cut)} interrupted by {kills} kills "
          f"(every {args.every[0]:g}-{args.every[1]:g} s), {errors} error exits, "
          f"{len(left)} left running or waiting, {seconds:.0f} s")
    print(f"trial numbers once each: {len({t.number for t in trials}) == len(trials)}; "
          f"settings once each: {len(set(settings)) == len(settings)}; interrupted "
          f"settings asked again: {asked_again}")
    print(f"clean worker: {len(clean.trials)} trials in {clean_seconds:.0f} s; values "
          f"differing: {len(differ)}" + (f" (trials {differ[:10]})" if differ else ""))
    ok = (len(complete) == args.trials and not left and not differ and not errors
          and len(set(settings)) == len(settings) and asked_again
          and len({t.number for t in trials}) == len(trials))
    print("soak:", "pass" if ok else "FAIL")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
