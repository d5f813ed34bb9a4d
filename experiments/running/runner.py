"""Runs a set of specs on a local process pool (forkserver) or a Ray cluster.

Workers only compute (`execution.execute`); the driver writes each run as it
arrives, so any worker count and either backend give identical files, and a run
killed at any moment leaves only an unfinished folder that the next call redoes.

A run that raises is recorded as failed (results.write_failure: run.json with
status "failed" and the error) while the others go on; a rerun retries it. Every
local run is made in a worker process, even with one worker, so that a run that
kills its process (a segfault in native code, the out-of-memory killer) cannot take
the command with it. A worker process that dies takes the pool with it: the runs
it held run again first on a fresh pool; a run in flight at a second death is run
alone once more (at once, with one worker), and recorded as failed (WorkerDied,
with the signal) if its worker dies then too, so a random kill costs one restart of
the pool and a run that crashes its worker is named. Ray retries a task
whose worker died once, then it is recorded the same way; a lost cluster is one
line (ClusterLost). A results folder that cannot be written (full, read-only) stops
the command (results.WriteError). Ctrl-C stops the local pool's workers at once;
finished runs stay on disk.

Test only: EBRL_TEST_FAIL="two_wheel/avoidance/1,floating/random/0" makes those
runs (robot/condition/seed) raise a dm_control PhysicsError in the worker, and
EBRL_TEST_CRASH, with the same syntax, makes their worker process exit abruptly
(status 70), or with "robot/condition/seed:SIGSEGV" crash in native code (ctypes
reads address 0) or with ":SIGKILL" (any signal's name) be killed, once the run is
computed. EBRL_TEST_HOLD=PATH makes every run, before it starts, announce itself (an
empty file PATH.NODE.ROBOT_CONDITION_seed_NNN, NODE the Ray node's id or "local") and
wait while PATH exists, so a test can take a Ray node away, or add one, with runs in
flight; EBRL_TEST_CLUSTER_TIMEOUT=SECONDS replaces CLUSTER_TIMEOUT (a lost cluster's test
then waits 3 s, not 10). They exist for the tests of failure handling and are never set
otherwise.
"""
import collections
import dataclasses
import logging
import os
import signal
import sys
import threading
import time

from experiments.running import execution, results

# One BLAS thread per worker: the agent's products are small, and parallelism
# comes from running several seeds at once. Set before workers import numpy.
_SINGLE_THREAD = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                   "MKL_NUM_THREADS")}
TEST_FAIL, TEST_CRASH, TEST_HOLD = "EBRL_TEST_FAIL", "EBRL_TEST_CRASH", "EBRL_TEST_HOLD"
TEST_CLUSTER_TIMEOUT = "EBRL_TEST_CLUSTER_TIMEOUT"

#: What run() did: runs made now, runs already on disk, and (spec, error) per failed run.
Ran = collections.namedtuple("Ran", "made on_disk failed")


def plan(robots, conditions, seeds, steps=None, overrides=(), drive=None, agent="ebrl",
         first_trial=False, protocol="adopted", room=None):
    """Specs in the order to start them: the longest first, for an even finish.

    steps: None for each robot's budget (the registry's), a number for all, or a dict
    by robot; drive: for robots given as files; first_trial: runs that end at their
    first goal (execution.RunSpec.first_trial); readings: a named protocol
    (tasks.robots.PROTOCOLS: RunSpec.protocol); room: the room (execution.RunSpec.room)."""
    from tasks.robots import resolve

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


def _selected(variable, spec):
    """What the test-only variable asks of spec: None when it does not name spec as
    robot/condition/seed, else the text after the seed's ':' ('' when none)."""
    me = f"{spec.label}/{spec.condition}/{spec.seed}"
    for wanted in os.environ.get(variable, "").split(","):
        name, _, how = wanted.strip().partition(":")
        if name == me:
            return how
    return None


