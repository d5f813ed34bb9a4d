"""Beams that see the room, never the robot.

MuJoCo's rangefinder ignores the geoms of its own site's body and nothing else: a beam
that crosses a geom of another of the robot's bodies (a child body, as the boxhead's
eyes under its head; a leg) reads the robot itself, a contact that never ends, and the
robot runs blind with no error. So:

- `check_self_hits` (tasks.load, at the start pose): a beam whose nearest hit is one of
  the robot's own geoms is refused at load, in one line naming the beam and the geom.
  Its ray is the one the rangefinder casts (`ray`: from its site along the site's z
  axis, every geom group, the room's static geoms too, its site's body excluded), so
  what is refused is exactly what the sensor would read.
- `heights` (for `ebrl check`): each beam's height above the floor at the start pose,
  where it leaves its site and at the end of its range: a beam over the walls' top
  (models.rooms.WALL_HEIGHT) sees nothing of the room.
- `origins` (for `ebrl check`): where the beams leave the robot, in units: no reading in
  free space may be nearer than the nearest wall is to its origin.

Distances and heights are in paper units (models.unit_of).
"""
from typing import NamedTuple

import numpy as np

from models import PREFIX, ContractError, unit_of
from tasks import navigation
from tasks.simulator import mujoco


class Hit(NamedTuple):
    """A beam that reads one of the robot's own geoms: the beam's and the geom's names (as
    the robot file writes them) and the distance from the beam's origin (units)."""
    beam: str
    geom: str
    distance: float


def _name(m, kind, i):
    """The element's name as the robot file writes it (the room's prefix removed)."""
    return (mujoco.mj_id2name(m, kind, i) or "").removeprefix(PREFIX)


def beam_sensors(m):
    """The ids of the model's rangefinders, in their order."""
    return np.flatnonzero(m.sensor_type == mujoco.mjtSensor.mjSENS_RANGEFINDER)


def beam_names(m):
    """The rangefinders' names as the robot file writes them (the contract's, or the file's
    where a mount names them)."""
    return [_name(m, mujoco.mjtObj.mjOBJ_SENSOR, int(s)) for s in beam_sensors(m)]


def robot_bodies(m, base):
    """The ids of the robot's bodies: every body of the base's tree (below the world body's
    child that holds the base) and every other body the robot file brought (its names
    carry the room's prefix)."""
    root = int(m.body_rootid[base])
    return {b for b in range(1, m.nbody)
            if int(m.body_rootid[b]) == root
            or (mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or "").startswith(PREFIX)}


def ray(m, d, sensor):
    """(distance in m, geom id) of the ray the rangefinder `sensor` casts at the state d
    (its kinematics computed): from its site along the site's z axis, any geom group, the
    static geoms included, its site's body excluded; (-1, -1) where it hits nothing."""
    site = int(m.sensor_objid[sensor])
    geom = np.array([-1], dtype=np.int32)
    axis = np.ascontiguousarray(d.site_xmat[site].reshape(3, 3)[:, 2])
    distance = mujoco.mj_ray(m, d, d.site_xpos[site], axis, None, 1, int(m.site_bodyid[site]),
                             geom)
    return float(distance), int(geom[0])


def _at_start(physics, measure):
    """measure(m, d) with the robot placed at the room's start; the physics' data as it was
    after (mj_copyData: every value, bit for bit), as tasks.placement.check_start."""
    m, d = physics.model.ptr, physics.data.ptr
    saved = mujoco.MjData(m)
    mujoco.mj_copyData(saved, m, d)
    try:
        physics.set_robot_pose(*physics.start)
        return measure(m, d)
    finally:
        mujoco.mj_copyData(d, m, saved)


def self_hits(physics):
    """The Hits of the beams whose nearest hit, at the start pose, is one of the robot's own
    geoms (physics: a tasks.navigation.Physics)."""
    def measure(m, d):
        robot = robot_bodies(m, navigation.named_id(m, mujoco.mjtObj.mjOBJ_BODY, "base"))
        unit = unit_of(m)
        hits = []
        for name, sensor in zip(beam_names(m), beam_sensors(m)):
            distance, geom = ray(m, d, sensor)
            if geom >= 0 and int(m.geom_bodyid[geom]) in robot:
                hits.append(Hit(name, _geom_name(m, geom), distance / unit))
        return hits
    return _at_start(physics, measure)


def _geom_name(m, geom):
    """A geom's name, or, unnamed, its number and its body's name."""
    name = _name(m, mujoco.mjtObj.mjOBJ_GEOM, geom)
    if name:
        return name
    body = _name(m, mujoco.mjtObj.mjOBJ_BODY, int(m.geom_bodyid[geom]))
    return f"#{geom - _first_geom(m, geom)} of body {body!r}"


def _first_geom(m, geom):
    """The id of the first geom of the geom's body (an unnamed geom is named by its place
    on its body)."""
    return int(m.body_geomadr[int(m.geom_bodyid[geom])])


def check_self_hits(physics, field="beams"):
    """ContractError (one line; field: the mount's field that sets the beams) naming every
    beam that reads the robot's own geom at the start pose, and the geom."""
    hits = self_hits(physics)
    if not hits:
        return
    listed = ", ".join(f"{h.beam!r} (its geom {h.geom!r}, {h.distance:.2f} units away)"
                       for h in hits)
    raise ContractError(
        f"{'beam' if len(hits) == 1 else 'beams'} {listed} "
        f"{'hits' if len(hits) == 1 else 'hit'} the robot itself at the start, not the room: "
        "a beam ignores only its own body's geoms, so put the beams where no other part of "
        "the robot crosses them", field=field)


class Height(NamedTuple):
    """A beam's height above the floor (units) where it leaves its site and at the end of
    its range, at the start pose."""
    beam: str
    origin: float
    end: float


def heights(physics, sensor_range):
    """Each beam's Height at the start pose; sensor_range: the beams' range (units,
    tasks.TaskConfig.sensor_range)."""
    def measure(m, d):
        unit = unit_of(m)
        out = []
        for name, sensor in zip(beam_names(m), beam_sensors(m)):
            site = int(m.sensor_objid[sensor])
            z = float(d.site_xpos[site][2]) / unit
            out.append(Height(name, z, z + float(d.site_xmat[site][8]) * sensor_range))
        return out
    return _at_start(physics, measure)


def origins(physics):
    """Where each beam leaves the robot now: (n, 3) positions in units."""
    m, d = physics.model.ptr, physics.data.ptr
    return d.site_xpos[m.sensor_objid[beam_sensors(m)]] / unit_of(m)
