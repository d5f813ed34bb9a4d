"""MJCF models: the rooms (maps) and one file per robot, composed at load time.

A room is a map (models.rooms: text maps in labmaze's convention, made into MJCF; the
paper's room is the shipped map `sutton`, the default).
`compose(robot_file, room=...)` attaches a robot file to the room with MuJoCo's own
``MjSpec.attach`` under the name prefix ``robot/``, so every robot exposes the same
element names (``robot/base``, ``robot/hull``, ``robot/range_0`` ...). A robot file's
top-level bodies enter the room's world body directly, so a free joint is allowed.
A new robot is a new XML file (here, or anywhere: see docs/adding_a_robot.md).

Importing this package imports nothing heavy and changes nothing: MuJoCo is imported
where a function needs it (tasks imports it first, with rendering off: tasks.simulator).

Contact bits, one per role (contype / conaffinity):
  walls and obstacles 1 / 1; robot bumpers 2 / 1 (they touch walls, never the floor);
  the floor 4 / 0; wheels, casters and skids 0 / 4 (they touch the floor, nothing else).
"""
import pathlib

import numpy as np

#: Metres per paper unit for the paper's robots. A robot larger than the paper's may have
#: its own (tasks.robots.Robot.unit, a mount's `unit`): the room, the start, the goal and
#: the beams' range scale with it; a composed model records a unit other than this one
#: in its numeric element UNIT_NUMERIC, and `unit_of` reads it back.
UNIT = 0.1
#: The name prefix of every element a robot file brings into the room.
PREFIX = "robot/"
#: The numeric element of a composed model that holds its metres per paper unit.
UNIT_NUMERIC = "ebrl_unit"
#: The text element of a mounted model that maps the naming contract's names to the
#: file's ("base=torso hull=pointbody ..."; tasks.mount).
NAMES_TEXT = "ebrl_names"
#: The text element of a mounted model that holds its rest pose, the file's joints'
#: values ("ankle_1=1.0 ..."; tasks.mount.frame), read by rest_qpos (qpos0 is the
#: joints' reference, where the file's bodies stand: it is left as it is).
REST_TEXT = "ebrl_rest"
#: The site a mount adds on a robot's base with the robot's frame (x forward, z up) where
#: it is not the base's own (tasks.mount.frame); the pose is read from it.
FRAME_SITE = "ebrl_frame"

MODEL_DIR = pathlib.Path(__file__).resolve().parent


class ContractError(ValueError):
    """A robot file that lacks a part the naming contract asks for (docs/adding_a_robot.md),
    or has one the room cannot honour; tasks.navigation reads the contract. `field`: the
    mount's field that fixes it, for a mounted robot (tasks.load names the mount file and
    the field: ``FILE: FIELD: problem``); None where the robot file itself must change."""

    def __init__(self, message, field=None):
        super().__init__(message)
        self.field = field

    def __reduce__(self):   # its field too, from a worker process
        return type(self), (str(self), self.field)


#: The integrators a robot's entry may name (MuJoCo's mjtIntegrator, by its <option> name).
INTEGRATORS = ("Euler", "RK4", "implicit", "implicitfast")


def room_spec(room=None):
    """The room's MjSpec (a map's name, random:WxH:SEED, a map file or a rooms.Map; None:
    the paper's `sutton`), at the paper's unit; rooms.MapError for a bad map."""
    import mujoco

    from models import rooms
    return mujoco.MjSpec.from_string(rooms.room_xml(room))


def compose(robot_file, *, timestep=None, integrator=None, unit=UNIT, robot=None, room=None):
    """An MjSpec of the room with the robot file attached at the origin.

    timestep (s) and integrator ("Euler", "implicitfast", ...) replace the room's
    when given: a robot file's own <option> is not used (attaching keeps the room's).
    unit: metres per paper unit; the room is scaled by unit / UNIT about the origin
    (scale_room). robot: the robot's MjSpec, already made (a mount's); else the file's.
    room: the room (room_spec); None: the paper's.
    """
    import mujoco
    path = pathlib.Path(robot_file)
    if not path.is_file():
        raise ValueError(f"no robot file at {path}")
    room = room_spec(room)
    if unit != UNIT:
        scale_room(room, unit)
    if robot is None:
        try:
            robot = mujoco.MjSpec.from_file(str(path))
        except ValueError as e:
            raise ValueError(f"{path} is not a MuJoCo model: {str(e).splitlines()[0]}") from None
    # The robot file's own <option> is not attached (tasks.robots.file_options reads its
    # timestep and integrator); aligned here so that attaching has no conflict to warn of.
    robot.option.timestep, robot.option.integrator = room.option.timestep, room.option.integrator
    room.attach(robot, prefix=PREFIX, frame=room.worldbody.add_frame())
    if timestep is not None:
        room.option.timestep = float(timestep)
    if integrator is not None:
        if integrator not in INTEGRATORS:
            raise ValueError(f"unknown integrator {integrator!r}; valid: {', '.join(INTEGRATORS)}")
        room.option.integrator = getattr(mujoco.mjtIntegrator, "mjINT_" + integrator.upper())
    return room


