"""Offscreen frames of a task's physics, with the OpenGL context made at the first frame.

`models` imports MuJoCo and dm_control with rendering off, so a process that never asks
for a frame loads no OpenGL library (Mesa's EGL brings its own LLVM, which crashes a
process that also loads torch's). The first frame picks the backend (`backend()`):
MUJOCO_GL if it names one (egl, osmesa, or glfw on a display), else EGL where libEGL is
installed, else OSMesa; then makes one context per physics, freed by the environment's
close() (or at exit). `Physics.render` (tasks.navigation), the Gymnasium ids and
`ebrl render` all render here, with MuJoCo's own mjv/mjr calls.
"""
import atexit
import ctypes.util
import os
import weakref

import numpy as np

from tasks.simulator import mujoco

#: The MUJOCO_GL values a frame can be rendered with.
BACKENDS = ("egl", "osmesa", "glfw")
#: Fonts (mjtFontScale) of text drawn on frames.
FONT_SCALE = mujoco.mjtFontScale.mjFONTSCALE_150
MAX_GEOM = 10_000


class RenderingError(RuntimeError):
    pass


def backend():
    """The backend a first frame uses: MUJOCO_GL when it names one of BACKENDS, else egl
    where libEGL is installed, else osmesa where libOSMesa is."""
    wanted = os.environ.get("MUJOCO_GL", "").strip().lower()
    if wanted in BACKENDS:
        return wanted
    if wanted:
        raise RenderingError(f"MUJOCO_GL={wanted} renders nothing; unset it, or set it to "
                             + ", ".join(BACKENDS))
    if ctypes.util.find_library("EGL"):
        return "egl"
    if ctypes.util.find_library("OSMesa"):
        return "osmesa"
    raise RenderingError("no OpenGL library to render with: install Mesa's EGL (libegl1) "
                         "or OSMesa (libosmesa6)")


def _context_class(name):
    try:
        if name == "egl":
            from mujoco.egl import GLContext
        elif name == "osmesa":
            from mujoco.osmesa import GLContext
        else:
            from mujoco.glfw import GLContext
    except (ImportError, OSError, AttributeError) as e:
        raise RenderingError(f"cannot render with {name} here ({e}); set MUJOCO_GL to "
                             "another of " + ", ".join(BACKENDS)) from None
    return GLContext


_live = weakref.WeakSet()  # open renderers, closed at exit while their backend still lives
_at_exit = []


def _close_all():
    for renderer in list(_live):
        renderer.close()


class Renderer:
    """Frames of one model's scenes, at most (max_height, max_width) pixels, with its own
    OpenGL context (made here: the first Renderer loads the OpenGL library)."""

    def __init__(self, model, max_height, max_width, max_geom=MAX_GEOM):
        self.model = model
        self.backend = backend()
        context_class = _context_class(self.backend)
        self._con = None
        try:
            self._gl = context_class(max_width, max_height)
        except Exception as e:  # a backend that imports but has no device, say
            raise RenderingError(f"cannot make an OpenGL context with {self.backend} ({e}); "
                                 "set MUJOCO_GL to another of " + ", ".join(BACKENDS)) from None
        if not _at_exit:  # after the backend's own exit handlers, so it runs before them
            atexit.register(_close_all)
            _at_exit.append(True)
        _live.add(self)
        # The offscreen buffer takes its size from the model; a larger frame enlarges it.
        g = model.vis.global_
        g.offwidth, g.offheight = max(g.offwidth, max_width), max(g.offheight, max_height)
        self.max_height, self.max_width = max_height, max_width
        self._gl.make_current()
        self._con = mujoco.MjrContext(model, FONT_SCALE)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._con)
        self.scene = mujoco.MjvScene(model, maxgeom=max_geom)
        self._option = mujoco.MjvOption()
        self._camera = mujoco.MjvCamera()

    def camera(self, camera):
        """An MjvCamera for camera: an MjvCamera (used as it is), a camera id or name of
        the model, or -1 for the free camera."""
        if isinstance(camera, mujoco.MjvCamera):
            return camera
        cam = self._camera
        if isinstance(camera, str):
            cam_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
            if cam_id < 0:
                raise ValueError(f"no camera named {camera!r}")
        else:
            cam_id = int(camera)
            if not -1 <= cam_id < self.model.ncam:
                raise ValueError(f"camera id {cam_id} out of range (-1 to {self.model.ncam - 1})")
        if cam_id == -1:
            mujoco.mjv_defaultFreeCamera(self.model, cam)
        else:
            cam.type, cam.fixedcamid = mujoco.mjtCamera.mjCAMERA_FIXED, cam_id
        return cam

    def render(self, data, camera=-1, *, height, width, scene_option=None,
               scene_callback=None, overlay=None):
        """An (height, width, 3) uint8 frame of data's state from camera.

        scene_callback(scene) may add geoms to the scene before it is drawn;
        overlay(viewport, context) may draw on the frame after (mjr_text, mjr_rectangle)."""
        if self._con is None:
            raise RenderingError("this renderer is closed")
        if height > self.max_height or width > self.max_width:
            raise ValueError(f"frame {width}x{height} larger than {self.max_width}x{self.max_height}")
        self._gl.make_current()
        mujoco.mjv_updateScene(self.model, data, scene_option or self._option, None,
                               self.camera(camera), mujoco.mjtCatBit.mjCAT_ALL, self.scene)
        if scene_callback is not None:
            scene_callback(self.scene)
        viewport = mujoco.MjrRect(0, 0, width, height)
        mujoco.mjr_render(viewport, self.scene, self._con)
        if overlay is not None:
            overlay(viewport, self._con)
        rgb = np.empty((height, width, 3), dtype=np.uint8)
        mujoco.mjr_readPixels(rgb, None, viewport, self._con)
        return np.flipud(rgb)

    def close(self):
        """Frees the MuJoCo context, then the OpenGL context (idempotent)."""
        if self._con is not None:
            self._gl.make_current()
            self._con.free()
            self._con = None
        gl, self._gl = getattr(self, "_gl", None), None
        if gl is not None:
            gl.free()
        _live.discard(self)

    def __del__(self):
        try:
            self.close()
        except Exception:  # an interpreter shutting down
            pass


_renderers = weakref.WeakKeyDictionary()  # physics -> its Renderer


def frame(physics, height=240, width=320, camera=-1, *, scene_option=None,
          scene_callback=None, overlay=None):
    """A frame of a dm_control physics from camera (an id, a name, -1 for the free camera,
    or an MjvCamera), through the physics' renderer, made at its first frame.

    scene_callback(physics, scene), as dm_control's; overlay(viewport, context), see
    Renderer.render."""
    renderer = _renderers.get(physics)
    if renderer is not None and (height > renderer.max_height or width > renderer.max_width):
        release(physics)
        renderer = None
    if renderer is None:
        renderer = Renderer(physics.model.ptr, height, width)
        _renderers[physics] = renderer
    callback = None if scene_callback is None else (lambda scene: scene_callback(physics, scene))
    return renderer.render(physics.data.ptr, camera, height=height, width=width,
                           scene_option=scene_option, scene_callback=callback, overlay=overlay)


def release(physics):
    """Frees the physics' renderer, if it has one."""
    renderer = _renderers.pop(physics, None)
    if renderer is not None:
        renderer.close()
