"""The action kinds that drive a file's own joints: `wheels` and `wheel_motors` (two wheel
hinges, by servos added on them or by the file's motors), `joint_motors` (the file's motors
on a forward and a turn joint, under the target plan) and `gait` (legs walked by a CPG).
Each a record of its [action] fields (tasks.mount.parsed.Action gives the hooks); the
table of every kind is tasks.mount.kinds. Nothing heavy is imported."""
from __future__ import annotations

import dataclasses
from typing import ClassVar

from tasks.actuators import OTHER_ADVICE, joints_moved, spec_kind, spec_why_other
from tasks.mount.fields import fail
from tasks.mount.frame import check_rests
from tasks.mount.parsed import Action
from tasks.mount.spec import actuator, file_actuator
from tasks.realisations import gait_parameters


def _refuse_planar(fields, joints, what):
    """The one-line refusal of joints = "planar" for a kind that drives the file's own
    motors (planar replaces the base's joints and drops them)."""
    if joints == "planar":
        fields.fail("joints", f"{what} (joints = file, free, slides or slides_z); planar "
                              "replaces the base's joints and drops the file's motors")


def _keep_actuators(mount, drop, what):
    """The one-line refusal of dropping the file's actuators, for a kind that drives them."""
    if "actuators" in drop:
        fail(mount.path, "drop", f"{what}: do not drop its actuators")


#: The contract names of a wheel kind's hinges (wheels, wheel_motors) and of a
#: wheel_motors mount's motors (motor_0, motor_1, ...), which the realisation reads
#: (tasks.realisations.wheel_motors).
WHEEL_JOINTS = ("left", "right")
MOTOR_ROLE = "motor_{}"


def _wheel_joints(fields, table):
    """The file's wheel joints by role (WHEEL_JOINTS: left, right)."""
    for role in WHEEL_JOINTS:
        if role not in table:
            fields.fail(f"action.{role}", "missing: the file's wheel joint")
    return {r: fields.text(table, r, f"action.{r}") for r in WHEEL_JOINTS}


@dataclasses.dataclass(frozen=True)
class Wheels(Action):
    """diff_drive.xml's integrated-velocity servos added on the file's wheel joints
    (tasks.realisations.wheels); the file's actuators are dropped."""

    name = "wheels"
    drives = ("two_wheel",)
    keys = frozenset({"left", "right", "kp", "kv", "force"})
    drops = frozenset({"actuators"})
    left: str = ""                  # the file's wheel joints
    right: str = ""
    # the wheel servos' gains: diff_drive.xml's unless given (kp N m/rad, kv N m s/rad,
    # force the servo's torque limit, N m)
    kp: float = 2.0
    kv: float = 0.05
    force: float = 0.12

    def on_floor(self, spec):
        return True

    @classmethod
    def parse(cls, fields, table, drive):
        joints = _wheel_joints(fields, table)
        gains = {k: fields.number(table, k, f"action.{k}", getattr(cls, k))
                 for k in ("kp", "kv", "force")}
        return cls(**joints, **gains)

    def claimed(self):
        return set(self.keys)

    def gains(self):
        return {"kp": self.kp, "kv": self.kv}

    def edit(self, mount, spec, base, names):
        import mujoco
        for role, joint in (("left", self.left), ("right", self.right)):
            if spec.joint(joint) is None:
                fail(mount.path, f"action.{role}", f"no joint named {joint!r} in {mount.model}")
            act = actuator(spec, f"{role}_wheel", mujoco.mjtTrn.mjTRN_JOINT, joint)
            act.set_to_intvelocity(kp=self.kp, kv=self.kv)
            act.forcerange = [-self.force, self.force]
            act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            act.actrange, act.actlimited = [-1e6, 1e6], mujoco.mjtLimited.mjLIMITED_TRUE


