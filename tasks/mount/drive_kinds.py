"""The action kinds that give a mount the paper's drives' contract: `servos` (the two-wheel
drive's forward, turn and grip servos added on the base), `thrusters` (the floating drive's
thrust on slides along x and y) and `actuators` (the file's own actuators mapped onto those
contract names). Each a record of its [action] fields (tasks.mount.parsed.Action gives
the hooks); the table of every kind is tasks.mount.kinds. Nothing heavy is imported."""
from __future__ import annotations

import dataclasses

from tasks.mount.fields import fail
from tasks.mount.frame import base_frame
from tasks.mount.parsed import Action
from tasks.mount.spec import actuator, file_actuator


@dataclasses.dataclass(frozen=True)
class Servos(Action):
    """two_wheel.xml's velocity servos added: forward and grip on a site of the base,
    turn on its yaw hinge (tasks.realisations.servos sets their kv at load)."""

    name = "servos"
    drives = ("two_wheel",)
    drops = frozenset({"actuators"})

    def check_joints(self, fields, joints):
        if joints == "free":
            fields.fail("action.kind", "servos drive planar joints (joints = file or planar), "
                                       "not a free joint")

    def edit(self, mount, spec, base, names):
        import mujoco

        site = base.add_site(name="drive")
        frame = base_frame(mount)
        if frame.robot is not None:   # its x the robot's forward, its y the robot's left
            site.quat = list(frame.robot_quat())
        actuator(spec, "forward", mujoco.mjtTrn.mjTRN_SITE, "drive",
                       [1, 0, 0, 0, 0, 0]).set_to_velocity(kv=1)
        actuator(spec, "grip", mujoco.mjtTrn.mjTRN_SITE, "drive",
                       [0, 1, 0, 0, 0, 0]).set_to_velocity(kv=1)
        yaw = "yaw" if mount.joints == "planar" else _yaw_joint(mount, base)
        actuator(spec, "turn", mujoco.mjtTrn.mjTRN_JOINT, yaw).set_to_velocity(kv=1)


def _yaw_joint(mount, base):
    """The base's hinge about the vertical (z or -z in the world of its file: the
    realisation reads which way it turns)."""
    import mujoco
    import numpy as np

    rotation = base_frame(mount).rotation
    for j in base.joints:
        if j.type == mujoco.mjtJoint.mjJNT_HINGE:
            axis = rotation @ np.asarray(j.axis, dtype=float)
            if abs(abs(axis[2]) - np.linalg.norm(axis)) <= 1e-9 * np.linalg.norm(axis):
                return j.name
    fail(mount.path, "action.kind", f"servos turn a hinge about z on {mount.base!r}; it has "
                                    "none (joints = \"planar\" adds one)")


@dataclasses.dataclass(frozen=True)
class Thrusters(Action):
    """The floating drive's motors added on the base's slides x and y."""

    name = "thrusters"
    drives = ("floating",)
    drops = frozenset({"actuators"})

    def edit(self, mount, spec, base, names):
        import mujoco
        joints = ("x", "y") if mount.joints == "planar" else _slides(mount, base)
        for role, joint in zip(("thrust_x", "thrust_y"), joints):
            actuator(spec, role, mujoco.mjtTrn.mjTRN_JOINT, joint).set_to_motor()


def _slides(mount, base):
    """The base's slides along the room's x and y (their axes in the world of its file)."""
    import mujoco
    import numpy as np

    rotation = base_frame(mount).rotation
    out = {}
    for j in base.joints:
        if j.type == mujoco.mjtJoint.mjJNT_SLIDE:
            axis = rotation @ np.asarray(j.axis, dtype=float)
            out[tuple(float(v) for v in np.round(axis / np.linalg.norm(axis), 9))] = j.name
    if (1, 0, 0) not in out or (0, 1, 0) not in out:
        fail(mount.path, "action.kind", f"thrusters push slides along x and y on {mount.base!r}; "
                                        "it has none (joints = \"planar\" adds them)")
    return out[(1, 0, 0)], out[(0, 1, 0)]


#: The contract's actuator names an "actuators" action maps, by drive, and those it needs.
ACTUATOR_ROLES = {"two_wheel": ("forward", "turn", "grip"), "floating": ("thrust_x", "thrust_y")}
REQUIRED_ROLES = {"two_wheel": ("forward", "turn"), "floating": ("thrust_x", "thrust_y")}


@dataclasses.dataclass(frozen=True)
class Actuators(Action):
    """The file's own actuators, mapped to the drive's contract names (forward, turn,
    grip; thrust_x, thrust_y)."""

    name = "actuators"
    drives = tuple(ACTUATOR_ROLES)
    keys = frozenset(r for roles in ACTUATOR_ROLES.values() for r in roles)
    #: (contract name, the file's actuator) pairs, in the drive's order.
    actuators: tuple[tuple[str, str], ...] = ()

    @classmethod
    def parse(cls, fields, table, drive):
        for role in REQUIRED_ROLES[drive]:
            if role not in table:
                fields.fail(f"action.{role}", "missing: the file's actuator for it")
        return cls(tuple((r, fields.text(table, r, f"action.{r}")) for r in ACTUATOR_ROLES[drive]
                         if r in table))

    def claimed(self):
        return {role for role, _ in self.actuators}

    def check_file(self, mount, spec, drop, names):
        for role, name in self.actuators:
            file_actuator(mount, spec, f"action.{role}", name)
            if name != role:
                names[role] = name

    def realisation(self, drive):
        return {"two_wheel": "servos", "floating": "thrusters"}[drive]
