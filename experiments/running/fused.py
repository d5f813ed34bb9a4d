"""Section 3.6's loop for a stretch of a trial in one compiled call: the speed path of
`experiments.running.execution.execute`, with the same bits as its step-by-step loop.

The step-by-step loop runs, per agent step, `ebrl.Agent.act`, `tasks.Environment.step`
and `ebrl.Agent.learn`: each a little Python around one compiled function
(`ebrl.agent.act_step`, `tasks.kernels.env_step.step` with the task's draws
`tasks.kernels.stream.task_draws`, `ebrl.steps.learn_step`, and at a goal
`ebrl.agent.end_trial`). `run` iterates those same functions inside one numba call, up
to a trial's end, on the same named records: the agent's (`Agent.record`, its numpy
Generator inside, drawn in place), its fallback's (`Agent.fallback_record`), the drive's
(`Physics.record`, the drive's record: tasks.kernels) and the task's random stream
(`Navigation.stream.record`, buffered doubles of its RandomState). So the Python per step
(argument checks, the dm_env TimeStep, the observation dict, bookkeeping) is paid once
per stretch.

It serves EBRL with a compiled fallback (the paper's) on a task with a compiled drive,
whose observation is the robot's modalities "range" and "velocity" (`observe`);
anything else (the baselines, an evolved genome's fallback, a video's per-step
callback, another drive or modality) runs the step-by-step loop (`Loop.supports`).
tests/test_fused.py checks the two alike, step for step, for every registered robot and
both conditions.
"""
import numpy as np
from numba import njit

import ebrl
import tasks
from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from ebrl import kernels as agent_kernels
from ebrl import steps as agent_steps
from compiled import records
from ebrl.agent import act_step, end_trial, invalid_observation
from tasks import navigation
from tasks.kernels import bindings, body
from tasks.kernels import env_step
from tasks.kernels.stream import task_draws

#: Why a stretch ended.
GOAL, BUDGET, REFILL, FAILED, INVALID = range(5)
#: The modalities the loop composes an observation of (Loop.supports refuses others).
MODALITIES = ("range", "velocity")


@records.record("codes", "velocity", "layout", "scale", "obs", "range_at", "u", "z",
                "sensor_noise", "vz", "velocity_noise", "env_action", "substeps", "status")
class Sensing(records.Record):
    """The loop's own record: the last sensor values (codes, velocity), the observation's
    layout (an index of MODALITIES per part) and the range codes' scale into it, the
    agent's input (obs) with the ranges' offset in it, the step's draws (u, z, vz) and
    their noise, the clipped action the drive takes, and the last stretch's substeps and
    MuJoCo status."""


Sensing.constructor = njit(cache=True)(lambda *values: Sensing(*values))


def layout(keys, n_codes):
    """(layout, range_at) of an observation of the modalities `keys` in order: each key's
    index in MODALITIES, and the range codes' offset in the agent's input."""
    parts = np.array([MODALITIES.index(k) for k in keys], dtype=np.int64)
    return parts, sum(n_codes if k == "range" else 2 for k in keys[:keys.index("range")])


@njit(cache=True)
def compose(codes, velocity, layout, scale, obs):
    """The agent's input, obs, from the sensor values by the modalities' layout: the range
    codes times the scale (Section 3.4: into [0, 1]), the velocity as it is. The one
    builder of the agent's input: the compiled loop's (`observe`) and the step-by-step
    loop's (experiments.running.execution.agent_input)."""
    at = 0
    for part in layout:
        if part == 0:
            for i in range(codes.shape[0]):
                obs[at + i] = codes[i] * scale
            at += codes.shape[0]
        else:
            for i in range(velocity.shape[0]):
                obs[at + i] = velocity[i]
            at += velocity.shape[0]


@njit(cache=True)
def observe(io):
    """The agent's input from the loop's sensor values (`compose`)."""
    compose(io.codes, io.velocity, io.layout, io.scale, io.obs)


