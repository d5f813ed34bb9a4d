"""Gymnasium environments for every registered robot, one id each, registered in one loop.

    import gymnasium, tasks.gym
    env = gymnasium.make("EBRL/TwoWheel-v1", render_mode="rgb_array")   # or DiffDrive, ...
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

An id is known in a process that imported this module. Gymnasium (1.0 on) no longer
loads plugins at import, so a process that did not, a worker of a vector environment
started with spawn or forkserver say, finds it through `"tasks.gym:EBRL/TwoWheel-v1"`:
`gymnasium.make` imports the module before the id, and registering again is harmless.
Options of
`tasks.load` pass through: `room` (models.rooms: "medium", "random:21x21:3", a map file),
any field of tasks.TaskConfig (`sensor_noise`, `action_noise`, `start_jitter`, `bump`,
...); and `max_episode_steps` (default: the robot's budget of Section 3.6).

An id's version names its dynamics, as Gymnasium's own ids do: `VERSION` (v1) is
protocol 8's (tasks.protocols.PROTOCOL_VERSION; `VERSIONS` says what each version is).
An older version stays registered (`DEPRECATED`): `gymnasium.make` of it warns
(DeprecationWarning) and makes the current version's environment, the only one the code
can make. docs/environments/ has a page per id, written from this registry by
experiments.outputs.gym_pages.

A thin adapter of our dm_env tasks rather than Shimmy's dm_control converter: reset(seed)
must reseed the task's own random stream (start jitter, sensor and action noise) to
reproduce a trajectory, and Shimmy's converter writes a wrong render_fps into the class
metadata. Reaching the goal is `terminated`; the step limit (Gymnasium's TimeLimit) is
`truncated`, never `terminated`.

Spaces are float32, as Gymnasium's own MuJoCo environments: the action in [-1, 1] (the
task takes it as float64), the range codes in [0, 255] (Section 3.2's codes). The
floating drive's velocity (units/step) has no bound: its thrust changes it by up to 0.2
units/step every step and nothing caps it (the floor is frictionless, there is no drag,
and with bump="bounce" a wall takes no speed away), so no finite bound holds for every
run. Rendering makes its OpenGL context at the first frame (tasks.render), so an
environment that never renders loads no OpenGL library.
"""
import warnings

import gymnasium
import numpy as np
from gymnasium import spaces

from tasks.kernels.bindings import stage_timers_off
from tasks.navigation import SENSOR_LEVELS
from tasks.robots import ROBOTS

NAMESPACE = "EBRL"
#: The current version of every id: the dynamics it makes.
VERSION = 1
#: Each version, what it makes (docs/environments/'s version history).
VERSIONS = {
    1: "protocol 8's dynamics (tasks.protocols.PROTOCOL_VERSION 8)",
    0: "the first id, registered on 2026-11-23 under protocol 2; its environment followed "
       "the protocols' bodies and task readings up to protocol 8 without a new version",
}
#: The older versions, each still registered: it warns and makes VERSION's environment.
DEPRECATED = (0,)
RENDER_SIZE = (480, 640)  # height, width of render_mode="rgb_array"
#: The observations' bounds by key; a key not here is unbounded (see above).
OBSERVATION_BOUNDS = {"range": (0.0, float(SENSOR_LEVELS))}


# Shown, as Gymnasium shows its own (gymnasium.logger): Python hides a DeprecationWarning
# raised outside __main__.
warnings.filterwarnings("default", category=DeprecationWarning, module=r"^tasks\.gym$")


def env_id(robot, version=VERSION):
    """'two_wheel' -> 'EBRL/TwoWheel-v1' (version: another of VERSIONS)."""
    return f"{NAMESPACE}/{''.join(p.capitalize() for p in robot.split('_'))}-v{version}"


def _space(spec, bounds=None):
    """A float32 Box of a dm_env spec's shape, bounded by `bounds` (low, high), else by the
    spec's own (a BoundedArray), else unbounded."""
    low, high = bounds or (getattr(spec, "minimum", -np.inf), getattr(spec, "maximum", np.inf))
    return spaces.Box(np.broadcast_to(np.float32(low), spec.shape),
                      np.broadcast_to(np.float32(high), spec.shape), spec.shape, np.float32)


def _observation(observation):
    return {k: np.asarray(v, dtype=np.float32) for k, v in observation.items()}


class NavigationEnv(gymnasium.Env):
    """One robot's navigation task (tasks.load) as a Gymnasium environment."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": None}  # set per instance

    def __init__(self, robot, *, render_mode=None, drive=None, **task_fields):
        import tasks
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.robot = robot
        self._env = tasks.load(robot, drive=drive, seed=0, **task_fields)
        self.render_mode = render_mode
        self.observation_space = spaces.Dict(
            {k: _space(s, OBSERVATION_BOUNDS.get(k))
             for k, s in self._env.observation_spec().items()})
        self.action_space = _space(self._env.action_spec())
        self._env.reset()
        self.metadata = dict(self.metadata,
                             render_fps=1.0 / self._env.physics.step_seconds)

    @property
    def physics(self):
        return self._env.physics

    def _info(self):
        x, y, heading = self._env.physics.robot_pose()
        return {"pose": np.array([x, y, heading]), "is_success": self._env.physics.in_goal()}

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        if seed is not None:  # the task's own stream: start jitter, sensor and action noise
            self._env.task.reseed(seed)
        ts = self._env.reset()
        return _observation(ts.observation), self._info()

    def step(self, action):
        with stage_timers_off():  # no clock reads for mjData.timer, which nothing reads
            ts = self._env.step(action)
        terminated = ts.last() and ts.discount == 0.0
        return _observation(ts.observation), float(ts.reward), terminated, False, self._info()

    @property
    def dm_env(self):
        """The dm_env environment this adapts (tasks.Environment)."""
        return self._env

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        height, width = RENDER_SIZE
        return self._env.physics.render(height=height, width=width, camera_id="top")

    def close(self):
        if self._env is not None:
            self._env.close()
            self._env = None


def deprecated(robot, version, **options):
    """The entry point of an id of a DEPRECATED version: warns, naming the current id, and
    makes the current environment (NavigationEnv)."""
    warnings.warn(f"{env_id(robot, version)} is deprecated: it makes {env_id(robot)}, "
                  f"{VERSIONS[VERSION]}; use {env_id(robot)} (docs/environments/{robot}.md)",
                  DeprecationWarning, stacklevel=1)
    return NavigationEnv(robot, **options)


def register_all():
    """Registers one id per robot of the registry and its DEPRECATED versions (idempotent)."""
    for name, robot in ROBOTS.items():
        if env_id(name) not in gymnasium.registry:
            gymnasium.register(env_id(name), entry_point=NavigationEnv,
                               max_episode_steps=robot.budget, kwargs={"robot": name})
        for version in DEPRECATED:
            if env_id(name, version) not in gymnasium.registry:
                gymnasium.register(env_id(name, version), entry_point=deprecated,
                                   max_episode_steps=robot.budget,
                                   kwargs={"robot": name, "version": version})


register_all()
