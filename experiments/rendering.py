"""Offscreen videos of a run, from the room's cameras or the robot's, with the path drawn.

MuJoCo reads MUJOCO_GL once, when dm_control is first imported, so a backend that
imports but cannot make a context (EGL without a device, say) is only found out by
trying. `choose_backend()` tries egl then osmesa in throw-away processes and
remembers the first that renders.
"""
import os
import subprocess
import sys

BACKENDS = ("egl", "osmesa")
HEIGHT, WIDTH = 320, 480
PATH_RGBA = (0.9, 0.15, 0.15, 1.0)

_PROBE = """
import tasks
env = tasks.load("floating", seed=0)
env.reset()
assert env.physics.render(height=16, width=24, camera_id="top").mean() > 0
env.close()
"""


class RenderingError(RuntimeError):
    pass


def choose_backend():
    """The first of MUJOCO_GL (if set), egl, osmesa that renders a frame here."""
    wanted = os.environ.get("MUJOCO_GL")
    candidates = [wanted] if wanted and wanted not in BACKENDS else []
    candidates += [b for b in ((wanted,) if wanted in BACKENDS else ()) + BACKENDS if b]
    errors = []
    for backend in dict.fromkeys(candidates):
        env = backend_environment(backend)
        proc = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True,
                              text=True, timeout=120)
        if proc.returncode == 0:
            return backend
        last = (proc.stderr.strip().splitlines() or ["no output"])[-1]
        errors.append(f"{backend}: {last}")
    raise RenderingError("no OpenGL backend renders here (" + "; ".join(errors)
                         + "); install Mesa's EGL or libosmesa6")


def backend_environment(backend):
    """os.environ for a child process that renders with backend. dm_control's EGL import
    sets PYOPENGL_PLATFORM=egl in its process, which would break OSMesa in a child."""
    env = dict(os.environ, MUJOCO_GL=backend)
    if backend in BACKENDS:
        env["PYOPENGL_PLATFORM"] = backend
    else:
        env.pop("PYOPENGL_PLATFORM", None)
    return env


def ensure_backend():
    """Sets MUJOCO_GL to a working backend; call before dm_control is imported."""
    if "dm_control" in sys.modules and os.environ.get("MUJOCO_GL") in BACKENDS:
        return os.environ["MUJOCO_GL"]
    backend = choose_backend()
    os.environ.update(backend_environment(backend))
    return backend


def camera_names(physics):
    """The cameras a video can use: the room's (top, perspective) and the robot's (by the
    name in its file)."""
    from models import PREFIX
    m = physics.model
    names = [m.id2name(i, "camera") for i in range(m.ncam)]
    return [n[len(PREFIX):] if n.startswith(PREFIX) else n for n in names]


def check_camera(spec, camera):
    """RenderingError unless the run's room and robot have `camera`."""
    import tasks
    env = tasks.load(spec.entry, seed=0)
    try:
        names = camera_names(env.physics)
    finally:
        env.close()
    if camera not in names:
        raise RenderingError(f"unknown camera {camera!r}; valid: {', '.join(names)}")


def _camera_id(physics, camera):
    from models import PREFIX
    m = physics.model
    for name in (camera, PREFIX + camera):
        if name in [m.id2name(i, "camera") for i in range(m.ncam)]:
            return name
    raise RenderingError(f"unknown camera {camera!r}")


def frame(physics, path_xy=(), height=HEIGHT, width=WIDTH, camera="top"):
    """A frame from `camera`; path_xy (paper units) is drawn as a line on the floor."""
    from models import UNIT

    def draw(_, scene):
        import mujoco
        import numpy as np
        pts = list(path_xy)
        for (x0, y0), (x1, y1) in zip(pts[:-1], pts[1:]):
            if scene.ngeom >= scene.maxgeom:
                break
            scene.ngeom += 1  # scene.geoms exposes the first ngeom entries
            g = scene.geoms[scene.ngeom - 1]
            mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_LINE, np.zeros(3), np.zeros(3),
                                np.eye(3).ravel(), np.array(PATH_RGBA, dtype=np.float32))
            mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_LINE, 3.0,
                                 np.array([x0 * UNIT, y0 * UNIT, 0.01]),
                                 np.array([x1 * UNIT, y1 * UNIT, 0.01]))

    return physics.render(height=height, width=width, camera_id=_camera_id(physics, camera),
                          scene_callback=draw if len(path_xy) > 1 else None)


def record(spec, path, *, frames=600, fps=30, camera="top"):
    """Runs spec exactly as `ebrl run` does and writes an MP4 of it, from `camera`,
    with the current trial's path drawn; at most `frames` frames."""
    import imageio.v2 as imageio
    import numpy as np

    from experiments import protocol
    every = max(1, spec.steps // frames)
    writer = imageio.get_writer(str(path), fps=fps, codec="libx264", quality=7,
                                macro_block_size=16, ffmpeg_log_level="error")

    def on_step(step, env, trace, trial_begin, start):
        if step % every:
            return
        # Trial path: its start, then the positions since (decimated to bound the scene).
        pts = trace[trial_begin:step + 1]
        pts = np.vstack([start, pts[:: max(1, len(pts) // 400)], pts[-1:]]) if len(pts) else [start]
        writer.append_data(frame(env.physics, pts, camera=camera))

    try:
        result = protocol.execute(spec, on_step=on_step)
    finally:
        writer.close()
    return result
