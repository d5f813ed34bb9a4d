"""MuJoCo and dm_control imported with rendering off: the first thing tasks does.

MuJoCo's Python package and dm_control load the OpenGL library that MUJOCO_GL names when
they are imported (EGL through Mesa brings its own LLVM, which crashes a process that
later loads torch's). tasks imports them here with MUJOCO_GL=disabled for the duration
(then as it was), so a process that never renders never loads an OpenGL library;
tasks.render makes a context at the first frame instead, with the backend MUJOCO_GL
names then (or one it finds). A value this package does not render with (glfw on a
display, say) is left to them. Where either is already imported, nothing changes.
"""
import contextlib
import os
import sys


@contextlib.contextmanager
def rendering_off():
    """MUJOCO_GL=disabled for the duration, then as it was (see the module)."""
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


def import_simulator():
    """Imports mujoco and dm_control.mujoco (each reads MUJOCO_GL once, at its import)
    with rendering off, unless already imported."""
    for name in ("mujoco", "dm_control.mujoco"):
        if name not in sys.modules:
            with rendering_off():
                __import__(name)
