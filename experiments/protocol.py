"""One run of the protocol: a robot, a condition and a seed, learning for a budget.

The agent learns from step 0. When the robot reaches the goal the trial ends, the
next starts from the jittered start, and the memory persists, until the budget of
agent steps is spent. `execute` computes a run and returns plain data, so the
same function serves a local process pool and a Ray cluster; the driver writes it.
"""
import dataclasses
import functools
import time

import numpy as np

import ebrl

#: Bump when a change alters what a run computes, so stale results are not reused.
PROTOCOL_VERSION = 2  # 2: the agent's float32 product and tie rule (f5fc609)
#: Positions are stored as int16 hundredths of a unit.
TRACE_SCALE = 100.0


@dataclasses.dataclass(frozen=True)
class RunSpec:
    robot: str
    condition: str
    seed: int
    steps: int
    #: Agent parameters that differ from Table 1 (for sweeps), as sorted pairs.
    overrides: tuple = ()

    @property
    def name(self):
        return f"{self.robot}/{self.condition}/seed_{self.seed:03d}"

    def agent_config(self):
        return ebrl.paper_config(self.robot, **dict(self.overrides))

    def parameters(self):
        """Everything that determines the run's result; a rerun matches on this."""
        return {
            "protocol_version": PROTOCOL_VERSION,
            "robot": self.robot,
            "condition": self.condition,
            "seed": self.seed,
            "steps": self.steps,
            "agent": dataclasses.asdict(self.agent_config()),
            "task": task_parameters(),
            "model_sha256": model_digest(self.robot),
        }


@functools.cache
def model_digest(robot):
    """A digest of the composed MJCF, so results made with another model never match.
    Computed once per process (composing takes about 20 ms, and every spec asks)."""
    import hashlib

    import models
    xml, _ = models.compose(robot)
    return hashlib.sha256(xml.encode()).hexdigest()[:16]


def task_parameters():
    from tasks import navigation
    return {
        "sensor_noise": navigation.SENSOR_NOISE,
        "action_noise": navigation.ACTION_NOISE,
        "start": list(navigation.START),
        "start_jitter_xy": navigation.START_JITTER_XY,
        "start_jitter_heading": navigation.START_JITTER_HEADING,
        "sensor_range": navigation.SENSOR_RANGE,
    }


def seeds_for(seed):
    """(environment seed, agent seed). A seed gives the same environment stream in
    both conditions, so the conditions are compared on paired random sequences."""
    env_state, agent_state = np.random.SeedSequence(seed).generate_state(2)
    return int(env_state), int(agent_state)


def make_agent(spec, env):
    """The agent for a run: Table 1 parameters, the condition's fallback behaviour, and
    for the floating robot eq 3's two modalities (ranges 0.7, velocity 0.3)."""
    obs = env.observation_spec()
    n_range = obs["range"].shape[0]
    obs_dim = n_range + (obs["velocity"].shape[0] if "velocity" in obs else 0)
    groups = weights = None
    if "velocity" in obs:
        groups = [np.arange(n_range), np.arange(n_range, obs_dim)]
        weights = [0.7, 0.3]
    _, agent_seed = seeds_for(spec.seed)
    config = spec.agent_config()
    fallback = ebrl.intrinsic.fallback_for(spec.robot, spec.condition,
                                           config.intrinsic_random_rate, config.random_sd)
    return ebrl.Agent(config, obs_dim, env.action_spec().shape[0], fallback,
                      groups=groups, group_weights=weights, seed=agent_seed)


@functools.cache
def _reading_scale():
    # Imported here, not at the top: tasks sets MUJOCO_GL, which rendering picks first.
    from tasks.navigation import SENSOR_LEVELS
    return 1.0 / SENSOR_LEVELS


def agent_input(observation):
    """(agent observation, readings for the fallback): readings scaled to [0, 1],
    then the velocity in units/step for the floating robot."""
    codes, velocity = observation["range"], observation.get("velocity")
    if velocity is None:
        readings = codes * _reading_scale()
        return readings, readings
    obs = np.empty(len(codes) + len(velocity))
    readings = np.multiply(codes, _reading_scale(), out=obs[: len(codes)])
    obs[len(codes):] = velocity
    return obs, readings


def execute(spec, on_step=None):
    """Runs one spec to its budget and returns its trials, trace and metrics.

    on_step(step, env, trace, trial_begin, trial_start), if given, is called after
    every step (videos use it).
    """
    import tasks

    env_seed, _ = seeds_for(spec.seed)
    env = tasks.load(spec.robot, seed=env_seed)
    agent = make_agent(spec, env)
    # trace[k]: the position after step k (k = 0: the first start); starts[i]: the
    # start of trial i. Trial i's path is starts[i] then trace[end(i-1)+1 : end(i)+1].
    trace = np.empty((spec.steps + 1, 2), dtype=np.float32)
    starts, trial_ends = [], []
    started = time.perf_counter()
    ts = env.reset()
    pose = env.physics.robot_pose
    starts.append(pose()[:2])
    trace[0] = starts[0]
    for step in range(1, spec.steps + 1):
        obs, readings = agent_input(ts.observation)
        ts = env.step(agent.act(obs, readings=readings))
        agent.learn(ts.reward, ts.last())
        trace[step] = pose()[:2]
        if ts.last():
            trial_ends.append(step)
            ts = env.reset()
            starts.append(pose()[:2])
        if on_step is not None:
            on_step(step, env, trace, (trial_ends[-1] + 1) if trial_ends else 0, starts[-1])
    seconds = time.perf_counter() - started
    env.close()
    return {
        "trial_ends": np.asarray(trial_ends, dtype=np.int64),
        "trace": compact(trace),
        "starts": compact(starts),
        "seconds": seconds,
        "memory_decisions": int(agent.memory_decisions),
    }


def compact(positions):
    """Positions in units -> int16 hundredths of a unit (the room spans 0..90)."""
    return np.rint(np.asarray(positions, dtype=np.float64) * TRACE_SCALE).astype(np.int16)


def trial_lengths(trial_ends):
    """Steps of each completed trial, from the steps at which they ended."""
    return np.diff(np.concatenate([[0], np.asarray(trial_ends, dtype=np.int64)]))


def metrics(trial_ends):
    """A run's figures: see the README's definitions."""
    lengths = trial_lengths(trial_ends)
    return {
        "goals": int(len(lengths)),
        "first_trial_steps": int(lengths[0]) if len(lengths) else None,
        "steps_per_trial": float(lengths.mean()) if len(lengths) else None,
        "last_trial_steps": int(lengths[-1]) if len(lengths) else None,
        "min_trial_steps": int(lengths.min()) if len(lengths) else None,
    }
