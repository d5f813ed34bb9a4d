"""The robot registry, the naming contract and the 3D robots, in real MuJoCo and through
the real command line."""
import dataclasses
import math
import re

import mujoco
import numpy as np
import pytest

import tasks
from experiments.running import execution, runner
from experiments.checks import robotcheck
from helpers import ROOT, ebrl_here
from tasks import navigation
from tasks.protocols import PROTOCOL_VERSION

MODELS = ROOT / "models"


@pytest.mark.slow
def test_every_command_takes_its_robots_from_the_registry():
    listed = ebrl_here("robots")
    assert listed.returncode == 0
    table, readings, mounted = listed.stdout.split("\n\n")
    assert [line.split()[0] for line in mounted.splitlines()[1:]] == list(tasks.MOUNTS)
    names = [line.split()[0] for line in table.splitlines()[1:]]
    assert names == list(tasks.ROBOTS) and {"diff_drive", "hovercraft"} <= set(names)
    assert [line.split()[0] for line in readings.splitlines()[1:]] == names
    assert "bump=stop" in readings and "leftover_turn=away" in readings
    for command in (["run"], ["sweep"], ["bench"], ["check"],
                    ["render", "--condition", "random", "--seed", "0", "--out", "x.mp4"]):
        proc = ebrl_here(*command, "--robot", "tricycle")
        assert proc.returncode == 2 and "tricycle" in proc.stderr, (command, proc.stderr)
        if command[0] != "render":
            assert "valid: " + ", ".join(tasks.ROBOTS) in proc.stderr, proc.stderr
    budgets = {s.robot: s.steps for s in runner.plan(tuple(tasks.ROBOTS), ["random"], [0])}
    assert budgets == {name: r.budget for name, r in tasks.ROBOTS.items()}


@pytest.mark.parametrize("robot", list(tasks.ROBOTS))
def test_pose_and_velocity_read_outs_for_slide_and_free_joints(robot):
    env = tasks.load(robot, seed=0, start_jitter=False, sensor_noise=0.0, action_noise=0.0)
    env.reset()
    physics = env.physics
    free = physics.free_dof is not None
    assert free == (robot in ("diff_drive", "hovercraft"))
    heading = 0.7 if "yaw" in physics.base_joints or free else 0.0
    if robot == "hovercraft":
        heading = 0.0  # its gyro holds the heading at 0
    physics.set_robot_pose(41.5, 33.25, heading)
    assert physics.robot_pose() == pytest.approx((41.5, 33.25, heading), abs=1e-9)
    assert physics.tilt() == pytest.approx(0.0, abs=1e-9)
    # The body velocity, in units per agent step, against the joints' own velocity.
    v = np.array([0.3, -0.2])  # m/s
    if free:
        physics.data.qvel[physics.free_dof: physics.free_dof + 2] = v  # free: x, y first
    else:
        physics.data.qvel[[physics.model.jnt_dofadr[physics.base_joints[k]] for k in "xy"]] = v
    physics.forward()
    np.testing.assert_allclose(physics.robot_velocity(), v * physics.step_seconds / 0.1,
                               rtol=1e-12)
    env.close()


def test_sensors_once_per_step_read_as_sensors_every_substep():
    """mjDSBL_SENSOR + one mj_sensorPos per agent step gives the observations of
    MuJoCo's every-substep sensor stage, bit for bit."""
    for robot in tasks.ROBOTS:
        once, every = tasks.load(robot, seed=1), tasks.load(robot, seed=1)
        every.physics.model.ptr.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
        once.reset(), every.reset()
        rng = np.random.default_rng(0)
        for _ in range(40):
            a = rng.uniform(-1, 1, once.action_spec().shape)
            got, want = once.step(a).observation, every.step(a).observation
            assert all(np.array_equal(got[k], want[k]) for k in want), robot
        assert once.physics.model.ptr.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
        once.close(), every.close()


