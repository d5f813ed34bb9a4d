"""The thrusters realisation: the floating drive's step as compiled kernels (Section
3.3): thrust, then coast (tasks.realisations.thrusters reads the model).

At the start of the step the velocity changes by the demand (the thrust reading) scaled
by the action noise, during one substep (the thrust phase); then the robot coasts for
the rest. With the bump readings "stop" and "bounce", a substep that brings the bumper
into a wall while moving towards it is undone and the velocity changed (`bump_phase`).
The velocity reading follows the range codes (`velocity_reading`).
"""
import numpy as np
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled import records
from tasks.kernels import bindings, sensing
from tasks.kernels.body import BODY_FIELDS, factors, step_phase
from tasks.readings import codes

#: The thrust readings' codes (tasks/readings.py).
THRUST_SCALED, THRUST_DEMAND, THRUST_CLIPPED = codes("thrust", "scaled", "demand", "clipped")
#: The bump readings' codes that the coast acts on: the velocity change at a contact
#: ("stop", "bounce"); under the others ("grip", "slide") the contact's physics alone.
BUMP_STOP, BUMP_BOUNCE = codes("bump", "stop", "bounce")


@records.record(
    *BODY_FIELDS,
    # the thrusters' ids, the substeps of the thrust and of the coast, the largest
    # velocity change (units/step per step), the thrust reading (THRUST_*) and the
    # force per unit/step of velocity change
    "thrust_x", "thrust_y", "n_thrust", "n_coast", "max_acceleration", "thrust",
    "thrust_force",
    # the velocity reading: m/s -> units per agent step, 1 for the 0-255 code, its full
    # scale (units/step), the 0-255 code's levels come from the body; scratch for
    # mj_objectVelocity
    "velocity", "velocity_code", "velocity_full", "velocity6",
    # the bump reading's code (tasks/readings.py), the share of the speed into a wall "bounce" reflects,
    # the bumper geom's id, the base's x and y velocity dofs, MuJoCo's contact count and
    # array (tasks.kernels.bindings.contact_views), scratch: the state before a substep, the
    # contact's normal
    "bump", "restitution", "hull", "dof_x", "dof_y", "ncon", "contact_f", "contact_i",
    "layout", "qpos0", "qvel0", "normal")
class ThrustersRecord(records.Record):
    """The thrusters' record (the fields' comments)."""


ThrustersRecord.constructor = njit(cache=True)(lambda *values: ThrustersRecord(*values))


@njit(cache=True)
def demand(s, a):
    """The velocity change (units/step) for a demand a, by the thrust reading: "scaled"
    MAX_ACCELERATION a, "demand" a, "clipped" a clipped to
    [-MAX_ACCELERATION, MAX_ACCELERATION] (Python's min(max(a, -g), g))."""
    gain = s.max_acceleration
    reading = s.thrust
    if reading == THRUST_SCALED:
        return gain * a
    if reading == THRUST_DEMAND:
        return a
    v = -gain if -gain > a else a
    return gain if gain < v else v


@njit(cache=True)
def hull_normal(ncon, contact_f, contact_i, layout, hull, normal):
    """The bumper's contact: the first contact of geom `hull`, its normal (the frame's
    first row, x and y) written into `normal` pointing from the wall into the robot.
    Returns False when the bumper touches nothing. layout: contact_views'."""
    for k in range(ncon[0]):
        f = k * layout[0] + layout[1]
        i = k * layout[2]
        if contact_i[i + layout[3]] == hull:
            normal[0] = -contact_f[f]
            normal[1] = -contact_f[f + 1]
            return True
        if contact_i[i + layout[4]] == hull:
            normal[0] = contact_f[f]
            normal[1] = contact_f[f + 1]
            return True
    return False


@njit(cache=True)
def bump_phase(s, n):
    """n substeps; with the bump readings "stop" and "bounce", a substep that brings the
    bumper into a wall while moving towards it is undone (qpos back, so no contact force
    acts), the velocity becomes 0 ("stop") or its mirror image off the wall, the part
    into it scaled by the restitution ("bounce"), and mj_forward recomputes the state."""
    if s.bump != BUMP_STOP and s.bump != BUMP_BOUNCE:
        return step_phase(s, n)
    qpos, qvel, qpos0, qvel0, normal = s.qpos, s.qvel, s.qpos0, s.qvel0, s.normal
    dx, dy = s.dof_x, s.dof_y
    for _ in range(n):
        qpos0[:] = qpos
        qvel0[:] = qvel
        status = step_phase(s, 1)
        if status != bindings.OK:
            return status
        if not hull_normal(s.ncon, s.contact_f, s.contact_i, s.layout, s.hull, normal):
            continue
        vx, vy = qvel0[dx], qvel0[dy]
        into = vx * normal[0] + vy * normal[1]
        if into >= 0:  # touching while moving away: the contact's physics alone
            continue
        qpos[:] = qpos0
        qvel[:] = 0.0
        if s.bump == BUMP_BOUNCE:
            back = (1.0 + s.restitution) * into
            qvel[dx] = vx - back * normal[0]
            qvel[dy] = vy - back * normal[1]
        before = s.bad_qacc[0]
        bindings.mj_forward(s.m, s.d)
        if s.bad_qacc[0] != before:
            return bindings.UNSTABLE
    return bindings.OK


@njit(cache=True)
def act(s, a, u):
    """One step for the clipped action a and the action noise's uniform draws u: the
    thrust during the thrust phase, then none for the coast. Returns (status, substeps)."""
    nh, nv = factors(s, u)
    scale = s.thrust_force
    s.ctrl[s.thrust_x] = demand(s, a[0]) * nh * scale
    s.ctrl[s.thrust_y] = demand(s, a[1]) * nv * scale
    status = bump_phase(s, s.n_thrust)
    s.ctrl[s.thrust_x] = 0.0 * scale
    s.ctrl[s.thrust_y] = 0.0 * scale
    n = s.n_thrust
    if status != bindings.OK:
        return status, n
    return bump_phase(s, s.n_coast), n + s.n_coast


@njit(cache=True)
def velocity_reading(s, v, noise):
    """The velocity reading on the velocity v (changed in place): plus the noise (an
    empty array: none), then, with the velocity code, the 0-255 code over +-full scale
    and back (np.clip as numpy's maximum then minimum)."""
    if noise.shape[0]:
        for i in range(v.shape[0]):
            v[i] = v[i] + noise[i]
    if s.velocity_code:
        half, full = s.levels / 2, s.velocity_full
        for i in range(v.shape[0]):
            x = v[i] / full
            x = x if x > -1.0 else -1.0
            x = x if x < 1.0 else 1.0
            code = np.rint(x * half + half)
            v[i] = (code - half) / half * full
    return v


@njit(cache=True)
def velocity(s, vel, noise):
    """The floating robot's velocity reading into vel: the base's velocity
    (sensing.velocity), then velocity_reading."""
    v = sensing.velocity(s.m, s.d, s.base, s.velocity, s.velocity6)
    vel[:] = velocity_reading(s, v, noise)
