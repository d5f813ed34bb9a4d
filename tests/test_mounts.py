"""Mounts (tasks/mount/): third-party robot files entered unchanged, the room scaled to
the robot, in real MuJoCo, from the real installed packages, through the real command line."""
import hashlib
import importlib.resources
import math

import numpy as np
import pytest

import models
import tasks
from experiments.running import execution
from helpers import ROOT, ebrl, ebrl_here
from tasks import mount, navigation
from tasks.realisations.wheel_motors import WheelMotorsPhysics

MOUNTS = ROOT / "models" / "mounts"
#: Each shipped mount's robot file: where the installed package (or the vendored copy) holds it.
SOURCES = {
    "point": lambda: importlib.resources.files("gymnasium") / "envs/mujoco/assets/point.xml",
    "point_mass": lambda: importlib.resources.files("dm_control") / "suite/point_mass.xml",
    "car": lambda: ROOT / "models" / "vendor" / "mujoco_car" / "car.xml",
    "ant": lambda: importlib.resources.files("dm_control") / "third_party/ant/ant.xml",
    "quadruped": lambda: importlib.resources.files("dm_control") / "suite/quadruped.xml",
    "gym_ant": lambda: importlib.resources.files("gymnasium") / "envs/mujoco/assets/ant.xml",
}
#: model/car/car.xml's git blob in google-deepmind/mujoco (last changed upstream in a276c49).
CAR_BLOB = "0ab791f05ad6b022e573a7bb13af6aa0efdddc1d"

CONTRACT_MOUNT = """
file = "{file}"
drive = "two_wheel"
base = "base"
[bumper]
geom = "hull"
[beams]
sensors = ["range_0", "range_1", "range_2", "range_3", "range_4", "range_5", "range_6"]
[action]
kind = "actuators"
forward = "forward"
turn = "turn"
grip = "grip"
"""


def _sha256(path):
    return hashlib.sha256(pathlib_bytes(path)).hexdigest()


def pathlib_bytes(path):
    with open(path, "rb") as f:
        return f.read()


@pytest.mark.parametrize("name", sorted(SOURCES))
def test_each_shipped_mount_runs_its_file_unchanged_from_where_it_lies(name):
    """The entry's robot file is the installed package's (or the vendored copy), byte for
    byte before and after a load, step and frame; nothing is copied."""
    source = pathlib_path(SOURCES[name]())
    entry = tasks.resolve(name)
    assert entry.model.resolve() == source.resolve()
    before = _sha256(source)
    env = tasks.load(name, seed=0)
    try:
        step = env.reset()
        dim = env.action_spec().shape[0]
        for _ in range(3):
            step = env.step(np.zeros(dim))
        assert np.isfinite(env.physics.robot_pose()).all()
        assert len(step.observation["range"]) == {"two_wheel": 7, "floating": 8}[entry.drive]
        frame = env.physics.render(48, 64, camera_id="top")
        assert frame.shape == (48, 64, 3) and frame.std() > 0
    finally:
        env.close()
    assert _sha256(source) == before
    if name == "car":
        data = pathlib_bytes(source)
        blob = hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()
        assert blob == CAR_BLOB
        assert (source.parent / "LICENSE").read_text().lstrip().startswith("Apache License")


def pathlib_path(resource):
    import pathlib
    return pathlib.Path(str(resource))


def test_a_mount_of_our_own_two_wheel_file_runs_bit_for_bit_as_the_registered_robot(tmp_path):
    """Full protocol runs (both conditions, 1,500 steps) of a mount of models/two_wheel.xml
    with the registered robot's own body readings (its radius, blocked move and leftover
    turn, tasks.robots) equal the registered robot's trace and trial ends, bit for bit."""
    path = tmp_path / "mine.toml"
    own = tasks.ROBOTS["two_wheel"].task_readings()
    assert {"radius", "blocked_move", "leftover_turn"} <= set(own)
    path.write_text(CONTRACT_MOUNT.format(file=ROOT / "models" / "two_wheel.xml")
                    + "[readings]\n" + "".join(f"{k} = {v!r}\n" for k, v in own.items()))
    for condition in ("random", "avoidance"):
        mine = execution.execute(execution.RunSpec(str(path), condition, 3, 1500))
        ours = execution.execute(execution.RunSpec("two_wheel", condition, 3, 1500))
        assert np.array_equal(mine["trace"], ours["trace"]), condition
        assert np.array_equal(mine["trial_ends"], ours["trial_ends"])
    a, b = tasks.compile_robot(tasks.resolve(str(path)))[0], tasks.compile_robot(tasks.ROBOTS["two_wheel"])[0]
    assert a.nbody == b.nbody and a.nu == b.nu and np.array_equal(a.geom_size, b.geom_size)


