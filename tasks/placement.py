"""Where the robot stands in the room: its base's joints by what they do in the world,
its pose set from its rest, and the start checked at load.

- `world_axes`: the base's joints' axes in the world at the model's rest (qpos0), by
  which tasks.navigation.Physics finds its slides along x and y and its hinge about z
  (or -z), whatever the base's rotation in its file.
- `Placement`: a pose set from the rest where the robot's frame is not the plain one
  (a base rotated or offset in its file, a frame site a mount adds: tasks.mount.frame, a
  hinge about -z, a rest pose): a free base's file orientation turned about the
  vertical, or the base's planar joints moved from their rest. The plain robots (every
  registered one and every shipped mount) have none and keep the plain setting, bit for
  bit.
- `check_start`: the robot placed at the room's start must stand there, facing its
  heading, inside the room's free space; else a one-line ContractError at load.
"""
import math
from typing import NamedTuple

import numpy as np

from models import ContractError
from tasks.mount.frame import rest_data
from tasks.simulator import mujoco

#: How far (units) the robot placed at the start may stand from it, and (rad) face away
#: from its heading, before the load refuses it (the placement is exact but for
#: rounding).
START_TOLERANCE = 0.05


def world_axes(model, joints, rest):
    """The joints' (ids) axes in the world at the robot's rest (a qpos), rounded to 12
    decimals."""
    d = rest_data(model, rest)
    return [tuple(float(v) for v in np.round(d.xaxis[j], 12)) for j in joints]


class BaseJoints(NamedTuple):
    """The base's joints (base_joints): a free joint's qpos and dof addresses and rest
    height (m), or the planar joints by role ("x", "y", "yaw": joint ids) and their qpos
    addresses, their senses (1 along x, y, about z; -1 along -x, -y, about -z), and
    whether the base has joints of its own beside them."""
    free_q: int | None = None
    free_dof: int | None = None
    rest_height: float | None = None
    roles: dict = {}
    qx: int | None = None
    qy: int | None = None
    qyaw: int | None = None
    x_sign: float = 1.0
    y_sign: float = 1.0
    yaw_sign: float = 1.0
    own: bool = False


def base_joints(model, base, rest):
    """The BaseJoints of body `base` of model (an MjModel): one free joint, or slide x and
    slide y (and a hinge about z or -z) by their axes in the world at rest, whatever the
    base's rotation in its file. Joints of its own beside them (a mount's root slides
    added beside them): its heading is then read from its frame, as for a free joint,
    and a pose is set from the file's rest (a qpos). ContractError for a base with
    neither."""
    joints = [j for j in range(model.njnt) if model.jnt_bodyid[j] == base]
    kinds = [int(model.jnt_type[j]) for j in joints]
    if kinds == [mujoco.mjtJoint.mjJNT_FREE]:
        q = int(model.jnt_qposadr[joints[0]])
        return BaseJoints(free_q=q, free_dof=int(model.jnt_dofadr[joints[0]]),
                          rest_height=float(rest[q + 2]), roles={})
    roles, signs = {}, {"x": 1.0, "y": 1.0, "yaw": 1.0}
    for j, kind, axis in zip(joints, kinds, world_axes(model, joints, rest)):
        sign = next((v for v in axis if v != 0.0), 0.0)
        role = {(1.0, 0.0, 0.0): "x", (0.0, 1.0, 0.0): "y", (0.0, 0.0, 1.0): "yaw"}.get(
            tuple(abs(v) for v in axis))
        if role is not None and kind == (mujoco.mjtJoint.mjJNT_HINGE if role == "yaw"
                                         else mujoco.mjtJoint.mjJNT_SLIDE):
            roles[role], signs[role] = j, sign
    adr = {role: int(model.jnt_qposadr[j]) for role, j in roles.items()}
    if "x" not in adr or "y" not in adr:
        raise ContractError("the base body needs a free joint, or slide joints along "
                            "x and y (and optionally a hinge about z)", field="joints")
    return BaseJoints(roles=roles, qx=adr["x"], qy=adr["y"], qyaw=adr.get("yaw"),
                      x_sign=signs["x"], y_sign=signs["y"], yaw_sign=signs["yaw"],
                      own=len(joints) > len(roles))


def frame_pose(xpos, xmat, unit):
    """(x, y, heading) of a frame (its position and row-major rotation), in units."""
    return xpos[0] / unit, xpos[1] / unit, math.atan2(xmat[3], xmat[0])