@dataclasses.dataclass(frozen=True)
class WheelMotors(Action):
    """The file's wheel hinges turned through its own motors (torque motors on the wheel
    joints or on tendons over them), none added (tasks.realisations.wheel_motors)."""

    name = "wheel_motors"
    drives = ("two_wheel",)
    keys = frozenset({"left", "right", "motors", "kp", "kv"})
    left: str = ""                  # the file's wheel hinges
    right: str = ""
    motors: tuple[str, ...] = ()    # the file's motors that turn them
    kp: float = 0.0                 # the PD gains on the wheel angles: N m/rad, N m s/rad
    kv: float = 0.0

    def on_floor(self, spec):
        return True

    @classmethod
    def parse(cls, fields, table, drive):
        joints = _wheel_joints(fields, table)
        if "motors" not in table:
            fields.fail("action.motors", "missing: the file's motors that turn the wheels, as a list")
        motors = fields.names(table, "motors", "action.motors")
        if len(motors) < 2 or len(set(motors)) != len(motors):
            fields.fail("action.motors", "needs two or more different motors of the file, "
                                         f"got {list(motors)}")
        for k in ("kp", "kv"):
            if k not in table:
                fields.fail(f"action.{k}", "missing: the PD gain on the wheel angles (a robot's own)")
        gains = {k: fields.number(table, k, f"action.{k}", positive=k == "kp") for k in ("kp", "kv")}
        if gains["kv"] < 0:
            fields.fail("action.kv", f"must not be negative, got {gains['kv']!r}")
        return cls(**joints, motors=motors, **gains)

    def claimed(self):
        return set(self.keys)

    def gains(self):
        return {"kp": self.kp, "kv": self.kv}

    def roles(self):
        """(contract name, the file's name) pairs: the hinges left and right, the motors
        motor_0, motor_1, ... (MOTOR_ROLE)."""
        return (("left", self.left), ("right", self.right),
                *((MOTOR_ROLE.format(k), name) for k, name in enumerate(self.motors)))

    def check_joints(self, fields, joints):
        _refuse_planar(fields, joints, "wheel_motors roll the file's wheels on a free base")

    def check_file(self, mount, spec, drop, names):
        """The file's wheel hinges and motors (before the drop: its motors and their
        tendons are kept)."""
        import mujoco
        _keep_actuators(mount, drop, "wheel_motors turn the wheels through the file's motors")
        hinges = (("left", self.left), ("right", self.right))
        for role, name in hinges:
            self._mappable(mount, f"action.{role}", role, name)
            joint = spec.joint(name)
            if joint is None:
                fail(mount.path, f"action.{role}", f"no joint named {name!r} in {mount.model}")
            if joint.type != mujoco.mjtJoint.mjJNT_HINGE:
                fail(mount.path, f"action.{role}", f"joint {name!r} is not a hinge (a wheel's joint)")
        for role, name in self.roles()[len(hinges):]:
            self._mappable(mount, "action.motors", role, name)
            motor = file_actuator(mount, spec, "action.motors", name)
            if motor.trntype == mujoco.mjtTrn.mjTRN_TENDON and "tendons" in drop:
                fail(mount.path, "drop", f"motor {name!r} pulls a tendon of the file: do not "
                                         "drop its tendons")

    @staticmethod
    def _mappable(mount, field, role, name):
        if role != name and any(ch.isspace() for ch in name):   # models.NAMES_TEXT's pairs
            fail(mount.path, field, f"{name!r}: a name with spaces cannot be mapped")

    def edit(self, mount, spec, base, names):
        names.update((role, name) for role, name in self.roles() if role != name)

    def physics_attributes(self):
        return {"motor_count": len(self.motors), "kp": self.kp, "kv": self.kv}


