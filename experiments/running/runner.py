"""Runs a set of specs: plans them, checks them, and runs those not yet on disk on the
local pool (pool.py: worker processes forked from a forkserver) or a Ray cluster
(ray_cluster.py); a worker's task is worker.execute.

Workers only compute (`execution.execute`); the driver writes each run as it
arrives, so any worker count and either backend give identical files, and a run
killed at any moment leaves only an unfinished folder that the next call redoes.

A run that raises is recorded as failed (results.write_failure: run.json with
status "failed" and the error) while the others go on; a rerun retries it. A run whose
worker process dies is run again, and recorded as failed (worker.WorkerDied, with the
signal) if it dies again (pool.run; Ray retries it once, ray_cluster.run); a lost
cluster is one line (ray_cluster.ClusterLost). A results folder that cannot be written
(full, read-only) stops the command (results.WriteError). Ctrl-C stops the local pool's
workers at once; finished runs stay on disk. The test-only hooks are worker.py's and
ray_cluster.py's.
"""
import collections
import dataclasses
import sys
import time

from experiments.running import execution, pool, ray_cluster, results
from tasks.robots import resolve


#: What run() did: runs made now, runs already on disk, and (spec, error) per failed run.
Ran = collections.namedtuple("Ran", "made on_disk failed")


def plan(robots, conditions, seeds, steps=None, overrides=(), drive=None, agent="ebrl",
         first_trial=False, protocol="adopted", room=None):
    """Specs in the order to start them: the longest first, for an even finish.

    steps: None for each robot's budget (the registry's), a number for all, or a dict
    by robot; drive: for robots given as files; first_trial: runs that end at their
    first goal (execution.RunSpec.first_trial); readings: a named protocol
    (tasks.robots.PROTOCOLS: RunSpec.protocol); room: the room (execution.RunSpec.room)."""

    def budget(robot):
        if isinstance(steps, dict):
            return steps[robot]
        return steps if steps is not None else resolve(robot, drive).budget

    specs = [execution.RunSpec(r, c, s, budget(r), tuple(sorted(dict(overrides).items())),
                              drive, agent, first_trial=first_trial, protocol=protocol,
                              room=room)
             for r in robots for c in conditions for s in seeds]
    return sorted(specs, key=lambda s: -s.steps)


def folder_of(out):
    """out as a function spec -> results folder: a folder for every spec, or a function
    already (a study keeps each setting's runs in its own folder)."""
    return out if callable(out) else (lambda spec: out)


def pending(out, specs, mend=True):
    """The specs without a matching complete run under out (a folder, or a function
    spec -> folder), failed and damaged ones included; with mend, a damaged run's files
    are set aside first (results.set_aside: one warning line each). ResultsError for a
    run made with other parameters."""
    where = folder_of(out)
    return [s for s in specs if results.existing(where(s), s, mend=mend) != "done"]


def check(specs):
    """Everything a run needs that the driver can build, built here before any work:
    each distinct robot, protocol, room and settings' configs and model (the model is
    composed into its room: a corridor narrower than the robot is models.rooms.MapError,
    one line), as the driver builds them again to write the run (cached)."""
    seen = set()
    for spec in specs:
        key = dataclasses.replace(spec, condition="random", seed=0, steps=1)
        try:
            if key in seen:
                continue
            seen.add(key)
        except TypeError:  # an unhashable genome: check it each time
            pass
        spec.parameters()


#: Our one-line errors of a bad input (a map, a mount, a robot file), by module and class
#: (looked up only once one is raised, so nothing is imported for them). Raised in a
#: worker, one ends the command as it would in the driver (input_error): every run of the
#: input would fail alike, so none is recorded as a failed run.
INPUT_ERRORS = (("models.rooms", "MapError"), ("tasks.mount.fields", "MountError"),
                ("models", "ContractError"))


def input_error(error):
    """The error (a Ray task error's own .cause) if it is one of INPUT_ERRORS, with no
    worker traceback attached; else None."""
    cause = getattr(error, "cause", None)
    error = cause if isinstance(cause, BaseException) else error
    classes = tuple(getattr(sys.modules.get(module), name, None) for module, name in INPUT_ERRORS)
    if not isinstance(error, tuple(c for c in classes if isinstance(c, type))):
        return None
    error.__cause__, error.__suppress_context__ = None, True
    return error.with_traceback(None)


def run(specs, out, *, workers=None, backend="local", progress=True, written=None):
    """Runs the specs not yet done under out (a folder, or a function spec -> folder;
    failed and damaged ones again), after checking them (check); returns a Ran. A worker
    that raises one of INPUT_ERRORS stops the command with that error. written(spec,
    run, result), if given, is called after each complete run's files are written (a
    study's own record of it: experiments.studies.multiverse_records)."""
    where = folder_of(out)
    check(specs)
    todo = pending(where, specs)
    if not todo:
        return Ran(0, len(specs), [])
    versions = results.versions()
    total_steps = sum(s.steps for s in todo)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(todo), unit="run", dynamic_ncols=True,
                   desc=f"runs ({len(specs) - len(todo)} already on disk)")
    started, steps_done = time.perf_counter(), 0
    failed = []

    def done(spec, result=None, error=None):
        nonlocal steps_done
        if error is not None and input_error(error) is not None:
            raise input_error(error)  # a bad input: the command's one line, exit status 2
        if error is not None:
            failed.append((spec, results.write_failure(where(spec), spec, error)))
        else:
            run = results.write_run(where(spec), spec, result, versions)
            if written is not None:
                written(spec, run, result)
            steps_done += result.get("steps_run", spec.steps)
        if bar is not None:
            rate = steps_done / max(time.perf_counter() - started, 1e-9)
            bar.set_postfix_str(f"{rate:,.0f} steps/s, {steps_done:,}/{total_steps:,} steps"
                                + (f", {len(failed)} failed" if failed else ""))
            bar.update(1)

    try:
        if backend == "ray":
            ray_cluster.run(todo, workers, done)
        else:
            pool.run(todo, workers, done)
    finally:
        if bar is not None:
            bar.close()
    return Ran(len(todo) - len(failed), len(specs) - len(todo), failed)


