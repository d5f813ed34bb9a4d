"""Videos of a run that show what the learner does, rendered offscreen.

A frame shows the room from a camera: the room's `top` or `perspective`, a camera of the
robot's file (`chase`), or `follow`, a perspective camera that tracks the robot at a
distance set by its size. On it, each a choice of `ebrl render`:

- beams: each rangefinder's beam from the robot to what it hits, shaded by its reading
  (Section 3.2's code, without the sensor noise): faint yellow at 0, red at 255, with a
  dot where it hits; a beam that hits nothing within range is drawn faint to its end;
- path: the current trial's path, each step coloured by who chose its action (the
  memory, the intrinsic behaviour, its random action, exploration: ebrl.agent.DECIDERS),
  with a legend giving each colour and its share of the run's steps so far; or one colour
  ("plain"), or none;
- caption: a line of text: step, trial, goals so far and who chose the last action; and
  the run's label (its condition, or the compared setting) at the bottom left.

The legend (bottom right), the caption (top left) and the label (bottom left) each take
the first corner of the frame, in that order of preference, where they cover neither the
start cell nor the goal cell as the camera shows them, nor each other (`place`): in a
room whose goal is at the bottom right, the legend moves.

`record_compare` puts two runs side by side (the same seed, one frame of each at the same
steps). Frames are 640x480 (each half of a comparison too), H.264 in yuv420p with the
index at the front of the file, so browsers play the MP4 as it downloads.

The backend is chosen at the first frame (tasks.render). `choose_backend()` tries
MUJOCO_GL's, then egl and osmesa, in throw-away processes: a backend whose library loads
but that cannot make a context (EGL without a device, say) is only found out by trying,
and a process cannot try another OpenGL platform after one has loaded.
"""
import contextlib
import errno
import os
import pathlib
import subprocess
import sys
import tempfile

import numpy as np

import tasks
from experiments.outputs.overlays import (GRID, box_at, landmark_boxes, legend_size,
                                         legend_swatches, place, text_size)
from experiments.running import execution, results
from models import PREFIX, contract_names

BACKENDS = ("egl", "osmesa")
HEIGHT, WIDTH = 480, 640
FPS = 30
PATH_RGBA = (0.9, 0.15, 0.15, 1.0)  # the "plain" path
#: Colours of the deciders (ebrl.agent.DECIDERS), then of a decider the video does not
#: know (a learner that does not say): path segments and legend swatches.
DECIDER_RGB = {"memory": (0.55, 0.05, 0.85), "intrinsic": (0.0, 0.55, 0.9),
               "random": (0.95, 0.5, 0.0), "exploration": (0.9, 0.0, 0.3)}
OTHER_RGB = (0.45, 0.45, 0.45)
PATH_STYLES = ("decider", "plain", "none")
#: At most this many path segments per frame (a longer trial is drawn decimated).
MAX_SEGMENTS = 3000
PATH_WIDTH, BEAM_WIDTH = 4.0, 2.0
#: The follow camera: elevation (degrees), azimuth (degrees from +x), and distance in
#: robot radii (at least FOLLOW_MIN_DISTANCE metres).
FOLLOW = (-35.0, 135.0, 10.0)
FOLLOW_MIN_DISTANCE = 1.0
ROOM_CAMERAS = ("top", "perspective")

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
    """os.environ for a child process that renders with backend. A process that rendered
    with EGL has PYOPENGL_PLATFORM=egl set, which would break OSMesa in a child."""
    env = dict(os.environ, MUJOCO_GL=backend)
    if backend in BACKENDS:
        env["PYOPENGL_PLATFORM"] = backend
    else:
        env.pop("PYOPENGL_PLATFORM", None)
    return env


def ensure_backend():
    """Sets MUJOCO_GL to a backend that renders here (tried in child processes), for this
    process's first frame; keeps a backend this process already renders with."""
    if os.environ.get("MUJOCO_GL") in BACKENDS and os.environ.get("PYOPENGL_PLATFORM"):
        return os.environ["MUJOCO_GL"]  # set by an earlier call, or a frame already made
    backend = choose_backend()
    os.environ.update(backend_environment(backend))
    return backend


def camera_names(physics):
    """The cameras a video can use: the room's (top, perspective), the robot's (by the
    name in its file) and follow."""
    m = physics.model
    names = [m.id2name(i, "camera") for i in range(m.ncam)]
    return [n[len(PREFIX):] if n.startswith(PREFIX) else n for n in names] + ["follow"]


