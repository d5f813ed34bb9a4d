"""The realisations: how a drive's action reaches a body. One name each, and that one name
is used by the mount's action kind, the Physics class (here, `<Name>Physics` in the
module of that name), the kernel module (tasks.kernels.<name>) and its record
(`<Name>Record`):

| realisation | drive | the body | robots |
|---|---|---|---|
| `servos` | two_wheel | a planar base under velocity servos on speed and yaw rate | two_wheel |
| `wheels` | two_wheel | two wheel hinges under integrated-velocity servos | diff_drive |
| `wheel_motors` | two_wheel | two wheel hinges through a file's own torque motors | the car |
| `joint_motors` | two_wheel | a forward and a turn joint through a file's own actuators | kind joint_motors |
| `gait` | two_wheel | a legged robot walked by a CPG on its own actuators | the Ant, the quadruped |
| `thrusters` | floating | force motors along the world's x and y | floating, hovercraft |

Every robot names its realisation in its registry entry (tasks.robots.Robot.realisation:
the shipped robots by name, a mount by its action kind, a robot file by the contract's
actuators it has), and tasks.load builds it from REALISATIONS alone. The compiled side's
table is tasks.kernels.env_step.DISPATCH, by the same names.
"""
import dataclasses
import importlib

#: The drives' tasks (tasks.two_wheel.TwoWheel, tasks.floating.Floating), by drive.
DRIVE_TASKS = {"two_wheel": "tasks.two_wheel:TwoWheel", "floating": "tasks.floating:Floating"}


@dataclasses.dataclass(frozen=True)
class Realisation:
    """A realisation: its name, its drive, and its Task class where it has its own (the
    gait's: "module:Class"; None: the drive's)."""
    name: str
    drive: str
    task: str | None = None

    @property
    def module(self):
        """Its Python module, tasks.realisations.<name> (imported on first use)."""
        return importlib.import_module(f"tasks.realisations.{self.name}")

    def physics(self, **attributes):
        """Its Physics class; with attributes (a mount's: its joints, gains, legs...), a
        subclass that sets them."""
        cls = getattr(self.module, "".join(p.title() for p in self.name.split("_")) + "Physics")
        return type(cls.__name__, (cls,), attributes) if attributes else cls

    def task_class(self):
        """Its Task class: its own, else its drive's."""
        module, name = (self.task or DRIVE_TASKS[self.drive]).split(":")
        return getattr(importlib.import_module(module), name)


REALISATIONS = {r.name: r for r in (
    Realisation("servos", "two_wheel"),
    Realisation("wheels", "two_wheel"),
    Realisation("wheel_motors", "two_wheel"),
    Realisation("joint_motors", "two_wheel"),
    Realisation("gait", "two_wheel", task="tasks.realisations.gait:GaitTask"),
    Realisation("thrusters", "floating"),
)}
