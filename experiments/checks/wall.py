"""Section 3.3's blocked move, checked on a two-wheel body in MuJoCo: "If the agent cannot
move any more because of collision with an object, the rest portion of move is
transferred into the angle of turn."

`wall_test` starts the robot `gap` units from the bottom wall, heading into it at each
angle, and makes one full move (a = 0, no noise); `wall_ideal` is what Section 3.3's
kinematics make of the same move: the robot moves until it touches and turns the rest at
1 rad per 2 units. tests/test_wall.py holds protocol 8's body to it (issue 56), and
docs/interpretation.md gives the table for every protocol's body
(`wall_test(robot=...)` for any two-wheel realisation, docs/adding_a_robot.md).
"""
import math

import mujoco
import numpy as np

import tasks
from tasks.two_wheel import MAX_MOVE, MAX_TURN


def wall_ideal(deg, gap=0.1):
    """Section 3.3's kinematics for wall_test's move: (along the wall, towards it, turn):
    gap / tan(angle) along, gap towards, and the rest of the 2 units, 2 - gap / sin(angle),
    turned at 1 rad per 2 units."""
    a = math.radians(deg)
    return gap / math.tan(a), gap, (MAX_MOVE - gap / math.sin(a)) * MAX_TURN / MAX_MOVE


def wall_test(angles=(90, 60, 45, 30, 15, 5), gap=0.1, task_overrides=(), protocol="adopted",
              robot="two_wheel"):
    """What one full move (a = 0, no noise) does to a two-wheel robot (a name or file
    tasks.load takes) whose hull is started `gap` units from the bottom wall, heading into
    it at each angle (degrees), under a protocol's readings and the overrides: {angle:
    (distance made along the wall, distance made towards it, turn taken)}; Section 3.3's
    kinematics: wall_ideal."""
    entry = tasks.resolve(robot).under(protocol)
    config = entry.task_config(**(dict(task_overrides) | {"action_noise": 0.0,
                                                          "sensor_noise": 0.0}))
    env = tasks.load(entry, seed=0, config=config)
    env.reset()
    r = env.physics.robot_radius
    out = {}
    for deg in angles:
        h = -math.radians(deg)
        env.physics.set_robot_pose(40.0, r + gap, h)
        mujoco.mj_forward(env.physics.model.ptr, env.physics.data.ptr)
        x0, y0, h0 = env.physics.robot_pose()
        env.step(np.array([0.0]))
        x1, y1, h1 = env.physics.robot_pose()
        out[deg] = (x1 - x0, y0 - y1, abs(math.remainder(h1 - h0, 2 * math.pi)))
    env.close()
    return out