def check_camera(spec, camera):
    """RenderingError unless the run's room and robot have `camera`."""
    env = tasks.load(spec.entry, seed=0, room=spec.room)
    try:
        names = camera_names(env.physics)
    finally:
        env.close()
    if camera not in names:
        raise RenderingError(f"unknown camera {camera!r}; valid: {', '.join(names)}")


def _camera(physics, camera):
    """A camera name of the model, or an MjvCamera for follow."""
    import mujoco

    m = physics.model
    if camera == "follow":
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
        cam.trackbodyid = m.name2id(PREFIX + contract_names(m).get("base", "base"), "body")
        cam.elevation, cam.azimuth, radii = FOLLOW
        cam.distance = max(FOLLOW_MIN_DISTANCE, radii * physics.robot_radius * physics.unit)
        return cam
    for name in (camera, PREFIX + camera):
        if name in [m.id2name(i, "camera") for i in range(m.ncam)]:
            return name
    raise RenderingError(f"unknown camera {camera!r}")


def decider_rgb(name):
    return DECIDER_RGB.get(name, OTHER_RGB)


def beams(physics, sensor_range):
    """(start, end, reading) of each rangefinder beam in metres: from its site to the point
    it hits, or to the end of its range (radius + sensor_range) when nothing is within
    it; reading: Section 3.2's code / 255, without noise. Read from the sensor data of
    the current state (the task computes it for each observation)."""
    import mujoco

    from tasks.navigation import SENSOR_LEVELS, encode_range
    m, d = physics.model.ptr, physics.data.ptr
    ids = np.flatnonzero(m.sensor_type == mujoco.mjtSensor.mjSENS_RANGEFINDER)
    raw = d.sensordata[m.sensor_adr[ids]]
    sites = m.sensor_objid[ids]
    radius = physics.robot_radius
    surface = np.where(raw < 0, np.inf, raw / physics.unit - radius)
    reading = encode_range(surface, sensor_range=sensor_range) / SENSOR_LEVELS
    start = d.site_xpos[sites]
    axis = d.site_xmat[sites][:, [2, 5, 8]]  # each site's z axis: its beam
    length = np.where(surface <= sensor_range, raw, (radius + sensor_range) * physics.unit)
    return start, start + axis * length[:, None], reading


def _add_line(scene, a, b, rgba, width):
    import mujoco
    if scene.ngeom >= scene.maxgeom:
        return None
    scene.ngeom += 1  # scene.geoms exposes the first ngeom entries
    g = scene.geoms[scene.ngeom - 1]
    mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_LINE, np.zeros(3), np.zeros(3),
                        np.eye(3).ravel(), np.asarray(rgba, dtype=np.float32))
    mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_LINE, width, np.asarray(a, dtype=np.float64),
                         np.asarray(b, dtype=np.float64))
    return g


def _add_dot(scene, at, rgba, size):
    import mujoco
    if scene.ngeom >= scene.maxgeom:
        return
    scene.ngeom += 1
    mujoco.mjv_initGeom(scene.geoms[scene.ngeom - 1], mujoco.mjtGeom.mjGEOM_SPHERE,
                        np.array([size, 0, 0]), np.asarray(at, dtype=np.float64),
                        np.eye(3).ravel(), np.asarray(rgba, dtype=np.float32))


def beam_rgba(reading):
    """A beam's colour: faint yellow at reading 0, opaque red at 1."""
    return (1.0, 0.9 * (1.0 - reading), 0.0, 0.35 + 0.65 * reading)


def frame(physics, path_xy=(), height=HEIGHT, width=WIDTH, camera="top", *, colours=None,
          sensor_range=None, caption=None, label=None, legend=None):
    """A frame from `camera`, with:

    path_xy: points in paper units drawn as a line on the floor, segment i (from point i
    to i + 1) in colours[i] (RGB) if given, else PATH_RGBA;
    sensor_range: the task's, to draw the beams (None: no beams);
    caption: a line of text at the top; label: one at the bottom left;
    legend: (text, RGB) rows drawn at the bottom right. Each of the three moves to
    another corner where it would cover the start or the goal cell (`place`)."""
    import mujoco

    pts = np.asarray(path_xy, dtype=np.float64).reshape(-1, 2)
    keep_out = []  # the start and goal cells' boxes on this frame, from its camera

    def draw(physics, scene):
        keep_out[:] = landmark_boxes(physics, scene, height, width)
        for i in range(len(pts) - 1):
            rgba = PATH_RGBA if colours is None else (*colours[i], 1.0)
            unit = physics.unit
            if _add_line(scene, (*pts[i] * unit, 0.01), (*pts[i + 1] * unit, 0.01), rgba,
                         PATH_WIDTH) is None:
                break
        if sensor_range is not None:
            for a, b, r in zip(*beams(physics, sensor_range)):
                _add_line(scene, a, b, beam_rgba(r), BEAM_WIDTH)
                if r > 0:
                    _add_dot(scene, b, beam_rgba(r), 0.025)

    def overlay(viewport, context):
        sizes = {"legend": legend_size(len(legend)) if legend else None,
                 "caption": text_size(context, caption) if caption else None,
                 "label": text_size(context, label) if label else None}
        corners = place(sizes, keep_out, viewport.height, viewport.width)
        for name, text in (("caption", caption), ("label", label)):
            if text:
                mujoco.mjr_overlay(mujoco.mjtFont.mjFONT_NORMAL, GRID[corners[name]],
                                   viewport, text, "", context)
        if legend:
            _legend(viewport, context, legend, corners["legend"])

    from tasks import render
    overlays = bool(caption or label or legend)
    return render.frame(physics, height, width, _camera(physics, camera),
                        scene_option=_scene_option(),
                        scene_callback=draw if len(pts) > 1 or sensor_range is not None
                        or overlays else None,
                        overlay=overlay if overlays else None)


