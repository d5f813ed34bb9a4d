"""dm_control tasks of Unemi (2000): one navigation base, one module per drive.

`tasks.load(robot, ...)` takes a registered robot name (`tasks.ROBOTS`) or a path to a
robot file with `drive="two_wheel"` or `drive="floating"`.

This package imports nothing heavy: its registries (tasks.robots, tasks.protocols,
tasks.readings, tasks.realisations' table, tasks.mount) import without MuJoCo, dm_control
or numba, so `ebrl --help` and an argument's check never load the simulator. The names
that need it (`load`, `compile_robot`, `compiled_model`, `Environment`: tasks.environment)
are imported at their first use.
"""
import importlib

from tasks.config import TaskConfig
from tasks.realisations import REALISATIONS
from tasks.robots import DRIVES, MOUNTS, PAPER_ROBOTS, ROBOTS, Robot, resolve

#: The names tasks.environment defines, imported (with the simulator) at their first use.
_ENVIRONMENT = ("load", "compile_robot", "compiled_model", "Environment")

__all__ = ["load", "compile_robot", "compiled_model", "TaskConfig", "ROBOTS", "MOUNTS",
           "PAPER_ROBOTS", "DRIVES", "Robot", "resolve", "REALISATIONS"]


def __getattr__(name):
    """tasks.load and the other names of tasks.environment: its import loads MuJoCo."""
    if name in _ENVIRONMENT:
        return getattr(importlib.import_module("tasks.environment"), name)
    raise AttributeError(f"module 'tasks' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_ENVIRONMENT))
