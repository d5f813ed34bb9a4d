"""The navigation environment: a registered robot compiled in its room (`compile_robot`,
`compiled_model`, once per process) and loaded as a dm_control Environment (`load`).

The heavy half of `tasks`: it imports MuJoCo and dm_control (tasks.simulator) and, through
the tasks, every kernel. `tasks` names these lazily (tasks.load, tasks.compiled_model, ...),
so its registries import without them.
"""
from __future__ import annotations

import copy
import dataclasses
import functools
import hashlib
import os

import dm_env
import numpy as np
from dm_control.rl import control

import models
from models import rooms
from tasks import beams, mount, navigation, placement, render
from tasks.config import TaskConfig
from tasks.realisations import REALISATIONS
from tasks.robots import Robot, resolve
from tasks.simulator import dm_mujoco, mujoco

__all__ = ["Environment", "load", "compile_robot", "compiled_model"]


class Environment(control.Environment):
    """dm_control's Environment whose step() runs the task's compiled step
    (Navigation.compiled_step: the hooks' work in one compiled call, tests/test_kernels.py
    checks it equal to the hooks step for step), and whose close()
    frees the physics and its renderer's GL context (tasks.render), so none is left for
    the interpreter's exit to trip over."""

    #: False runs dm_control's hooks one by one (the same kernels, a call each).
    compiled = True

    @property
    def steps_compiled(self) -> bool:
        """True when step() runs the task's compiled step (tasks.kernels.env_step.step): not
        switched off, and the observation not flattened (dm_control's hooks do that)."""
        return self.compiled and not self._flat_observation

    def step(self, action) -> dm_env.TimeStep:
        if self._reset_next_step or not self.steps_compiled:
            return super().step(action)
        reward, observation, discount = self._task.compiled_step(action, self._physics)
        if self.advance(1, discount is not None) and discount is None:
            discount = 1.0
        if discount is not None:
            return dm_env.TimeStep(dm_env.StepType.LAST, reward, discount, observation)
        return dm_env.TimeStep(dm_env.StepType.MID, reward, 1.0, observation)

    def advance(self, steps: int, goal: bool) -> bool:
        """Counts `steps` agent steps run by compiled code (this step() or a compiled
        loop); the episode ends at the goal or at the time limit, and the next step()
        then resets. Returns True when it ended. (dm_control's Environment keeps these
        counts in private fields and has no public way to set them: they are used here,
        in its subclass, and nowhere else.)"""
        self._step_count += steps
        last = goal or self._step_count >= self._step_limit
        if last:
            self._reset_next_step = True
        return last

    def close(self) -> None:
        physics, self._physics = getattr(self, "_physics", None), None
        if physics is not None:
            render.release(physics)
            physics.free()


def compile_robot(entry: Robot, config: TaskConfig = TaskConfig(),
                  room=None) -> tuple[mujoco.MjModel, mujoco.MjSpec]:
    """(MjModel, MjSpec) of the room with the registry entry's robot, and the task
    config's changes to the model: the robot's radius, the floating bump's walls.
    room: a map's name, random:WxH:SEED, a map file or a rooms.Map (models.rooms); None:
    the paper's. rooms.MapError when the map is bad or its corridors are narrower than
    the robot."""
    robot = mount.robot_spec(entry.mount) if entry.mount is not None else None
    layout = rooms.load(room)
    spec = models.compose(entry.model, timestep=entry.timestep, integrator=entry.integrator,
                          unit=entry.unit, robot=robot, room=layout)
    REALISATIONS[entry.realisation].task_class().edit_model(spec, config)
    try:
        model = spec.compile()
    except ValueError as e:
        raise ValueError(_refusal(entry, f"the robot does not compile in the room: "
                                         f"{str(e).splitlines()[0]}", "file")) from None
    if room is not None:
        radius = navigation.robot_radius(model) if navigation.named_id(
            model, mujoco.mjtObj.mjOBJ_GEOM, "hull") >= 0 else 0.0
        rooms.check_fits(layout, radius)
    return model, spec


@functools.lru_cache(maxsize=16)
def compiled_model(entry: Robot, config: TaskConfig = TaskConfig(),
                   room=None) -> tuple[mujoco.MjModel, str]:
    """(MjModel, digest): compile_robot's model, compiled once per process for these
    arguments, and a digest of its MJCF (sha256 of the spec's XML, 16 hex digits: what a
    run records, so results made with another model never match). tasks.load runs on a
    copy of the model; never change the one returned."""
    model, spec = compile_robot(entry, config, room)
    return model, hashlib.sha256(spec.to_xml().encode()).hexdigest()[:16]


def _refusal(entry, problem, field=None):
    """The one line of a robot refused at load: a mounted robot's in the mount's style,
    ``FILE: FIELD: problem`` (tasks.mount.MountError's; the field that fixes it, "file"
    where the robot file itself must change), a robot file's ``robot file FILE: problem``.
    problem: a message, or a ContractError (its field, ContractError.field)."""
    field = getattr(problem, "field", None) or field
    if entry.mount is not None:
        return f"{entry.mount.path}: {field or 'file'}: {problem}"
    return f"robot file {entry.model}: {problem}"


def _beams_field(entry):
    """The mount's field that sets a mounted robot's beams (None for a robot file)."""
    if entry.mount is None:
        return None
    return "beams.height" if entry.mount.beams.added else "beams.sensors"


def load(robot: str | os.PathLike | Robot, *, drive: str | None = None, seed: int | None = None,
         config: TaskConfig | None = None, room=None, **fields) -> Environment:
    """The navigation environment for `robot`: a name in tasks.ROBOTS or tasks.MOUNTS, a
    path to a mount file (.toml, tasks.mount), or a path to a robot file with drive
    "two_wheel" or "floating". config: a TaskConfig (default: the
    paper's with the robot's readings, Robot.task_config); room: the room (a shipped
    map's name, "random:WxH:SEED" or a map file: models.rooms; None: the paper's
    `sutton`); fields: TaskConfig fields to change (sensor_noise=0.0, bump="slide", ...)."""
    entry = robot if isinstance(robot, Robot) else resolve(robot, drive)
    config = dataclasses.replace(config or entry.task_config(), **fields)
    model = copy.copy(compiled_model(entry, config, room)[0])
    realisation = REALISATIONS[entry.realisation]
    task_cls = realisation.task_class()
    physics_cls = realisation.physics_class(**(entry.mount.action.physics_attributes()
                                               if entry.mount is not None else {}))
    try:
        physics = physics_cls.from_model(dm_mujoco.wrapper.MjModel(model))
        placement.check_start(physics, heading=entry.drive == "two_wheel")
        beams.check_self_hits(physics, _beams_field(entry))   # none reads the robot itself
    except navigation.ContractError as e:
        raise navigation.ContractError(_refusal(entry, e), e.field) from None
    task = task_cls(config, time_scale=entry.time_scale, random=np.random.RandomState(seed))
    # n_sub_steps 0: dm_control's step runs no substeps of its own; the drive's action
    # (before_step) runs its phases' substeps.
    return Environment(physics, task, n_sub_steps=0, time_limit=float("inf"))