def _scene_option():
    """MuJoCo's defaults without its own rangefinder rays (yellow, to whatever each beam
    hits however far): the beams, when asked for, are drawn here."""
    import mujoco
    option = mujoco.MjvOption()
    option.flags[mujoco.mjtVisFlag.mjVIS_RANGEFINDER] = 0
    return option


def _legend(viewport, context, rows, corner="bottom right"):
    import mujoco
    w, h = viewport.width, viewport.height
    left, bottom, right, top = box_at("legend", corner, legend_size(len(rows)), h, w)
    mujoco.mjr_rectangle(mujoco.MjrRect(left, bottom, right - left, top - bottom),
                         0.1, 0.1, 0.1, 0.75)
    swatches = legend_swatches(h, w, len(rows), corner)
    for (_, rgb), (left, bottom, sw, sh) in zip(rows, swatches):
        mujoco.mjr_rectangle(mujoco.MjrRect(left, bottom, sw, sh), *rgb, 1.0)
    # mjr_text places text relative to the last viewport set (mjr_rectangle sets its own):
    # back to the whole frame, with a transparent rectangle. Its text rises about 8 px
    # above the point given.
    mujoco.mjr_rectangle(viewport, 0.0, 0.0, 0.0, 0.0)
    for (label, _), (left, bottom, sw, sh) in zip(rows, swatches):
        mujoco.mjr_text(mujoco.mjtFont.mjFONT_NORMAL, label, context,
                        (left + sw + 8) / w, (bottom - 7) / h, 1.0, 1.0, 1.0)


