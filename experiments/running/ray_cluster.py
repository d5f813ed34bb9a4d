"""The Ray backend: runs as Ray tasks on the cluster at RAY_ADDRESS, or on one started here.
A run that raises is recorded as with the local pool; a task whose worker dies is tried
once more, then recorded as worker.WorkerDied; a cluster that stops answering for
CLUSTER_TIMEOUT seconds is one line (ClusterLost), the runs written before on disk.

Test only: EBRL_TEST_CLUSTER_TIMEOUT=SECONDS replaces CLUSTER_TIMEOUT (a lost cluster's test
then waits 3 s, not 10); never set otherwise.
"""
import logging
import os
import time

from experiments.running import results, worker

TEST_CLUSTER_TIMEOUT = "EBRL_TEST_CLUSTER_TIMEOUT"


#: Seconds the Ray cluster may not answer before its connection counts as lost (Ray's
#: own driver waits 60 s and then aborts with a core dump's worth of log).
CLUSTER_TIMEOUT = 10.0


class ClusterLost(ConnectionError):
    """The Ray cluster stopped answering; the runs written before stay on disk. The
    process should end with os._exit (exit_now): Ray's own exit would wait on the lost
    cluster, then crash."""
    exit_now = True


def run(specs, workers, done):
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
        remote = ray.remote(num_cpus=1, max_retries=1)(worker.execute)
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
    hooks = (worker.TEST_FAIL, worker.TEST_CRASH, worker.TEST_HOLD)
    env = dict(worker.SINGLE_THREAD, **{k: os.environ[k] for k in hooks if os.environ.get(k)})
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
        done(spec, error=worker.WorkerDied(f"the Ray worker running {spec.name} died "
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
