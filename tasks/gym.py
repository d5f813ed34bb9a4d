"""Gymnasium environments for every registered robot, one id each, registered in one loop.

    import gymnasium, tasks.gym
    env = gymnasium.make("EBRL/TwoWheel-v0", render_mode="rgb_array")   # or DiffDrive, ...
    obs, info = env.reset(seed=0)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())

An id is known in a process that imported this module. Gymnasium (1.0 on) no longer
loads plugins at import, so a process that did not, a worker of a vector environment
started with spawn or forkserver say, finds it through `"tasks.gym:EBRL/TwoWheel-v0"`:
`gymnasium.make` imports the module before the id, and registering again is harmless.
Options of
`tasks.load` pass through: `room` (models.rooms: "medium", "random:21x21:3", a map file),
any field of tasks.TaskConfig (`sensor_noise`, `action_noise`, `start_jitter`, `bump`,
...); and `max_episode_steps` (default: the robot's budget of Section 3.6).

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
import gymnasium
import numpy as np
from gymnasium import spaces

from tasks.kernels.bindings import stage_timers_off
from tasks.navigation import SENSOR_LEVELS
from tasks.robots import ROBOTS

NAMESPACE = "EBRL"
VERSION = 0
RENDER_SIZE = (480, 640)  # height, width of render_mode="rgb_array"
#: The observations' bounds by key; a key not here is unbounded (see above).
OBSERVATION_BOUNDS = {"range": (0.0, float(SENSOR_LEVELS))}


def env_id(robot):
    """'two_wheel' -> 'EBRL/TwoWheel-v0'."""
    return f"{NAMESPACE}/{''.join(p.capitalize() for p in robot.split('_'))}-v{VERSION}"


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


def register_all():
    """Registers one id per robot of the registry (idempotent)."""
    for name, robot in ROBOTS.items():
        if env_id(name) not in gymnasium.registry:
            gymnasium.register(env_id(name), entry_point=NavigationEnv,
                               max_episode_steps=robot.budget, kwargs={"robot": name})


register_all()
