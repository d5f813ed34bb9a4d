"""The Gymnasium environments: every registered robot, Gymnasium's own checker, the
terminated / truncated / seed semantics and a vector environment."""
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tasks
import tasks.gym

IDS = [tasks.gym.env_id(name) for name in tasks.ROBOTS]


def test_one_id_per_registered_robot():
    assert IDS == ["EBRL/TwoWheel-v0", "EBRL/Floating-v0", "EBRL/DiffDrive-v0",
                   "EBRL/Hovercraft-v0"][: len(tasks.ROBOTS)]
    for name, env_id in zip(tasks.ROBOTS, IDS):
        assert gymnasium.spec(env_id).max_episode_steps == tasks.ROBOTS[name].budget


@pytest.mark.parametrize("env_id", IDS)
def test_check_env_passes(env_id):
    env = gymnasium.make(env_id, render_mode="rgb_array")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*Box observation space m.*infinity")
        check_env(env.unwrapped)
    obs, info = env.reset(seed=0)
    dm = env.unwrapped._env
    for key, spec in dm.observation_spec().items():  # spaces match the dm_env specs
        assert env.observation_space[key].shape == spec.shape == obs[key].shape
    assert env.action_space.shape == dm.action_spec().shape
    assert np.all(env.action_space.low == -1) and np.all(env.action_space.high == 1)
    frame = env.render()
    assert frame.shape == (*tasks.gym.RENDER_SIZE, 3) and frame.std() > 0
    assert env.metadata["render_fps"] == pytest.approx(1 / dm.physics.step_seconds)
    env.close()


def test_goal_terminates_and_the_step_limit_truncates():
    env = gymnasium.make("EBRL/TwoWheel-v0", start_jitter=False, sensor_noise=0.0,
                         action_noise=0.0, max_episode_steps=3)
    env.reset(seed=0)
    env.unwrapped.physics.set_robot_pose(84.0, 55.0, 0.0)  # inside the goal square
    obs, reward, terminated, truncated, info = env.step(np.array([1.0]))  # turn in place
    assert (reward, terminated, truncated, info["is_success"]) == (1.0, True, False, True)
    env.reset(seed=0)
    for k in range(3):
        obs, reward, terminated, truncated, info = env.step(np.array([1.0]))
    assert (reward, terminated, truncated, info["is_success"]) == (0.0, False, True, False)
    assert info["pose"].shape == (3,)
    env.close()


@pytest.mark.parametrize("env_id", ["EBRL/TwoWheel-v0", "EBRL/Floating-v0"])
def test_reset_with_a_seed_reproduces_a_trajectory(env_id):
    def rollout(env, seed):
        obs, _ = env.reset(seed=seed)
        out = [obs["range"].copy()]
        rng = np.random.default_rng(1)
        for _ in range(30):
            obs, *_ = env.step(rng.uniform(-1, 1, env.action_space.shape))
            out.append(obs["range"].copy())
        return np.array(out)

    a, b = gymnasium.make(env_id), gymnasium.make(env_id)
    first = rollout(a, 7)
    rollout(a, 8)  # something else in between
    assert np.array_equal(first, rollout(a, 7)) and np.array_equal(first, rollout(b, 7))
    assert not np.array_equal(first, rollout(b, 8))
    a.close(), b.close()


def test_sync_vector_env_of_four_steps():
    envs = gymnasium.vector.SyncVectorEnv([lambda: gymnasium.make("EBRL/Floating-v0")] * 4)
    obs, info = envs.reset(seed=0)
    assert obs["range"].shape == (4, 8) and obs["velocity"].shape == (4, 2)
    for _ in range(5):
        obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
    assert reward.shape == terminated.shape == (4,)
    assert len({tuple(r) for r in obs["range"]}) == 4  # four seeds, four rooms of noise
    envs.close()
