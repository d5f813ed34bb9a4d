"""Runs a set of specs on a local process pool (spawn) or a Ray cluster.

Workers only compute (`protocol.execute`); the driver writes each run as it
arrives, so any worker count and either backend give identical files, and a run
killed at any moment leaves only an unfinished folder that the next call redoes.
"""
import os
import time

from experiments import protocol, results

# One BLAS thread per worker: the agent's products are small, and parallelism
# comes from running several seeds at once. Set before workers import numpy.
_SINGLE_THREAD = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                   "MKL_NUM_THREADS")}


def plan(robots, conditions, seeds, steps=None, overrides=(), drive=None):
    """Specs in the order to start them: the longest first, for an even finish.

    steps: None for each robot's budget (the registry's), a number for all, or a dict
    by robot; drive: for robots given as files."""
    from tasks.robots import resolve

    def budget(robot):
        if isinstance(steps, dict):
            return steps[robot]
        return steps if steps is not None else resolve(robot, drive).budget

    specs = [protocol.RunSpec(r, c, s, budget(r), tuple(sorted(dict(overrides).items())),
                              drive)
             for r in robots for c in conditions for s in seeds]
    return sorted(specs, key=lambda s: -s.steps)


def pending(out, specs):
    """The specs without a matching complete run under out (ResultsError if damaged)."""
    return [s for s in specs if results.existing(out, s) == "missing"]


def _execute(spec):
    return protocol.execute(spec)


def run(specs, out, *, workers=None, backend="local", progress=True):
    """Runs the specs not yet done under out; returns how many it ran."""
    todo = pending(out, specs)
    if not todo:
        return 0
    versions = results.versions()
    total_steps = sum(s.steps for s in todo)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(todo), unit="run", dynamic_ncols=True,
                   desc=f"runs ({len(specs) - len(todo)} already on disk)")
    started, steps_done = time.perf_counter(), 0

    def done(spec, result):
        nonlocal steps_done
        results.write_run(out, spec, result, versions)
        steps_done += spec.steps
        if bar is not None:
            rate = steps_done / max(time.perf_counter() - started, 1e-9)
            bar.set_postfix_str(f"{rate:,.0f} steps/s, {steps_done:,}/{total_steps:,} steps")
            bar.update(1)

    try:
        if backend == "ray":
            _run_ray(todo, workers, done)
        else:
            _run_local(todo, workers, done)
    finally:
        if bar is not None:
            bar.close()
    return len(todo)


def _run_local(specs, workers, done):
    workers = workers or os.cpu_count() or 1
    if workers == 1:
        for spec in specs:
            done(spec, protocol.execute(spec))
        return
    import concurrent.futures
    import multiprocessing
    saved = {k: os.environ.get(k) for k in _SINGLE_THREAD}
    os.environ.update(_SINGLE_THREAD)
    try:
        ctx = multiprocessing.get_context("spawn")
        with concurrent.futures.ProcessPoolExecutor(workers, mp_context=ctx) as pool:
            futures = {pool.submit(_execute, s): s for s in specs}
            for future in concurrent.futures.as_completed(futures):
                done(futures[future], future.result())
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


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
            done(refs[ready[0]], ray.get(ready[0]))
    finally:
        if started_here:
            ray.shutdown()