@dataclasses.dataclass(frozen=True)
class JointMotors(Action):
    """The file's own actuators on two named joints, none added: `forward` (a wheel's
    hinge rolling on the floor, or a slide along the base's heading) and `turn` (a hinge
    about z that turns the base), driven by a controller on their targets for torque
    motors, position servos or velocity servos (tasks.realisations.joint_motors)."""

    name = "joint_motors"
    drives = ("two_wheel",)
    keys = frozenset({"forward", "turn", "kp", "kv"})
    forward: str = ""
    turn: str = ""
    # the gains: one for both joints, or (forward's, turn's) where their motors differ
    # (kp = [80, 120]); torque motors: kp N m/rad, kv N m s/rad (PD); velocity servos:
    # kp 1/s (P)
    kp: float | tuple[float, float] | None = None
    kv: float | tuple[float, float] | None = None
    gain_joints: ClassVar[tuple[str, ...]] = ("forward", "turn")

    def on_floor(self, spec):
        """A forward joint that is a hinge rolls a wheel (or a ball) on the floor."""
        import mujoco
        joint = spec.joint(self.forward)
        return joint is not None and joint.type == mujoco.mjtJoint.mjJNT_HINGE

    @classmethod
    def parse(cls, fields, table, drive):
        joints = {}
        for role in ("forward", "turn"):
            if role not in table:
                fields.fail(f"action.{role}", "missing: the file's joint for it")
            joints[role] = fields.text(table, role, f"action.{role}")
        if joints["forward"] == joints["turn"]:
            fields.fail("action.turn", f"joint {joints['turn']!r} is the forward joint too")
        kp = _per_joint(fields, table, "kp", cls.gain_joints, positive=True)
        kv = _per_joint(fields, table, "kv", cls.gain_joints, positive=False)
        return cls(**joints, kp=kp, kv=kv)

    def claimed(self):
        return {"forward", "turn"} | {k for k in ("kp", "kv") if getattr(self, k) is not None}

    def check_joints(self, fields, joints):
        _refuse_planar(fields, joints, "joint_motors drive the file's own joints")

    def check_file(self, mount, spec, drop, names):
        """The two joints (a hinge or slide forward, a hinge about z to turn) and the
        file's actuators on them, all of one kind, kept; the gains that kind needs."""
        import mujoco
        _keep_actuators(mount, drop, "joint_motors drive the file's own actuators")
        for role, name in (("forward", self.forward), ("turn", self.turn)):
            joint = spec.joint(name)
            if joint is None:
                fail(mount.path, f"action.{role}", f"no joint named {name!r} in {mount.model}")
            kinds = ((mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE) if role == "forward"
                     else (mujoco.mjtJoint.mjJNT_HINGE,))
            if joint.type not in kinds:
                fail(mount.path, f"action.{role}", f"joint {name!r} is not a "
                                                   + ("hinge or a slide" if role == "forward" else "hinge"))
        on = [a for a in spec.actuators if joints_moved(spec, a) & {self.forward, self.turn}]
        for role, name in (("forward", self.forward), ("turn", self.turn)):
            if not any(name in joints_moved(spec, a) for a in on):
                fail(mount.path, f"action.{role}", f"no actuator of {mount.model.name} moves "
                                                   f"joint {name!r}")
        other = next((a for a in on if spec_kind(a) is None), None)
        if other is not None:
            fail(mount.path, "action.kind", f"joint_motors need the joints' actuators to act as "
                                            f"torque motors, position servos or velocity servos; "
                                            f"{other.name!r} is none: {spec_why_other(other)}: "
                                            f"{OTHER_ADVICE}")
        kind = {spec_kind(a) for a in on}
        if len(kind) != 1:
            fail(mount.path, "action.kind", "joint_motors need the joints' actuators all torque "
                                            "motors, position servos or velocity servos; got "
                                            + ", ".join(f"{a.name!r}: {spec_kind(a)}" for a in on))
        kind = kind.pop()
        need = {"torque motors": ("kp", "kv"), "velocity servos": ("kp",), "position servos": ()}[kind]
        for k in ("kp", "kv"):
            if k in need and getattr(self, k) is None:
                fail(mount.path, f"action.{k}", f"missing: the {kind}' gain (a robot's own)")
            if k not in need and getattr(self, k) is not None:
                fail(mount.path, f"action.{k}", f"not a gain of {kind} (they hold their "
                                                "targets with their own)")

    def gains(self):
        return {k: getattr(self, k) for k in ("kp", "kv") if getattr(self, k) is not None}

    def physics_attributes(self):
        return {"joints": (self.forward, self.turn), "kp": self.kp or 0.0, "kv": self.kv or 0.0}


def _per_joint(fields, table, key, roles, positive):
    """[action] `key`: a number for every joint, or a list of one per joint role (roles,
    in their order); positive, or (not positive) at least 0. None when absent."""
    where = f"action.{key}"
    v = table.get(key)
    if not isinstance(v, list):
        n = fields.number(table, key, where, positive=positive)
        if n is not None and n < 0:
            fields.fail(where, f"must not be negative, got {v!r}")
        return n
    if len(v) != len(roles):
        fields.fail(where, f"one number for both joints, or a list of {len(roles)}, one per "
                           f"joint ({', '.join(roles)}), got {len(v)}")
    values = tuple(fields.number({key: x}, key, f"{where}[{i}]", positive=positive)
                   for i, x in enumerate(v))
    for i, n in enumerate(values):
        if n < 0:
            fields.fail(f"{where}[{i}]", f"must not be negative, got {v[i]!r}")
    return values


#: A gait leg's keys ([[action.legs]]): its swing joint, its lift joint or joints, its
#: held joint or joints (an optional yaw, kept at rest): tasks.realisations.gait.Leg.
LEG_KEYS = ("swing", "lift", "yaw")