def test_the_scaled_room_against_hand_computed_corners(tmp_path):
    """At 0.4 m per unit (the ant's) the room is the paper's in units and four times its
    metres: the field 36 m x 24 m, the west block's corners at (8, 8) and (12, 20) m, the
    start at (2, 14) m, the goal square's corner at (32, 20) m."""
    path = tmp_path / "big_point.toml"
    path.write_text((MOUNTS / "point.toml").read_text().replace(
        "unit = 0.3333333333333333", "unit = 0.4").replace(
        '"gymnasium:', f'"{pathlib_path(SOURCES["point"]()).parent}/').replace(
        'envs/mujoco/assets/point.xml"', 'point.xml"'))
    entry = tasks.resolve(str(path))
    assert entry.unit == 0.4
    model, _ = tasks.compile_robot(entry)
    assert models.unit_of(model) == 0.4
    field, obstacles, goal, start = models.room_layout(model)
    paper = models.room_layout(models.room_model())
    assert np.allclose(field, (0, 90, 0, 60)) and np.allclose(field, paper[0])
    assert np.allclose(sorted(obstacles), sorted(paper[1]))
    assert np.allclose(goal, (80, 90, 50, 60)) and np.allclose(start[:2], (5, 35))
    west = model.geom("block_west")
    assert np.allclose(west.pos[:2] - west.size[:2], (8.0, 8.0))
    assert np.allclose(west.pos[:2] + west.size[:2], (12.0, 20.0))
    assert np.allclose(model.geom("floor").size[:2], (18.0, 12.0))
    assert np.allclose(model.site("start").pos[:2], (2.0, 14.0))
    goal_site = model.site("goal")
    assert np.allclose(goal_site.pos[:2] - goal_site.size[:2], (32.0, 20.0))
    # a beam reads in paper units in a scaled room: the point (1/3 m per unit) 10 units
    # west of the east block (x = 70), facing it, reads 10 less its 1.5 radius
    env = tasks.load("point", sensor_noise=0.0, start_jitter=False, seed=0)
    try:
        env.reset()
        physics = env.physics
        physics.set_robot_pose(60.0, 45.0, 0.0)
        assert math.isclose(physics.ranges()[3], 10.0 - physics.robot_radius, rel_tol=1e-9)
        assert math.isclose(physics.robot_radius, 1.5)
    finally:
        env.close()


#: The car's mount with its file named by a placeholder (the test's tmp_path is elsewhere).
CAR = (MOUNTS / "car.toml").read_text().replace('"../vendor/mujoco_car/car.xml"', '"{{car}}"')

