"""The protocol pipeline end to end, through the real command in real processes."""
import ctypes.util
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def ebrl(*args, check=True, **kw):
    proc = subprocess.run([sys.executable, "-m", "experiments", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, timeout=600, **kw)
    if check and proc.returncode != 0:
        raise AssertionError(f"ebrl {args} failed:\n{proc.stdout}\n{proc.stderr}")
    return proc


def summary(out):
    return json.loads((pathlib.Path(out) / "summary.json").read_text())


def arrays(out):
    """Every run's trials.csv text and trace arrays, keyed by run folder."""
    got = {}
    for run in sorted(pathlib.Path(out).glob("*/*/seed_*")):
        with np.load(run / "trace.npz") as z:
            got[str(run.relative_to(out))] = ((run / "trials.csv").read_text(),
                                              z["trace"].tobytes(), z["starts"].tobytes())
    return got


SMALL = ["--robot", "paper", "--condition", "all", "--seeds", "0-1", "--steps", "400", "--no-progress"]


@pytest.fixture(scope="module")
def clean_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("clean") / "results"
    ebrl("run", *SMALL, "--workers", "1", "--out", out)
    return out


def test_a_short_run_writes_every_file(clean_run):
    runs = sorted(clean_run.glob("*/*/seed_*"))
    assert len(runs) == 8
    for run in runs:
        assert {p.name for p in run.iterdir()} == {"config.json", "trials.csv", "trace.npz", "run.json"}
        config = json.loads((run / "config.json").read_text())
        assert config["steps"] == 400 and config["agent"]["recall_size"] == 7
        assert {"mujoco", "numpy", "git_commit"} <= set(config["versions"])
        record = json.loads((run / "run.json").read_text())
        assert record["status"] == "complete"
        rows = (run / "trials.csv").read_text().splitlines()
        assert rows[0] == "trial,steps,cumulative_steps,reached"
        assert sum(int(r.split(",")[1]) for r in rows[1:]) == 400
        with np.load(run / "trace.npz") as z:
            assert z["trace"].shape == (401, 2) and z["trace"].dtype == np.int16
    s = summary(clean_run)
    assert len(s["groups"]) == 4
    g = s["groups"][0]
    assert {"robot", "condition", "steps", "seeds", "first_trial_steps", "steps_per_trial",
            "shrink", "goals"} <= set(g)
    assert {"mean", "sd", "reached", "ci95"} <= set(g["first_trial_steps"])
    assert {"min", "median", "max"} <= set(g["goals"])
    for fig in ("cumulative_reward_two_wheel.png", "cumulative_reward_floating.png",
                "traces_two_wheel.png", "traces_floating.png", "first_vs_learned.png"):
        assert (clean_run / "figures" / fig).stat().st_size > 5000
    report = (clean_run / "REPORT.md").read_text()
    assert "first-trial steps" in report and "6,087" in report


def test_rerun_skips_and_report_is_reproducible(clean_run):
    before = (clean_run / "summary.json").read_bytes()
    proc = ebrl("run", *SMALL, "--out", clean_run)
    assert "0 runs made, 8 already on disk" in proc.stdout
    ebrl("report", clean_run)
    assert (clean_run / "summary.json").read_bytes() == before


def test_worker_count_does_not_change_results(clean_run, tmp_path):
    ebrl("run", *SMALL, "--workers", "2", "--out", tmp_path / "w2")
    assert arrays(tmp_path / "w2") == arrays(clean_run)
    assert summary(tmp_path / "w2") == summary(clean_run)


def test_ray_backend_gives_the_same_results(clean_run, tmp_path):
    pytest.importorskip("ray")
    env = dict(os.environ)
    env.pop("RAY_ADDRESS", None)
    ebrl("run", *SMALL, "--backend", "ray", "--workers", "2", "--out", tmp_path / "ray", env=env)
    assert arrays(tmp_path / "ray") == arrays(clean_run)


def test_kill_then_resume_gives_the_clean_summary(tmp_path):
    args = ["run", "--robot", "two_wheel", "--condition", "all", "--seeds", "0-2",
            "--steps", "1500", "--workers", "1", "--no-progress"]
    ebrl(*args, "--out", tmp_path / "clean")
    out = tmp_path / "killed"
    proc = subprocess.Popen([sys.executable, "-m", "experiments", *args, "--out", str(out)],
                            cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)
    deadline = time.time() + 120
    while time.time() < deadline and len(list(out.glob("*/*/seed_*/run.json"))) < 2:
        time.sleep(0.05)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = len(list(out.glob("*/*/seed_*/run.json")))
    assert 2 <= done < 6, done
    ebrl(*args, "--out", out)
    assert summary(out) == summary(tmp_path / "clean")
    assert arrays(out) == arrays(tmp_path / "clean")


@pytest.mark.parametrize("args,message", [
    (["run", "--robot", "tricycle"], "tricycle"),
    (["run", "--condition", "lazy"], "lazy"),
    (["run", "--seeds", "9-3"], "reversed"),
    (["run", "--seeds", ""], "seed"),
    (["run", "--steps", "0"], "positive"),
    (["run", "--steps", "-5"], "positive"),
    (["run", "--workers", "0"], "positive"),
    (["report", "no_such_folder"], "no results folder"),
    (["render", "--robot", "two_wheel", "--condition", "avoidance", "--seed", "0",
      "--out", "x.gif"], "mp4"),
])
def test_bad_arguments_fail_in_one_line_and_write_nothing(tmp_path, args, message):
    if args[0] == "run":
        args = args + ["--out", str(tmp_path / "out")]
    proc = subprocess.run([sys.executable, "-m", "experiments", *args], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode != 0
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], proc.stderr
    assert "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_corrupted_run_is_named_never_averaged(clean_run, tmp_path):
    import shutil
    out = tmp_path / "results"
    shutil.copytree(clean_run, out)
    bad = out / "floating" / "random" / "seed_001" / "run.json"
    bad.write_text(bad.read_text()[:40])
    before = (out / "summary.json").read_bytes()
    for args in (["report", out], ["run", *SMALL, "--out", out]):
        proc = ebrl(*args, check=False)
        assert proc.returncode != 0
        assert str(bad) in proc.stderr and "corrupted" in proc.stderr
        assert "Traceback" not in proc.stderr
    assert (out / "summary.json").read_bytes() == before  # nothing overwritten


def test_other_parameters_are_refused_not_overwritten(clean_run, tmp_path):
    import shutil
    out = tmp_path / "results"
    shutil.copytree(clean_run, out)
    proc = ebrl("run", *SMALL[:-3], "--steps", "500", "--out", out, check=False)
    assert proc.returncode != 0 and "other parameters" in proc.stderr
    assert json.loads((out / "two_wheel/random/seed_000/run.json").read_text())["parameters"]["steps"] == 400


def test_sweep_table_takes_the_default_rows_from_a_baseline_run(clean_run, tmp_path):
    sweep = ["sweep", "--robot", "two_wheel", "--condition", "avoidance", "--values", "0.05",
             "--steps", "400", "--out", tmp_path / "sweeps", "--baseline", clean_run, "--no-progress"]
    ebrl(*sweep, "--seeds", "0-1")
    table = (tmp_path / "sweeps" / "SWEEP.md").read_text()
    base = summary(clean_run)["groups"]
    goals = next(g for g in base if (g["robot"], g["condition"]) == ("two_wheel", "avoidance"))["goals"]
    row = next(line for line in table.splitlines() if line.startswith("| 0.0 (default"))
    assert row.endswith(f"| {goals['min']} / {goals['median']:.1f} |")
    assert table.index("| 0.0 (default") < table.index("| 0.05 |")
    # Seeds the baseline lacks: refused in one line, before anything runs.
    proc = ebrl(*sweep, "--seeds", "0-2", check=False)
    assert proc.returncode != 0 and "lacks some of these runs" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert not (tmp_path / "sweeps" / "policy_threshold_0.05" / "two_wheel" / "avoidance" / "seed_002").exists()


def test_rendered_video_has_moving_frames(tmp_path):
    import imageio.v3 as iio
    video = tmp_path / "run.mp4"
    proc = ebrl("render", "--robot", "floating", "--condition", "avoidance", "--seed", "0",
                "--steps", "60", "--out", video)
    assert proc.stderr.strip() == ""
    frames = np.stack(list(iio.imiter(video)))
    assert frames.shape[0] >= 30 and frames.shape[1:] == (320, 480, 3)
    assert np.abs(frames[-1].astype(int) - frames[0].astype(int)).mean() > 0.05


_RENDER = """
import tasks
env = tasks.load("two_wheel", seed=0)
env.reset()
px = env.physics.render(height=240, width=360, camera_id="top")
assert px.shape == (240, 360, 3) and px.std() > 10
# The top camera sees the whole room: the dark outer walls lie on all four borders.
import numpy as np
dark = px.mean(axis=2) < 110
assert dark[:, :40].any() and dark[:, -40:].any() and dark[:40].any() and dark[-40:].any()
env.close()
"""


@pytest.mark.parametrize("backend,library", [("egl", "EGL"), ("osmesa", "OSMesa")])
def test_offscreen_frame_renders_with_no_error_at_exit(backend, library):
    if not ctypes.util.find_library(library):
        pytest.skip(f"lib{library} is not installed")
    from experiments.rendering import backend_environment
    proc = subprocess.run([sys.executable, "-c", _RENDER], cwd=ROOT, capture_output=True,
                          text=True, timeout=120, env=backend_environment(backend))
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.strip() == "", proc.stderr


def test_intrinsic_parameters_reach_the_fallback():
    """--set intrinsic_random_rate / random_sd must change the behaviour a run uses."""
    import tasks
    from ebrl import intrinsic
    from experiments import protocol
    env = tasks.load("two_wheel", seed=0)
    try:
        spec = protocol.RunSpec("two_wheel", "avoidance", 0, 100,
                                overrides=(("intrinsic_random_rate", 0.0), ("random_sd", 0.1)))
        fb = protocol.make_agent(spec, env).fallback
        assert (fb.random_rate, fb.sd) == (0.0, 0.1)
        rng = np.random.default_rng(0)
        readings = np.array([1.0, 0, 0, 0, 0, 0, 0])
        # With the random replacement off, eq 8 acts every time.
        assert all(fb(readings, rng)[0] == intrinsic.avoid_by_turning(readings) for _ in range(50))
    finally:
        env.close()
