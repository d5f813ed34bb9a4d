"""The protocol's loop for a stretch of a trial in one compiled call: the speed path of
`experiments.running.protocol.execute`, with the same bits as its step-by-step loop.

The step-by-step loop runs, per agent step, `ebrl.Agent.act`, `tasks.Environment.step`
and `ebrl.Agent.learn`, each a little Python around compiled kernels (ebrl.kernels,
ebrl.intrinsic, tasks.kernels). `run` calls those same kernels from one numba function
for up to a trial's end, so the Python per step (15-20 us: argument checks, the random
draws, the dm_env TimeStep, the observation dict, bookkeeping) is paid once per
stretch. What it needs inside numba:

- The agent's random stream: its numpy Generator, which numba draws from directly
  (`rng.random()`, `rng.normal(0.0, sd)`: NumPy's own algorithms on the Generator's
  own state, which advances in place).
- The task's random stream: dm_control's `RandomState` (MT19937, legacy), which numba
  cannot take. Its draws are doubles from one stream (`random_sample`; the legacy
  normal's polar method takes its pairs from the same doubles), so a stretch gets a
  buffer of the next doubles (`random_sample(N)`) and the legacy normal's cached value,
  uses what it needs by the legacy algorithm (`_gauss`), and the RandomState is then
  wound to just past what was used, with the cached value put back (`_StreamState`).

It serves EBRL (`ebrl.Agent`) with the paper's fallbacks (`ebrl.intrinsic.RandomWalk`,
`Intrinsic` with eq 8 or eq 9-10) on the tasks' compiled steps; anything else (the
baselines, an evolved genome's fallback, a video's per-step callback) runs the
step-by-step loop. tests/test_fused.py checks the two alike, step for step, for every
registered robot and both conditions.
"""
import math

import numpy as np
from numba import njit

from ebrl import intrinsic
from ebrl import kernels as agent_kernels
from ebrl.agent import DECIDERS
from experiments.running import protocol
from tasks import kernels as task_kernels

#: Doubles of the task's stream drawn per stretch; a step uses about a dozen.
BUFFER = 8192
#: A stretch stops before a step when fewer doubles than this are left (a step's draws:
#: 2 uniforms and 2 per attempt of each pair of normals, whose attempts repeat with
#: probability 1 - pi / 4; a step that would run out is undone and the stretch ends).
RESERVE = 64

#: Why a stretch ended.
GOAL, BUDGET, REFILL, FAILED = range(4)
#: Who chose a step's action, an index of ebrl.agent.DECIDERS.
MEMORY, INTRINSIC, RANDOM, EXPLORATION = range(4)
#: The agent's fallback as the stretch runs it.
FALLBACK_RANDOM_WALK, FALLBACK_TURNING, FALLBACK_ACCELERATING = range(3)


@njit(cache=True)
def _gauss(buf, cursor, cache):
    """numpy's legacy_gauss on the buffered doubles: the cached value if there is one
    (cache = [has it, value]), else the polar method on pairs of doubles, keeping the
    second value. cursor[0]: the next double."""
    if cache[0] != 0.0:
        value = cache[1]
        cache[0] = 0.0
        cache[1] = 0.0
        return value
    while True:
        p = cursor[0]
        x1 = 2.0 * buf[p] - 1.0
        x2 = 2.0 * buf[p + 1] - 1.0
        cursor[0] = p + 2
        r2 = x1 * x1 + x2 * x2
        if not (r2 >= 1.0 or r2 == 0.0):
            break
    f = math.sqrt(-2.0 * math.log(r2) / r2)
    cache[1] = f * x1
    cache[0] = 1.0
    return f * x2


@njit(cache=True)
def _normals(buf, cursor, cache, sd, out):
    """RandomState.normal(0.0, sd, size=len(out)): legacy_normal's loc + scale * gauss."""
    for i in range(out.shape[0]):
        out[i] = 0.0 + sd * _gauss(buf, cursor, cache)