class Explainer:
    """Follows one run step by step (execution.execute's on_step) and makes its frames:
    who chose each step (agent.decision), the trial and the goals so far."""

    def __init__(self, spec, *, every, camera="top", label="", beams=True, path="decider",
                 caption=True, height=HEIGHT, width=WIDTH):
        from ebrl.agent import DECIDERS
        self.names = list(DECIDERS) + ["other"]
        self.code = {n: i for i, n in enumerate(self.names)}
        #: decisions[k]: the code (an index of names) of who chose step k's action.
        self.decisions = np.full(spec.steps + 1, len(self.names) - 1, dtype=np.int8)
        self.counts = np.zeros(len(self.names), dtype=np.int64)
        self.rgb = np.array([decider_rgb(n) for n in self.names])
        self.goals, self._trial_begin = 0, 0
        self.every, self.camera, self.label = every, camera, label
        self.beams, self.path, self.caption = beams, path, caption
        self.size = (height, width)
        self.sensor_range = spec.task_config().sensor_range

    def on_step(self, step, env, trace, trial_begin, start, agent):
        """Records the step; returns its frame at every `every`-th step, else None."""
        name = getattr(agent, "decision", None)
        if name is None:
            name = "memory" if getattr(agent, "used_memory", False) else "other"
        code = self.code.get(name, len(self.names) - 1)
        self.decisions[step] = code
        self.counts[code] += 1
        if trial_begin != self._trial_begin:
            self.goals += 1
            self._trial_begin = trial_begin
        if step % self.every:
            return None
        return self.frame(step, env, trace, trial_begin, start, name)

    def frame(self, step, env, trace, trial_begin, start, name):
        pts, colours = [start], None
        if self.path != "none":
            idx = np.arange(trial_begin, step + 1)
            if len(idx) > MAX_SEGMENTS:
                idx = np.concatenate([idx[:: len(idx) // MAX_SEGMENTS + 1][:-1], idx[-1:]])
            pts = np.vstack([np.asarray(start, dtype=np.float64)[None],
                             trace[idx].astype(np.float64)]) if len(idx) else [start]
            if self.path == "decider":
                colours = self.rgb[self.decisions[idx]]
        else:
            pts = ()
        caption = label = legend = None
        if self.caption:
            caption = (f"step {step:,}   trial {self.goals + 1}   goals {self.goals}"
                       f"   chose: {name}")
            label = self.label
        if self.path == "decider":
            total = max(1, int(self.counts.sum()))
            legend = [(f"{n} {100 * c / total:.0f}%", tuple(self.rgb[i]))
                      for i, (n, c) in enumerate(zip(self.names, self.counts))
                      if n != "other" or c]
        height, width = self.size
        return frame(env.physics, pts, height, width, self.camera, colours=colours,
                     sensor_range=self.sensor_range if self.beams else None,
                     caption=caption, label=label, legend=legend)


def _writer(path, fps=FPS, quality=7):
    """An MP4 writer to path (any name: the container is given, not guessed from it)."""
    import imageio.v2 as imageio
    return imageio.get_writer(str(path), format=".mp4", fps=fps, codec="libx264",
                              quality=quality, pixelformat="yuv420p", macro_block_size=16,
                              ffmpeg_log_level="error",
                              output_params=["-movflags", "+faststart", "-f", "mp4"])


@contextlib.contextmanager
def _video(path, fps=FPS, quality=7):
    """A writer of the video at path through the one atomic write (results.atomic_file):
    a full disk is results.WriteError naming the folder, an earlier video kept whole. An
    encoder that stops on the disk's error (a broken pipe, imageio's RuntimeError) is
    reported as the disk's."""
    with results.atomic_file(path) as tmp:
        writer = _writer(tmp, fps, quality)
        try:
            yield writer
            writer.close()
        except (BrokenPipeError, RuntimeError) as e:
            _close_quietly(writer)
            raise OSError(errno.ENOSPC if _full(tmp) else errno.EIO,
                          f"the video encoder stopped ({type(e).__name__})") from e
        except BaseException:
            _close_quietly(writer)
            raise


def _close_quietly(writer):
    try:
        writer.close()
    except (OSError, RuntimeError):
        pass


def _full(path):
    try:
        return os.statvfs(pathlib.Path(path).parent).f_bavail == 0
    except OSError:
        return False


def _every(spec, frames):
    return max(1, spec.steps // frames)


def record(spec, path, *, frames=600, fps=FPS, camera="top", beams=True, path_style="decider",
           caption=True, label="", quality=7):
    """Runs spec exactly as `ebrl run` does and writes an MP4 of it, from `camera`, with the
    overlays chosen (see the module's docstring); at most about `frames` frames. Returns
    the run's result (execution.execute's) with `decisions`, who chose each step's action
    (indices of `decider_names`)."""
    explainer = Explainer(spec, every=_every(spec, frames), camera=camera, label=label,
                          beams=beams, path=path_style, caption=caption)
    with _video(path, fps, quality) as writer:
        def on_step(*args):
            image = explainer.on_step(*args)
            if image is not None:
                writer.append_data(image)

        result = execution.execute(spec, on_step=on_step)
    result["decisions"] = explainer.decisions
    result["decider_names"] = explainer.names
    return result


def record_compare(specs, labels, path, *, frames=600, fps=FPS, camera="top", beams=True,
                   path_style="decider", caption=True):
    """Two runs side by side in one MP4: specs[0] on the left, specs[1] on the right, a
    frame of each at the same steps (the specs must have the same number of steps). The
    left run is recorded first to a temporary file, read back beside the right one."""
    left, right = specs
    if left.steps != right.steps:
        raise ValueError("the two runs of a comparison must have the same number of steps")
    every = _every(left, frames)
    options = dict(every=every, camera=camera, beams=beams, path=path_style, caption=caption)
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        first = pathlib.Path(tmp) / "left.mp4"
        results.append(record(left, first, frames=frames, fps=fps, camera=camera, beams=beams,
                              path_style=path_style, caption=caption, label=labels[0],
                              quality=10))  # read back and encoded again: near lossless
        import imageio.v2 as imageio
        explainer = Explainer(right, label=labels[1], **options)
        with contextlib.closing(imageio.get_reader(str(first))) as reader:
            frames_left = iter(reader)
            with _video(path, fps) as writer:
                def on_step(*args):
                    image = explainer.on_step(*args)
                    if image is not None:
                        writer.append_data(np.hstack([next(frames_left), image]))

                result = execution.execute(right, on_step=on_step)
        result["decisions"], result["decider_names"] = explainer.decisions, explainer.names
        results.append(result)
    return results
