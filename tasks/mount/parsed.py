"""A parsed mount, as named records: Mount, its Bumper and Beams, and the base of the
action kinds' records (Action; the kinds themselves: tasks.mount.kinds)."""
from __future__ import annotations

import dataclasses
import pathlib
from typing import ClassVar


@dataclasses.dataclass(frozen=True)
class Bumper:
    """The robot's bumper: a geom of the file (geom), or a shape added to the base as the
    geom ``hull`` (shape, radius, height, half_length; metres)."""
    geom: str | None = None
    shape: str | None = None        # "sphere" or "capsule"
    radius: float = 0.0
    height: float = 0.0             # above the base's frame
    half_length: float = 0.0        # a capsule's


@dataclasses.dataclass(frozen=True)
class Beams:
    """The beams: the drive's arrangement added at a height above the base (metres), or
    the file's rangefinders by name, in the drive's order."""
    height: float | None = None
    sensors: tuple[str, ...] = ()

    @property
    def added(self) -> bool:
        return self.height is not None


@dataclasses.dataclass(frozen=True)
class Action:
    """How the drive's action reaches the robot: one subclass per action kind, registered
    by name (tasks.mount.kinds.KINDS), each a record of its [action] fields that
    knows their parsing, its edit of the robot's MjSpec and the realisation it runs on
    (tasks.realisations)."""
    #: The kind's name (the [action] table's kind), set in its class.
    name: ClassVar[str]
    #: The drives that take it.
    drives: ClassVar[tuple[str, ...]] = ()
    #: The [action] keys, besides kind, an action of this kind may hold (for any drive).
    keys: ClassVar[frozenset[str]] = frozenset()
    #: What of the file the kind's own elements replace (added to the mount's drop).
    drops: ClassVar[frozenset[str]] = frozenset()
    #: The joints, by role, whose gains may differ: a gain given as a list gives one per
    #: role, in this order (joint_motors: kp = [forward's, turn's]); () where one gain
    #: serves every joint.
    gain_joints: ClassVar[tuple[str, ...]] = ()

    @classmethod
    def parse(cls, fields, table: dict, drive: str) -> Action:
        """The action from its [action] table (fields: tasks.mount.fields.Fields)."""
        return cls()

    def claimed(self) -> set[str]:
        """The [action] keys this action read (any other is not a field of its kind)."""
        return set()

    def check_joints(self, fields, joints: str) -> None:
        """Refuses root joints (the mount's joints) the kind cannot drive."""

    def check_file(self, mount: Mount, spec, drop: set[str], names: dict[str, str]) -> None:
        """Before anything of the file is dropped: checks the file's elements the action
        names and maps them (names: contract name -> the file's, models.NAMES_TEXT)."""

    def edit(self, mount: Mount, spec, base, names: dict[str, str]) -> None:
        """Adds the kind's actuators to the spec (base: the base body), or checks and maps
        the file's."""

    def realisation(self, drive: str) -> str:
        """The realisation the mount runs on (a name of tasks.realisations.REALISATIONS):
        the kind's own name, but for a kind that serves several drives."""
        return self.name

    def gains(self) -> dict:
        """The drive's gains the mount gives, by [action] field (a number, or one per
        gain_joints role): its open drive values beside time_scale, which `ebrl check
        --tune` searches (experiments.checks.tune); none for a kind whose actuators hold
        their targets with gains of their own."""
        return {}

    def physics_attributes(self) -> dict:
        """The class attributes the realisation's Physics takes from the mount (its
        joints, gains, legs...; tasks.realisations.Realisation.physics_class)."""
        return {}

    def on_floor(self, spec) -> bool:
        """Whether the kind moves the robot through its contact with the floor (wheels,
        legs, a rolling joint): such a base needs a free joint, or, beside joints of its
        own, slides x, y and z ("slides_z": it rests on the floor by gravity), where any
        other is moved as a planar base (tasks.mount.spec names the joints that fit).
        spec: the robot file's MjSpec."""
        return False

    def check_task_config(self, config) -> None:
        """Refuses task readings (a tasks.TaskConfig) the kind cannot run: ValueError."""


@dataclasses.dataclass(frozen=True)
class Mount:
    """A parsed mount file (tasks.mount.parse)."""
    path: pathlib.Path              # the mount file
    name: str
    file: str                       # the robot file as written ("package:path" or a path)
    model: pathlib.Path             # the robot file, resolved
    drive: str
    unit: float
    base: str
    joints: str
    drop: tuple[str, ...]
    drop_geoms: tuple[str, ...]
    drop_bodies: tuple[str, ...]
    keep_options: tuple[str, ...]
    bumper: Bumper
    beams: Beams
    action: Action
    timestep: float | None = None
    integrator: str | None = None
    time_scale: float = 1.0
    #: The robot's geoms' condim (their contact with the floor and walls), None: the
    #: file's. The room's floor is condim 1 (frictionless unless a geom asks for more).
    condim: int | None = None
    #: The base's axis the robot moves along ("x", "y", "z", "-x", "-y", "-z"; its
    #: frame's x by default): the heading, the beams and the servos follow it.
    forward: str = "x"
    #: The rest pose: a keyframe of the file by name, or (joint, value) pairs (rad, m);
    #: None: the file's qpos0 (tasks.mount.frame).
    rest: str | tuple[tuple[str, float], ...] | None = None
    #: The [readings] table as sorted (field, value) pairs (Robot.readings).
    readings: tuple[tuple[str, object], ...] = ()
    description: str = ""
    #: `ebrl check`'s accuracy limits where the drive's 5% is not reached, as (error,
    #: limit) pairs ("turn" rad, "move" units, "velocity_x", "velocity_y" units/step).
    check: tuple[tuple[str, float], ...] = ()
