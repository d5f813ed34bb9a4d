"""One run of Section 3.6's procedure: a robot, a condition and a seed, learning for a
budget, under a protocol's readings (tasks.protocols).

The agent learns from step 0. When the robot reaches the goal the trial ends, the
next starts from the jittered start, and the memory persists, until the budget of
agent steps is spent. `execute` computes a run and returns plain data, so the
same function serves a local process pool and a Ray cluster; the driver writes it.
"""
from __future__ import annotations

import dataclasses
import functools
import pathlib
import time
from typing import TYPE_CHECKING, Any

import numpy as np

import ebrl
import tasks
from experiments.running.learners import learner
from models import rooms
from tasks.config import TaskConfig
from tasks.protocols import PROTOCOLS
from tasks.robots import resolve

if TYPE_CHECKING:
    from ebrl.behaviour import Accelerating, Turning
    from tasks.robots import Robot

#: Positions are stored as int16 hundredths of a unit.
TRACE_SCALE = 100.0
#: The end of a first-trial run's label (RunSpec.first_trial): "two_wheel.first_trial".
FIRST_TRIAL = ".first_trial"
#: Between a label and its room's name (models.rooms.tag): "two_wheel@random-21x21-3".
ROOM_MARK = "@"


@dataclasses.dataclass(frozen=True)
class RunSpec:
    #: A name in the robot registry (tasks.ROBOTS), or a path to a robot file.
    robot: str
    condition: str
    seed: int
    steps: int
    #: Agent parameters that differ from Table 1 (for sweeps), as sorted pairs.
    overrides: tuple[tuple[str, Any], ...] = ()
    #: The drive of a robot file (None for a registered robot: the registry has it).
    drive: str | None = None
    #: The learner: "ebrl" (the paper's) or a baseline of ebrl.baselines ("qtable", "mfec").
    agent: str = "ebrl"
    #: A genome of ebrl.behaviour (`ebrl run --behaviour FILE`): the fallback, its random
    #: action and the learning variables' initial values; None: Section 3.4's rules.
    behaviour: Turning | Accelerating | None = None
    #: True: the run ends at its first goal (or its budget), its first trial bit for bit
    #: a full run's (`ebrl run --first-trial`); in its own folders (`label`).
    first_trial: bool = False
    #: A protocol's name (tasks.protocols.PROTOCOLS): "adopted" (this replication's current
    #: readings) or "literal" (the paper as written).
    protocol: str = "adopted"
    #: The room (models.rooms: a shipped map's name, random:WxH:SEED or a map file); None:
    #: the paper's `sutton` (so named, it is made None). A run in another room has
    #: "@<room>" after its label, so runs in different rooms never share a folder.
    room: str | None = None

    def __post_init__(self):
        if self.room is not None:
            if str(self.room) == rooms.DEFAULT:
                object.__setattr__(self, "room", None)
            else:
                object.__setattr__(self, "room", str(self.room))

    @property
    def entry(self) -> Robot:
        """The robot's registry entry (tasks.robots.Robot), under the spec's protocol."""
        return resolve(self.robot, self.drive).under(self.protocol)

    @property
    def label(self) -> str:
        """The robot's name in folders and tables: its registered name, or its file's stem;
        with ".<agent>" after it for a learner other than EBRL, and FIRST_TRIAL after
        that for a first-trial run; "@<room>" (models.rooms.tag) last, in a room other
        than the paper's."""
        name = (self.robot if self.drive is None and not self.robot.endswith(".toml")
                else pathlib.Path(self.robot).stem)
        name = name if self.agent == "ebrl" else f"{name}.{self.agent}"
        name = name + FIRST_TRIAL if self.first_trial else name
        if self.room is None:
            return name
        return f"{name}{ROOM_MARK}{rooms.tag(self.room)}"

    @property
    def name(self) -> str:
        return f"{self.label}/{self.condition}/seed_{self.seed:03d}"

    def agent_config(self) -> Any:
        """EBRL: Table 1's column for the robot; a baseline: its config's defaults; with the
        robot's readings (its protocol's: tasks.protocols.Protocol.readings_for), then the
        overrides, that name the config's fields."""
        config_cls = learner(self.agent).config
        fields = {f.name for f in dataclasses.fields(config_cls)}
        mine = {k: v for k, v in (self.entry.agent_readings() | dict(self.overrides)).items()
                if k in fields}
        if self.behaviour is not None:
            genome = ebrl.behaviour.config_fields(self.behaviour)
            mine.update({k: v for k, v in genome.items() if k in fields})
        if self.agent == "ebrl":
            return ebrl.paper_config(self.entry.table1, **mine)
        return config_cls(**mine)

    def task_config(self) -> TaskConfig:
        """The paper's task with the robot's readings, then the overrides that name task
        fields."""
        fields = {f.name for f in dataclasses.fields(TaskConfig)}
        return self.entry.task_config(**{k: v for k, v in self.overrides if k in fields})

    def parameters(self) -> dict[str, Any]:
        """Everything that determines the run's result; a rerun matches on this."""
        entry, task = self.entry, self.task_config()
        return {
            "protocol_version": PROTOCOLS[self.protocol].version,
            "robot": self.label,
            "robot_file": None if self.drive is None else str(entry.model),
            "robot_name": entry.name,
            "drive": entry.drive,
            "condition": self.condition,
            "seed": self.seed,
            "steps": self.steps,
            "learner": self.agent,
            "agent": dataclasses.asdict(self.agent_config()),
            "avoidance": entry.avoidance,
            "modalities": [list(m) for m in entry.modalities],
            "task": dataclasses.asdict(task),
            "model_sha256": model_digest(entry, task, self.room),
        } | ({} if self.behaviour is None else {"behaviour": _genome_dict(self.behaviour)}) \
          | ({"first_trial": True} if self.first_trial else {}) \
          | ({"mount_file": str(pathlib.Path(self.robot).resolve())}
             if self.robot.endswith(".toml") else {}) \
          | ({} if self.protocol == "adopted" else {"protocol": self.protocol}) \
          | ({} if self.room is None else {"room": self.room})


