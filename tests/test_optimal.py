"""The optimal path (experiments.outputs.optimal), the report's yardstick for learned
trials: each step count against a hand-computed case, the geometry on a made-up room,
and the registered robots' rooms as compiled, with their radius readings."""
import math

import numpy as np
import pytest

import models
import tasks
from experiments.outputs import optimal
from tasks import navigation


def test_floating_lower_bound_by_hand():
    # a = 0.2 sqrt(2) = 0.28284: 7 steps cover 28 a = 7.92 units, 8 steps 36 a = 10.18
    assert optimal.floating_lower_bound(10.0) == 8
    assert optimal.floating_lower_bound(7.9) == 7
    assert optimal.floating_lower_bound(0.2) == 1


def test_two_wheel_steps_by_hand():
    # 10 units east, then 6 north: 16 / 2 = 8 steps of moving, plus a quarter turn
    path = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 6.0]])
    assert optimal.two_wheel_steps(path, heading=0.0) == math.ceil(8 + math.pi / 2)
    # facing west at the start: half a turn more
    assert optimal.two_wheel_steps(path, heading=math.pi) == math.ceil(8 + math.pi + math.pi / 2)


def test_floating_steps_by_hand():
    # one leg of 10 units along x at 0.2 units/step^2: accelerate n steps, brake n steps,
    # a n^2 >= 10, n = ceil(sqrt(50)) = 8
    assert optimal.floating_steps(np.array([[0.0, 0.0], [10.0, 0.0]])) == 16
    # a bend of 90 degrees stops the plan: two legs of 10 and 5 (n = 8 and ceil(5) = 5)
    assert optimal.floating_steps(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]])) == 16 + 10


def test_shortest_path_empty_room_is_the_straight_line():
    length, path = optimal.shortest_path((5.0, 5.0), (0.0, 40.0, 0.0, 40.0), [],
                                         (20.0, 30.0, 20.0, 30.0), radius=1.0)
    assert length == pytest.approx(math.hypot(15.0, 15.0))
    np.testing.assert_allclose(path, [[5.0, 5.0], [20.0, 20.0]])


def test_shortest_path_goes_round_an_obstacle_at_the_radius():
    box, radius = (8.0, 12.0, 0.0, 30.0), 1.5
    length, path = optimal.shortest_path((2.0, 10.0), (0.0, 40.0, 0.0, 40.0), [box],
                                         (30.0, 40.0, 0.0, 10.0), radius)
    assert length > math.hypot(28.0, 0.0)  # longer than through the box
    for p, q in zip(path[:-1], path[1:]):
        assert optimal.segment_box_distance(p, q, box) >= radius - 1e-4
    # over the box's top (y = 30) and no higher than its corner arc needs
    assert 30.0 + radius - 1e-3 <= path[:, 1].max() <= 30.0 + radius / math.cos(math.pi / 24) + 2e-3


@pytest.mark.parametrize("robot", tasks.PAPER_ROBOTS)
def test_optimal_uses_the_room_and_radius_as_simulated(robot):
    entry = tasks.ROBOTS[robot]
    best = optimal.optimal(robot)
    env = tasks.load(robot, seed=0)
    try:
        # the radius the environment simulates is the robot's reading, read from the
        # compiled room alone as optimal() reads it
        model, _ = tasks.compile_robot(entry, entry.task_config())
        assert navigation.robot_radius(model) == env.physics.robot_radius
        assert env.physics.robot_radius == pytest.approx(dict(entry.readings)["radius"])
        _, _, goal, start = models.room_layout(env.physics.model)
    finally:
        env.close()
    np.testing.assert_allclose(best["path"][0], start[:2])
    end = best["path"][-1]
    assert goal[0] <= end[0] <= goal[1] and goal[2] <= end[1] <= goal[3]
    assert best["steps_lower"] <= best["steps"]
    assert best["length"] == pytest.approx(np.linalg.norm(np.diff(best["path"], axis=0), axis=1).sum())
