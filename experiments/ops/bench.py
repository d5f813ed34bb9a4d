"""`ebrl bench`: microseconds per agent step, by part, for every registered robot.

Each robot runs Section 3.6's loop (avoidance condition) until the agent's memory
is full, then times blocks of N more steps: env.step, the agent's act and learn
(with the observation's conversion), and the whole loop; medians over the blocks.
Beside them, the references the issues set: raw `mujoco.mj_step` over the same
substeps with the sensors computed once (as the tasks do), and a plain float32 numpy
pass over a full memory (one matrix-vector product and the top-N_r selection), timed
after each block; "agent/ref" is the median of the blocks' own ratios, so that a machine
whose speed drifts from minute to minute compares the two over the same minutes. The
column "tasks" is env.step less the raw physics: the tasks' own work around MuJoCo.
"fused loop" is the protocol's own loop, `ebrl run`'s: the same steps in stretches of
one compiled call each (experiments.running.fused), timed over blocks of N steps after the rest.
Everything runs with MuJoCo's stage timers off, as a run does (tasks.kernels.bindings.stage_timers_off).
"""
import statistics
import time

import tasks
from ebrl.benchmark import reference_pass
from experiments.running import execution
from tasks.kernels.bindings import stage_timers_off
from tasks.robots import ROBOTS
from tasks.simulator import mujoco


def measure(robot, steps, blocks=5, room=None, drive=None):
    """Medians over `blocks` blocks of `steps` timed steps each (this machine's timings
    vary by about 10% from one moment to the next; the median of blocks much less)."""
    spec = execution.RunSpec(robot, "avoidance", 0, steps, drive=drive, room=room)
    env = tasks.load(spec.entry, seed=0, room=spec.room)
    agent = execution.make_agent(spec, env)
    config = spec.agent_config()
    keys = tuple(key for key, _ in spec.entry.modalities)
    clock = time.perf_counter
    ts = env.reset()

    def step():
        """One protocol step; returns (seconds in env.step, seconds in the agent)."""
        nonlocal ts
        t0 = clock()
        action = agent.act(*execution.agent_input(ts.observation, keys))
        t1 = clock()
        ts = env.step(action)
        t2 = clock()
        agent.learn(ts.reward, ts.last())
        t3 = clock()
        if ts.last():
            ts = env.reset()
        return t2 - t1, (t1 - t0) + (t3 - t2)

    for _ in range(config.memory_size + 200):  # fill the memory first
        step()
    m, d = env.physics.model.ptr, env.physics.data.ptr
    rows, substeps, ratios = [], [], []
    for _ in range(blocks):
        substeps0, started = env.physics.substeps, clock()
        t_env, t_agent = map(sum, zip(*(step() for _ in range(steps))))
        whole = clock() - started
        substeps.append((env.physics.substeps - substeps0) / steps)
        # Raw physics over the same number of substeps, on the same model and state, with
        # the sensors computed once per agent step (the model has them disabled).
        n = max(1, round(substeps[-1]))
        bit = int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
        t0 = clock()
        for _ in range(steps):
            mujoco.mj_step(m, d, n)
            m.opt.disableflags &= ~bit
            mujoco.mj_sensorPos(m, d)
            m.opt.disableflags |= bit
        # The reference pass in the same minutes (a shared machine drifts by 10% or more
        # from minute to minute): the agent's ratio to it is taken block by block.
        ref = reference_pass(config.memory_size, agent.obs_dim, config.recall_size,
                             repeats=max(100, steps // 4), blocks=1)
        ratios.append(t_agent / steps * 1e6 / ref)
        rows.append((clock() - t0, t_env, t_agent, whole, ref * steps / 1e6))
    # The protocol's own loop: stretches of steps in one compiled call (experiments.running.fused).
    env.close()
    fused_times = []
    spec = execution.RunSpec(robot, "avoidance", 0, config.memory_size + 200 + blocks * steps,
                            drive=drive, room=room)
    env = tasks.load(spec.entry, seed=0, room=spec.room)
    trials = execution.Trials(env, execution.make_agent(spec, env), keys, spec.steps)
    if trials.fused:
        trials.run(config.memory_size + 200)  # fill the memory first, as above
        for _ in range(blocks):
            started = clock()
            trials.run(steps)
            fused_times.append(clock() - started)
    env.close()
    raw, t_env, t_agent, whole, ref = (statistics.median(col) * 1e6 / steps
                                       for col in zip(*rows))
    fused_loop = statistics.median(fused_times) * 1e6 / steps if fused_times else float("nan")
    return {"robot": robot, "memory": config.memory_size, "substeps": statistics.mean(substeps),
            "raw_physics": raw, "env_step": t_env, "tasks": t_env - raw, "agent": t_agent,
            "whole_loop": whole, "fused_loop": fused_loop, "reference_pass": ref,
            "agent_over_reference": statistics.median(ratios)}


def main(steps=2000, blocks=5, robots=None, room=None, drive=None):
    with stage_timers_off():  # as `ebrl run` steps (execution.execute), raw physics too
        rows = [measure(robot, steps, blocks, room, drive)
                for robot in (robots or tuple(ROBOTS))]
    print(f"microseconds per agent step, memory full: medians of {blocks} blocks of {steps} steps"
          + (f", room {room}" if room is not None else ""))
    head = ("robot", "memory", "substeps", "raw physics", "env.step", "tasks", "env/raw",
            "ref pass", "agent", "agent/ref", "whole loop", "loop/(raw+ref)", "fused loop",
            "fused/(raw+ref)")
    print(("{:>10} " * len(head)).format(*head))
    for r in rows:
        floor = r["raw_physics"] + r["reference_pass"]
        print(("{:>10} {:>10} {:>10.2f} {:>10.1f} {:>10.1f} {:>10.1f} {:>10.2f} {:>10.1f} "
               "{:>10.1f} {:>10.2f} {:>10.1f} {:>10.2f} {:>10.1f} {:>10.2f}").format(
            r["robot"], r["memory"], r["substeps"], r["raw_physics"], r["env_step"],
            r["tasks"], r["env_step"] / r["raw_physics"], r["reference_pass"], r["agent"],
            r["agent_over_reference"], r["whole_loop"], r["whole_loop"] / floor,
            r["fused_loop"], r["fused_loop"] / floor))
    return rows


if __name__ == "__main__":
    main()