@pytest.mark.slow
def test_planar_trajectories_unchanged_by_the_registry():
    """The first 3,000 steps of seeds 0-1, every paper robot and condition, as the full
    run behind RESULTS.md made them (tests/data/planar_traces_v<PROTOCOL_VERSION>.npz, made by
    tests/data/make_golden.py at the protocol's code: a run's first steps are the same
    whatever its budget). Bit for bit on one kind of machine: numpy's BLAS and math kernels
    round the last bit per CPU (same code, same seeds), so on another kind a run may part
    from these by a hundredth of a unit after some thousands of steps. Made again, or
    checked, by tests/data/make_golden.py."""
    with np.load(ROOT / "tests" / "data" / f"planar_traces_v{PROTOCOL_VERSION}.npz") as z:
        expected = {k: z[k] for k in z.files}
    for key, trace in expected.items():
        robot, condition, seed = key.split("__")
        spec = execution.RunSpec(robot, condition, int(seed[5:]), len(trace) - 1)
        got = execution.execute(spec)["trace"]
        assert np.array_equal(got, trace), key


def _copy_robot(tmp_path, name, edit=None):
    text = (MODELS / f"{name}.xml").read_text()
    if edit:
        text = edit(text)
    path = tmp_path / "robots" / f"my_{name}.xml"
    path.parent.mkdir(exist_ok=True)
    path.write_text(text)
    return path


@pytest.mark.slow
def test_a_robot_file_outside_the_package_loads_and_runs(tmp_path):
    path = _copy_robot(tmp_path, "two_wheel")
    # the registered robot's body readings (its radius, blocked move and leftover turn)
    # are its entry's, not its file's or its drive's
    ours = tasks.load(str(path), drive="two_wheel", seed=4)
    drive = dict(tasks.protocols.ADOPTED.drives["two_wheel"])
    theirs = tasks.load("two_wheel", seed=4, radius=None, blocked_move="stop",
                        leftover_turn=drive["leftover_turn"])
    ours.reset(), theirs.reset()
    for a in np.linspace(-1, 1, 25):
        assert ours.step([a]).observation["range"].tolist() == theirs.step([a]).observation["range"].tolist()
    assert ours.physics.robot_pose() == theirs.physics.robot_pose()
    ours.close(), theirs.close()
    out = tmp_path / "results"
    proc = ebrl_here("run", "--robot", path, "--drive", "two_wheel", "--condition", "avoidance",
                     "--seeds", "0", "--steps", "200", "--workers", "1", "--no-progress", "--out", out)
    assert proc.returncode == 0, proc.stderr
    assert (out / "my_two_wheel" / "avoidance" / "seed_000" / "run.json").is_file()
    assert "my_two_wheel" in (out / "REPORT.md").read_text()


@pytest.mark.parametrize("robot,drive,edit,missing", [
    ("two_wheel", "two_wheel", lambda t: re.sub(r"<sensor>.*</sensor>", "", t, flags=re.S),
     "no rangefinder sensors"),
    ("two_wheel", "two_wheel", lambda t: t.replace('name="base"', 'name="chassis"'),
     "no body named 'base'"),
    ("two_wheel", "two_wheel", lambda t: t.replace('name="hull"', 'name="bumper"'),
     "no geom named 'hull'"),
    ("two_wheel", "two_wheel", lambda t: t.replace('name="forward"', 'name="ahead"'),
     "needs actuators 'forward' and 'turn'"),
    ("floating", "floating", lambda t: t.replace('name="thrust_y"', 'name="jet"'),
     "needs actuators 'thrust_x' and 'thrust_y'"),
    ("two_wheel", "floating", None, "needs actuators 'thrust_x' and 'thrust_y'"),
    ("floating", "floating", lambda t: re.sub(r'<rangefinder name="range_7"[^>]*>', "", t),
     "needs 8 rangefinders"),
])
@pytest.mark.slow
def test_a_missing_part_is_one_line_naming_it(tmp_path, robot, drive, edit, missing):
    path = _copy_robot(tmp_path, robot, edit)
    with pytest.raises(navigation.ContractError, match=re.escape(missing)):
        tasks.load(str(path), drive=drive)
    out = tmp_path / "out"
    proc = ebrl_here("run", "--robot", path, "--drive", drive, "--out", out)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and missing in lines[0], proc.stderr
    assert str(path) in lines[0] and not out.exists()