BAD = [
    ("", "file: missing (required)"),
    ('file = "x.xml"\ndrive = "two_wheel"\nbase = "b"', "file: no robot file at"),
    ('file = "nopackage_xyz:a/b.xml"\ndrive = "two_wheel"\nbase = "b"',
     "file: package 'nopackage_xyz' is not installed"),
    ('file = "{pt}"\ndrive = "walking"\nbase = "torso"', "drive: unknown drive 'walking'"),
    ('file = "{pt}"\ndrive = "two_wheel"\nbase = "torso"\ncolour = 1', "colour: unknown key"),
    ('file = "{pt}"\ndrive = "two_wheel"\nbase = "torso"\n[bumper]\ngeom = "pointbody"\n'
     '[beams]\nheight = 0.5\n[action]\nkind = "thrusters"',
     "action.kind: the two_wheel drive takes one of"),
    ('file = "{pt}"\ndrive = "two_wheel"\nbase = "torso"\n[bumper]\ngeom = "pointbody"\n'
     '[beams]\nsensors = ["a", "b"]\n[action]\nkind = "servos"',
     "beams.sensors: the two_wheel drive needs 7 rangefinders, got 2"),
    ('file = "{pt}"\ndrive = "two_wheel"\nbase = "body"\n[bumper]\ngeom = "pointbody"\n'
     '[beams]\nheight = 0.5\n[action]\nkind = "servos"', "base: no body named 'body'"),
    ('file = "{pt}"\ndrive = "two_wheel"\nbase = "torso"\n[bumper]\ngeom = "hull"\n'
     '[beams]\nheight = 0.5\n[action]\nkind = "servos"', "bumper.geom: no geom named 'hull'"),
    ('file = "{pt}"\ndrive = "two_wheel"\nbase = "torso"\n[bumper]\ngeom = "pointbody"\n'
     '[beams]\nheight = 0.5\n[action]\nkind = "actuators"\nforward = "go"\nturn = "rot"',
     "action.forward: no actuator named 'go'"),
    ('file = "{pt}"\ndrive = "two_wheel"\nbase = "torso"\njoints = "free"\n[bumper]\n'
     'geom = "pointbody"\n[beams]\nheight = 0.5\n[action]\nkind = "wheels"\nleft = "a"\nright = "b"',
     "joints: body 'torso' has joints of its own"),
    ('file = "{pt}"\ndrive = "two_wheel"\nbase = "torso"\n[bumper]\nradius = 0.2\n'
     '[beams]\nheight = 0.5\n[action]\nkind = "servos"', "bumper: missing"),
    ('file = "{pt}"\ndrive = "floating"\nbase = "torso"\n[bumper]\ngeom = "pointbody"\n'
     '[beams]\nheight = 0.5\n[action]\nkind = "wheels"', "action.kind: the floating drive takes one of"),
    (CAR.replace('"turn"]', '"steer"]'), "action.motors: no actuator named 'steer' in"),
    (CAR.replace('left = "left"', 'left = "left_hinge"'), "action.left: no joint named 'left_hinge' in"),
    (CAR.replace('motors = ["forward", "turn"]\n', ""), "action.motors: missing"),
    (CAR.replace('motors = ["forward", "turn"]', 'motors = ["forward"]'),
     "action.motors: needs two or more different motors"),
    (CAR.replace("kp = 0.2\n", ""), "action.kp: missing"),
    (CAR.replace('drop = ["world", "lights"]', 'drop = ["world", "actuators"]'),
     "drop: wheel_motors turn the wheels through the file's motors"),
    (CAR.replace('joints = "file"', 'joints = "planar"'), "joints: wheel_motors roll the file's wheels"),
    ((MOUNTS / "ant.toml").read_text().replace('lift = "back_left_ankle"\n', "").replace(
        '"dm_control:', '"{{ant}}').replace("third_party/ant/ant.xml", ""),
     "action.legs[3].lift: missing: the file's joint(s) for it"),
    ((MOUNTS / "ant.toml").read_text().replace("frequency = 1.0", "speed = 1.0").replace(
        '"dm_control:', '"{{ant}}').replace("third_party/ant/ant.xml", ""),
     "action.gait.speed: unknown key"),
]


