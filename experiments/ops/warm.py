"""Every compiled kernel into numba's on-disk cache, once, before many processes want it.

`make test` runs this first (`python -m experiments.ops.warm [MOUNT.toml ...]`, with the
mounts of the tests' own robots whose realisation no shipped robot has). On a fresh clone no
kernel is cached: a cold run spends most of its time compiling (docs/speed.md, "Compiling,
and what was not adopted"), and the test processes that start together (two pytest
workers, the `ebrl` commands and pool workers they start) would each compile the same
kernels before the first of them has written its cache entry. Here one short run of each
robot, condition and learner, in both loops (the compiled stretches and dm_control's step
by step), compiles each kernel once, on two processes; every later process loads them
(compiled/cache.py). A warm cache makes this a few seconds. Nothing is written but
numba's cache.

No two processes compile the same kernel at once (tasks.realisations: the robots of a
realisation share its kernels; every realisation shares the agent and the loop). One
process runs the paper's two-wheel realisation first, which compiles the agent and the loop
(about half of the whole); meanwhile the other steps each other realisation's environment
(`tasks.load`, a few steps), which compiles its kernels and not the agent's, and the
first process free takes the environments still waiting before any run. A realisation's
runs start once both are done, and compile only what joins its kernels to the loop.
"""
import concurrent.futures
import multiprocessing
import sys
import time

STEPS = 30
#: Steps of a realisation's environment in the first phase.
ENV_STEPS = 3


def specs(files=()):
    """[(RunSpec, fused), ...] per realisation, the paper's two-wheel one first (it also
    compiles what every realisation shares: the agent and the loop), that reach every
    kernel: each registered robot, shipped mount and robot file in files in both
    conditions in the compiled loop; the paper robots also step by step and with the other
    learners."""
    from experiments.running import execution
    from tasks.robots import MOUNTS, ROBOTS, resolve
    groups = {}
    for robot in [*ROBOTS, *MOUNTS, *map(str, files)]:
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


def _step_env(robot):
    """A few steps of robot's environment, no agent: its realisation's kernels."""
    import numpy as np

    import tasks
    env = tasks.load(robot, seed=0)
    try:
        env.reset()
        for _ in range(ENV_STEPS):
            env.step(np.zeros(env.action_spec().shape))
    finally:
        env.close()
    return 0


def key(kind, what):
    """A job's name among the jobs: (kind, robot), a run's robot its group's first."""
    return kind, what if kind == "env" else what[0][0].robot


def jobs(groups):
    """The jobs in the order they may start: ("run", group) for the first group, ("env",
    robot) for each other group, then each other group's ("run", group) after its env and
    the first group's run. The environments, the longest chain, come first: a process
    free after the first run takes the environments still waiting before any run."""
    first, *others = groups
    yield ("run", first), ()
    for group in others:
        yield ("env", group[0][0].robot), ()
    for group in others:
        yield ("run", group), (key("run", first), key("env", group[0][0].robot))


def main(files=(), workers=2):
    """Warms every shipped robot's kernels and those of the robot files (mounts, .toml)."""
    start = time.perf_counter()
    waiting = [(kind, what, after) for (kind, what), after in jobs(specs(files))]
    done, made = set(), 0
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(workers, mp_context=context) as pool:
        running = {}
        while waiting or running:
            # Fill free processes with the first jobs whose jobs before them are done.
            for job in [j for j in waiting if all(a in done for a in j[2])]:
                if len(running) == workers:
                    break
                kind, what, _ = job
                waiting.remove(job)
                running[pool.submit(_run if kind == "run" else _step_env, what)] = key(kind, what)
            finished, _ = concurrent.futures.wait(
                running, return_when=concurrent.futures.FIRST_COMPLETED)
            for future in finished:
                made += future.result()
                done.add(running.pop(future))
    print(f"warm: {made} short runs, every kernel in numba's cache "
          f"({time.perf_counter() - start:.0f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
