"""The file's own frame and rest, read once per mount from the unedited file compiled
alone: the base's orientation and position at rest in the file's world (its quat, euler,
axisangle, xyaxes or zaxis and those of its ancestors and frames), the robot's frame in
the base's coordinates (x along the mount's `forward` axis, z up: `BaseFrame.robot`), and
the rest pose (a keyframe of the file, or the mount's `rest` table), checked against the
joints' ranges.

What the mount adds follows from them (tasks.mount.spec): root slides along the room's
x and y whatever the base's rotation, the beams and the bumper in the robot's frame, and
a site FRAME_SITE on the base with the robot's frame where it is not the base's own (a
base tilted in its file, a forward axis other than x), from which tasks.navigation reads
the pose. The rest is recorded in the model's text element models.REST_TEXT, which
models.rest_qpos reads (the model's qpos0 stays the file's: it is the joints' reference,
where the file's bodies stand)."""
from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from models import FRAME_SITE  # noqa: F401  the site a mount adds with the robot's frame
from tasks.mount.fields import fail

#: The axes a mount's `forward` may name: the base's own, in its coordinates.
FORWARDS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0),
            "-x": (-1.0, 0.0, 0.0), "-y": (0.0, -1.0, 0.0), "-z": (0.0, 0.0, -1.0)}
#: A forward axis more than this far from the floor's plane (degrees) is refused.
MAX_FORWARD_SLOPE = 30.0


@functools.lru_cache(maxsize=32)
def _compiled(path: str):
    import mujoco
    return mujoco.MjSpec.from_file(path).compile()


def file_model(mount):
    """The robot file compiled alone, unedited (an MjModel, once per file and process)."""
    try:
        return _compiled(str(mount.model))
    except ValueError as e:
        fail(mount.path, "file", f"{mount.model} does not compile: {str(e).splitlines()[0]}")


def rest_data(model, qpos=None):
    """An MjData of model at qpos (default: its qpos0), its kinematics computed."""
    import mujoco
    d = mujoco.MjData(model)
    if qpos is not None:
        d.qpos[:] = qpos
    mujoco.mj_kinematics(model, d)
    return d


@dataclasses.dataclass(frozen=True)
class BaseFrame:
    """The base in its file at rest: its rotation (3 x 3, its axes in the world's) and its
    position (m); the robot's frame in the base's coordinates (3 x 3: its columns the
    robot's forward, left and up), None where it is the base's own (an upright base,
    forward = "x")."""
    rotation: np.ndarray
    position: np.ndarray
    robot: np.ndarray | None

    @property
    def turned(self) -> bool:
        """Whether the base is rotated at all in its file (a pure identity is not)."""
        return not np.array_equal(self.rotation, np.eye(3))

    def world_axis(self, i):
        """The world's axis i (0 x, 1 y, 2 z) in the base's coordinates: a joint added
        on the base along it moves or turns the base along the room's axis."""
        if not self.turned:
            return [1.0 if k == i else 0.0 for k in range(3)]
        return [float(v) for v in self.rotation[i]]   # row i of R is R^T e_i

    def in_base(self, v):
        """A vector of the robot's frame in the base's coordinates."""
        if self.robot is None:
            return list(v)
        return [float(c) for c in self.robot @ np.asarray(v, dtype=float)]

    def robot_quat(self):
        """The robot's frame's orientation in the base's, as a quaternion."""
        import mujoco
        q = np.zeros(4)
        mujoco.mju_mat2Quat(q, np.ascontiguousarray(self.robot).ravel())
        return q


@functools.lru_cache(maxsize=32)
def base_frame(mount) -> BaseFrame:
    """The mount's BaseFrame, from its file compiled alone. MountError (forward) where
    the forward axis stands more than MAX_FORWARD_SLOPE degrees off the floor's plane."""
    import mujoco
    model = file_model(mount)
    b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, mount.base)
    if b <= 0:
        fail(mount.path, "base", f"no body named {mount.base!r} in {mount.model}")
    d = rest_data(model)
    rotation = d.xmat[b].reshape(3, 3).copy()
    forward = rotation @ np.array(FORWARDS[mount.forward])
    slope = math.degrees(math.atan2(abs(forward[2]), math.hypot(forward[0], forward[1])))
    if slope > MAX_FORWARD_SLOPE:
        fail(mount.path, "forward", f"axis {mount.forward} of body {mount.base!r} points "
                                    f"{'up' if forward[2] > 0 else 'down'} in the file "
                                    f"({slope:.0f} degrees off the floor): name the base's "
                                    f"axis the robot moves along ({', '.join(FORWARDS)})")
    upright = rotation[2, 2] >= 1.0 - 1e-12
    robot = None
    if mount.forward != "x" or not upright:
        phi = math.atan2(forward[1], forward[0])
        c, s = math.cos(phi), math.sin(phi)
        robot = rotation.T @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return BaseFrame(rotation, d.xpos[b].copy(), robot)


