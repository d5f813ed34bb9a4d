"""`ebrl ablate` and the task settings through the real command line."""
import json

import pytest

from helpers import ebrl, ebrl_here

#: The slow tier (pyproject.toml's markers): whole `ebrl ablate` and `ebrl run` commands (one a real process).
pytestmark = pytest.mark.slow


def test_a_task_setting_is_recorded_and_changes_the_run(tmp_path):
    base = ["run", "--robot", "floating", "--condition", "random", "--seeds", "0",
            "--steps", "400", "--workers", "1", "--no-progress"]
    # The floating robot's bump reading is "stop" (tasks.robots); --set changes it.
    assert ebrl_here(*base, "--out", tmp_path / "own").returncode == 0
    proc = ebrl_here(*base, "--set", "bump=grip", "--out", tmp_path / "grip")
    assert proc.returncode == 0, proc.stderr
    run = tmp_path / "grip" / "floating" / "random" / "seed_000"
    config = json.loads((run / "config.json").read_text())
    assert config["task"]["bump"] == "grip" and config["task"]["sensor_range"] == 14.0
    own = tmp_path / "own" / "floating" / "random" / "seed_000"
    assert json.loads((own / "config.json").read_text())["task"]["bump"] == "stop"
    assert (run / "trace.npz").read_bytes() != (own / "trace.npz").read_bytes()
    bad = ebrl_here(*base, "--set", "bump=wobble", "--out", tmp_path / "bad")
    assert bad.returncode == 2 and "bump must be one of" in bad.stderr
    assert not (tmp_path / "bad").exists()


def test_ablate_runs_each_cell_where_it_applies_and_resumes(tmp_path):
    out = tmp_path / "ablation"
    args = ["ablate", "--readings", "bump,radius", "--seeds", "0-1", "--steps", "300",
            "--combo", "bump=slide,radius=1.0", "--workers", "2", "--no-progress", "--out", out]
    proc = ebrl(*args)
    assert proc.returncode == 0, proc.stderr
    cells = sorted(p.name for p in out.iterdir() if p.is_dir())
    # stop is the floating robot's own bump (no cell); radius=None (the files' 1.5) is
    # both paper robots' other radius (each has its own reading, tasks.robots).
    assert cells == sorted(["default", "bump=grip", "bump=bounce", "bump=slide", "radius=None",
                            "radius=1.0", "radius=2.5", "bump=slide+radius=1.0"])
    # bump concerns the floating drive only; radius every robot.
    assert [p.name for p in (out / "bump=bounce").iterdir() if p.is_dir()] == ["floating"]
    assert sorted(p.name for p in (out / "radius=None").iterdir() if p.is_dir()) == \
        ["floating", "two_wheel"]
    assert sorted(p.name for p in (out / "radius=2.5").iterdir() if p.is_dir()) == \
        ["floating", "two_wheel"]
    data = json.loads((out / "ablation.json").read_text())
    assert set(data["cells"]) == set(cells)
    assert "bump=bounce" in (out / "ABLATION.md").read_text()
    again = ebrl_here(*args)
    assert again.returncode == 0 and again.stdout.strip().endswith("ABLATION.md")
    assert json.loads((out / "ablation.json").read_text()) == data
    bad = ebrl_here("ablate", "--readings", "colour", "--out", tmp_path / "x")
    assert bad.returncode == 2 and "unknown reading" in bad.stderr