def _genome_dict(genome):
    return ebrl.behaviour.to_dict(genome)


def model_digest(entry, task_config, room=None):
    """A digest of the composed MJCF with the entry's options and the task config's edits,
    so results made with another model never match (tasks.compiled_model: composed and
    compiled once per process and model, the run then loads a copy)."""
    return tasks.compiled_model(entry, task_config, room)[1]


def seeds_for(seed):
    """(environment seed, agent seed). A seed gives the same environment stream in
    both conditions, so the conditions are compared on paired random sequences."""
    env_state, agent_state = np.random.SeedSequence(seed).generate_state(2)
    return int(env_state), int(agent_state)


def make_agent(spec, env):
    """The agent for a run: Table 1's column for the robot, the condition's fallback
    behaviour, and eq 3's modalities with their weights (one group per modality)."""
    entry = spec.entry
    obs = env.observation_spec()
    sizes = [obs[key].shape[0] for key, _ in entry.modalities]
    groups = weights = None
    if len(sizes) > 1:
        bounds = np.cumsum([0] + sizes)
        groups = [np.arange(lo, hi) for lo, hi in zip(bounds[:-1], bounds[1:])]
        weights = [w for _, w in entry.modalities]
    _, agent_seed = seeds_for(spec.seed)
    config = spec.agent_config()
    # The fallback's own readings: fields of every learner's config (ebrl.Config, the
    # baselines' ebrl.baselines.common._Fallback), so the drive's readings reach every learner.
    switches = {k: getattr(config, k) for k in ebrl.config.FALLBACK_READINGS}
    if spec.behaviour is not None:
        switches.pop("eq9_dead_zone", None)  # the genome's hold decides
        fallback = ebrl.behaviour.fallback(spec.behaviour, spec.condition, **switches)
    else:
        fallback = ebrl.intrinsic.fallback_for(entry.avoidance, spec.condition,
                                               config.intrinsic_random_rate, config.random_sd,
                                               **switches)
    agent_cls = learner(spec.agent).agent
    return agent_cls(config, sum(sizes), env.action_spec().shape[0], fallback,
                     groups=groups, group_weights=weights, seed=agent_seed)


@functools.cache
def _composer(keys, n_codes):
    """(compose, its layout, the ranges' offset, the input's size, the codes' scale) for
    the modalities `keys` (experiments.running.fused.compose; imported here, not at the
    top: importing it loads MuJoCo and numba, which the command line's checks do
    without)."""
    from experiments.running import fused
    from tasks.navigation import READING_SCALE
    parts, range_at = fused.layout(keys, n_codes)
    size = sum(n_codes if k == "range" else 2 for k in keys)
    return fused.compose, parts, range_at, size, READING_SCALE


def agent_input(observation, keys=("range",)):
    """(agent observation, ranges for the fallback): the modalities `keys` in order,
    the range codes scaled to [0, 1] (Section 3.4), the velocity (units/step) as it is
    (experiments.running.fused.compose, the compiled loop's builder too)."""
    codes = observation["range"]
    compose, parts, range_at, size, scale = _composer(tuple(keys), len(codes))
    obs = np.empty(size)
    compose(codes, observation.get("velocity", _NO_VELOCITY), parts, scale, obs)
    return obs, obs[range_at: range_at + len(codes)]


#: The velocity of an observation without one.
_NO_VELOCITY = np.zeros(0)


