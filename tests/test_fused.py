"""The protocol's compiled stretches (experiments.running.fused) against the step-by-step loop."""
import numpy as np
import pytest

import tasks
from experiments.running import fused, protocol


def _pair(robot, condition, seed=0):
    spec = protocol.RunSpec(robot, condition, seed, 10)
    env_seed, _ = protocol.seeds_for(seed)
    out = []
    for _ in range(2):
        env = tasks.load(spec.entry, seed=env_seed, config=spec.task_config())
        out.append((env, protocol.make_agent(spec, env)))
    return spec, out


def _state(env, agent):
    """What the next steps depend on: the agent's memory and streams, the task's stream,
    the physics."""
    a = agent
    arrays = [a._inputs, a._action, a._utility, a._rel, a._time, a._next, a._prev, a._sums,
              a._var, a._table, a._table_w, a._decided, env.physics.data.qpos,
              env.physics.data.qvel, env.physics.data.act, env.physics.data.ctrl]
    last = getattr(a.fallback, "last", None)
    if last is not None:
        arrays.append(last)
    scalars = (a.steps, a._size, a._tail, a._referred, a.memory_decisions,
               a.fallback_decisions, a.decision, a.used_memory,
               getattr(a.fallback, "choice", None), env._step_count, env._reset_next_step,
               env.physics.substeps, str(a.rng.bit_generator.state))
    task_state = env.task.random.get_state()
    return ([x.tobytes() for x in arrays], scalars,
            (task_state[1].tobytes(),) + tuple(task_state[2:]))


@pytest.mark.parametrize("robot,steps", [("two_wheel", 9000), ("floating", 6000),
                                         ("diff_drive", 1200), ("hovercraft", 1500)])
@pytest.mark.parametrize("condition", ["avoidance", "random"])
def test_a_stretch_is_the_step_by_step_loop(robot, steps, condition):
    spec, ((env1, agent1), (env2, agent2)) = _pair(robot, condition)
    assert fused.Loop.supports(env2, agent2)
    keys = tuple(k for k, _ in spec.entry.modalities)
    trace1, trace2 = (np.zeros((steps + 1, 2), dtype=np.float32) for _ in range(2))
    ts1, ts2 = env1.reset(), env2.reset()
    goals1 = []
    for step in range(1, steps + 1):
        obs, readings = protocol.agent_input(ts1.observation, keys)
        ts1 = env1.step(agent1.act(obs, readings=readings))
        agent1.learn(ts1.reward, ts1.last())
        trace1[step] = env1.physics.robot_pose()[:2]
        if ts1.last():
            goals1.append(step)
            ts1 = env1.reset()
    loop, step, goals2, observation = fused.Loop(env2, agent2, trace2), 0, [], ts2.observation
    while step < steps:
        # stretches of at most 700 steps: a stretch also resumes where one stopped
        done, goal = loop.stretch(step + 1, min(700, steps - step), observation)
        step, observation = step + done, None
        if goal:
            goals2.append(step)
            observation = env2.reset().observation
    assert goals1 == goals2
    assert trace1.tobytes() == trace2.tobytes()
    assert _state(env1, agent1) == _state(env2, agent2)
    for key in ts1.observation:  # the last observation, as the next stretch would read it
        assert np.array_equal(ts1.observation[key], loop.io[1 if key == "range" else 2])
    env1.close(), env2.close()


def test_runs_are_the_same_fused_or_not_and_reach_the_goal():
    for robot, condition, steps in (("two_wheel", "avoidance", 12_000),
                                    ("floating", "random", 8000)):
        spec = protocol.RunSpec(robot, condition, 1, steps)
        a, b = protocol.execute(spec, fused=False), protocol.execute(spec)
        assert len(a["trial_ends"]) >= 3, (robot, condition)
        for key in ("trial_ends", "trace", "starts"):
            assert np.array_equal(a[key], b[key]), key
        assert a["memory_decisions"] == b["memory_decisions"]


def test_the_task_stream_is_numpys_legacy_stream():
    """The buffered doubles through the legacy normal and back: the RandomState ends
    where its own calls leave it, the cached normal included."""
    ours, theirs = np.random.RandomState(3), np.random.RandomState(3)
    stream = fused._StreamState(ours)
    for n_z in (7, 8, 3):
        stream.fill()
        u, z, vz = np.zeros(2), np.zeros(n_z), np.zeros(2)
        for _ in range(50):
            assert fused._task_draws(stream.buffer, stream.cursor, stream.cache, 0.1, 0.05,
                                     u, z, vz)
            want_u = theirs.random_sample(2)
            want_z = theirs.normal(0.0, 0.1, size=n_z)
            want_vz = theirs.normal(0.0, 0.05, size=2)
            assert (u.tobytes(), z.tobytes(), vz.tobytes()) == (
                want_u.tobytes(), want_z.tobytes(), want_vz.tobytes())
        stream.settle()
        a, b = ours.get_state(), theirs.get_state()
        assert a[1].tobytes() == b[1].tobytes() and a[2:] == b[2:]
    assert ours.normal() == theirs.normal() and ours.random_sample() == theirs.random_sample()


def test_what_a_stretch_cannot_run_takes_the_step_by_step_loop():
    spec = protocol.RunSpec("two_wheel", "avoidance", 0, 10, agent="qtable")
    env = tasks.load(spec.entry, seed=0)
    assert not fused.Loop.supports(env, protocol.make_agent(spec, env))
    ebrl_spec = protocol.RunSpec("two_wheel", "avoidance", 0, 10)
    agent = protocol.make_agent(ebrl_spec, env)
    assert fused.Loop.supports(env, agent)
    assert not fused.Loop.supports(env, agent, on_step=lambda *a: None)
    env.close()


def test_bench_times_the_fused_loop_beside_the_step_loop():
    from experiments.checks import bench
    row = bench.measure("two_wheel", 200, blocks=3)  # the median leaves out the first (loading)
    for key in ("raw_physics", "env_step", "agent", "whole_loop", "fused_loop",
                "reference_pass"):
        assert np.isfinite(row[key]) and row[key] > 0, key
    assert row["fused_loop"] < row["whole_loop"] * 2
