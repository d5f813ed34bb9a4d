"""Videos that explain: the beams, the caption and the legend where they belong, the path's
colours from the decision record, a comparison's two moving halves, and a video's run is
the run itself."""
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import tasks
from ebrl.agent import DECIDERS
from experiments.running import execution
from experiments.outputs import overlays, rendering
from helpers import ebrl_here
from models import UNIT

#: The slow tier (pyproject.toml's markers): videos rendered.
pytestmark = pytest.mark.slow

ROOT = pathlib.Path(__file__).resolve().parents[1]
H, W = rendering.HEIGHT, rendering.WIDTH


def project(physics, camera, point):
    """(row, column) of a world point (m) in an (H, W) frame from a fixed camera."""
    m, d = physics.model.ptr, physics.data.ptr
    cam = m.camera(camera).id
    axes = d.cam_xmat[cam].reshape(3, 3)  # columns: the camera's x, y, z in the world
    x, y, z = axes.T @ (np.asarray(point) - d.cam_xpos[cam])
    f = (H / 2) / np.tan(np.radians(m.cam_fovy[cam]) / 2)
    return H / 2 - f * y / -z, W / 2 + f * x / -z


def changed(a, b):
    return np.abs(a.astype(int) - b.astype(int)).sum(axis=2) > 0


@pytest.fixture(scope="module")
def two_wheel():
    env = tasks.load("two_wheel", seed=0)
    env.reset()
    for a in (0.0, 0.0, 0.3, 0.0, -0.2):
        env.step([a])
    yield env
    env.close()


