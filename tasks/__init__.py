"""dm_control tasks of Unemi (2000): one navigation base, one module per robot."""
import gc

import numpy as np
from dm_control.rl import control

import models
from tasks import floating, navigation, two_wheel

# robot name -> (Physics class, Task class, substeps the Environment runs per step)
ROBOTS = {
    "two_wheel": (two_wheel.Physics, two_wheel.TwoWheel, two_wheel.MOVE_SUBSTEPS),
    "floating": (floating.Physics, floating.Floating, floating.SUBSTEPS - 1),
}


class Environment(control.Environment):
    """dm_control's Environment whose close() frees the physics and its GL context, so
    no renderer is left for the interpreter's exit to trip over."""

    def close(self):
        physics, self._physics = getattr(self, "_physics", None), None
        if physics is not None:
            # Cameras made by render() hold the GL context until collected; the context
            # is freed only when none is left.
            gc.collect()
            physics.free()


def load(robot, *, seed=None, sensor_noise=navigation.SENSOR_NOISE,
         action_noise=navigation.ACTION_NOISE, start_jitter=True):
    """The navigation environment for `robot` ("two_wheel" or "floating")."""
    if robot not in ROBOTS:
        raise ValueError(f"unknown robot {robot!r}; valid: {', '.join(ROBOTS)}")
    physics_cls, task_cls, n_sub_steps = ROBOTS[robot]
    physics = physics_cls.from_xml_string(*models.compose(robot))
    task = task_cls(sensor_noise=sensor_noise, action_noise=action_noise,
                    start_jitter=start_jitter, random=np.random.RandomState(seed))
    return Environment(physics, task, n_sub_steps=n_sub_steps, time_limit=float("inf"))
