"""MJCF models: Sutton's room and one file per robot, composed at load time.

`compose(robot)` attaches ``<robot>.xml`` to ``room.xml`` under the name scope
``robot/``, so every robot exposes the same element names (``robot/x``,
``robot/hull``, ``robot/range_0`` ...). A new robot is a new XML file here.
"""
import ctypes.util
import os
import pathlib


def _default_gl_backend():
    """An OpenGL backend that imports here without a display: egl, osmesa or none."""
    if ctypes.util.find_library("EGL"):
        return "egl"
    if ctypes.util.find_library("OSMesa"):
        return "osmesa"
    return "disabled"


# dm_control picks its renderer at import and tries GLFW (a display) first; on a
# headless machine choose before it is imported. An explicit MUJOCO_GL wins.
os.environ.setdefault("MUJOCO_GL", _default_gl_backend())

from dm_control import mjcf  # noqa: E402  (after MUJOCO_GL is set)

#: Metres per paper unit. The only place where paper units meet SI units.
UNIT = 0.1

MODEL_DIR = pathlib.Path(__file__).resolve().parent
ROOM_FILE = MODEL_DIR / "room.xml"


def robot_names():
    """The robot files available next to the room, without their extension."""
    return sorted(p.stem for p in MODEL_DIR.glob("*.xml") if p.stem != "room")


def compose(robot):
    """Returns (xml_string, assets) of the room with `robot` attached at the origin."""
    path = MODEL_DIR / f"{robot}.xml"
    if robot == "room" or not path.is_file():
        raise ValueError(f"unknown robot {robot!r}; valid: {', '.join(robot_names())}")
    room = mjcf.from_path(str(ROOM_FILE))
    body = mjcf.from_path(str(path))
    body.model = "robot"
    room.attach(body)
    return room.to_xml_string(), room.get_assets()