@dataclasses.dataclass(frozen=True)
class Gait(Action):
    """The gait (tasks.realisations.gait): a legged robot's legs, listed with their joints by
    role, walk the two-wheel action family through the file's own torque motors or
    position servos."""

    name = "gait"
    drives = ("two_wheel",)
    keys = frozenset({"gait", "legs"})
    #: The legs, as tasks.realisations.gait.Leg tuples (swing, lifts, held), in the mount's order.
    legs: tuple[tuple[str, tuple[str, ...], tuple[str, ...]], ...] = ()
    #: The [action.gait] table: (parameter, value) pairs, sorted
    #: (tasks.realisations.gait_parameters.PARAMETERS).
    parameters: tuple[tuple[str, float], ...] = ()

    def on_floor(self, spec):
        return True

    @classmethod
    def parse(cls, fields, table, drive):
        listed = table.get("legs")
        if listed is None:
            fields.fail("action.legs", "missing: the legs, as [[action.legs]] tables of "
                                       "swing, lift (and yaw) joints")
        if not isinstance(listed, list) or not listed:
            fields.fail("action.legs", "must be one or more [[action.legs]] tables")
        legs, seen = [], set()
        for i, leg in enumerate(listed):
            where = f"action.legs[{i}]"
            fields.table(leg, set(LEG_KEYS), where)
            for key in ("swing", "lift"):
                if key not in leg:
                    fields.fail(f"{where}.{key}", "missing: the file's joint(s) for it")
            roles = []
            for key in LEG_KEYS:
                v = leg.get(key, [])
                v = [v] if isinstance(v, str) else v
                if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
                    fields.fail(f"{where}.{key}", "must be a joint's name or a list of them")
                if key != "yaw" and not v:
                    fields.fail(f"{where}.{key}", "must name a joint")
                if key == "swing" and len(v) != 1:
                    fields.fail(f"{where}.{key}", f"one joint, got {v}")
                for name in v:
                    if name in seen:
                        fields.fail(f"{where}.{key}", f"joint {name!r} is listed twice")
                    seen.add(name)
                roles.append(tuple(v))
            legs.append((roles[0][0], roles[1], roles[2]))
        g = table.get("gait", {})
        if not isinstance(g, dict):
            fields.fail("action.gait", "must be a table")
        for k, v in g.items():
            if k not in gait_parameters.PARAMETERS:
                fields.fail(f"action.gait.{k}",
                            f"unknown key; valid: {', '.join(gait_parameters.PARAMETERS)}")
            fields.within(v, gait_parameters.RANGES[k], f"action.gait.{k}")
        return cls(tuple(legs), tuple(sorted((k, float(v)) for k, v in g.items())))

    def claimed(self):
        return {"legs"} | {k for k, _ in self.parameters}

    def check_joints(self, fields, joints):
        _refuse_planar(fields, joints, "the gait walks a free base on its own legs")

    def check_file(self, mount, spec, drop, names):
        """The listed joints are hinges or slides of the file, each moved by one of its
        actuators (on the joint, or on a tendon over it), which are kept."""
        import mujoco
        _keep_actuators(mount, drop, "the gait walks the legs through the file's own actuators")
        moved = set()
        for act in spec.actuators:
            if (act.trntype == mujoco.mjtTrn.mjTRN_TENDON and "tendons" in drop
                    and any(t.name == act.target for t in spec.tendons)):
                fail(mount.path, "drop", f"actuator {act.name!r} pulls a tendon of "
                                         "the file: do not drop its tendons")
            moved |= joints_moved(spec, act)
        for i, (swing, lifts, held) in enumerate(self.legs):
            for key, group in (("swing", (swing,)), ("lift", lifts), ("yaw", held)):
                for name in group:
                    field = f"action.legs[{i}].{key}"
                    joint = spec.joint(name)
                    if joint is None:
                        fail(mount.path, field, f"no joint named {name!r} in {mount.model}")
                    if joint.type not in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
                        fail(mount.path, field, f"joint {name!r} is not a hinge or a slide")
                    if key != "yaw" and name not in moved:
                        fail(mount.path, field, f"no actuator of {mount.model.name} moves "
                                                f"joint {name!r}")
        check_rests(mount, [name for swing, lifts, held in self.legs
                            for name in (swing, *lifts, *held)])

    def physics_attributes(self):
        return {"gait": gait_parameters.PARAMETERS | dict(self.parameters),
                "legs": tuple(self.legs)}

    def check_task_config(self, config):
        from tasks.realisations import gait
        gait.check_config(config)
