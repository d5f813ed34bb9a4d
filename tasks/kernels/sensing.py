"""The robot's read-outs as compiled kernels: its pose, its rangefinders' distances and
Section 3.2's code of them, its velocity. Called by every drive's compiled step
(tasks.kernels.env_step) and by tasks.navigation.Physics's read-outs, so each exists once."""
import math

import numpy as np
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from tasks.kernels.bindings import OBJ_BODY, SENSOR_BIT, mj_objectVelocity, mj_sensorPos


@njit(cache=True)
def pose(xpos, xmat, qpos, qyaw, unit):
    """(x, y, heading) in units and radians (navigation.Physics.robot_pose): the
    heading is the yaw hinge's angle (qyaw >= 0), else the frame's x axis in the plane."""
    x = xpos[0] / unit
    y = xpos[1] / unit
    heading = qpos[qyaw] if qyaw >= 0 else math.atan2(xmat[3], xmat[0])
    return x, y, heading


# -- sensing (Section 3.2) ----------------------------------------------------------

@njit(cache=True)
def surface_distances(raw, metres_to_units, radius):
    """Rangefinder values (m from the centre; -1 = no hit) -> units from the surface."""
    out = np.empty(raw.shape[0])
    for i in range(raw.shape[0]):
        out[i] = np.inf if raw[i] < 0.0 else raw[i] * metres_to_units - radius
    return out


@njit(cache=True)
def encode(distance, noise, levels, per_unit):
    """Section 3.2's code of each distance, plus noise (if any) clipped to [0, levels].
    max/min as numpy's maximum/minimum (the second argument unless the first is larger:
    max(-0.0, 0.0) is 0.0)."""
    out = np.empty(distance.shape[0])
    for i in range(distance.shape[0]):
        d = distance[i]
        c = d if d > 0.0 else 0.0
        c = c * per_unit
        c = c + levels
        c = np.rint(c)
        c = c if c > 0.0 else 0.0
        if noise.shape[0]:
            c = c + noise[i]
            c = c if c > 0.0 else 0.0
            c = c if c < levels else levels
        out[i] = c
    return out


@njit(cache=True)
def ranges(m, d, flags, sensordata, first, end, metres_to_units, radius):
    """The sensor stage run once at the current state (MuJoCo's is disabled while
    stepping), then each beam's distance from the body surface in units (inf: no hit).
    first, end: the rangefinders' span of sensordata."""
    flags[0] &= ~SENSOR_BIT
    mj_sensorPos(m, d)
    flags[0] |= SENSOR_BIT
    return surface_distances(sensordata[first:end], metres_to_units, radius)


@njit(cache=True)
def velocity(m, d, base, scale, out6):
    """(vx, vy) of the base body's frame times scale (units per agent step over m/s)."""
    mj_objectVelocity(m, d, OBJ_BODY, base, out6.ctypes.data, 0)
    out = np.empty(2)
    out[0] = out6[3] * scale
    out[1] = out6[4] * scale
    return out
