"""Every compiled kernel into numba's on-disk cache, once, before many processes want it.

`make test` runs this first (`python -m experiments.ops.warm`). On a fresh clone no
kernel is cached: a cold run spends most of its time compiling (docs/speed.md, "Compiling,
and what was not adopted"), and the test processes that start together (two pytest
workers, the `ebrl` commands and pool workers they start) would each compile the same
kernels before the first of them has written its cache entry. Here one short run of each robot, condition
and learner, in both loops (the compiled stretches and dm_control's step by step), compiles
each kernel once, on two processes; every later process loads them (compiled/cache.py).
The runs go to the processes one realisation at a time (tasks.realisations): the robots of
a realisation share its kernels, so a process that has compiled them runs the others in
no time, where two processes given one realisation's robots at once would both compile
them. A warm cache makes this a few seconds. Nothing is written but numba's cache.
"""
import concurrent.futures
import multiprocessing
import sys
import time

STEPS = 30


def specs():
    """[(RunSpec, fused), ...] per realisation, the paper's two-wheel one first (it also
    compiles what every realisation shares: the agent and the loop), that reach every
    kernel: each registered robot and shipped mount in both conditions in the compiled
    loop; the paper robots also step by step and with the other learners."""
    from experiments.running import execution
    from tasks.robots import MOUNTS, ROBOTS, resolve
    groups = {}
    for robot in [*ROBOTS, *MOUNTS]:
        group = groups.setdefault(resolve(robot).realisation, [])
        for condition in ("random", "avoidance"):
            group.append((execution.RunSpec(robot, condition, 0, STEPS), True))
        if robot in ("two_wheel", "floating"):
            group.append((execution.RunSpec(robot, "avoidance", 0, STEPS), False))
            for agent in ("qtable", "mfec"):
                group.append((execution.RunSpec(robot, "avoidance", 0, STEPS, agent=agent),
                              True))
    return list(groups.values())


def _run(batch):
    from experiments.running import execution
    for spec, fused in batch:
        execution.execute(spec, fused=fused)
    return len(batch)


def main(workers=2):
    start = time.perf_counter()
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(workers, mp_context=context) as pool:
        made = sum(pool.map(_run, specs()))  # one realisation at a time, to the first free
    print(f"warm: {made} short runs, every kernel in numba's cache "
          f"({time.perf_counter() - start:.0f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
