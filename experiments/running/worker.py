"""What runs in a worker process, local or Ray's: one run's task (execute), and how a worker
that died without returning is named (WorkerDied).

Test only: EBRL_TEST_FAIL="two_wheel/avoidance/1,floating/random/0" makes those
runs (robot/condition/seed) raise a dm_control PhysicsError in the worker, and
EBRL_TEST_CRASH, with the same syntax, makes their worker process exit abruptly
(status 70), or with "robot/condition/seed:SIGSEGV" crash in native code (ctypes
reads address 0) or with ":SIGKILL" (any signal's name) be killed, once the run is
computed. EBRL_TEST_HOLD=PATH makes every run, before it starts, announce itself (an
empty file PATH.NODE.ROBOT_CONDITION_seed_NNN, NODE the Ray node's id or "local") and
wait while PATH exists, so a test can take a Ray node away, or add one, with runs in
flight. They exist for the tests of failure handling and are never set otherwise.
"""
import contextlib
import os
import signal
import sys
import time

from experiments.running import execution

# One BLAS thread per worker: the agent's products are small, and parallelism
# comes from running several seeds at once. Set before workers import numpy.
SINGLE_THREAD = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                   "MKL_NUM_THREADS")}
TEST_FAIL, TEST_CRASH, TEST_HOLD = "EBRL_TEST_FAIL", "EBRL_TEST_CRASH", "EBRL_TEST_HOLD"


@contextlib.contextmanager
def single_threaded():
    """SINGLE_THREAD in this process's environment while the block runs (the workers it
    starts inherit it), each variable as it was afterwards."""
    saved = {k: os.environ.get(k) for k in SINGLE_THREAD}
    os.environ.update(SINGLE_THREAD)
    try:
        yield
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def selected(variable, spec):
    """What the test-only variable asks of spec: None when it does not name spec as
    robot/condition/seed, else the text after the seed's ':' ('' when none)."""
    me = f"{spec.label}/{spec.condition}/{spec.seed}"
    for wanted in os.environ.get(variable, "").split(","):
        name, _, how = wanted.strip().partition(":")
        if name == me:
            return how
    return None


def execute(spec):
    """A worker's task: spec's run (execution.execute), with the test hooks (never run by
    the driver itself)."""
    hold = os.environ.get(TEST_HOLD)
    if hold:
        ray = sys.modules.get("ray")
        node = ray.get_runtime_context().get_node_id() if ray else "local"
        open(f"{hold}.{node}.{spec.name.replace('/', '_')}", "w").close()
        while os.path.exists(hold):
            time.sleep(0.05)
    if selected(TEST_FAIL, spec) is not None:
        from dm_control.rl.control import PhysicsError
        raise PhysicsError(f"failure injected by {TEST_FAIL} (test only) in {spec.name}")
    crash = selected(TEST_CRASH, spec)
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
