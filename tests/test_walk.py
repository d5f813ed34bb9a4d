"""The walk study (issue 48, item 6: experiments.studies.walk) and its grid of settings
(experiments.studies.grid): Section 3.3's per-step numbers by hand, the kinematic walk's
geometry, the real MuJoCo body at a wall, and the grid's real runs."""
import math

import numpy as np
import pytest

from experiments.studies import grid, walk


def test_section_3_3_per_step_by_hand():
    """a = clip(N(0, 0.5), -1, 1): E|a| = E[|Z|; |Z| < 1] + P(|Z| >= 1), the half-normal's
    0.5 sqrt(2 / pi) (1 - e^-2) = 0.344951 plus 2 (1 - Phi(2)) = 0.045500: 0.390452. The
    turn is E|a| times the 5% discount's mean factor 0.975, the move 2 (1 - E|a|) 0.975."""
    mean_abs = 0.5 * math.sqrt(2 / math.pi) * (1 - math.exp(-2)) + math.erfc(2 / math.sqrt(2))
    assert mean_abs == pytest.approx(0.390452, abs=1e-6)
    got = walk.implied()
    assert got["turn"] == pytest.approx(mean_abs * 0.975, abs=1e-6)
    assert got["move"] == pytest.approx(2 * (1 - mean_abs) * 0.975, abs=1e-6)
    assert got["saturated"] == pytest.approx(math.erfc(2 / math.sqrt(2)), abs=1e-5)


def test_the_kinematic_room_and_walk():
    # the start, 5 units from the left wall, 15 from the first block's face
    assert walk._clearance(5.0, 35.0, 1.5) == pytest.approx(3.5)
    assert walk._clearance(25.0, 52.0, 1.5) == pytest.approx(0.5)  # 2 above the block x 20-30, y 20-50
    assert walk._clearance(25.0, 40.0, 1.5) < 0  # inside it
    # a move straight at the left wall from clearance 3.5 stops after 3.5 units
    assert walk._advance(5.0, 35.0, -1.0, 0.0, 10.0, 1.5) == pytest.approx(3.5, abs=1e-6)
    (first, trace, per), = walk.kinematic([7], 1.5, steps=3000)
    assert all(walk._clearance(x, y, 1.5) > -1e-6 for x, y in trace)  # never inside a wall
    steps = np.hypot(*np.diff(trace, axis=0).T)
    assert steps.max() <= 2.0 + 1e-9 and np.allclose(steps, per[:, 0])
    assert (per[:, 3] > 0).any() and (per[:, 0] <= per[:, 1] + 1e-9).all()
    if first is not None:  # it ends where Section 3.1's goal is
        x, y = trace[-1]
        assert 80 <= x <= 90 and 50 <= y <= 60


@pytest.mark.parametrize("protocol", ["adopted", "literal"])
def test_the_mujoco_body_stops_at_a_wall_as_section_3_3_says(protocol):
    """A full move (a = 0) from 0.1 units off the bottom wall, heading into it at 60, 45, 30
    and 15 degrees, under each protocol's body: the body moves until it touches, gap / tan
    along the wall (0.058, 0.100, 0.173, 0.373 units), and turns the rest of the 2 units at
    1 rad per 2 (0.942, 0.929, 0.900, 0.807 rad): Section 3.3's kinematics within 0.06 units
    and 0.08 rad (issue 56), and the move towards the wall is the gap. Head-on (90) it
    makes nothing along it and turns (2 - 0.1) / 2 = 0.95 rad."""
    assert walk.wall_ideal(45) == pytest.approx((0.1, 0.1, (2 - 0.1 * math.sqrt(2)) / 2))
    got = walk.wall_test((90, 60, 45, 30, 15), protocol=protocol)
    for deg, (along, towards, turn) in got.items():
        ideal_along, ideal_towards, ideal_turn = walk.wall_ideal(deg)
        assert along == pytest.approx(ideal_along, abs=0.06), deg
        assert towards == pytest.approx(ideal_towards, abs=0.02), deg
        assert turn == pytest.approx(ideal_turn, abs=0.08), deg


def test_a_refused_move_turns_all_of_it():
    """blocked_move "refuse" (protocol 7's, kept to remake its runs): no motion, all of the
    move (2 units) turned, 1 rad."""
    body = (("radius", 1.5), ("leftover_turn", "commanded"), ("blocked_move", "refuse"))
    for along, towards, turn in walk.wall_test((90, 45), task_overrides=body).values():
        assert abs(along) < 1e-6 and abs(towards) < 1e-6 and turn == pytest.approx(1.0, abs=1e-6)


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
