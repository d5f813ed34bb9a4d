"""The grid of settings (experiments.studies.grid) that the body fit and the first-trial
studies run: each setting in its own folder, real runs, and its summaries and table."""
import math

import pytest

from experiments.studies import grid


def test_a_grid_runs_each_setting_in_its_folder(tmp_path):
    settings = grid.product(blocked_move=("stop", "refuse"))
    assert settings == [(("blocked_move", "stop"),), (("blocked_move", "refuse"),)]
    assert grid.name(settings[1]) == "blocked_move=refuse" and grid.name(()) == "default"
    runs = grid.run(tmp_path, "two_wheel", settings, ("random",), [0, 1], steps=200)
    for setting in settings:
        assert set(runs[setting]) == {("random", 0), ("random", 1)}
        folder = tmp_path / "two_wheel" / grid.name(setting)
        assert (folder / "two_wheel.first_trial/random/seed_001/run.json").exists()
        for run in runs[setting].values():
            assert run["parameters"]["task"]["blocked_move"] == dict(setting)["blocked_move"]
    firsts = grid.first_trials(runs[settings[0]], "random")
    assert len(firsts) == 2 and all(f is None or 0 < f <= 200 for f in firsts)
    s = grid.summary([10, 20, None], 30)
    assert (s["mean"], s["reached"], s["runs"]) == (15.0, 2, 3)
    assert s["sd"] == pytest.approx(math.sqrt(50))
    table = grid.table({"a": {"mean": 1234.5, "p": 0.01234, "n": None}}, ["mean", "p", "n"])
    assert table.splitlines() == ["| setting | mean | p | n |", "|---|---:|---:|---:|",
                                  "| a | 1,234 | 0.012 | - |"]
