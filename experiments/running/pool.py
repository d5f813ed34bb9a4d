"""The local backend: runs on worker processes of this machine, forked from a forkserver
(context), even for one worker, so that a run that kills its process (a segfault in native
code, the out-of-memory killer) cannot take the command with it. A worker process that
dies takes the pool with it: the runs it held run again first on a fresh pool; a run in
flight at a second death is run alone once more (at once, with one worker), and recorded
as failed (worker.WorkerDied, with the signal) if its worker dies then too, so a random
kill costs one restart of the pool and a run that crashes its worker is named. Ctrl-C
stops the workers at once; finished runs stay on disk.
"""
import collections
import os
import signal
import threading

from experiments.running import worker


def run(specs, workers, done):
    """Runs specs on worker processes (context), even for one worker: a run that kills its
    process (a segfault in native code, the out-of-memory killer) is then recorded
    with the signal while the others go on."""
    workers = workers or os.cpu_count() or 1
    with worker.single_threaded():
        queue, deaths = list(specs), collections.Counter()
        while queue:
            lost, rest, exits = _pool(queue, workers, done)
            deaths.update(lost)
            # A run whose worker died runs again first. One in flight at two deaths is a
            # suspect: alone already (one worker), recorded; else it runs once more alone.
            if workers == 1:
                for spec in [s for s in lost if deaths[s] >= 2]:
                    done(spec, error=worker.WorkerDied.of(spec, exits[0] if exits else None))
            suspects = [s for s in lost if deaths[s] >= 2 and workers > 1]
            queue = [s for s in lost if deaths[s] < 2] + rest
            while suspects:  # one at a time on one worker, so a death names its run
                again, suspects, exits = _pool(suspects, 1, done)
                for spec in again:
                    done(spec, error=worker.WorkerDied.of(spec, exits[0] if exits else None))


#: What the pool's server process imports once, before it forks each worker
#: (experiments/running/preload.py): the worker, the simulator, the kernels and the agent a
#: run loads, and numba's CPU target started. The worker module is light (the command line
#: imports it) and does not pull them in, so without them each worker would import MuJoCo,
#: dm_control and numba again (docs/speed.md, "The test suite's time").
PRELOAD = ["experiments.running.preload"]


def context():
    """The pool's start method: forkserver (where the platform has it; else spawn). Each
    worker is forked from one server process per command that has imported PRELOAD, where
    a spawned worker would start a fresh interpreter and import them itself; a study, which
    makes a pool per batch, saves that at every batch (the cost: docs/speed.md, "The test
    suite's time"). The server is started from _submit, SIGINT ignored, so its workers
    ignore SIGINT as spawned ones did. It lives as long as the process that started it,
    and its workers get the environment it had then (with worker.SINGLE_THREAD): a
    variable set later in the same process reaches no worker. The workers are the server's
    children, not the command's (experiments.ops.procs.pool_workers finds them)."""
    import multiprocessing
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(PRELOAD)
    return context


def _pool(specs, workers, done):
    """Runs specs, in order, on a fresh pool (context) with at most `workers` in flight.
    Returns (runs lost because a worker died, runs not started then, the exit codes of
    the worker processes that ended abnormally); ([], [], ...) when every run was done
    or recorded as failed."""
    import concurrent.futures
    from concurrent.futures.process import BrokenProcessPool
    pool = concurrent.futures.ProcessPoolExecutor(workers, mp_context=context())
    queue, running, lost, broken = list(reversed(specs)), {}, [], False
    processes = {}  # every worker process the pool started (it forgets them at shutdown)

    def fill():  # keeps `workers` runs in flight, so a dead worker loses few
        nonlocal broken
        while queue and not broken and len(running) < workers:
            spec = queue.pop()
            try:
                running[_submit(pool, spec)] = spec
            except BrokenProcessPool:  # a worker died since the last wait
                queue.append(spec)
                broken = True
            processes.update(worker_processes(pool))

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
    # The pool terminates (SIGTERM) the others when one dies: that one's code comes first.
    exits = sorted((p.exitcode for p in processes.values() if p.exitcode),
                   key=lambda code: code == -signal.SIGTERM)
    return lost, list(reversed(queue)), exits


def _submit(pool, spec):
    """pool.submit, with SIGINT ignored while it may start a worker process: the worker
    inherits the ignored SIGINT, so a Ctrl-C at the terminal reaches the driver alone
    (which then stops the workers) and never prints a worker's traceback."""
    if threading.current_thread() is not threading.main_thread():
        return pool.submit(worker.execute, spec)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        return pool.submit(worker.execute, spec)
    finally:
        signal.signal(signal.SIGINT, previous)


def worker_processes(pool):
    """{pid: process} of a ProcessPoolExecutor's workers: the one read of
    concurrent.futures' private `_processes` (Python 3.10 to 3.13 have no public way to
    the workers; 3.14's terminate_workers ends them but does not name them)."""
    return dict(getattr(pool, "_processes", None) or {})


def _stop(pool):
    """Terminates the pool's worker processes, then shuts it down, the runs in flight
    lost (their folders hold no run.json, so a rerun redoes them). The shutdown waits for
    the pool's own thread, which the dead workers end at once: left running (shutdown
    without waiting), it could close its wake-up pipe while the interpreter's exit
    writes to it, and Python 3.11's concurrent.futures then printed an ignored
    "Bad file descriptor" traceback after the command's one line (seen once under load,
    in tests/test_bad_inputs.py; CPython's gh-132969 is of the same kind)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C while stopping
    processes = list(worker_processes(pool).values())
    for p in processes:
        p.terminate()
    for p in processes:
        p.join(5)
    pool.shutdown(wait=True, cancel_futures=True)