def scale_room(room, unit):
    """Scales the room's world (its geoms, sites, cameras and lights: positions and
    sizes) by unit / UNIT about the origin, and records the unit in the model
    (UNIT_NUMERIC), so the room is the paper's in paper units at `unit` metres each."""
    if not (isinstance(unit, (int, float)) and unit > 0 and np.isfinite(unit)):
        raise ValueError(f"unit must be a positive number of metres, got {unit!r}")
    s = float(unit) / UNIT
    for geom in room.worldbody.geoms:
        geom.pos = np.asarray(geom.pos) * s
        geom.size = np.asarray(geom.size) * s
    for site in room.worldbody.sites:
        site.pos = np.asarray(site.pos) * s
        site.size = np.asarray(site.size) * s
    for item in (*room.worldbody.cameras, *room.worldbody.lights):
        item.pos = np.asarray(item.pos) * s
    room.add_numeric(name=UNIT_NUMERIC, data=[float(unit)])
    return room


def unit_of(model):
    """Metres per paper unit of a composed model (an MjModel, or dm_control's wrapper)."""
    import mujoco
    m = getattr(model, "ptr", model)
    i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_NUMERIC, UNIT_NUMERIC)
    return UNIT if i < 0 else float(m.numeric_data[m.numeric_adr[i]])


def contract_names(model):
    """{contract name: the file's name} of a mounted model (tasks.mount); {} otherwise."""
    import mujoco
    m = getattr(model, "ptr", model)
    i = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_TEXT, PREFIX + NAMES_TEXT)  # attached
    if i < 0:
        return {}
    adr, size = int(m.text_adr[i]), int(m.text_size[i])
    text = bytes(m.text_data[adr: adr + size]).rstrip(b"\0").decode()
    return dict(pair.split("=", 1) for pair in text.split())


def rest_qpos(model):
    """The robot's rest pose in a composed model (an MjModel): its qpos0, with the values
    its mount's rest records (REST_TEXT) in a copy; qpos0 itself without one."""
    import mujoco
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXT, PREFIX + REST_TEXT)
    if i < 0:
        return model.qpos0
    adr, size = int(model.text_adr[i]), int(model.text_size[i])
    text = bytes(model.text_data[adr: adr + size]).rstrip(b"\0").decode()
    rest = model.qpos0.copy()
    for pair in text.split():
        name, value = pair.split("=", 1)
        j = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, PREFIX + name)
        rest[model.jnt_qposadr[j]] = float(value)
    return rest


def room_layout(model):
    """(field, obstacles, goal, start) of a compiled room, in paper units.

    field, goal: (x0, x1, y0, y1) rectangles of the floor and the goal site; obstacles:
    the world's colliding boxes inside the field, as rectangles; start: (x, y, heading)
    of the start site. The room as simulated, so figures and the optimal path follow
    any room file."""
    import mujoco
    unit = unit_of(model)

    def rect(pos, size):
        (cx, cy), (hx, hy) = np.asarray(pos[:2]) / unit, np.asarray(size[:2]) / unit
        return float(cx - hx), float(cx + hx), float(cy - hy), float(cy + hy)

    floor, goal, start = model.geom("floor"), model.site("goal"), model.site("start")
    field = rect(floor.pos, floor.size)
    obstacles = []
    for i in range(model.ngeom):
        g = model.geom(i)
        x, y = g.pos[:2] / unit
        if (int(g.bodyid[0]) == 0 and int(g.type[0]) == mujoco.mjtGeom.mjGEOM_BOX
                and g.contype[0] & 1 and field[0] < x < field[1] and field[2] < y < field[3]):
            obstacles.append(rect(g.pos, g.size))
    heading = float(np.arctan2(*_planar_axis(start.quat)[::-1]))
    return field, obstacles, rect(goal.pos, goal.size), (*(start.pos[:2] / unit), heading)


def _planar_axis(quat):
    """The x axis of a frame with orientation quat, in the plane: (cos, sin)."""
    import mujoco
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat, dtype=np.float64))
    return mat[0], mat[3]


def room_model(room=None):
    """The room alone, compiled (for its layout)."""
    return room_spec(room).compile()