@pytest.mark.parametrize("args,message", [
    (["--robot", "models/two_wheel.xml"], "needs a drive"),
    (["--robot", "no/such/robot.xml", "--drive", "two_wheel"], "no robot file"),
    (["--robot", "two_wheel", "--drive", "floating"], "has the two_wheel drive"),
])
@pytest.mark.slow
def test_robot_file_arguments_are_checked(tmp_path, args, message):
    proc = ebrl_here("run", *args, "--out", tmp_path / "out", cwd=ROOT)
    assert proc.returncode == 2 and message in proc.stderr and not (tmp_path / "out").exists()


@pytest.mark.parametrize("robot", ["diff_drive", "hovercraft"])
def test_3d_robot_free_space_actions_within_five_percent(robot):
    errors, limits = robotcheck.accuracy(robot, actions=60)
    for key, e in errors.items():
        assert e.max() <= limits[key], (key, e.max())


@pytest.mark.slow
@pytest.mark.parametrize("robot", ["diff_drive", "hovercraft"])
def test_3d_robot_random_action_fuzz(robot):
    """The fuzz of `ebrl check` with 1,500 actions (all 100,000: `ebrl check`)."""
    r = robotcheck.fuzz(robot, actions=1500, seed=2)
    assert r["worst_clearance"] > -r["sink_limit"]
    assert r["max_tilt_degrees"] < navigation.MAX_TILT_DEGREES
    assert r["nan_steps"] == 0 and r["warnings"] == 0


@pytest.mark.parametrize("robot", ["diff_drive", "hovercraft"])
def test_3d_robot_same_seed_same_trajectory(robot):
    runs = []
    for _ in range(2):
        env = tasks.load(robot, seed=11)
        env.reset()
        rng = np.random.default_rng(5)
        poses = []
        for _ in range(150):
            env.step(rng.uniform(-1, 1, env.action_spec().shape))
            poses.append(env.physics.robot_pose())
        env.close()
        runs.append(poses)
    assert runs[0] == runs[1]


def test_a_tipped_robot_raises():
    env = tasks.load("diff_drive", seed=0)
    env.reset()
    physics = env.physics
    q = physics.data.qpos
    q[3:7] = [math.cos(0.3), math.sin(0.3), 0.0, 0.0]  # rolled 34 degrees
    q[2] = 0.3
    physics.forward()
    from dm_control.rl import control
    with pytest.raises(control.PhysicsError, match="tipped over"):
        physics.step(1)
    env.close()


def test_room_layout_is_read_from_the_composed_model():
    import models
    env = tasks.load("diff_drive", seed=0)
    field, obstacles, goal, start = models.room_layout(env.physics.model)
    env.close()
    assert field == pytest.approx((0, 90, 0, 60)) and goal == pytest.approx((80, 90, 50, 60))
    np.testing.assert_allclose(sorted(obstacles), [(20, 30, 20, 50), (50, 60, 10, 20),
                                                   (70, 80, 30, 60)], atol=1e-9)
    assert start == pytest.approx((5, 35, 0))


def test_hovercraft_glides_and_a_bump_takes_most_of_its_speed_into_the_wall():
    env = tasks.load("hovercraft", seed=0, config=tasks.TaskConfig(), start_jitter=False,
                     sensor_noise=0.0, action_noise=0.0)
    env.reset()
    env.physics.set_robot_pose(40.0, 30.0)
    env.step([1.0, -0.5])
    for _ in range(10):  # coasts on its skids: the velocity stays, the craft stays level
        ts = env.step([0.0, 0.0])
    np.testing.assert_allclose(ts.observation["velocity"], [0.2, -0.1], rtol=1e-3)
    assert env.physics.tilt() < math.radians(0.1)
    env.physics.set_robot_pose(40.0, 3.0)
    env.step([0.0, -1.0]), env.step([0.0, -1.0])  # 0.4 units/step head-on into the south wall
    for _ in range(25):
        env.step([0.0, 0.0])
    vx, vy = env.physics.robot_velocity()
    assert 0.0 <= vy < 0.25 * 0.4 and abs(vx) < 1e-3
    env.close()


