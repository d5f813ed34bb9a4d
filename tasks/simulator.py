"""MuJoCo and dm_control's MuJoCo, imported with rendering off (tasks.gl): the one place
the tasks' modules import them from, so whichever of them a process imports first, the
simulator never loads an OpenGL library at its import.

`tasks` itself imports nothing heavy (its registries: tasks.robots, tasks.protocols,
tasks.readings, tasks.mount); a module that needs the simulator writes
``from tasks.simulator import mujoco`` (and `dm_mujoco` for dm_control.mujoco) in place
of ``import mujoco``.
"""
from tasks import gl

gl.import_simulator()

import mujoco  # noqa: E402
from dm_control import mujoco as dm_mujoco  # noqa: E402

__all__ = ["mujoco", "dm_mujoco"]
