"""Runs a set of specs on a local process pool (spawn) or a Ray cluster.

Workers only compute (`protocol.execute`); the driver writes each run as it
arrives, so any worker count and either backend give identical files, and a run
killed at any moment leaves only an unfinished folder that the next call redoes.

A run that raises is recorded as failed (results.write_failure: run.json with
status "failed" and the error) while the others go on; a rerun retries it. A
worker process that dies takes the pool with it: the runs it held are then run
again one at a time, so only the one that kills its worker is recorded as failed.
Ctrl-C stops the local pool's workers at once; finished runs stay on disk.

Test only: EBRL_TEST_FAIL="two_wheel/avoidance/1,floating/random/0" makes those
runs (robot/condition/seed) raise a dm_control PhysicsError in the worker, and
EBRL_TEST_CRASH, with the same syntax, makes their pool worker process exit
abruptly; both exist for the tests of failure handling and are never set otherwise.
"""
import collections
import os
import signal
import threading
import time

from experiments import protocol, results

# One BLAS thread per worker: the agent's products are small, and parallelism
# comes from running several seeds at once. Set before workers import numpy.
_SINGLE_THREAD = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                   "MKL_NUM_THREADS")}
TEST_FAIL, TEST_CRASH = "EBRL_TEST_FAIL", "EBRL_TEST_CRASH"

#: What run() did: runs made now, runs already on disk, and (spec, error) per failed run.
Ran = collections.namedtuple("Ran", "made on_disk failed")


def plan(robots, conditions, seeds, steps=None, overrides=(), drive=None, agent="ebrl"):
    """Specs in the order to start them: the longest first, for an even finish.

    steps: None for each robot's budget (the registry's), a number for all, or a dict
    by robot; drive: for robots given as files."""
    from tasks.robots import resolve

    def budget(robot):
        if isinstance(steps, dict):
            return steps[robot]
        return steps if steps is not None else resolve(robot, drive).budget

    specs = [protocol.RunSpec(r, c, s, budget(r), tuple(sorted(dict(overrides).items())),
                              drive, agent)
             for r in robots for c in conditions for s in seeds]
    return sorted(specs, key=lambda s: -s.steps)


def folder_of(out):
    """out as a function spec -> results folder: a folder for every spec, or a function
    already (a study keeps each setting's runs in its own folder)."""
    return out if callable(out) else (lambda spec: out)


def pending(out, specs):
    """The specs without a matching complete run under out (a folder, or a function
    spec -> folder), failed ones included (ResultsError if damaged)."""
    where = folder_of(out)
    return [s for s in specs if results.existing(where(s), s) != "done"]


def _selected(variable, spec):
    """Whether the test-only variable names spec as robot/condition/seed."""
    wanted = {w.strip() for w in os.environ.get(variable, "").split(",")}
    return f"{spec.label}/{spec.condition}/{spec.seed}" in wanted


def _execute(spec):
    if _selected(TEST_FAIL, spec):
        from dm_control.rl.control import PhysicsError
        raise PhysicsError(f"failure injected by {TEST_FAIL} (test only) in {spec.name}")
    if _selected(TEST_CRASH, spec) and _in_worker():
        os._exit(70)
    return protocol.execute(spec)


def _in_worker():
    import multiprocessing
    return multiprocessing.parent_process() is not None


def run(specs, out, *, workers=None, backend="local", progress=True):
    """Runs the specs not yet done under out (a folder, or a function spec -> folder;
    failed ones again); returns a Ran."""
    where = folder_of(out)
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
        if error is not None:
            failed.append((spec, results.write_failure(where(spec), spec, error)))
        else:
            results.write_run(where(spec), spec, result, versions)
            steps_done += spec.steps
        if bar is not None:
            rate = steps_done / max(time.perf_counter() - started, 1e-9)
            bar.set_postfix_str(f"{rate:,.0f} steps/s, {steps_done:,}/{total_steps:,} steps"
                                + (f", {len(failed)} failed" if failed else ""))
            bar.update(1)

    try:
        if backend == "ray":
            _run_ray(todo, workers, done)
        else:
            _run_local(todo, workers, done)
    finally:
        if bar is not None:
            bar.close()
    return Ran(len(todo) - len(failed), len(specs) - len(todo), failed)