def test_each_overlay_changes_the_frame_only_where_it_belongs(two_wheel):
    physics = two_wheel.physics
    plain = rendering.frame(physics)
    assert plain.shape == (H, W, 3)
    assert np.array_equal(rendering.frame(physics), plain)  # no overlay, no change

    # Beams: around the robot, within its radius plus the sensor range.
    beams = changed(rendering.frame(physics, sensor_range=14.0), plain)
    x, y, _ = physics.robot_pose()
    row, col = project(physics, "top", (x * UNIT, y * UNIT, 0.1))
    reach = project(physics, "top", ((x + physics.robot_radius + 14.0) * UNIT, y * UNIT, 0.1))[1] - col
    rows, cols = np.nonzero(beams)
    assert len(rows) > 200
    assert np.hypot(rows - row, cols - col).max() <= reach + 4
    # A beam that touches something within range is red-ish: the obstacle beside the start.
    readings = rendering.beams(physics, 14.0)[2]
    assert readings.max() > 0.5

    # Caption at the top, label at the bottom left, legend at the bottom right.
    caption = changed(rendering.frame(physics, caption="step 1   trial 1"), plain)
    assert caption.any() and not caption[40:].any()
    label = changed(rendering.frame(physics, label="avoidance"), plain)
    assert label.any() and not label[: H - 40].any() and not label[:, W // 2:].any()
    rows_rgb = [(n, rendering.DECIDER_RGB[n]) for n in DECIDERS]
    legend = changed(rendering.frame(physics, legend=rows_rgb), plain)
    margin, row_h, _, panel = overlays.LEGEND_BOX
    top = H - (margin + len(rows_rgb) * row_h + 8)
    assert legend.any() and not legend[: top - 2].any() and not legend[:, : W - panel - margin - 2].any()


def _explained(spec, **options):
    """The run's result, its Explainer, the frame of its last step and the same frame
    with nothing drawn on it."""
    explainer = rendering.Explainer(spec, every=spec.steps, **options)
    last = {}

    def on_step(*args):
        image = explainer.on_step(*args)
        if image is not None:
            last["frame"], last["bare"] = image, rendering.frame(args[1].physics)

    result = execution.execute(spec, on_step=on_step)
    return result, explainer, last["frame"], last["bare"]


def test_legend_and_path_colours_match_the_decision_record():
    # policy_threshold -1: the memory acts as soon as it holds something, exploration hands
    # 5% of those steps to the fallback; the first step is the fallback's own.
    spec = execution.RunSpec("floating", "avoidance", 0, 300, (("policy_threshold", -1.0),))
    result, explainer, image, bare = _explained(spec, beams=False, caption=False)
    names = explainer.names
    record = explainer.decisions[1:]
    assert (record == names.index("memory")).sum() == result["memory_decisions"] > 200
    assert (record == names.index("exploration")).sum() > 0
    assert names[record[0]] in ("intrinsic", "random")
    assert list(explainer.counts) == [int((record == i).sum()) for i in range(len(names))]

    # The legend's swatches, in DECIDERS order, have exactly the deciders' colours.
    rgb8 = {n: np.round(255 * np.array(rendering.DECIDER_RGB[n])).astype(np.uint8)
            for n in DECIDERS}
    swatches = overlays.legend_swatches(H, W, len(DECIDERS))
    for name, (left, bottom, size, _) in zip(DECIDERS, swatches):
        assert np.array_equal(image[H - 1 - (bottom + size // 2), left + size // 2], rgb8[name])

    # The path's pixels (above the legend): only the colours of deciders in the record,
    # the memory's most of all.
    path_px = image[changed(image, bare) & (np.arange(H)[:, None] < H - 140)]
    counts = {n: int((path_px == c).all(axis=1).sum()) for n, c in rgb8.items()}
    found = {n for n, k in counts.items() if k}
    assert found <= {names[i] for i in np.unique(record)}
    assert max(counts, key=counts.get) == "memory"


def test_a_video_runs_the_run_itself():
    """Recording changes no bit of the run: the same trace and trials as `ebrl run`'s."""
    spec = execution.RunSpec("two_wheel", "avoidance", 3, 200)
    plain = execution.execute(spec)
    explained = _explained(spec)[0]
    assert np.array_equal(plain["trace"], explained["trace"])
    assert np.array_equal(plain["trial_ends"], explained["trial_ends"])
    assert plain["memory_decisions"] == explained["memory_decisions"]


def test_compare_writes_one_video_with_both_halves_moving(tmp_path):
    import imageio.v3 as iio
    video = tmp_path / "compare.mp4"
    proc = subprocess.run([sys.executable, "-m", "experiments", "render", "--robot", "two_wheel",
                           "--seed", "0", "--steps", "30", "--compare", "condition", "--out",
                           str(video)], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "(random)" in proc.stdout and "(avoidance)" in proc.stdout
    frames = np.stack(list(iio.imiter(video)))
    assert frames.shape == (30, H, 2 * W, 3)  # one frame per step, both halves
    left, right = frames[:, :, :W], frames[:, :, W:]
    for half in (left, right):
        assert np.abs(half[-1].astype(int) - half[0].astype(int)).mean() > 0.05
    assert np.abs(left[-1].astype(int) - right[-1].astype(int)).mean() > 0.05
    # Browser-playable: H.264 in yuv420p, the index (moov) before the data (mdat).
    meta = iio.immeta(video)
    assert meta["codec"] == "h264" and meta["pix_fmt"].startswith("yuv420p")
    data = video.read_bytes()
    assert 0 < data.find(b"moov") < data.find(b"mdat")


def test_compare_behaviour_puts_the_papers_rule_beside_a_genome(tmp_path):
    import dataclasses

    import imageio.v3 as iio

    from ebrl import behaviour as genomes
    genome = tmp_path / "mine.json"
    paper = genomes.load(ROOT / "behaviours" / "paper_eq8.json")
    genomes.save(dataclasses.replace(paper, bias=0.6, random_rate=0.0), genome)
    base = [sys.executable, "-m", "experiments", "render", "--robot", "two_wheel", "--seed", "0",
            "--condition", "avoidance", "--steps", "30", "--compare", "behaviour"]
    video = tmp_path / "behaviours.mp4"
    proc = subprocess.run(base + ["--behaviour", str(genome), "--out", str(video)], cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "(hand-coded (paper))" in proc.stdout and "(evolved (mine))" in proc.stdout
    frames = np.stack(list(iio.imiter(video)))
    left, right = frames[:, :, :W], frames[:, :, W:]
    assert np.abs(left[-1].astype(int) - right[-1].astype(int)).mean() > 0.05  # they part
    bad = ebrl_here(*base[3:], "--out", tmp_path / "x.mp4")  # refused before any work
    assert bad.returncode == 2 and "--compare behaviour needs --behaviour" in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1 and not (tmp_path / "x.mp4").exists()


def test_follow_camera_frames_a_3d_robot():
    """The follow camera looks at the robot from a few of its radii: the robot fills the
    frame's centre and many times the pixels it has from the top camera."""
    env = tasks.load("diff_drive", seed=0)
    env.reset()
    physics = env.physics
    model = physics.model.ptr
    robot = model.geom_bodyid != 0  # the room's geoms are the world body's

    def robot_pixels(camera):
        shown = rendering.frame(physics, camera=camera)
        rgba = model.geom_rgba.copy()
        model.geom_rgba[robot, 3] = 0.0  # MuJoCo draws no geom of alpha 0
        try:
            hidden = rendering.frame(physics, camera=camera)
        finally:
            model.geom_rgba[:] = rgba
        return changed(shown, hidden)

    follow, top = robot_pixels("follow"), robot_pixels("top")
    env.close()
    assert follow[H // 2 - 5: H // 2 + 5, W // 2 - 5: W // 2 + 5].all()
    assert follow.mean() > 0.03 and follow.sum() > 20 * top.sum() > 0
