"""What every drive's record holds, and the kernels every drive shares.

A realisation's record (a compiled.records.Record: tasks.kernels.servos.ServosRecord,
tasks.kernels.thrusters.ThrustersRecord, ...) starts with BODY_FIELDS, the robot's body in
MuJoCo and the task's sensing, goal and action noise; its own fields follow. The kernels
here work on any such record (numba compiles one version per record type): the substeps
with the tilt check, the pose, the goal test, the range codes, the action noise's
factors. tasks.navigation.Physics fills the body's values (`Physics.body`), the task its
sensing and noise (`Navigation.body_settings`).
"""
import math

from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled.clip import clip_unit
from tasks.kernels import bindings, sensing

#: The body's fields, as every drive's record starts.
BODY_FIELDS = (
    # MuJoCo: the structs' addresses, the int views, MjData's arrays, the base's frame
    "m", "d", "flags", "bad_qacc", "ctrl", "qpos", "qvel", "act", "sensordata", "xpos", "xmat",
    # the robot: its yaw hinge's qpos address (-1: none), 1 for a free-joint base (its tilt
    # is checked against min_cos_tilt), the base body's id, the rangefinders' sensordata
    # span, metres per unit and its inverse, the radius (units), the model's timestep (s)
    "qyaw", "free", "base", "beam0", "beam1", "unit", "metres_to_units", "radius", "timestep",
    "min_cos_tilt",
    # the goal square (units) and Section 3.2's code (255; -255 / sensor range), Section
    # 3.3's action noise, the room's floor (units: a centre off it has left the room)
    "x0", "x1", "y0", "y1", "levels", "per_unit", "action_noise", "room_x0", "room_x1",
    "room_y0", "room_y1")


@njit(cache=True)
def step_phase(s, n):
    """n substeps (tasks.kernels.bindings.run) with the robot's tilt check."""
    return bindings.run(s.m, s.d, n, s.bad_qacc, s.xmat, s.free != 0, s.min_cos_tilt)


@njit(cache=True)
def base_pose(s):
    """(x, y, heading) in units and radians (tasks.kernels.sensing.pose)."""
    return sensing.pose(s.xpos, s.xmat, s.qpos, s.qyaw, s.unit)


@njit(cache=True)
def in_box(x, y, x0, x1, y0, y1):
    """True when (x, y) lies in the box [x0, x1] x [y0, y1] (edges included)."""
    return x0 <= x <= x1 and y0 <= y <= y1


@njit(cache=True)
def goal_reached(s):
    """True when the robot's centre is in the goal square (Section 3.1)."""
    x, y, _ = base_pose(s)
    return in_box(x, y, s.x0, s.x1, s.y0, s.y1)


@njit(cache=True)
def in_room(s):
    """True while the robot's centre is on the room's floor (a robot outside it went
    through a wall: never in a run that is right)."""
    x, y, _ = base_pose(s)
    return in_box(x, y, s.room_x0, s.room_x1, s.room_y0, s.room_y1)


@njit(cache=True)
def sense(s, noise):
    """Section 3.2: the range codes plus noise (an empty array: none)."""
    return sensing.encode(sensing.ranges(s.m, s.d, s.flags, s.sensordata, s.beam0, s.beam1,
                                         s.metres_to_units, s.radius),
                          noise, s.levels, s.per_unit)


@njit(cache=True)
def clip_finite(a):
    """A finite action's parts clipped to [-1, 1] in place (compiled.clip.clip_unit, the one
    clip: as Python's min(max(v, -1), 1) for any finite v), returning True; NaN and inf are
    refused (returns False, nothing clipped)."""
    for i in range(a.shape[0]):
        if not math.isfinite(a[i]):
            return False
    clip_unit(a)
    return True


@njit(cache=True)
def noise_factor(noise, u):
    """Section 3.3's factor from a uniform draw u in [0, 1): low + (1 - low) u with
    low = 1 - noise, i.e. uniform in [1 - noise, 1] (RandomState.uniform's formula)."""
    low = 1.0 - noise
    return low + (1.0 - low) * u


@njit(cache=True)
def factors(s, u):
    """Section 3.3's two noise factors from their uniform draws u (none are drawn, and
    both factors are 1, without noise)."""
    noise = s.action_noise
    if noise <= 0:
        return 1.0, 1.0
    return noise_factor(noise, u[0]), noise_factor(noise, u[1])
