"""dm_control tasks of Unemi (2000): one navigation base, one module per drive.

`tasks.load(robot, ...)` takes a registered robot name (`tasks.ROBOTS`) or a path to a
robot file with `drive="two_wheel"` or `drive="floating"`.
"""
import gc

import models  # first: it picks the headless OpenGL backend before dm_control loads

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
from dm_control.mujoco import wrapper  # noqa: E402
from dm_control.rl import control  # noqa: E402

from tasks import floating, navigation, two_wheel  # noqa: E402
from tasks.robots import DRIVES, PAPER_ROBOTS, ROBOTS, Robot, resolve  # noqa: E402

__all__ = ["load", "compile_robot", "ROBOTS", "PAPER_ROBOTS", "DRIVES", "Robot", "resolve"]

# drive -> (Task class, Physics classes by the actuator that marks them, substeps the
# Environment runs per agent step)
_DRIVES = {
    "two_wheel": (two_wheel.TwoWheel, {"left_wheel": two_wheel.WheelPhysics,
                                       "forward": two_wheel.Physics},
                  two_wheel.move_substeps),
    "floating": (floating.Floating, {"thrust_x": floating.Physics}, floating.move_substeps),
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


def compile_robot(entry):
    """(MjModel, MjSpec) of the room with the registry entry's robot."""
    spec = models.compose(entry.model, timestep=entry.timestep, integrator=entry.integrator)
    try:
        return spec.compile(), spec
    except ValueError as e:
        raise ValueError(f"robot file {entry.model} does not compile in the room: "
                         f"{str(e).splitlines()[0]}") from None


def load(robot, *, drive=None, seed=None, sensor_noise=navigation.SENSOR_NOISE,
         action_noise=navigation.ACTION_NOISE, start_jitter=True):
    """The navigation environment for `robot`: a name in tasks.ROBOTS, or a path to a
    robot file with drive "two_wheel" or "floating"."""
    entry = robot if isinstance(robot, Robot) else resolve(robot, drive)
    task_cls, physics_classes, n_sub_steps = _DRIVES[entry.drive]
    model, _ = compile_robot(entry)
    names = {mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, i)
             for i in range(model.nu)}
    physics_cls = next((cls for act, cls in physics_classes.items()
                        if models.PREFIX + act in names), physics_classes[next(iter(physics_classes))])
    try:
        physics = physics_cls.from_model(wrapper.MjModel(model))
    except navigation.ContractError as e:
        raise navigation.ContractError(f"robot file {entry.model}: {e}") from None
    task = task_cls(sensor_noise=sensor_noise, action_noise=action_noise,
                    start_jitter=start_jitter, time_scale=entry.time_scale,
                    random=np.random.RandomState(seed))
    return Environment(physics, task, n_sub_steps=n_sub_steps(physics.timestep, entry.time_scale),
                       time_limit=float("inf"))