def _execute(spec):
    """A worker's task (never run by the driver itself)."""
    hold = os.environ.get(TEST_HOLD)
    if hold:
        ray = sys.modules.get("ray")
        node = ray.get_runtime_context().get_node_id() if ray else "local"
        open(f"{hold}.{node}.{spec.name.replace('/', '_')}", "w").close()
        while os.path.exists(hold):
            time.sleep(0.05)
    if _selected(TEST_FAIL, spec) is not None:
        from dm_control.rl.control import PhysicsError
        raise PhysicsError(f"failure injected by {TEST_FAIL} (test only) in {spec.name}")
    crash = _selected(TEST_CRASH, spec)
    if crash == "":
        os._exit(70)
    result = execution.execute(spec)
    if crash == "SIGSEGV":  # a real one: native code reading address 0
        import ctypes
        ctypes.string_at(0)
    elif crash:
        os.kill(os.getpid(), getattr(signal, crash))
        time.sleep(60)  # a signal that does not end the process at once
    return result


def run(specs, out, *, workers=None, backend="local", progress=True):
    """Runs the specs not yet done under out (a folder, or a function spec -> folder;
    failed and damaged ones again), after checking them (check); returns a Ran. A worker
    that raises one of INPUT_ERRORS stops the command with that error."""
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
            results.write_run(where(spec), spec, result, versions)
            steps_done += result.get("steps_run", spec.steps)
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
    """Runs specs on worker processes (_context), even for one worker: a run that kills its
    process (a segfault in native code, the out-of-memory killer) is then recorded
    with the signal while the others go on."""
    workers = workers or os.cpu_count() or 1
    saved = {k: os.environ.get(k) for k in _SINGLE_THREAD}
    os.environ.update(_SINGLE_THREAD)
    try:
        queue, deaths = list(specs), collections.Counter()
        while queue:
            lost, rest, exits = _pool(queue, workers, done)
            deaths.update(lost)
            # A run whose worker died runs again first. One in flight at two deaths is a
            # suspect: alone already (one worker), recorded; else it runs once more alone.
            if workers == 1:
                for spec in [s for s in lost if deaths[s] >= 2]:
                    done(spec, error=WorkerDied.of(spec, exits[0] if exits else None))
            suspects = [s for s in lost if deaths[s] >= 2 and workers > 1]
            queue = [s for s in lost if deaths[s] < 2] + rest
            while suspects:  # one at a time on one worker, so a death names its run
                again, suspects, exits = _pool(suspects, 1, done)
                for spec in again:
                    done(spec, error=WorkerDied.of(spec, exits[0] if exits else None))
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


class WorkerDied(RuntimeError):
    """A run whose worker process ended without returning (killed, a crash); .signal is
    the signal's name (SIGSEGV, SIGKILL) or None, .exit_status the status or None."""

    def __init__(self, message, signal_name=None, exit_status=None):
        super().__init__(message)
        self.signal, self.exit_status = signal_name, exit_status

    @classmethod
    def of(cls, spec, exitcode, where="worker process"):
        """The error for spec's run, whose worker ended with exitcode (multiprocessing's:
        -N for signal N; None when unknown)."""
        head = f"the {where} running {spec.name}"
        if exitcode is not None and exitcode < 0:
            name = _signal_name(-exitcode)
            what = signal.strsignal(-exitcode) or name
            hint = {"SIGSEGV": "a crash in native code", "SIGBUS": "a crash in native code",
                    "SIGABRT": "a crash in native code",
                    "SIGKILL": "out of memory, or killed by hand"}.get(name)
            return cls(f"{head} was killed by {name} ({what}{'; ' + hint if hint else ''})",
                       signal_name=name)
        if exitcode is not None:
            return cls(f"{head} exited with status {exitcode} without returning",
                       exit_status=exitcode)
        return cls(f"{head} died (killed, out of memory or crashed)")