def test_each_action_kind_is_one_registered_class_and_a_mount_is_named_records():
    """The drives take the kinds in their registration order (the errors list them so);
    the shipped mounts parse to named records, by kind."""
    assert mount.ACTIONS == {"two_wheel": ("servos", "actuators", "wheels", "wheel_motors",
                                           "joint_motors", "gait"),
                             "floating": ("thrusters", "actuators")}
    for name, kind in mount.KINDS.items():
        assert kind.name == name and issubclass(kind, mount.Action)
    car = mount.parse(MOUNTS / "car.toml")
    assert car.action == mount.KINDS["wheel_motors"](left="left", right="right",
                                                     motors=("forward", "turn"), kp=0.2, kv=0.01)
    assert car.bumper == mount.Bumper(shape="sphere", radius=0.12)
    assert car.beams == mount.Beams(height=0.04) and car.beams.added
    ant = mount.parse(MOUNTS / "ant.toml")
    assert ant.action.name == "gait" and len(ant.action.legs) == 4
    assert dict(ant.action.parameters) == {"frequency": 1.0, "control_substeps": 1.0}
    point, point_mass = mount.parse(MOUNTS / "point.toml"), mount.parse(MOUNTS / "point_mass.toml")
    assert point.bumper == mount.Bumper(geom="pointbody") and point.action == mount.KINDS["servos"]()
    assert point_mass.action.name == "thrusters" and point_mass.drive == "floating"


