"""Videos, offscreen frames and the other learners through the real command (split from
test_experiments.py, whose helpers it shares)."""
import ctypes.util
import json
import subprocess
import sys

import numpy as np
import pytest

from helpers import ROOT, ebrl_here
from test_experiments import ebrl, summary


@pytest.mark.parametrize("robot,camera", [("floating", "top"), ("diff_drive", "follow"),
                                          ("hovercraft", "chase")])
@pytest.mark.slow
def test_rendered_video_has_moving_frames(tmp_path, robot, camera):
    import imageio.v3 as iio
    video = tmp_path / "run.mp4"
    proc = ebrl("render", "--robot", robot, "--condition", "avoidance", "--seed", "0",
                "--steps", "30", "--camera", camera, "--out", video)
    assert proc.stderr.strip() == ""
    frames = np.stack(list(iio.imiter(video)))
    assert frames.shape[0] >= 30 and frames.shape[1:] == (480, 640, 3)
    assert np.abs(frames[-1].astype(int) - frames[0].astype(int)).mean() > 0.05
    bad = ebrl_here("render", "--robot", robot, "--condition", "avoidance", "--seed", "0",
               "--camera", "ceiling", "--out", tmp_path / "x.mp4")
    assert bad.returncode == 2 and "unknown camera 'ceiling'" in bad.stderr
    assert not (tmp_path / "x.mp4").exists()


_RENDER = """
import tasks
env = tasks.load("two_wheel", seed=0)
env.reset()
px = env.physics.render(height=240, width=360, camera_id="top")
assert px.shape == (240, 360, 3) and px.std() > 10
# The top camera sees the whole room: the dark outer walls lie on all four borders.
import numba
import numpy as np
dark = px.mean(axis=2) < 110
assert dark[:, :40].any() and dark[:, -40:].any() and dark[:40].any() and dark[-40:].any()
env.close()
"""


@pytest.mark.slow
@pytest.mark.parametrize("backend,library", [("egl", "EGL"), ("osmesa", "OSMesa")])
def test_offscreen_frame_renders_with_no_error_at_exit(backend, library):
    if not ctypes.util.find_library(library):
        pytest.skip(f"lib{library} is not installed")
    from experiments.outputs.rendering import backend_environment
    proc = subprocess.run([sys.executable, "-c", _RENDER], cwd=ROOT, capture_output=True,
                          text=True, timeout=120, env=backend_environment(backend))
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.strip() == "", proc.stderr


def test_intrinsic_parameters_reach_the_fallback():
    """--set intrinsic_random_rate / random_sd must change the behaviour a run uses."""
    import tasks
    from ebrl import intrinsic
    from experiments.running import execution
    env = tasks.load("two_wheel", seed=0)
    try:
        spec = execution.RunSpec("two_wheel", "avoidance", 0, 100,
                                overrides=(("intrinsic_random_rate", 0.0), ("random_sd", 0.1)))
        fb = execution.make_agent(spec, env).fallback
        assert (fb.random_rate, fb.sd) == (0.0, 0.1)
        rng = np.random.default_rng(0)
        readings = np.array([1.0, 0, 0, 0, 0, 0, 0])
        # With the random replacement off, eq 8 acts every time.
        assert all(fb(readings, rng)[0] == intrinsic.avoid_by_turning(readings) for _ in range(50))
    finally:
        env.close()


@pytest.mark.slow
@pytest.mark.parametrize("agent", ["qtable", "mfec"])
def test_run_with_another_learner(tmp_path, agent):
    out = tmp_path / "results"
    proc = ebrl_here("run", "--agent", agent, "--robot", "paper", "--seeds", "0", "--steps", "300",
                     "--workers", "1", "--no-progress", "--out", out)
    assert proc.returncode == 0, proc.stderr
    for robot in ("two_wheel", "floating"):
        run = out / f"{robot}.{agent}" / "avoidance" / "seed_000"
        config = json.loads((run / "config.json").read_text())
        assert config["learner"] == agent and "memory_decisions" in json.loads(
            (run / "run.json").read_text())
    groups = {(g["robot"], g["agent"]) for g in summary(out)["groups"]}
    assert groups == {("two_wheel." + agent, agent), ("floating." + agent, agent)}
    assert f"two_wheel.{agent}" in (out / "REPORT.md").read_text()
    bad = ebrl_here("run", "--agent", agent, "--set", "policy_threshold=0.1", "--out",
               tmp_path / "bad")
    assert bad.returncode == 2 and f"not a parameter of the {agent} agent" in bad.stderr
