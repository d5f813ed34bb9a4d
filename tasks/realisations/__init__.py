"""The realisations: how a drive's action reaches a body, one row each in REALISATIONS, the
one table that reaches all of a realisation's parts by explicit "module:Name" entries
(imported on first use, as Gymnasium's registry keeps its entry points):

| realisation | drive | the body | robots |
|---|---|---|---|
| `servos` | two_wheel | a planar base under velocity servos on speed and yaw rate | two_wheel |
| `wheels` | two_wheel | two wheel hinges under integrated-velocity servos | diff_drive |
| `wheel_motors` | two_wheel | two wheel hinges through a file's own torque motors | the car |
| `joint_motors` | two_wheel | a forward and a turn joint through a file's own actuators | kind joint_motors |
| `gait` | two_wheel | a legged robot walked by a CPG on its own actuators | the Ant, the quadruped |
| `thrusters` | floating | force motors along the world's x and y | floating, hovercraft |

A row names the realisation's Physics (its module here, tasks.realisations.<name>), its
compiled record, whose module holds its kernels (tasks.kernels.<name>: a two-wheel
realisation's PHASES, a floating one's `act` and `velocity`; tasks.kernels.env_step
picks them by the record's type), the mount action kind that selects it
(tasks.mount.kinds.KINDS, which also holds `actuators`, a kind that maps a file's
actuators onto the servos' or the thrusters' contract and so runs on theirs), and a Task
class where it has its own. Every robot names its realisation in its registry entry
(tasks.robots.Robot.realisation: the shipped robots by name, a mount by its action
kind, a robot file by the contract's actuators it has), and tasks.load builds it from
its row alone. Adding a realisation is its two modules and one row.
"""
import dataclasses
import importlib

#: The drives' tasks (tasks.two_wheel.TwoWheel, tasks.floating.Floating), by drive.
DRIVE_TASKS = {"two_wheel": "tasks.two_wheel:TwoWheel", "floating": "tasks.floating:Floating"}


def _load(entry):
    """The object a "module:Name" entry names (its module imported on first use)."""
    module, name = entry.split(":")
    return getattr(importlib.import_module(module), name)


@dataclasses.dataclass(frozen=True)
class Realisation:
    """A realisation: its name, its drive, and its parts as "module:Name" entries: the
    Physics class, the compiled record (its module the kernels'), the mount action kind,
    and the Task class where it has its own (None: the drive's)."""
    name: str
    drive: str
    physics: str
    record: str
    kind: str
    task: str | None = None

    def physics_class(self, **attributes):
        """Its Physics class; with attributes (a mount's: its joints, gains, legs...), a
        subclass that sets them."""
        cls = _load(self.physics)
        return type(cls.__name__, (cls,), attributes) if attributes else cls

    def record_class(self):
        """Its compiled record (a compiled.records.Record)."""
        return _load(self.record)

    def kernels(self):
        """Its kernels' module: the record's."""
        return importlib.import_module(self.record.split(":")[0])

    def kind_class(self):
        """Its mount action kind (a tasks.mount.parsed.Action class)."""
        return _load(self.kind)

    def task_class(self):
        """Its Task class: its own, else its drive's."""
        return _load(self.task or DRIVE_TASKS[self.drive])


REALISATIONS = {r.name: r for r in (
    Realisation("servos", "two_wheel", physics="tasks.realisations.servos:ServosPhysics",
                record="tasks.kernels.servos:ServosRecord",
                kind="tasks.mount.drive_kinds:Servos"),
    Realisation("wheels", "two_wheel", physics="tasks.realisations.wheels:WheelsPhysics",
                record="tasks.kernels.wheels:WheelsRecord",
                kind="tasks.mount.joint_kinds:Wheels"),
    Realisation("wheel_motors", "two_wheel",
                physics="tasks.realisations.wheel_motors:WheelMotorsPhysics",
                record="tasks.kernels.wheel_motors:WheelMotorsRecord",
                kind="tasks.mount.joint_kinds:WheelMotors"),
    Realisation("joint_motors", "two_wheel",
                physics="tasks.realisations.joint_motors:JointMotorsPhysics",
                record="tasks.kernels.joint_motors:JointMotorsRecord",
                kind="tasks.mount.joint_kinds:JointMotors"),
    Realisation("gait", "two_wheel", physics="tasks.realisations.gait:GaitPhysics",
                record="tasks.kernels.gait:GaitRecord", kind="tasks.mount.joint_kinds:Gait",
                task="tasks.realisations.gait:GaitTask"),
    Realisation("thrusters", "floating", physics="tasks.realisations.thrusters:ThrustersPhysics",
                record="tasks.kernels.thrusters:ThrustersRecord",
                kind="tasks.mount.drive_kinds:Thrusters"),
)}


def of_record(record_type):
    """The realisation whose compiled record's numba type record_type is, or None: how
    compiled code picks a realisation's kernels when numba compiles it for a record
    (tasks.kernels.env_step, tasks.kernels.two_wheel)."""
    for realisation in REALISATIONS.values():
        if isinstance(record_type, realisation.record_class().numba_type):
            return realisation
    return None