@pytest.mark.parametrize("text, message", BAD)
def test_a_bad_mount_is_one_line_naming_the_field_and_the_file(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    point = pathlib_path(SOURCES["point"]())
    ant = pathlib_path(SOURCES["ant"]())
    car = pathlib_path(SOURCES["car"]())
    path.write_text(text.format(pt=point).replace("{ant}", str(ant)).replace("{car}", str(car)))
    with pytest.raises(mount.MountError) as e:
        tasks.load(str(path)).close()
    line = str(e.value)
    assert "\n" not in line and line.startswith(str(path)) and message in line, line


def test_a_bad_mount_on_the_command_line_exits_2_before_any_work(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(f'file = "{pathlib_path(SOURCES["point"]())}"\ndrive = "two_wheel"\n'
                    'base = "torso"\n[bumper]\ngeom = "arrow"\n[beams]\nheight = 0.5\n'
                    '[action]\nkind = "servos"\n')
    out = tmp_path / "out"
    out.mkdir()
    proc = ebrl_here("run", "--robot", str(path), "--condition", "random", "--seeds", "0",
                "--steps", "10", "--out", str(out), "--no-progress")
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f"ebrl: error: {path}: bumper.geom: no geom named 'arrow' in {pathlib_path(SOURCES['point']())}"]
    assert not any(out.iterdir())


def test_a_run_of_a_mount_file_of_its_own_name_is_reported(tmp_path):
    """A mount file outside models/mounts, named as no shipped robot: its runs and their
    report (the optimal-path yardstick finds the robot by the file, not by its name)."""
    path = tmp_path / "my_point.toml"
    text = tasks.robots.MOUNTS["point"].read_text()
    path.write_text(text.replace('name = "point"', 'name = "my_point"', 1))
    assert 'name = "my_point"' in path.read_text()
    out = tmp_path / "out"
    proc = ebrl("run", "--robot", str(path), "--condition", "avoidance", "--seeds", "0",
                "--steps", "300", "--out", str(out), "--no-progress")
    assert proc.returncode == 0, proc.stderr
    assert "| my_point | avoidance |" in (out / "REPORT.md").read_text()


def test_mounted_planar_robots_do_what_their_drive_promises():
    """`ebrl check`'s accuracy for the point (two-wheel servos added on its own joints) and
    the point mass (thrusters on its replaced slides): within the paper's 5%."""
    from experiments.checks import robotcheck
    for name in ("point", "point_mass"):
        errors, limits = robotcheck.accuracy(name, 100)
        for key, e in errors.items():
            assert e.max() <= limits[key], (name, key, e.max())


def test_the_fused_loop_takes_every_shipped_mount():
    """Every drive is compiled (tasks.kernels): the gait, the car's motors
    (WheelMotorsPhysics), the point's servos, the point mass's thrusters."""
    from experiments.running import fused
    for name, supported in ((name, True) for name in tasks.MOUNTS):
        env = tasks.load(name, seed=0)
        try:
            agent = execution.make_agent(execution.RunSpec(name, "avoidance", 0, 10), env)
            assert fused.Loop.supports(env, agent) is supported, name
        finally:
            env.close()


@pytest.mark.parametrize("ant", ["ant", "gym_ant"])
def test_the_ant_walks_the_two_wheel_actions_within_its_stated_limits(ant):
    """The gait drive (tasks/realisations/gait.py) over 60 random free-space actions: the turn and the
    move errors within the limits the ant's mount states, and no fall in 200 random
    actions that ram the walls; dm_control's Ant, and Gymnasium's from its mount's rest
    (its init_qpos: the file's qpos0 has its ankles outside their ranges)."""
    from experiments.checks import robotcheck
    errors, limits = robotcheck.accuracy(ant, 60, seed=1)
    assert limits == {"turn": 0.08, "move": 0.12}
    for key, e in errors.items():
        assert e.max() <= limits[key], (key, e.max())
    assert np.median(errors["turn"]) < 0.03 and np.median(errors["move"]) < 0.06
    r = robotcheck.fuzz(ant, 200, seed=3)
    assert r["falls"] == 0 and r["nan_steps"] == 0 and r["warnings"] == 0


@pytest.mark.parametrize("leftover_turn,way", [("commanded", -1.0), ("away", 1.0)])
def test_the_gait_turns_a_blocked_moves_rest_the_way_its_reading_says(leftover_turn, way):
    """a = 0 into the east wall with the south wall close on the right: "commanded" turns
    the rest clockwise (a = 0's fixed way), "away" counter-clockwise, away from the nearer
    (right) side, as tasks.two_wheel does; about 1 rad per 2 units of the move's rest."""
    env = tasks.load("ant", seed=0, sensor_noise=0.0, action_noise=0.0, start_jitter=False,
                     leftover_turn=leftover_turn)
    try:
        env.reset()
        r = env.physics.robot_radius
        env.physics.set_robot_pose(90.0 - r - 0.4, r + 0.8, 0.0)
        env.step([0.0])
        _, _, heading = env.physics.robot_pose()
        assert way * heading > 0.3, heading
    finally:
        env.close()


@pytest.mark.parametrize("robot", ["ant", "quadruped"])
def test_the_gait_judges_a_fall_at_a_phases_end(robot):
    """Dropped from 0.3 units above its rest height rolled 40 degrees (past max_tilt, 30,
    from the first tick), the robot lands on its legs and the step ends: a tilt within a
    phase is no fall. Dropped on its back, the phase ends at 180 degrees: a PhysicsError."""
    from dm_control.rl import control
    env = tasks.load(robot, seed=0, sensor_noise=0.0, action_noise=0.0, start_jitter=False)
    try:
        assert env.physics.gait["max_tilt"] == 30.0
        for roll, falls in ((40.0, False), (180.0, True)):
            env.reset()
            physics = env.physics
            half = math.radians(roll) / 2
            physics.data.qpos[3:7] = (math.cos(half), math.sin(half), 0.0, 0.0)
            physics.data.qpos[2] += 0.3
            physics.forward()
            assert math.degrees(physics.tilt()) == pytest.approx(roll)
            if falls:
                with pytest.raises(control.PhysicsError, match="tipped over"):
                    env.step([0.5])
            else:
                env.step([0.5])
                assert math.degrees(physics.tilt()) < 5.0
    finally:
        env.close()


def test_the_car_runs_through_its_own_motors_and_adds_no_actuator():
    """The compiled car's actuators and tendons are exactly its file's (its motors
    "forward" and "turn" on its tendons), driven by WheelMotorsPhysics, whose measured
    force per unit control on the wheels is the tendons' coefficients; no compiled step
    drives it."""
    import mujoco
    own = mujoco.MjModel.from_xml_path(str(pathlib_path(SOURCES["car"]())))
    env = tasks.load("car", seed=0)
    try:
        m = env.physics.model.ptr
        names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, i) for i in range(m.nu)]
        assert names == [models.PREFIX + mujoco.mj_id2name(own, mujoco.mjtObj.mjOBJ_ACTUATOR, i)
                         for i in range(own.nu)] == ["robot/forward", "robot/turn"]
        assert m.ntendon == own.ntendon == 2
        for field in ("actuator_trntype", "actuator_gear", "actuator_ctrlrange", "actuator_gainprm",
                      "actuator_biasprm", "tendon_adr", "wrap_prm"):
            assert np.array_equal(getattr(m, field), getattr(own, field)), field
        physics = env.physics
        assert isinstance(physics, WheelMotorsPhysics) and env.steps_compiled
        assert np.allclose(physics.motor_forces, [[0.5, 0.5], [-0.5, 0.5]], atol=1e-12)
        assert (physics.kp, physics.kv) == (0.2, 0.01)
    finally:
        env.close()