class Trials:
    """Section 3.6's loop over an environment and an agent: the agent learns at every
    step; at the goal the trial ends (the agent's learn(last=True)) and the next starts
    from a reset. `run(steps)` goes on from where the last call stopped, step by step
    (act, env.step, learn) or, where experiments.running.fused supports the pair (EBRL
    with a compiled fallback, a compiled drive, no on_step), in stretches of one compiled
    call each: the same bits (tests/test_fused.py). `stretch` caps a stretch's length.

    trace[k]: the position after step k (k = 0: the first start); starts[i]: the start of
    trial i; trial_ends[i]: the step at which trial i ended. Trial i's path is starts[i]
    then trace[end(i-1)+1 : end(i)+1].

    trials: stop after that many trials end (1: a first-trial run, RunSpec.first_trial),
    even with steps left; `done` then says so and `run` does nothing more. The trial
    that ends is the same bits as in a run without the stop (its reset included, so
    starts has the next trial's start as ever)."""

    def __init__(self, env, agent, keys, budget, *, fused=True, on_step=None, stretch=None,
                 trials=None):
        self.env, self.agent, self.keys, self.on_step = env, agent, keys, on_step
        self.trials = trials
        self.trace = np.empty((budget + 1, 2), dtype=np.float32)
        self.starts, self.trial_ends, self.step = [], [], 0
        self._ts = env.reset()
        self._pose = env.physics.robot_pose
        self.starts.append(self._pose()[:2])
        self.trace[0] = self.starts[0]
        self._loop = None
        if fused:
            from experiments.running import fused as fused_loop
            if fused_loop.Loop.supports(env, agent, on_step, keys):
                self._loop = fused_loop.Loop(env, agent, self.trace, keys)
        self._stretch = stretch
        self._observation = self._ts.observation

    @property
    def fused(self):
        """True when the loop runs in compiled stretches."""
        return self._loop is not None

    @property
    def done(self):
        """True once `trials` trials have ended (never without `trials`)."""
        return self.trials is not None and len(self.trial_ends) >= self.trials

    @property
    def observation(self):
        """The last observation, as the next step reads it."""
        if self._loop is not None and self._observation is None:
            return self._loop.last_observation
        return self._ts.observation

    def _trial_ended(self):
        self.trial_ends.append(self.step)
        self._ts = self.env.reset()
        self._observation = self._ts.observation
        self.starts.append(self._pose()[:2])

    def run(self, steps):
        """`steps` more protocol steps."""
        end = self.step + steps
        while self._loop is not None and self.step < end and not self.done:
            n = end - self.step if self._stretch is None else min(self._stretch, end - self.step)
            done, goal = self._loop.stretch(self.step + 1, n, self._observation)
            self.step, self._observation = self.step + done, None
            if goal:
                self._trial_ended()
        env, agent, on_step = self.env, self.agent, self.on_step
        while self.step < end and not self.done:
            self.step += 1
            obs, ranges = agent_input(self._ts.observation, self.keys)
            self._ts = env.step(agent.act(obs, ranges=ranges))
            agent.learn(self._ts.reward, self._ts.last())
            self.trace[self.step] = self._pose()[:2]
            if self._ts.last():
                self._trial_ended()
            if on_step is not None:
                ends = self.trial_ends
                on_step(self.step, env, self.trace, (ends[-1] + 1) if ends else 0,
                        self.starts[-1], agent)
        return self


def execute(spec, on_step=None, fused=True):
    """Runs one spec to its budget (a first-trial spec: to its first goal, if sooner) and
    returns its trials, trace (the positions up to its last step) and metrics.

    on_step(step, env, trace, trial_begin, trial_start, agent), if given, is called after
    every step (videos use it; agent.decision says who chose the step's action).
    fused: where experiments.running.fused supports the run, run stretches of steps in
    one compiled call each (Trials); fused=False forces the step-by-step loop.
    """
    from tasks.kernels.bindings import stage_timers_off

    env_seed, _ = seeds_for(spec.seed)
    env = tasks.load(spec.entry, seed=env_seed, config=spec.task_config(), room=spec.room)
    agent = make_agent(spec, env)
    keys = tuple(key for key, _ in spec.entry.modalities)
    started = time.perf_counter()
    trials = Trials(env, agent, keys, spec.steps, fused=fused, on_step=on_step,
                    trials=1 if spec.first_trial else None)
    with stage_timers_off():
        trials.run(spec.steps)
    seconds = time.perf_counter() - started
    env.close()
    return {
        "trial_ends": np.asarray(trials.trial_ends, dtype=np.int64),
        "steps_run": int(trials.step),
        "trace": compact(trials.trace[:trials.step + 1]),
        "starts": compact(trials.starts),
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
