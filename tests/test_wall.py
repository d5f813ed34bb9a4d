"""Section 3.3's blocked move on the real MuJoCo body (experiments.checks.wall): the robot
moves until it touches and turns the rest."""
import math

import pytest

from experiments.checks import wall


@pytest.mark.parametrize("protocol", ["adopted", "literal"])
def test_the_mujoco_body_stops_at_a_wall_as_section_3_3_says(protocol):
    """A full move (a = 0) from 0.1 units off the bottom wall, heading into it at 60, 45, 30
    and 15 degrees, under each protocol's body: the body moves until it touches, gap / tan
    along the wall (0.058, 0.100, 0.173, 0.373 units), and turns the rest of the 2 units at
    1 rad per 2 (0.942, 0.929, 0.900, 0.807 rad): Section 3.3's kinematics within 0.06 units
    and 0.08 rad (issue 56), and the move towards the wall is the gap. Head-on (90) it
    makes nothing along it and turns (2 - 0.1) / 2 = 0.95 rad."""
    assert wall.wall_ideal(45) == pytest.approx((0.1, 0.1, (2 - 0.1 * math.sqrt(2)) / 2))
    got = wall.wall_test((90, 60, 45, 30, 15), protocol=protocol)
    for deg, (along, towards, turn) in got.items():
        ideal_along, ideal_towards, ideal_turn = wall.wall_ideal(deg)
        assert along == pytest.approx(ideal_along, abs=0.06), deg
        assert towards == pytest.approx(ideal_towards, abs=0.02), deg
        assert turn == pytest.approx(ideal_turn, abs=0.08), deg


def test_a_refused_move_turns_all_of_it():
    """blocked_move "refuse" (protocol 7's, kept to remake its runs): no motion, all of the
    move (2 units) turned, 1 rad."""
    body = (("radius", 1.5), ("leftover_turn", "commanded"), ("blocked_move", "refuse"))
    for along, towards, turn in wall.wall_test((90, 45), task_overrides=body).values():
        assert abs(along) < 1e-6 and abs(towards) < 1e-6 and turn == pytest.approx(1.0, abs=1e-6)