def _signal_name(number):
    try:
        return signal.Signals(number).name
    except ValueError:
        return f"signal {number}"


#: What the pool's server process imports once, before it forks each worker.
PRELOAD = ["experiments.running.execution"]


def _context():
    """The pool's start method: forkserver (where the platform has it; else spawn). Each
    worker is forked from one server process per command that has imported PRELOAD, where
    a spawned worker starts a fresh interpreter and imports them itself (0.56 s of CPU a
    worker; a worker then loads its kernels from numba's cache, about 0.5 s, either way).
    Measured (the machine's CPU, /proc/stat): a 12-run `ebrl run` with two workers, 4.3 s
    with spawn, 3.6 s with the forkserver; a study, which makes a pool per batch, saves it
    at every batch. The server
    is started from _submit, SIGINT ignored, so its workers ignore SIGINT as spawned ones
    did. The server lives as long as the process that started it, and its workers get the
    environment it had then (with _SINGLE_THREAD): a variable set later in the same
    process reaches no worker. The workers are the server's children, not the command's
    (experiments.checks.procs.pool_workers finds them)."""
    import multiprocessing
    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    context = multiprocessing.get_context("forkserver")
    context.set_forkserver_preload(PRELOAD)
    return context


def _pool(specs, workers, done):
    """Runs specs, in order, on a fresh pool (_context) with at most `workers` in flight.
    Returns (runs lost because a worker died, runs not started then, the exit codes of
    the worker processes that ended abnormally); ([], [], ...) when every run was done
    or recorded as failed."""
    import concurrent.futures
    from concurrent.futures.process import BrokenProcessPool
    pool = concurrent.futures.ProcessPoolExecutor(workers, mp_context=_context())
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
        return pool.submit(_execute, spec)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        return pool.submit(_execute, spec)
    finally:
        signal.signal(signal.SIGINT, previous)


def worker_processes(pool):
    """{pid: process} of a ProcessPoolExecutor's workers: the one read of
    concurrent.futures' private `_processes` (Python 3.10 to 3.13 have no public way to
    the workers; 3.14's terminate_workers ends them but does not name them)."""
    return dict(getattr(pool, "_processes", None) or {})


def _stop(pool):
    """Terminates the pool's worker processes and shuts it down without waiting for
    the runs in flight (lost: their folders hold no run.json, so a rerun redoes them)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C while stopping
    processes = list(worker_processes(pool).values())
    for p in processes:
        p.terminate()
    pool.shutdown(wait=False, cancel_futures=True)
    for p in processes:
        p.join(5)


#: Seconds the Ray cluster may not answer before its connection counts as lost (Ray's
#: own driver waits 60 s and then aborts with a core dump's worth of log).
CLUSTER_TIMEOUT = 10.0


class ClusterLost(ConnectionError):
    """The Ray cluster stopped answering; the runs written before stay on disk. The
    process should end with os._exit (exit_now): Ray's own exit would wait on the lost
    cluster, then crash."""
    exit_now = True


def _run_ray(specs, workers, done):
    """Runs specs as Ray tasks. A run that raises is recorded as with the local pool; a
    task whose worker dies is tried once more (max_retries=1, as the local pool runs a
    lost run again) and then recorded as WorkerDied. A cluster that stops answering
    for CLUSTER_TIMEOUT seconds raises ClusterLost: the runs written so far stay on disk,
    the others are unfinished and the same command resumes them."""
    ray = _import_ray()
    started_here = not ray.is_initialized()
    if started_here:
        _init_ray(ray, workers)
    watch = _Watch(_gcs_address(ray))
    try:
        remote = ray.remote(num_cpus=1, max_retries=1)(_execute)
        refs = {remote.remote(s): s for s in specs}
        waiting, watch.answered = list(refs), time.monotonic()
        while waiting:
            ready, waiting = ray.wait(waiting, num_returns=1, timeout=1.0)
            if not ready:
                watch.check()
                continue
            _record_ray(ray, ready[0], refs[ready[0]], done, watch)
            watch.written += 1
    finally:
        if started_here and not watch.lost:  # ray.shutdown would wait on a lost cluster
            ray.shutdown()


def _import_ray():
    """The ray module (with ray.exceptions), or SystemExit saying how to install it."""
    try:
        import ray
        import ray.exceptions
    except ImportError:
        raise SystemExit("error: --backend ray needs Ray: pip install -e '.[ray]'") from None
    return ray


def _init_ray(ray, workers):
    """Connects to the cluster at RAY_ADDRESS, or starts one here with `workers` CPUs."""
    # Without RAY_ADDRESS, "local": ray.init(address=None) would join whichever cluster this
    # machine started last (Ray reads it from its temp folder), not start ours.
    address = os.environ.get("RAY_ADDRESS") or "local"
    # The test-only hooks travel to workers that a cluster started elsewhere runs.
    env = dict(_SINGLE_THREAD, **{k: os.environ[k] for k in (TEST_FAIL, TEST_CRASH, TEST_HOLD)
                                  if os.environ.get(k)})
    kwargs = {"address": address, "include_dashboard": False, "log_to_driver": False,
              "logging_level": logging.WARNING, "runtime_env": {"env_vars": env}}
    if address == "local":
        kwargs["num_cpus"] = workers or os.cpu_count() or 1
    ray.init(**kwargs)


def _gcs_address(ray):
    """The cluster's GCS address ("host:port"), or None for a Ray Client connection."""
    try:
        return ray.get_runtime_context().gcs_address
    except Exception:  # a Ray Client connection (ray://): its own errors tell a loss
        return None