@njit(cache=True)
def _task_draws(buf, cursor, cache, sensor_noise, velocity_noise, u, z, vz):
    """One step's draws of the task, in its order (Navigation.draws, then the floating
    velocity's): the action noise's two uniforms (u), the sensor noise's normals (z),
    the velocity noise's normals (vz); an array is empty where its noise is off.
    Returns False, with the cursor and the cache as they were, when the buffer might
    run out meanwhile."""
    start, had, value = cursor[0], cache[0], cache[1]
    if start + u.shape[0] + 4 * (z.shape[0] + vz.shape[0]) + RESERVE > buf.shape[0]:
        return False
    for i in range(u.shape[0]):
        u[i] = buf[cursor[0]]
        cursor[0] += 1
    _normals(buf, cursor, cache, sensor_noise, z)
    _normals(buf, cursor, cache, velocity_noise, vz)
    if cursor[0] > buf.shape[0] - RESERVE:  # pragma: no cover - many rejections in a row
        cursor[0], cache[0], cache[1] = start, had, value
        return False
    return True


@njit(cache=True)
def _fallback(kind, readings, rng, rate, sd, add, theta, last, action):
    """ebrl.intrinsic's RandomWalk or Intrinsic: their draws in their order, then
    fallback_act. Returns RANDOM or INTRINSIC."""
    dim = action.shape[0]
    if kind == FALLBACK_RANDOM_WALK:
        for i in range(dim):
            action[i] = rng.normal(0.0, sd)
        intrinsic.clip_unit(action)
        return RANDOM
    if rng.random() < rate:
        random = np.empty(dim)
        for i in range(dim):
            random[i] = rng.normal(0.0, sd)
    else:
        random = np.empty(0)
    avoid = intrinsic.TURNING if kind == FALLBACK_TURNING else intrinsic.ACCELERATING
    chose_random = intrinsic.fallback_act(avoid, readings, random, add, theta, last, action)
    return RANDOM if chose_random else INTRINSIC


@njit(cache=True)
def run(steps, floating, scale, agent, act_args, learn_args, fallback, task, physics, bump,
        stream, io, trace, first):
    """Up to `steps` protocol steps from the current state, stopping after a step that
    reaches the goal (GOAL), before a step the task's buffered draws might not cover
    (REFILL), or at a step MuJoCo refuses (FAILED: the task kernel's status in io).
    Returns (steps done, why). trace[first + k] gets the position after step k + 1.

    agent: (rng, exploration, actions, decided, flag decisions, counts = [steps, size,
    tail, referred, memory decisions, fallback decisions, last decider, the fallback's
    last choice]); act_args and
    learn_args: ebrl.Agent's kernel arguments; fallback: (kind, rate, sd, add, theta,
    last); task: (action noise, sensor noise, velocity noise, plan, act, velocity6,
    qvel, substeps = [count]); physics: Physics.kernel_args; bump: Physics.bump_args or
    None's stand-in; stream: (buffer, cursor, cache); io: (obs, codes, velocity, action,
    env action, u, z, vz, status = [code]): codes and velocity hold the last
    observation, obs the agent's input (the range codes times `scale`, then the
    velocity: protocol.agent_input's)."""
    rng, exploration, actions, decided, flag_decisions, counts = agent
    kind, rate, sd, add, theta, last = fallback
    sensor_noise, velocity_noise, plan, act, velocity6, qvel, substeps = task
    buf, cursor, cache = stream
    obs, codes, velocity, action, env_action, u, z, vz, status_out = io
    m, d, flags, ctrl, qpos, xpos, xmat, sensordata, bad_qacc, ints, floats = physics
    n_codes = codes.shape[0]
    for k in range(steps):
        if not _task_draws(buf, cursor, cache, sensor_noise, velocity_noise, u, z, vz):
            return k, REFILL
        # ebrl.Agent.act on protocol.agent_input's observation
        for i in range(n_codes):
            obs[i] = codes[i] * scale
        if floating:
            for i in range(velocity.shape[0]):
                obs[n_codes + i] = velocity[i]
        element = agent_kernels.act(obs, counts[1], *act_args)
        explore = rng.random() < exploration
        if element >= 0 and not explore:
            action[:] = actions[element]
            counts[3] = element
            if flag_decisions:
                decided[element] = True
            counts[4] += 1
            counts[6] = MEMORY
        else:
            chose = _fallback(kind, obs[:n_codes], rng, rate, sd, add, theta, last, action)
            counts[5] += 1
            counts[6] = EXPLORATION if element >= 0 else chose
            counts[7] = chose
        # tasks.Environment.step: the compiled step on a clipped copy of the action
        env_action[:] = action
        if floating:
            status, n, goal, new_codes, new_velocity = task_kernels.floating_step(
                env_action, u, z, vz, m, d, flags, ctrl, qpos, xpos, xmat, sensordata,
                bad_qacc, ints, floats, velocity6, qvel, bump)
        else:
            status, n, goal, new_codes = task_kernels.two_wheel_step(
                env_action, u, z, m, d, flags, ctrl, qpos, xpos, xmat, sensordata, bad_qacc,
                ints, floats, plan, act)
            new_velocity = velocity
        substeps[0] += n
        if status != task_kernels.OK:
            status_out[0] = status
            return k, FAILED
        codes[:] = new_codes
        if floating:
            velocity[:] = new_velocity
        # ebrl.Agent.learn, then the trace
        reward = 1.0 if goal else 0.0
        counts[1], counts[2], counts[3] = agent_kernels.learn(
            obs, action, reward, counts[0], counts[1], counts[2], counts[3], *learn_args)
        counts[0] += 1
        x, y, _ = task_kernels.base_pose(qpos, xpos, xmat, ints, floats)
        trace[first + k, 0] = x
        trace[first + k, 1] = y
        if goal:
            return k + 1, GOAL
    return steps, BUDGET


