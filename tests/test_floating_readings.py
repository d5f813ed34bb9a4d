"""The floating drive's open readings (tasks.TaskConfig: thrust, velocity_noise,
velocity_code, wall_friction, restitution), each on a case computed by hand."""
import numpy as np
import pytest

import models
import tasks
from tasks import floating


def _env(**kw):
    # the paper's base task (the fields' defaults), each test changing one reading
    return tasks.load("floating", seed=0, config=tasks.TaskConfig(), start_jitter=False,
                      sensor_noise=0.0, action_noise=0.0, **kw)


@pytest.mark.parametrize("thrust,demand,dv", [
    ("scaled", 1.0, 0.2), ("scaled", -0.5, -0.1), ("scaled", 0.1, 0.02),
    ("demand", 1.0, 1.0), ("demand", -0.5, -0.5), ("demand", 0.1, 0.1),
    ("clipped", 1.0, 0.2), ("clipped", -0.5, -0.2), ("clipped", 0.1, 0.1),
])
def test_thrust_readings_change_the_velocity_as_named(thrust, demand, dv):
    """From rest in free space, one step of demand (a, 0): "scaled" 0.2 a, "demand" a,
    "clipped" a within +-0.2, in units/step."""
    env = _env(thrust=thrust)
    env.reset()
    env.physics.set_robot_pose(45.0, 5.0)
    env.step([demand, 0.0])
    np.testing.assert_allclose(env.physics.robot_velocity(), [dv, 0.0], atol=1e-9)
    env.close()


def test_velocity_code_rounds_to_the_0_255_code_and_back():
    """v = (0.5, -0.2) units/step over +-2: codes rint(0.25 * 127.5 + 127.5) = 159 and
    rint(-0.1 * 127.5 + 127.5) = rint(114.75) = 115, read back as (159 - 127.5) / 127.5 * 2
    and (115 - 127.5) / 127.5 * 2."""
    assert floating.VELOCITY_FULL_SCALE == 2.0
    env = _env(velocity_code="code")
    env.reset()
    env.physics.set_robot_pose(45.0, 5.0)
    env.step([1.0, 0.0]), env.step([1.0, -1.0])       # 0.4, -0.2
    ts = env.step([0.5, 0.0])                         # 0.5, -0.2
    np.testing.assert_allclose(env.physics.robot_velocity(), [0.5, -0.2], atol=1e-9)
    want = [(159 - 127.5) / 127.5 * 2, (115 - 127.5) / 127.5 * 2]
    np.testing.assert_allclose(ts.observation["velocity"], want, atol=1e-12)
    # Beyond the full scale the code saturates at 255 and 0.
    fast = _env(velocity_code="code", thrust="demand")
    fast.reset()
    fast.physics.set_robot_pose(45.0, 30.0)
    fast.step([1.0, -1.0]), fast.step([1.0, -1.0])
    ts = fast.step([1.0, -1.0])                       # 3, -3 units/step
    np.testing.assert_allclose(ts.observation["velocity"], [2.0, -2.0], atol=1e-12)
    env.close(), fast.close()


def test_velocity_noise_has_its_sd_and_leaves_the_physics_alone():
    quiet, noisy = _env(), _env(velocity_noise=0.05)
    quiet.reset(), noisy.reset()
    errors = []
    for env in (quiet, noisy):
        env.physics.set_robot_pose(45.0, 5.0)
    for _ in range(400):
        a, b = quiet.step([0.0, 0.0]), noisy.step([0.0, 0.0])
        errors.append(b.observation["velocity"] - a.observation["velocity"])
        assert quiet.physics.robot_pose() == noisy.physics.robot_pose()
    errors = np.array(errors)
    assert errors.std() == pytest.approx(0.05, rel=0.1) and abs(errors.mean()) < 0.01
    quiet.close(), noisy.close()


def test_wall_friction_sets_the_bumpers_friction_under_grip_only():
    env = _env(wall_friction=0.25)
    hull = env.physics.model.name2id(models.PREFIX + "hull", "geom")
    assert env.physics.model.geom_friction[hull][0] == 0.25
    slide = _env(wall_friction=0.25, bump="slide")  # slide: frictionless, condim 1
    assert slide.physics.model.geom_condim[hull] == 1
    env.close(), slide.close()


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_restitution_scales_the_bounce(e):
    """Head-on into the south wall at 0.4 units/step: back at 0.4 e. At 45 degrees
    (0.4, -0.4): the motion along the wall kept, (0.4, 0.4 e)."""
    def bump(vx, vy):
        env = _env(bump="bounce", restitution=e)
        env.reset()
        env.physics.set_robot_pose(40.0, 3.0)
        for _ in range(2):
            env.step([vx / 0.4, vy / 0.4])
        for _ in range(25):
            env.step([0.0, 0.0])
        v = env.physics.robot_velocity()
        env.close()
        return v
    np.testing.assert_allclose(bump(0.0, -0.4), [0.0, 0.4 * e], atol=1e-6)
    np.testing.assert_allclose(bump(0.4, -0.4), [0.4, 0.4 * e], atol=1e-6)


@pytest.mark.parametrize("field,value,message", [
    ("thrust", "rocket", "thrust must be one of"), ("velocity_code", "gray", "velocity_code must be one of"),
    ("restitution", 1.5, "at most 1"), ("restitution", -0.1, "non-negative"),
    ("wall_friction", float("inf"), "finite"), ("velocity_noise", -1.0, "non-negative"),
])
def test_floating_readings_refuse_bad_values(field, value, message):
    with pytest.raises(ValueError, match=message):
        tasks.TaskConfig(**{field: value})