@njit(cache=True)
def run(steps, agent, fallback, drive, stream, io, trace, first):
    """Up to `steps` protocol steps from the current state, stopping after a step that
    reaches the goal (GOAL, the trial ended for the agent), before a step the task's
    buffered draws might not cover (REFILL), at an observation the agent refuses
    (INVALID) or at a step MuJoCo refuses (FAILED, the status in io). Returns (steps
    done, why); trace[first + k] gets the position after step k + 1."""
    n_codes = io.codes.shape[0]
    io.substeps = 0
    for k in range(steps):
        if not task_draws(stream, io.u, io.z, io.sensor_noise, io.vz,
                                       io.velocity_noise):
            return k, REFILL
        observe(io)
        ranges = io.obs[io.range_at:io.range_at + n_codes]
        if act_step(agent, fallback, io.obs, ranges) == agent_kernels.INVALID:
            return k, INVALID
        io.env_action[:] = agent.action
        status, n, goal = env_step.step(drive, io.env_action, io.u, io.z, io.vz,
                                            io.codes, io.velocity)
        io.substeps += n
        if status != bindings.OK:
            io.status = status
            return k, FAILED
        agent_steps.learn_step(agent, 1.0 if goal else 0.0)
        x, y, _ = body.base_pose(drive)
        trace[first + k, 0] = x
        trace[first + k, 1] = y
        if goal:
            end_trial(agent, fallback)
            return k + 1, GOAL
    return steps, BUDGET


@njit(cache=True)
def outcome(io):
    """(substeps, status) of the last stretch, for Python."""
    return io.substeps, io.status


class Loop:
    """The compiled stretches for one run's environment and agent (`supports` first);
    keys: the observation's modalities in order (the robot's)."""

    def __init__(self, env, agent, trace, keys=("range",)):
        task, physics = env.task, env.physics
        self.env, self.agent, self.trace = env, agent, trace
        n_codes = physics.n_beams
        u, z, vz = task.draw_buffers(n_codes)
        parts, range_at = layout(keys, n_codes)
        #: The loop's record (Sensing): the last sensor values, the agent's input, draws.
        self._codes, self._velocity, self._obs = (np.zeros(n_codes), np.zeros(2),
                                                  np.zeros(agent.obs_dim))
        self.io = Sensing.build(
            codes=self._codes, velocity=self._velocity, layout=parts,
            scale=navigation.READING_SCALE, obs=self._obs, range_at=range_at, u=u, z=z,
            sensor_noise=float(task.sensor_noise), vz=vz,
            velocity_noise=float(task.velocity_noise), env_action=np.zeros(agent.action_dim),
            substeps=0, status=0)

    @property
    def last_observation(self):
        """The last sensor values, as the next stretch reads them: {"range", "velocity"}."""
        return {"range": self._codes, "velocity": self._velocity}

    @staticmethod
    def supports(env, agent, on_step=None, keys=("range",)):
        """True where `run` computes what the step-by-step loop does: EBRL with a compiled
        fallback, on a task with a compiled drive whose modalities it composes, and no
        per-step callback."""
        return (on_step is None and type(agent) is ebrl.Agent and agent.compiled
                and isinstance(env, tasks.Environment) and env.steps_compiled
                and "range" in keys and set(keys) <= set(MODALITIES))

    def stretch(self, first, steps, observation=None):
        """Runs up to `steps` steps, writing trace[first:], from `observation` (a
        TimeStep's: the first, or one after a reset), or, without one, from where the
        last stretch stopped. Returns (steps done, True at the goal); the agent, the
        environment and the task's random stream are left as the step-by-step loop
        leaves them."""
        env, agent = self.env, self.agent
        task, physics = env.task, env.physics
        if observation is not None:
            self._codes[:] = observation["range"]
            if "velocity" in observation:
                self._velocity[:] = observation["velocity"]
        done, why, stream = 0, REFILL, task.stream
        substeps, status = 0, bindings.OK
        while why == REFILL and done < steps:
            stream.ready()
            k, why = run(steps - done, agent.record, agent.fallback_record,
                         physics.record, stream.record, self.io, self.trace, first + done)
            n, status = outcome(self.io)
            done, substeps = done + k, substeps + n
            if why == REFILL:
                stream.fill()
        goal = why == GOAL
        env.advance(done, goal)
        task.finish(substeps, goal, physics, status if why == FAILED else bindings.OK)
        if why == INVALID:
            raise invalid_observation(self._obs)
        return done, goal
