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


def reference_pass(memory_size=4096, dim=10, recall_size=7, repeats=3000, seed=0):
    """Microseconds for one float32 (memory_size, dim) @ (dim,) product plus the top
    recall_size by np.argpartition, averaged over repeats."""
    key = (memory_size, dim, seed)
    if key not in _REFERENCE_DATA:
        rng = np.random.default_rng(seed)
        _REFERENCE_DATA[key] = (rng.random((memory_size, dim), dtype=np.float32),
                                rng.random(dim, dtype=np.float32))
    memory, x = _REFERENCE_DATA[key]
    t0 = time.perf_counter()
    for _ in range(repeats):
        np.argpartition(memory @ x, -recall_size)[-recall_size:]
    return (time.perf_counter() - t0) / repeats * 1e6


def bench_agent(memory_size=4096, steps=100_000, seed=0, window=2_000):
    """Runs a floating-like agent for steps (random inputs, a cheap random fallback,
    reward 1 and the end of a trial every 500 steps) and times it in windows.

    Returns a dict: reference_us and agent_us (medians over the windows after the memory
    is full), ratio (their quotient), agent_us_10k / agent_us_100k (the windows ending
    there, when steps reaches them) and windows: [(last step, agent us, reference us)]."""
    rng = np.random.default_rng(seed)
    agent = Agent(paper_config("floating", memory_size=memory_size), 10, 2,
                  lambda readings, r: np.clip(r.normal(0.0, 0.5, 2), -1.0, 1.0),
                  groups=[np.arange(8), np.arange(8, 10)], group_weights=[0.7, 0.3],
                  seed=seed)
    stream = rng.random((4096 + 1, 10))  # cycled through: cheap, and not all alike
    windows = []
    clock = time.perf_counter
    t0 = clock()
    for step in range(1, steps + 1):
        agent.act(stream[step % len(stream)])
        last = step % 500 == 0
        agent.learn(1.0 if last else 0.0, last)
        if step % window == 0:
            agent_us = (clock() - t0) / window * 1e6
            ref_us = reference_pass(memory_size, 10, agent.config.recall_size, window // 4, seed)
            windows.append((step, agent_us, ref_us))
            t0 = clock()
    full = [w for w in windows if w[0] - window >= memory_size] or windows
    agent_us = float(np.median([w[1] for w in full]))
    ref_us = float(np.median([w[2] for w in full]))
    at = {w[0]: w[1] for w in windows}
    return {"memory_size": memory_size, "steps": steps, "reference_us": ref_us,
            "agent_us": agent_us, "ratio": agent_us / ref_us,
            "agent_us_10k": at.get(10_000), "agent_us_100k": at.get(100_000),
            "memory_decisions": agent.memory_decisions,
            "fallback_decisions": agent.fallback_decisions, "windows": windows}


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    steps = int(argv[0]) if argv else 100_000
    r = bench_agent(steps=steps)
    print(f"reference float32 pass ({r['memory_size']} x 10 matvec + top 7): "
          f"{r['reference_us']:.1f} us")
    print(f"agent act + learn, full memory (median):  {r['agent_us']:.1f} us "
          f"({r['ratio']:.2f}x the reference)")
    if r["agent_us_10k"] is not None and r["agent_us_100k"] is not None:
        print(f"agent at 10k steps: {r['agent_us_10k']:.1f} us; "
              f"at 100k steps: {r['agent_us_100k']:.1f} us")
    print(f"decisions from memory: {r['memory_decisions']}, "
          f"from the fallback: {r['fallback_decisions']}")
    return r


if __name__ == "__main__":
    main()