def _run_local(specs, workers, done):
    workers = workers or os.cpu_count() or 1
    if workers == 1:
        for spec in specs:
            try:
                result = _execute(spec)
            except Exception as e:  # recorded; KeyboardInterrupt goes through
                done(spec, error=e)
            else:
                done(spec, result)
        return
    saved = {k: os.environ.get(k) for k in _SINGLE_THREAD}
    os.environ.update(_SINGLE_THREAD)
    try:
        queue = list(specs)
        while queue:
            lost, queue = _pool(queue, workers, done)
            for spec in lost:  # a worker died: each of its pool's runs again, alone
                for again in _pool([spec], 1, done)[0]:
                    done(again, error=WorkerDied(f"the worker process running {again.name} "
                                                 "died (killed, out of memory or crashed)"))
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


class WorkerDied(RuntimeError):
    """A run whose worker process ended without returning (killed, a crash)."""


def _pool(specs, workers, done):
    """Runs specs, in order, on a fresh spawn pool with at most `workers` in flight.
    Returns (runs lost because a worker died, runs not started then); ([], []) when
    every run was done or recorded as failed."""
    import concurrent.futures
    import multiprocessing
    from concurrent.futures.process import BrokenProcessPool
    pool = concurrent.futures.ProcessPoolExecutor(
        workers, mp_context=multiprocessing.get_context("spawn"))
    queue, running, lost, broken = list(reversed(specs)), {}, [], False

    def fill():  # keeps `workers` runs in flight, so a dead worker loses few
        nonlocal broken
        while queue and not broken and len(running) < workers:
            spec = queue.pop()
            try:
                running[_submit(pool, spec)] = spec
            except BrokenProcessPool:  # a worker died since the last wait
                queue.append(spec)
                broken = True

    try:
        fill()
        while running:
            finished, _ = concurrent.futures.wait(
                running, return_when=concurrent.futures.FIRST_COMPLETED)
            finished = [(future, running.pop(future)) for future in finished]
            fill()  # before writing the results, so that no worker waits for the disk
            for future, spec in finished:
                try:
                    result = future.result()
                except BrokenProcessPool:
                    lost.append(spec)
                    broken = True
                except Exception as e:
                    done(spec, error=e)
                else:
                    done(spec, result)
            fill()
    except BaseException:  # Ctrl-C, or a result that cannot be written: stop the workers now
        _stop(pool)
        raise
    pool.shutdown(wait=True)
    return lost, list(reversed(queue))


def _submit(pool, spec):
    """pool.submit, with SIGINT ignored while it may start a worker process: the worker
    inherits the ignored SIGINT, so a Ctrl-C at the terminal reaches the driver alone
    (which then stops the workers) and never prints a worker's traceback."""
    if threading.current_thread() is not threading.main_thread():
        return pool.submit(_execute, spec)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        return pool.submit(_execute, spec)
    finally:
        signal.signal(signal.SIGINT, previous)


def _stop(pool):
    """Terminates the pool's worker processes and shuts it down without waiting for
    the runs in flight (lost: their folders hold no run.json, so a rerun redoes them)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C while stopping
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for p in processes:
        p.terminate()
    pool.shutdown(wait=False, cancel_futures=True)
    for p in processes:
        p.join(5)


def _run_ray(specs, workers, done):
    try:
        import ray
    except ImportError:
        raise SystemExit("error: --backend ray needs Ray: pip install -e '.[ray]'") from None
    started_here = not ray.is_initialized()
    if started_here:
        address = os.environ.get("RAY_ADDRESS") or None
        kwargs = {"address": address, "include_dashboard": False, "log_to_driver": False,
                  "runtime_env": {"env_vars": _SINGLE_THREAD}}
        if address is None:
            kwargs["num_cpus"] = workers or os.cpu_count() or 1
        ray.init(**kwargs)
    try:
        remote = ray.remote(num_cpus=1)(_execute)
        refs = {remote.remote(s): s for s in specs}
        waiting = list(refs)
        while waiting:
            ready, waiting = ray.wait(waiting, num_returns=1)
            try:
                result = ray.get(ready[0])
            except Exception as e:  # a RayTaskError: the worker's traceback, its error as .cause
                done(refs[ready[0]], error=e)
            else:
                done(refs[ready[0]], result)
    finally:
        if started_here:
            ray.shutdown()