class _Watch:
    """Whether the Ray cluster at gcs still answers: when it last did (.answered), the
    runs written since the start (.written), and whether it counts as lost (.lost)."""

    def __init__(self, gcs):
        self.gcs, self.written, self.lost = gcs, 0, False
        self.answered = time.monotonic()
        self.timeout = float(os.environ.get(TEST_CLUSTER_TIMEOUT) or CLUSTER_TIMEOUT)

    def check(self):
        """Raises ClusterLost once the cluster has not answered since .answered for
        CLUSTER_TIMEOUT seconds; .answered becomes now if it answers."""
        if _answers(self.gcs):
            self.answered = time.monotonic()
            return
        if time.monotonic() - self.answered < self.timeout:
            return
        self.lost = True
        raise ClusterLost(f"lost the connection to the Ray cluster at {self.gcs} (no answer "
                          f"for {self.timeout:.0f} s); the {self.written} runs written are "
                          "on disk; rerun the same command when the cluster is back")


def _record_ray(ray, ref, spec, done, watch):
    """Records the finished task ref of spec's run: its result, its error, or WorkerDied
    when its worker died (raises the error when the cluster went with it)."""
    died = (ray.exceptions.WorkerCrashedError, ray.exceptions.OutOfMemoryError,
            ray.exceptions.NodeDiedError)
    try:
        result = ray.get(ref)
    except ray.exceptions.RayTaskError as e:  # the run raised: its error as .cause
        done(spec, error=e)
    except died + (ray.exceptions.RayError,) as e:
        # A worker that died, unless the whole cluster went with it.
        while not _answers(watch.gcs):
            watch.check()
            time.sleep(0.5)
        if not isinstance(e, died):
            raise
        done(spec, error=WorkerDied(f"the Ray worker running {spec.name} died "
                                    f"({results.error_line(e, 200)})"))
    else:
        done(spec, result)


def _answers(address, timeout=2.0):
    """Whether something accepts a connection at address ("host:port"; None: assumed)."""
    import socket
    if not address:
        return True
    host, _, port = address.rpartition(":")
    try:
        socket.create_connection((host, int(port)), timeout=timeout).close()
    except (OSError, ValueError):
        return False
    return True