def _fallback_spec(fallback):
    """(kind, rate, sd, add, theta, last) for `run`, or None for a fallback it cannot run."""
    if type(fallback) is intrinsic.RandomWalk:
        return (FALLBACK_RANDOM_WALK, 0.0, float(fallback.sd), False, intrinsic.THETA,
                np.zeros(0))
    if type(fallback) is intrinsic.Intrinsic and fallback._kind is not None:
        kind = (FALLBACK_TURNING if fallback._kind == intrinsic.TURNING
                else FALLBACK_ACCELERATING)
        last = fallback.last if fallback.last is not None else np.zeros(0)
        return (kind, float(fallback.random_rate), float(fallback.sd), fallback._add,
                intrinsic.THETA, last)
    return None


class _StreamState:
    """The task's RandomState as buffered doubles for `run`, and back: `fill` saves its
    state and draws the buffer; `settle` winds it to just past the doubles used, with
    legacy_gauss's cached value as `run` left it."""

    def __init__(self, random):
        self.random = random
        self.buffer = np.zeros(0)
        self.cursor = np.zeros(1, dtype=np.int64)
        self.cache = np.zeros(2)
        self._saved = None

    def fill(self):
        self._saved = state = self.random.get_state()
        self.cache[0], self.cache[1] = float(state[3]), float(state[4])
        self.buffer = self.random.random_sample(BUFFER)
        self.cursor[0] = 0

    def settle(self):
        if self._saved is None:
            return
        self.random.set_state(self._saved)
        if self.cursor[0]:
            self.random.random_sample(int(self.cursor[0]))
        state = self.random.get_state()
        self.random.set_state(state[:3] + (int(self.cache[0]), float(self.cache[1])))
        self._saved = None