def test_the_motor_controls_by_hand():
    """tau = M^T c solved for c: two motors M = [[1, 1], [-1, 2]] and tau = (1, 4) give
    c0 - c1 = 1, c0 + 2 c1 = 4, so c = (2, 1); clipped to [-1.5, 1.5] x [-1, 0.5]:
    (1.5, 0.5). Three motors [[1, 0], [0, 1], [1, 1]] and tau = (1, 2): the least-norm c
    is M (M^T M)^-1 tau = M (0, 1) = (0, 1, 1) (the exact (1, 2, 0) has a larger norm)."""
    from tasks.kernels.plan import gram, motor_controls
    c = np.zeros(2)
    inf = np.full(2, np.inf)
    m2 = np.array([[1.0, 1.0], [-1.0, 2.0]])
    motor_controls(m2, gram(m2), np.array([1.0, 4.0]), -inf, inf, c)
    assert np.allclose(c, (2.0, 1.0), rtol=0, atol=1e-12)
    motor_controls(m2, gram(m2), np.array([1.0, 4.0]),
                   np.array([-1.5, -1.0]), np.array([1.5, 0.5]), c)
    assert np.allclose(c, (1.5, 0.5), rtol=0, atol=1e-12)
    c3 = np.zeros(3)
    m3 = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    motor_controls(m3, gram(m3), np.array([1.0, 2.0]),
                   np.full(3, -np.inf), np.full(3, np.inf), c3)
    assert np.allclose(c3, (0.0, 1.0, 1.0), rtol=0, atol=1e-12)


def test_the_car_does_what_its_mount_states():
    """`ebrl check`'s accuracy for the car over 100 free-space actions, within its
    mount's limits (turn 0.2 rad, move 0.8 units), and 100 wall-ramming actions
    without a warning, a NaN or a sink."""
    from experiments.checks import robotcheck
    errors, limits = robotcheck.accuracy("car", 100)
    assert limits == {"turn": 0.2, "move": 0.8}
    for key, e in errors.items():
        assert e.max() <= limits[key], (key, e.max())
    r = robotcheck.fuzz("car", 100, seed=1)
    assert r["nan_steps"] == 0 and r["warnings"] == 0
    assert r["worst_clearance"] > -r["sink_limit"]
    assert r["max_tilt_degrees"] < navigation.MAX_TILT_DEGREES


def test_a_refused_move_of_the_car_returns_its_wheel_targets_too():
    """blocked_move "refuse" against a wall: the state after the turn is restored, the
    wheels' targets with it, so the leftover turn turns the car where it stood (its frame
    moves along the turn's arc, 0.875 units about the axle) instead of driving the
    wheels on to the blocked move's targets, into the wall."""
    env = tasks.load("car", seed=0, sensor_noise=0.0, action_noise=0.0, start_jitter=False,
                     blocked_move="refuse")
    try:
        env.reset()
        physics = env.physics
        physics.set_robot_pose(2.5, 30.0, math.pi)   # facing the west wall, 1 unit clear
        x0, y0, _ = physics.robot_pose()
        substeps = physics.substeps
        env.step([0.0])
        x1, y1, _ = physics.robot_pose()
        # the turn and the leftover turn (100 substeps each), the move ended at the touch,
        # short of its 200
        assert 200 < physics.substeps - substeps < 400
        assert math.hypot(x1 - x0, y1 - y0) < 2 * 0.875 and x1 > x0 - 0.1
    finally:
        env.close()
