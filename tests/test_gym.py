"""The Gymnasium environments: every registered robot, Gymnasium's own checker, the
terminated / truncated / seed semantics and a vector environment."""
import warnings

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import tasks
import tasks.gym
from tasks.kernels import bindings

IDS = [tasks.gym.env_id(name) for name in tasks.ROBOTS]


def test_one_id_per_registered_robot():
    assert IDS == ["EBRL/TwoWheel-v1", "EBRL/Floating-v1", "EBRL/DiffDrive-v1",
                   "EBRL/Hovercraft-v1"][: len(tasks.ROBOTS)]
    for name, env_id in zip(tasks.ROBOTS, IDS):
        assert gymnasium.spec(env_id).max_episode_steps == tasks.ROBOTS[name].budget


def _made(env_id):
    """(the environment gymnasium.make makes of env_id, the warnings it raised)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        env = gymnasium.make(env_id)
    return env, caught


def test_the_ids_are_versioned_and_the_old_ones_warn_and_make_the_current():
    """v1 is protocol 8's dynamics; v0, the id before it, stays registered: it warns
    (DeprecationWarning, naming the current id) and makes the current environment."""
    assert tasks.gym.VERSION == 1 and set(tasks.gym.VERSIONS) == {0, 1}
    for name in tasks.ROBOTS:
        new, old = tasks.gym.env_id(name), tasks.gym.env_id(name, 0)
        assert old in gymnasium.registry and gymnasium.spec(old).max_episode_steps == \
            gymnasium.spec(new).max_episode_steps
    env, caught = _made("EBRL/TwoWheel-v1")
    assert not [w for w in caught if issubclass(w.category, DeprecationWarning)], caught
    old, caught = _made("EBRL/TwoWheel-v0")
    ours = [str(w.message) for w in caught if issubclass(w.category, DeprecationWarning)
            and w.filename == tasks.gym.__file__]
    assert ours and ours[0].startswith("EBRL/TwoWheel-v0 is deprecated: it makes EBRL/TwoWheel-v1")
    assert type(old.unwrapped) is type(env.unwrapped) is tasks.gym.NavigationEnv
    assert old.observation_space == env.observation_space and old.action_space == env.action_space
    # the same dynamics: one seed, one action sequence, the same observations
    for e in (env, old):
        e.reset(seed=3)
    for a in np.linspace(-1, 1, 5):
        o1, o2 = env.step(np.array([a])), old.step(np.array([a]))
        assert np.array_equal(o1[0]["range"], o2[0]["range"]) and o1[1:4] == o2[1:4]
    env.close(), old.close()


@pytest.mark.parametrize("env_id", IDS)
def test_check_env_passes(env_id):
    env = gymnasium.make(env_id, render_mode="rgb_array")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*Box observation space m.*infinity")
        check_env(env.unwrapped)
    obs, info = env.reset(seed=0)
    dm = env.unwrapped.dm_env
    for key, spec in dm.observation_spec().items():  # spaces match the dm_env specs
        assert env.observation_space[key].shape == spec.shape == obs[key].shape
    assert env.action_space.shape == dm.action_spec().shape
    assert np.all(env.action_space.low == -1) and np.all(env.action_space.high == 1)
    frame = env.render()
    assert frame.shape == (*tasks.gym.RENDER_SIZE, 3) and frame.std() > 0
    assert env.metadata["render_fps"] == pytest.approx(1 / dm.physics.step_seconds)
    env.close()


def test_goal_terminates_and_the_step_limit_truncates():
    env = gymnasium.make("EBRL/TwoWheel-v1", start_jitter=False, sensor_noise=0.0,
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


@pytest.mark.parametrize("env_id", ["EBRL/TwoWheel-v1", "EBRL/Floating-v1"])
def test_reset_with_a_seed_reproduces_a_trajectory(env_id):
    def rollout(env, seed):
        obs, _ = env.reset(seed=seed)
        out = [obs["range"].copy()]
        rng = np.random.default_rng(1)
        for _ in range(30):
            obs, *_ = env.step(rng.uniform(-1, 1, env.action_space.shape))
            out.append(obs["range"].copy())
        return np.array(out)

    timer = bindings.TIMER_CALLBACK.value  # step turns MuJoCo's timers off, then back on
    a, b = gymnasium.make(env_id), gymnasium.make(env_id)
    first = rollout(a, 7)
    assert bindings.TIMER_CALLBACK.value == timer is not None
    rollout(a, 8)  # something else in between
    assert np.array_equal(first, rollout(a, 7)) and np.array_equal(first, rollout(b, 7))
    assert not np.array_equal(first, rollout(b, 8))
    a.close(), b.close()


def test_sync_vector_env_of_four_steps():
    envs = gymnasium.vector.SyncVectorEnv([lambda: gymnasium.make("EBRL/Floating-v1")] * 4)
    obs, info = envs.reset(seed=0)
    assert obs["range"].shape == (4, 8) and obs["velocity"].shape == (4, 2)
    for _ in range(5):
        obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
    assert reward.shape == terminated.shape == (4,)
    assert len({tuple(r) for r in obs["range"]}) == 4  # four seeds, four rooms of noise
    envs.close()


@pytest.mark.parametrize("env_id", IDS)
def test_spaces_are_float32_and_bounded_where_a_bound_exists(env_id):
    env = gymnasium.make(env_id)
    assert env.action_space.dtype == np.float32
    assert np.all(env.action_space.low == -1) and np.all(env.action_space.high == 1)
    for key, space in env.observation_space.spaces.items():
        assert space.dtype == np.float32, key
    rng = env.observation_space["range"]
    assert np.all(rng.low == 0) and np.all(rng.high == 255)
    if "velocity" in env.observation_space.spaces:  # no finite bound: see tasks.gym
        vel = env.observation_space["velocity"]
        assert np.all(vel.low == -np.inf) and np.all(vel.high == np.inf)
    obs, _ = env.reset(seed=0)
    for _ in range(3):
        assert all(v.dtype == np.float32 for v in obs.values())
        assert obs in env.observation_space
        obs, *_ = env.step(env.action_space.sample())
    env.close()


@pytest.mark.slow
@pytest.mark.parametrize("env_id", [tasks.gym.env_id(name) for name in ("two_wheel", "floating")])
def test_async_vector_env_with_spawned_workers(env_id):
    """Workers started with spawn (as SB3's SubprocVecEnv does) import nothing of ours
    but what unpickling the environment's maker brings. One id per drive: every id is
    made by the same maker (the other ids step in this process, above)."""
    envs = gymnasium.make_vec(env_id, num_envs=2, vectorization_mode="async",
                              vector_kwargs={"context": "spawn"})
    try:
        obs, info = envs.reset(seed=0)
        for _ in range(3):
            obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
        assert obs["range"].shape[0] == 2 and obs["range"].dtype == np.float32
        assert reward.shape == (2,) and info["pose"].shape == (2, 3)
        assert not np.array_equal(info["pose"][0], info["pose"][1])  # two seeds, two paths
    finally:
        envs.close()


_NO_GL = r"""
import re
import gymnasium

def gl():
    return sorted({line.split()[-1].rsplit("/", 1)[-1] for line in open("/proc/self/maps")
                   if re.search(r"lib(EGL|OSMesa|GL)", line)})

for env_id in IDS:  # the module's own form of the id: gymnasium imports tasks.gym first
    env = gymnasium.make("tasks.gym:" + env_id)
    env.reset(seed=0)
    for _ in range(3):
        env.step(env.action_space.sample())
    env.close()
print("before", gl())
env = gymnasium.make("tasks.gym:EBRL/TwoWheel-v1", render_mode="rgb_array")
env.reset(seed=0)
assert env.render().std() > 0
print("after", gl())
env.close()
"""


@pytest.mark.slow
@pytest.mark.parametrize("backend", [None, "egl"])
def test_a_process_that_does_not_render_loads_no_opengl_library(backend):
    """Not even with MUJOCO_GL=egl set; the first frame loads it."""
    import ctypes.util
    import os
    import pathlib
    import subprocess
    import sys
    if backend is not None and not ctypes.util.find_library("EGL"):
        pytest.skip("libEGL is not installed")
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    if backend is not None:
        env["MUJOCO_GL"] = backend
    proc = subprocess.run([sys.executable, "-c", f"IDS = {IDS!r}\n" + _NO_GL], env=env,
                          cwd=pathlib.Path(__file__).resolve().parents[1], capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    before, after = proc.stdout.splitlines()[-2:]
    assert before == "before []", proc.stdout
    assert "libEGL" in after or "libOSMesa" in after, proc.stdout