class Loop:
    """The compiled stretches for one run's environment and agent (`supports` first)."""

    def __init__(self, env, agent, trace):
        import tasks
        task, physics = env.task, env.physics
        self.env, self.agent, self.trace = env, agent, trace
        self.floating = isinstance(task, tasks.floating.Floating)
        self.scale = protocol._reading_scale()
        config = task.config
        velocity_noise = float(config.velocity_noise) if self.floating else 0.0
        self.counts = np.zeros(8, dtype=np.int64)
        self.stream = _StreamState(task.random)
        self.substeps = np.zeros(1, dtype=np.int64)
        n_codes = physics.n_beams
        dim = agent.action_dim
        self.codes, self.velocity = np.zeros(n_codes), np.zeros(2)
        self.status = np.zeros(1, dtype=np.int64)
        def noise(on, n):
            return np.zeros(n if on else 0)
        self.io = (np.zeros(agent.obs_dim), self.codes, self.velocity, np.zeros(dim),
                   np.zeros(dim), noise(task.action_noise > 0, 2),
                   noise(task.sensor_noise > 0, n_codes), noise(velocity_noise > 0, 2),
                   self.status)
        plan = getattr(task, "_plan", np.zeros(6))
        bump = getattr(physics, "bump_args", None)
        if bump is None:  # the two-wheel drive: a stand-in of the same types
            bump = (np.zeros(1, dtype=np.int32), np.zeros(0), np.zeros(0, dtype=np.int32),
                    np.zeros(6, dtype=np.int64), np.zeros(0), np.zeros(0), np.zeros(2))
        self.task_args = (float(task.sensor_noise), velocity_noise, plan, physics._act, physics._body_velocity, physics._qvel,
                          self.substeps)
        self.bump = bump
        self.fallback = _fallback_spec(agent.fallback)

    @staticmethod
    def supports(env, agent, on_step=None):
        """True where `run` computes what the step-by-step loop does: EBRL with a paper
        fallback, on a task with a compiled step, and no per-step callback."""
        import ebrl
        import tasks
        return (on_step is None and type(agent) is ebrl.Agent
                and _fallback_spec(agent.fallback) is not None
                and isinstance(env, tasks.Environment) and env.compiled
                and not env._flat_observation
                and isinstance(env.task, (tasks.two_wheel.TwoWheel, tasks.floating.Floating)))

    def stretch(self, first, steps, observation=None):
        """Runs up to `steps` steps, writing trace[first:], from `observation` (a
        TimeStep's: the first, or one after a reset), or, without one, from where the
        last stretch stopped. Returns (steps done, True at the goal); the agent, the
        environment and the task's RandomState are left as the step-by-step loop leaves
        them."""
        env, agent, counts = self.env, self.agent, self.counts
        task, physics = env.task, env.physics
        if observation is not None:
            self.codes[:] = observation["range"]
            if self.floating:
                self.velocity[:] = observation["velocity"]
        counts[:] = (agent.steps, agent._size, agent._tail, agent._referred,
                     agent.memory_decisions, agent.fallback_decisions, -1, -1)
        self.substeps[0] = physics.substeps
        agent_args = (agent.rng, agent._exploration, agent._action, agent._decided,
                      agent._flag_decisions, counts)
        done, why = 0, REFILL
        try:
            while why == REFILL and done < steps:
                self.stream.fill()
                k, why = run(steps - done, self.floating, self.scale, agent_args, agent._act_args,
                             agent._learn_args, self.fallback, self.task_args,
                             physics.kernel_args, self.bump,
                             (self.stream.buffer, self.stream.cursor, self.stream.cache),
                             self.io, self.trace, first + done)
                done += k
                self.stream.settle()
        finally:
            agent.steps, agent._size, agent._tail, agent._referred = map(int, counts[:4])
            agent.memory_decisions, agent.fallback_decisions = int(counts[4]), int(counts[5])
            physics.substeps = int(self.substeps[0])
            env._step_count += done
            if counts[6] >= 0:
                agent.decision = DECIDERS[counts[6]]
                agent.used_memory = bool(counts[6] == MEMORY)
            if counts[7] >= 0 and type(agent.fallback) is intrinsic.Intrinsic:
                agent.fallback.choice = DECIDERS[counts[7]]
        if why == FAILED:
            physics.raise_for(int(self.status[0]))
        goal = why == GOAL
        task._at_goal = goal
        if goal:
            env._reset_next_step = True
            agent.end_episode()
        return done, goal

