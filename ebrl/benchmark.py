"""The agent's cost per step against a plain float32 numpy pass over the same memory.

    python -m ebrl.benchmark [steps]

prints microseconds per step for the reference (one float32 matrix-vector product over
the (M, 10) memory plus np.argpartition for the top N_r), for the agent's act + learn
with a full memory (a floating-like input: 8 readings and 2 velocities, eq 3 groups
0.7 / 0.3), their ratio, and the agent's cost around step 10k and step 100k.

The reference is timed in every window beside the agent, so a machine that gets busier
or quieter during the run moves both.
"""
import sys
import time

import numpy as np

from ebrl.agent import Agent
from ebrl.config import paper_config

_REFERENCE_DATA = {}


def reference_pass(memory_size=4096, dim=10, recall_size=7, repeats=3000, seed=0,
                   clock=time.perf_counter):
    """Microseconds for one float32 (memory_size, dim) @ (dim,) product plus the top
    recall_size by np.argpartition, averaged over repeats."""
    key = (memory_size, dim, seed)
    if key not in _REFERENCE_DATA:
        rng = np.random.default_rng(seed)
        _REFERENCE_DATA[key] = (rng.random((memory_size, dim), dtype=np.float32),
                                rng.random(dim, dtype=np.float32))
    memory, x = _REFERENCE_DATA[key]
    t0 = clock()
    for _ in range(repeats):
        np.argpartition(memory @ x, -recall_size)[-recall_size:]
    return (clock() - t0) / repeats * 1e6


def bench_agent(memory_size=4096, steps=100_000, seed=0, window=1_000):
    """Runs a floating-like agent for steps (random inputs, a cheap random fallback,
    reward 1 and the end of a trial every 500 steps) and times it in windows of
    `window` steps, each followed by window // 4 reference passes.

    Times are process CPU time (time.process_time), so that other processes taking the
    CPU do not count; wall-clock figures are given beside them. Returns a dict:
    reference_us, agent_us (medians over the windows after the memory is full), ratio
    (median over those windows of agent / reference), agent_us_10k and agent_us_100k
    (the windows ending there), their wall-clock counterparts (*_wall) and windows:
    [(last step, agent us, reference us)] in CPU time."""
    rng = np.random.default_rng(seed)
    agent = Agent(paper_config("floating", memory_size=memory_size), 10, 2,
                  lambda readings, r: np.clip(r.normal(0.0, 0.5, 2), -1.0, 1.0),
                  groups=[np.arange(8), np.arange(8, 10)], group_weights=[0.7, 0.3],
                  seed=seed)
    stream = rng.random((4096 + 1, 10))  # cycled through: cheap, and not all alike
    k = agent.config.recall_size
    windows, walls = [], []
    cpu, wall = time.process_time, time.perf_counter
    c0, w0 = cpu(), wall()
    for step in range(1, steps + 1):
        agent.act(stream[step % len(stream)])
        last = step % 500 == 0
        agent.learn(1.0 if last else 0.0, last)
        if step % window == 0:
            agent_cpu, agent_wall = (cpu() - c0) / window * 1e6, (wall() - w0) / window * 1e6
            c1, w1 = cpu(), wall()
            ref_cpu = reference_pass(memory_size, 10, k, window // 4, seed, clock=cpu)
            ref_wall = (wall() - w1) / (window // 4) * 1e6
            windows.append((step, agent_cpu, ref_cpu))
            walls.append((step, agent_wall, ref_wall))
            c0, w0 = cpu(), wall()
    full = [i for i, w in enumerate(windows) if w[0] - window >= memory_size] or \
        list(range(len(windows)))
    med = lambda rows, j: float(np.median([rows[i][j] for i in full]))
    at = {w[0]: w[1] for w in windows}
    at_wall = {w[0]: w[1] for w in walls}
    return {"memory_size": memory_size, "steps": steps,
            "reference_us": med(windows, 2), "agent_us": med(windows, 1),
            "ratio": float(np.median([windows[i][1] / windows[i][2] for i in full])),
            "reference_us_wall": med(walls, 2), "agent_us_wall": med(walls, 1),
            "ratio_wall": float(np.median([walls[i][1] / walls[i][2] for i in full])),
            "agent_us_10k": at.get(10_000), "agent_us_100k": at.get(100_000),
            "agent_us_10k_wall": at_wall.get(10_000), "agent_us_100k_wall": at_wall.get(100_000),
            "memory_decisions": agent.memory_decisions,
            "fallback_decisions": agent.fallback_decisions, "windows": windows}


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    steps = int(argv[0]) if argv else 100_000
    r = bench_agent(steps=steps)
    print(f"microseconds per step, CPU time (wall clock in brackets), memory {r['memory_size']}")
    print(f"reference: float32 ({r['memory_size']}, 10) @ (10,) + np.argpartition top 7: "
          f"{r['reference_us']:6.1f}  ({r['reference_us_wall']:.1f})")
    print(f"agent act + learn, full memory (median):          {r['agent_us']:6.1f}  "
          f"({r['agent_us_wall']:.1f})")
    print(f"ratio agent / reference (median over windows):   {r['ratio']:6.2f}  "
          f"({r['ratio_wall']:.2f})")
    if r["agent_us_10k"] is not None and r["agent_us_100k"] is not None:
        print(f"agent in the window ending at 10k steps: {r['agent_us_10k']:.1f} "
              f"({r['agent_us_10k_wall']:.1f}); at 100k steps: {r['agent_us_100k']:.1f} "
              f"({r['agent_us_100k_wall']:.1f})")
    print(f"decisions from memory: {r['memory_decisions']}, "
          f"from the fallback: {r['fallback_decisions']}")
    return r


if __name__ == "__main__":
    main()
