"""`ebrl bench`: microseconds per agent step, by part, for both robots.

Each robot runs the protocol's loop (avoidance condition) until the agent's memory
is full, then times N more steps: env.step, the agent's act and learn, and the
whole loop. Beside them, the references the issues set: raw `mujoco.mj_step` over
the same substeps, and a plain float32 numpy pass over a full memory (one
matrix-vector product and the top-N_r selection).
"""
import time

import mujoco

from ebrl.benchmark import reference_pass
from experiments import protocol


def measure(robot, steps):
    import tasks
    spec = protocol.RunSpec(robot, "avoidance", 0, steps)
    env = tasks.load(robot, seed=0)
    agent = protocol.make_agent(spec, env)
    config = spec.agent_config()
    ts = env.reset()
    clock = time.perf_counter
    t_env = t_agent = 0.0
    warm = config.memory_size + 200
    for step in range(warm + steps):
        if step == warm:
            t_env = t_agent = 0.0
            substeps0 = env.physics.substeps
            started = clock()
        t0 = clock()
        obs, readings = protocol.agent_input(ts.observation)
        action = agent.act(obs, readings=readings)
        t1 = clock()
        ts = env.step(action)
        t2 = clock()
        agent.learn(ts.reward, ts.last())
        t3 = clock()
        if ts.last():
            ts = env.reset()
        t_env += t2 - t1
        t_agent += (t1 - t0) + (t3 - t2)
    whole = clock() - started
    substeps = (env.physics.substeps - substeps0) / steps
    # Raw physics over the same number of substeps, on the same model and state.
    m, d = env.physics.model.ptr, env.physics.data.ptr
    t0 = clock()
    for _ in range(steps):
        mujoco.mj_step(m, d, max(1, int(round(substeps))))
    raw = (clock() - t0) / steps
    env.close()
    obs_dim = len(protocol.agent_input(ts.observation)[0])
    ref = reference_pass(config.memory_size, obs_dim, config.recall_size)
    us = 1e6 / steps
    return {"robot": robot, "memory": config.memory_size, "substeps": substeps,
            "raw_physics": raw * 1e6, "env_step": t_env * us, "agent": t_agent * us,
            "whole_loop": whole * us, "reference_pass": ref}


def main(steps=3000):
    rows = [measure(robot, steps) for robot in ("two_wheel", "floating")]
    print(f"microseconds per agent step ({steps} timed steps after the memory is full)")
    head = ("robot", "memory", "substeps", "raw mj_step", "env.step", "env/raw",
            "ref pass", "agent", "agent/ref", "whole loop", "loop/(raw+ref)")
    print(("{:>10} " * len(head)).format(*head))
    for r in rows:
        print(("{:>10} {:>10} {:>10.2f} {:>10.1f} {:>10.1f} {:>10.2f} {:>10.1f} {:>10.1f} "
               "{:>10.2f} {:>10.1f} {:>10.2f}").format(
            r["robot"], r["memory"], r["substeps"], r["raw_physics"], r["env_step"],
            r["env_step"] / r["raw_physics"], r["reference_pass"], r["agent"],
            r["agent"] / r["reference_pass"], r["whole_loop"],
            r["whole_loop"] / (r["raw_physics"] + r["reference_pass"])))
    return rows


if __name__ == "__main__":
    main()