def joint_axis(mount, name):
    """A joint's axis in the world of its file at rest (unit), or None for no such
    joint."""
    import mujoco
    model = file_model(mount)
    j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
    if j < 0:
        return None
    return rest_data(model).xaxis[j].copy()


# -- the rest pose ---------------------------------------------------------------------

@functools.lru_cache(maxsize=32)
def rest_values(mount) -> tuple[tuple[str, float], ...]:
    """The rest pose the mount gives, as (joint, value) pairs of the file's hinges and
    slides (rad, m): its `rest` table's, or the keyframe it names (every hinge and slide
    of the file, the keyframe's values); () for none. MountError (rest) for a joint that
    is not a hinge or slide of the file, a keyframe that is not there, or a value outside
    its joint's range."""
    import mujoco
    if mount.rest is None:
        return ()
    model = file_model(mount)
    plain = (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))
    if isinstance(mount.rest, str):
        k = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, mount.rest)
        if k < 0:
            keys = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_KEY, i) or str(i)
                    for i in range(model.nkey)]
            fail(mount.path, "rest", f"no keyframe named {mount.rest!r} in {mount.model} "
                                     f"(its keyframes: {', '.join(keys) or 'none'})")
        pairs = [(mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j),
                  float(model.key_qpos[k, model.jnt_qposadr[j]]), f"rest ({mount.rest!r})")
                 for j in range(model.njnt) if int(model.jnt_type[j]) in plain]
        pairs = [p for p in pairs if p[0]]
    else:
        pairs = [(name, value, f"rest.{name}") for name, value in mount.rest]
    for name, value, field in pairs:
        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
        if j < 0 or int(model.jnt_type[j]) not in plain:
            fail(mount.path, field, f"no hinge or slide named {name!r} in {mount.model}")
        out_of_range(mount, field, model, j, value, "")
        unlimited(mount, field, model, j, value)
    return tuple((name, value) for name, value, _ in pairs)


#: Where a joint without limits may rest: a hinge within a turn either way (rad), a
#: slide within UNLIMITED_SLIDE m (farther than a room's side; MuJoCo's positions lose
#: their precision long before 1e20).
UNLIMITED_HINGE = 2 * math.pi
UNLIMITED_SLIDE = 1000.0


def unlimited(mount, field, model, j, value):
    """MountError at `field` when a joint without limits (joint j of the file's model)
    rests farther than UNLIMITED_HINGE or UNLIMITED_SLIDE."""
    if model.jnt_limited[j]:
        return
    import mujoco
    hinge = int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE)
    bound, unit = (UNLIMITED_HINGE, "rad (a turn either way)") if hinge else \
        (UNLIMITED_SLIDE, "m")
    if not -bound <= value <= bound:
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
        fail(mount.path, field, f"joint {name!r} has no limits; its rest must be within "
                                f"[{-bound:.4g}, {bound:.4g}] {unit}, got {value:.4g}")


def out_of_range(mount, field, model, j, value, how, advice=""):
    """MountError at `field` when `value` lies outside joint j's range (a limited joint
    of the file's model): `how` after the value, `advice` at the end."""
    if not model.jnt_limited[j]:
        return
    lo, hi = (float(v) for v in model.jnt_range[j])
    if not lo - 1e-9 <= value <= hi + 1e-9:
        import mujoco
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)
        hinge = int(model.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_HINGE)
        unit = "rad" if hinge else "m"
        degrees = (f" ({math.degrees(value):.0f} degrees, range {math.degrees(lo):.0f} to "
                   f"{math.degrees(hi):.0f})" if hinge else "")
        fail(mount.path, field, f"joint {name!r} rests at {value:.4g} {unit}{how}, outside its "
                                f"range [{lo:.4g}, {hi:.4g}] {unit}{degrees}{advice}")


def check_rests(mount, joints):
    """MountError (rest) where one of the file's `joints` (names) rests outside its
    range: at the mount's rest, else at the file's qpos0."""
    import mujoco
    model = file_model(mount)
    given = dict(rest_values(mount))
    for name in joints:
        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)
        if j < 0 or name in given:
            continue
        out_of_range(mount, "rest", model, j, float(model.qpos0[model.jnt_qposadr[j]]),
                     " in the file's qpos0", ": give the mount a rest (rest = \"a keyframe of "
                     "the file\", or a [rest] table of joint = value)")