class Placement:
    """A pose set from the robot's rest (a qpos: models.rest_qpos): the robot's frame (frame_at(d): its
    position and rotation rows in an MjData d, tasks.navigation.Physics.frame_at) at
    (x, y) m facing `heading`, every other joint at rest. A free base (joints.free_q)
    keeps its file orientation turned about the vertical; a planar base turns its hinge
    about z or -z (joints.qyaw, joints.yaw_sign) by the heading's change from the rest's,
    then its slides along x or -x, y or -y (joints.qx, joints.qy) move it. joints: a
    BaseJoints."""

    def __init__(self, model, frame_at, joints, rest):
        self.model, self.frame_at, self.joints, self.rest = model, frame_at, joints, rest
        _, _, self.rest_heading = frame_pose(*frame_at(rest_data(model, rest)), 1.0)

    @staticmethod
    def plain(model, frame_at, joints, own_frame, rest):
        """Whether a robot's pose is set the plain way (no Placement): no frame of its own
        (own_frame: a mount's frame site), a base unrotated at the origin in its file and
        at rest at zero, a hinge about +z."""
        if own_frame or (joints.x_sign, joints.y_sign, joints.yaw_sign) != (1.0, 1.0, 1.0):
            return False
        if joints.free_q is not None:
            a = joints.free_q
            return bool(np.array_equal(rest[a + 3: a + 7], [1.0, 0.0, 0.0, 0.0]))
        position, rotation = frame_at(rest_data(model, rest))
        planar = [rest[a] for a in (joints.qx, joints.qy, joints.qyaw) if a is not None]
        return bool(np.array_equal(rotation, np.eye(3).ravel()) and position[0] == 0.0
                    and position[1] == 0.0 and not any(planar))

    def place(self, d, x, y, heading):
        """Sets d's qpos (an MjData of the model) to the pose: x, y in m."""
        q, m, joints = d.qpos, self.model, self.joints
        q[:] = self.rest
        turn = heading - self.rest_heading
        if joints.free_q is not None:
            a = joints.free_q
            yaw = np.array([math.cos(turn / 2), 0.0, 0.0, math.sin(turn / 2)])
            quat = np.zeros(4)
            mujoco.mju_mulQuat(quat, yaw, self.rest[a + 3: a + 7].copy())
            mujoco.mju_normalize4(quat)
            q[a + 3: a + 7] = quat
            q[a: a + 2] = x, y
            mujoco.mj_kinematics(m, d)
            position, _ = self.frame_at(d)
            q[a: a + 2] += (x - position[0], y - position[1])
            return
        if joints.qyaw is not None:
            q[joints.qyaw] += joints.yaw_sign * turn
        mujoco.mj_kinematics(m, d)
        position, _ = self.frame_at(d)
        q[joints.qx] += joints.x_sign * (x - position[0])
        q[joints.qy] += joints.y_sign * (y - position[1])


def check_start(physics, heading=True):
    """ContractError (one line) unless the robot placed at the room's start stands there
    (within START_TOLERANCE), facing its heading (where `heading`: the two-wheel drive),
    inside the room's free space (the floor, outside every obstacle). The physics' data
    is as it was after (mj_copyData: every value, bit for bit)."""
    m, d = physics.model.ptr, physics.data.ptr
    saved = mujoco.MjData(m)
    mujoco.mj_copyData(saved, m, d)
    x, y, h = physics.start
    try:
        physics.set_robot_pose(x, y, h)
        px, py, ph = physics.robot_pose()
    finally:
        mujoco.mj_copyData(d, m, saved)
    (fx0, fx1, fy0, fy1), obstacles = physics.field, physics.obstacles
    inside = fx0 < px < fx1 and fy0 < py < fy1 and not any(
        bx0 < px < bx1 and by0 < py < by1 for bx0, bx1, by0, by1 in obstacles)
    off = math.hypot(px - x, py - y) > START_TOLERANCE or (
        heading and abs(math.remainder(ph - h, 2 * math.pi)) > START_TOLERANCE)
    if inside and not off:
        return
    placed = f"placed at the room's start ({x:.2f}, {y:.2f}) facing {h:.2f} rad, the robot"
    if inside and math.hypot(px - x, py - y) <= START_TOLERANCE:
        raise ContractError(f"{placed} faces {ph:.2f} rad: its base has no hinge about z "
                            f"(or -z) to face the start heading (a mount's joints = "
                            f"\"planar\" adds one, \"free\" a free joint)", field="joints")
    where = "outside the room's free space" if not inside else "not where it was placed"
    raise ContractError(
        f"{placed} stands at ({px:.2f}, {py:.2f}) facing {ph:.2f} rad, {where}: its base's "
        f"joints do not move it in the room's plane (a mount's joints = \"planar\", "
        f"\"slides\" or \"free\" adds joints that do)", field="joints")
