"""Agent cost per step against a plain float32 numpy pass over the same memory.

`python -m ebrl.benchmark` prints microseconds per step for: the reference (one
float32 matrix-vector product over the (M, n) memory plus the top-N_r selection),
the agent's act + learn with a full memory, and the agent at 10k and 100k steps.
"""
import time

import numpy as np

from ebrl.agent import Agent
from ebrl.config import paper_config


def reference_pass(memory_size=4096, dim=10, recall_size=7, repeats=1000, blocks=5, seed=0):
    """us per plain float32 pass: (M, n) memory @ x, then argpartition's top N_r; the
    median of `blocks` blocks of `repeats` passes."""
    rng = np.random.default_rng(seed)
    memory = rng.random((memory_size, dim), dtype=np.float32)
    x = rng.random(dim, dtype=np.float32)
    times = []
    for _ in range(blocks):
        t0 = time.perf_counter()
        for _ in range(repeats):
            np.argpartition(memory @ x, -recall_size)[-recall_size:]
        times.append((time.perf_counter() - t0) / repeats * 1e6)
    return float(np.median(times))


def bench_agent(memory_size=4096, steps=100_000, window=5_000, seed=0):
    """Floating-like agent (10 inputs, eq 3 groups 8 + 2): us/step in windows."""
    rng = np.random.default_rng(seed)
    agent = Agent(paper_config("F", memory_size=memory_size), 10, 2,
                  lambda readings, r: r.normal(0.0, 0.5, 2).clip(-1, 1),
                  groups=[np.arange(8), np.arange(8, 10)], group_weights=[0.7, 0.3], seed=seed)
    obs = rng.random((window, 10))
    marks = {}
    t0 = time.perf_counter()
    for step in range(1, steps + 1):
        agent.act(obs[step % window])
        last = step % 500 == 0
        agent.learn(1.0 if last else 0.0, last)
        if step % window == 0:
            t1 = time.perf_counter()
            marks[step] = (t1 - t0) / window * 1e6
            t0 = t1
    return {"reference_us": reference_pass(memory_size), "agent_us_at": marks,
            "agent_us_full": float(np.median([v for k, v in marks.items() if k > memory_size]))}


def main():
    r = bench_agent()
    at = r["agent_us_at"]
    print(f"reference float32 pass (4096 x 10 matvec + top 7): {r['reference_us']:.1f} us")
    print(f"agent act+learn, full memory (median):            {r['agent_us_full']:.1f} us "
          f"({r['agent_us_full'] / r['reference_us']:.2f}x)")
    print(f"agent at 10k steps: {at[10_000]:.1f} us, at 100k steps: {at[100_000]:.1f} us")


if __name__ == "__main__":
    main()
