"""Agent cost per step against a plain float32 numpy pass over the same memory.

`python -m ebrl.benchmark` prints, for both of Table 1's memories (1024 x 7 inputs in
one group, as the two-wheel robot; 4096 x 10 in eq 3's groups 8 + 2 weighted 0.7 / 0.3,
as the floating robot), microseconds per step of: the reference (one float32
matrix-vector product over the (M, n) memory plus the top-N_r selection), the agent's
act + learn with a full memory, their ratio, and the agent at 10k and 100k steps.

Timings on a shared machine drift by about 10% from minute to minute, so both are
medians of blocks, and a reference block runs after each block of agent steps: the
ratio compares the two over the same minutes.
"""
import time

import numpy as np

from ebrl.agent import Agent
from ebrl.config import Config

CASES = (  # name, memory size, obs_dim, action_dim, groups, group weights
    ("1024 x 7 (one group)", 1024, 7, 1, None, None),
    ("4096 x 10 (groups 8 + 2, 0.7 / 0.3)", 4096, 10, 2, [range(8), range(8, 10)], [0.7, 0.3]),
)


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


def bench_agent(memory_size=4096, obs_dim=10, action_dim=2, groups=None, group_weights=None,
                steps=100_000, window=5_000, seed=0):
    """us/step of act + learn in windows of `window` steps on random inputs (an episode
    of 500 steps, rewarded at its end), with a reference block after each window.

    Returns {"agent_us_at": {step: us of the window ending there}, "agent_us_full": the
    median over the windows with a full memory, "reference_us": the reference blocks'
    median}."""
    rng = np.random.default_rng(seed)
    groups = None if groups is None else [np.asarray(g) for g in groups]
    agent = Agent(Config(memory_size=memory_size), obs_dim, action_dim,
                  lambda ranges, r: r.normal(0.0, 0.5, action_dim).clip(-1, 1),
                  groups=groups, group_weights=group_weights, seed=seed)
    obs = rng.random((window, obs_dim))
    marks, references = {}, []
    for end in range(window, steps + 1, window):
        t0 = time.perf_counter()
        for step in range(end - window + 1, end + 1):
            agent.act(obs[step % window])
            last = step % 500 == 0
            agent.learn(1.0 if last else 0.0, last)
        marks[end] = (time.perf_counter() - t0) / window * 1e6
        references.append(reference_pass(memory_size, obs_dim, agent.config.recall_size,
                                         repeats=500, blocks=1))
    full = [v for k, v in marks.items() if k - window >= memory_size]
    return {"reference_us": float(np.median(references)), "agent_us_at": marks,
            "agent_us_full": float(np.median(full))}


def main():
    print("us per step; medians of blocks (agent: windows of 5000 steps with a full memory;"
          " reference: 500 passes after each window)")
    for name, memory_size, obs_dim, action_dim, groups, weights in CASES:
        r = bench_agent(memory_size, obs_dim, action_dim, groups, weights)
        at, ref, full = r["agent_us_at"], r["reference_us"], r["agent_us_full"]
        print(f"{name}:")
        print(f"  reference float32 pass (matvec + top 7): {ref:6.1f} us")
        print(f"  agent act+learn, full memory:           {full:6.1f} us ({full / ref:.2f}x)")
        print(f"  agent at 10k steps: {at[10_000]:.1f} us, at 100k steps: {at[100_000]:.1f} us")


if __name__ == "__main__":
    main()
