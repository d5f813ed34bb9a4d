"""MJCF models: Sutton's room and one file per robot, composed at load time.

`compose(robot_file)` attaches a robot file to ``room.xml`` with MuJoCo's own
``MjSpec.attach`` under the name prefix ``robot/``, so every robot exposes the same
element names (``robot/base``, ``robot/hull``, ``robot/range_0`` ...). A robot file's
top-level bodies enter the room's world body directly, so a free joint is allowed.
A new robot is a new XML file (here, or anywhere: see docs/adding_a_robot.md).

Contact bits, one per role (contype / conaffinity):
  walls and obstacles 1 / 1; robot bumpers 2 / 1 (they touch walls, never the floor);
  the floor 4 / 0; wheels, casters and skids 0 / 4 (they touch the floor, nothing else).
"""
import contextlib
import os
import pathlib
import sys

import numpy as np


@contextlib.contextmanager
def _rendering_off():
    """MUJOCO_GL=disabled for the duration, then as it was.

    MuJoCo's Python package and dm_control load the OpenGL library that MUJOCO_GL names
    when they are imported (EGL through Mesa brings its own LLVM, which crashes a process
    that later loads torch's). They are imported here with rendering off, so a process
    that never renders never loads an OpenGL library; tasks.render makes a context at the
    first frame instead, with the backend MUJOCO_GL names then (or one it finds). A value
    this package does not render with (glfw on a display, say) is left to them."""
    wanted = os.environ.get("MUJOCO_GL")
    if wanted not in (None, "", "egl", "osmesa"):
        yield
        return
    os.environ["MUJOCO_GL"] = "disabled"
    try:
        yield
    finally:
        if wanted is None:
            os.environ.pop("MUJOCO_GL", None)
        else:
            os.environ["MUJOCO_GL"] = wanted


for _name in ("mujoco", "dm_control.mujoco"):  # each reads MUJOCO_GL once, at import
    if _name not in sys.modules:
        with _rendering_off():
            __import__(_name)

import mujoco  # noqa: E402

#: Metres per paper unit. The only place where paper units meet SI units.
UNIT = 0.1
#: The name prefix of every element a robot file brings into the room.
PREFIX = "robot/"

MODEL_DIR = pathlib.Path(__file__).resolve().parent
ROOM_FILE = MODEL_DIR / "room.xml"

INTEGRATORS = {"Euler": mujoco.mjtIntegrator.mjINT_EULER,
               "RK4": mujoco.mjtIntegrator.mjINT_RK4,
               "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}


def compose(robot_file, *, timestep=None, integrator=None):
    """An MjSpec of the room with the robot file attached at the origin.

    timestep (s) and integrator ("Euler", "implicitfast", ...) replace the room's
    when given: a robot file's own <option> is not used (attaching keeps the room's).
    """
    path = pathlib.Path(robot_file)
    if not path.is_file():
        raise ValueError(f"no robot file at {path}")
    room = mujoco.MjSpec.from_file(str(ROOM_FILE))
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
        room.option.integrator = INTEGRATORS[integrator]
    return room


def room_layout(model):
    """(field, obstacles, goal, start) of a compiled room, in paper units.

    field, goal: (x0, x1, y0, y1) rectangles of the floor and the goal site; obstacles:
    the world's colliding boxes inside the field, as rectangles; start: (x, y, heading)
    of the start site. The room as simulated, so figures and the optimal path follow
    any room file."""
    def rect(pos, size):
        (cx, cy), (hx, hy) = np.asarray(pos[:2]) / UNIT, np.asarray(size[:2]) / UNIT
        return float(cx - hx), float(cx + hx), float(cy - hy), float(cy + hy)

    floor, goal, start = model.geom("floor"), model.site("goal"), model.site("start")
    field = rect(floor.pos, floor.size)
    obstacles = []
    for i in range(model.ngeom):
        g = model.geom(i)
        x, y = g.pos[:2] / UNIT
        if (int(g.bodyid[0]) == 0 and int(g.type[0]) == mujoco.mjtGeom.mjGEOM_BOX
                and g.contype[0] & 1 and field[0] < x < field[1] and field[2] < y < field[3]):
            obstacles.append(rect(g.pos, g.size))
    heading = float(np.arctan2(*_planar_axis(start.quat)[::-1]))
    return field, obstacles, rect(goal.pos, goal.size), (*(start.pos[:2] / UNIT), heading)


def _planar_axis(quat):
    """The x axis of a frame with orientation quat, in the plane: (cos, sin)."""
    mat = np.zeros(9)
    mujoco.mju_quat2Mat(mat, np.asarray(quat, dtype=np.float64))
    return mat[0], mat[3]


def room_model():
    """The room alone, compiled (for its layout)."""
    return mujoco.MjModel.from_xml_path(str(ROOM_FILE))