def test_a_drives_readings_reach_its_robots_runs_and_set_overrides_them():
    """Protocol 7's readings (tasks.protocols.ADOPTED: every robot's, a drive's, a robot's
    own on top) are each run's config; --set (a spec's overrides) changes any of them.
    Both drives share one learner and one fallback (ADOPTED.readings: LEARNER, FALLBACK)."""
    floating = dict(tasks.ROBOTS["floating"].readings)
    spec = execution.RunSpec("floating", "avoidance", 0, 10)
    agent, task = spec.agent_config(), spec.task_config()
    assert agent.policy_threshold == floating["policy_threshold"] == \
        dict(tasks.protocols.ADOPTED.readings)["policy_threshold"] > 0
    assert agent.initial_reliability == 1.0
    assert (agent.eq9_dead_zone, agent.random_in_avoidance, agent.random_demand) == \
        ("keep", "replace", "gaussian") == (floating["eq9_dead_zone"],
                                            *(dict(tasks.protocols.FALLBACK)[k] for k in
                                              ("random_in_avoidance", "random_demand")))
    assert (task.bump, task.radius, task.velocity_code) == ("stop", floating["radius"], "code")
    assert agent.memory_size == 4096 and task.sensor_noise == 0.05 * 255   # Table 1, 3.2
    # The hovercraft shares the drive's readings, not the planar puck's body.
    hover = execution.RunSpec("hovercraft", "avoidance", 0, 10)
    assert hover.agent_config() == agent
    assert hover.task_config().action_noise == task.action_noise == floating["action_noise"]
    assert (hover.task_config().bump, hover.task_config().radius) == ("grip", None)
    # The two-wheel drive: the same learner and fallback, the paper's 5% action noise;
    # diff_drive keeps its own body (no radius reading) and the drive's leftover turn.
    two = execution.RunSpec("diff_drive", "random", 0, 10)
    assert (two.agent_config().initial_reliability, two.agent_config().policy_threshold) == \
        (1.0, agent.policy_threshold)
    assert (two.agent_config().random_demand, two.agent_config().random_in_avoidance) == \
        (agent.random_demand, agent.random_in_avoidance)
    assert (two.task_config().leftover_turn, two.task_config().radius) == ("away", None)
    assert two.task_config().action_noise == 0.05
    # The planar two-wheel robot's own body (protocol 8): the file's radius, the blocked move
    # stopped at the touch (stated), the commanded leftover turn, over its drive's.
    planar = execution.RunSpec("two_wheel", "random", 0, 10).task_config()
    assert (planar.radius, planar.blocked_move, planar.leftover_turn) == \
        (1.5, "stop", "commanded")
    assert two.task_config().blocked_move == "stop"
    over = execution.RunSpec("floating", "avoidance", 0, 10,
                            (("bump", "grip"), ("policy_threshold", 0.1)))
    assert (over.task_config().bump, over.agent_config().policy_threshold) == ("grip", 0.1)
    assert over.parameters()["task"]["bump"] == "grip"
    env = tasks.load("floating", seed=0)
    assert env.task.config.bump == "stop"
    env.close()


def test_the_literal_protocol_lists_every_reading_once_and_reaches_the_run():
    """tasks.protocols.LITERAL names every reading of the registry once, with an allowed
    value; a spec under it carries them all in its configs, whatever the entry's own."""
    from experiments.running.execution import RunSpec
    from tasks import readings
    LITERAL = tasks.protocols.LITERAL.readings
    names = [name for name, _ in LITERAL]
    assert sorted(names) == sorted(readings.READING_BY_NAME) and len(set(names)) == len(names)
    for name, value in LITERAL:
        readings.READING_BY_NAME[name].check(value)
    for robot in ("two_wheel", "floating"):
        spec = RunSpec(robot, "avoidance", 0, 100, protocol="literal")
        configs = dataclasses.asdict(spec.agent_config()) | dataclasses.asdict(spec.task_config())
        assert {name: configs[name] for name in names} == dict(LITERAL)
        assert spec.parameters()["protocol"] == "literal"
        assert "protocol" not in RunSpec(robot, "avoidance", 0, 100).parameters()
