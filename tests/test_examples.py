"""examples/: the Stable-Baselines3 script, run as a user would (skipped without SB3, an
optional extra: pip install -e '.[sb3]')."""
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def test_sb3_ppo_example_trains_evaluates_and_renders(tmp_path):
    pytest.importorskip("stable_baselines3")
    import imageio.v3 as iio
    video = tmp_path / "ppo.mp4"
    env = dict(os.environ, PYTHONPATH=str(ROOT))  # this checkout's code, in the workers too
    proc = subprocess.run([sys.executable, "examples/sb3_ppo.py", "--timesteps", "128",
                           "--envs", "2", "--episode-steps", "20", "--eval-episodes", "1",
                           "--out", str(video)], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "PPO after 128 steps" in proc.stdout and "episode:" in proc.stdout
    frames = np.stack(list(iio.imiter(video)))
    assert 2 <= len(frames) <= 21 and frames.shape[1:] == (480, 640, 3)
    assert np.abs(frames[-1].astype(int) - frames[0].astype(int)).mean() > 0.01
