"""Mounts (tasks/mount.py): third-party robot files entered unchanged, the room scaled to
the robot, in real MuJoCo, from the real installed packages, through the real command line."""
import hashlib
import importlib.resources
import math

import numpy as np
import pytest

import models
import tasks
from experiments.running import protocol
from helpers import ROOT, ebrl
from tasks import mount, navigation

MOUNTS = ROOT / "models" / "mounts"
#: Each shipped mount's robot file: where the installed package (or the vendored copy) holds it.
SOURCES = {
    "point": lambda: importlib.resources.files("gymnasium") / "envs/mujoco/assets/point.xml",
    "point_mass": lambda: importlib.resources.files("dm_control") / "suite/point_mass.xml",
    "car": lambda: ROOT / "models" / "vendor" / "mujoco_car" / "car.xml",
    "ant": lambda: importlib.resources.files("dm_control") / "third_party/ant/ant.xml",
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
    equal the registered robot's trace and trial ends, bit for bit."""
    path = tmp_path / "mine.toml"
    path.write_text(CONTRACT_MOUNT.format(file=ROOT / "models" / "two_wheel.xml"))
    for condition in ("random", "avoidance"):
        mine = protocol.execute(protocol.RunSpec(str(path), condition, 3, 1500))
        ours = protocol.execute(protocol.RunSpec("two_wheel", condition, 3, 1500))
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
     '[beams]\nheight = 0.5\n[action]\nkind = "servos"', "bumper: missing"),    ('file = "{pt}"\ndrive = "floating"\nbase = "torso"\n[bumper]\ngeom = "pointbody"\n'
     '[beams]\nheight = 0.5\n[action]\nkind = "wheels"', "action.kind: the floating drive takes one of"),
    ((MOUNTS / "ant.toml").read_text().replace('hip_3 = "back_left_hip"\n', "").replace(
        '"dm_control:', '"{{ant}}').replace("third_party/ant/ant.xml", ""),
     "action.hip_3: missing: the file's motor for it"),
    ((MOUNTS / "ant.toml").read_text().replace("frequency = 1.0", "speed = 1.0").replace(
        '"dm_control:', '"{{ant}}').replace("third_party/ant/ant.xml", ""),
     "action.gait.speed: unknown key"),
]


@pytest.mark.parametrize("text, message", BAD)
def test_a_bad_mount_is_one_line_naming_the_field_and_the_file(tmp_path, text, message):
    path = tmp_path / "bad.toml"
    point = pathlib_path(SOURCES["point"]())
    ant = pathlib_path(SOURCES["ant"]())
    path.write_text(text.format(pt=point).replace("{ant}", str(ant)))
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
    proc = ebrl("run", "--robot", str(path), "--condition", "random", "--seeds", "0",
                "--steps", "10", "--out", str(out), "--no-progress")
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == [
        f"ebrl: error: {path}: bumper.geom: no geom named 'arrow' in {pathlib_path(SOURCES['point']())}"]
    assert not any(out.iterdir())


def test_mounted_planar_robots_do_what_their_drive_promises():
    """`ebrl check`'s accuracy for the point (two-wheel servos added on its own joints) and
    the point mass (thrusters on its replaced slides): within the paper's 5%."""
    from experiments.checks import robotcheck
    for name in ("point", "point_mass"):
        errors, limits = robotcheck.accuracy(name, 100)
        for key, e in errors.items():
            assert e.max() <= limits[key], (name, key, e.max())


def test_the_fused_loop_refuses_the_gait_drive_and_takes_a_mounted_two_wheel_robot():
    from experiments.running import fused
    for name, supported in (("ant", False), ("point", True)):
        env = tasks.load(name, seed=0)
        try:
            agent = protocol.make_agent(protocol.RunSpec(name, "avoidance", 0, 10), env)
            assert fused.Loop.supports(env, agent) is supported, name
        finally:
            env.close()


def test_the_ant_walks_the_two_wheel_actions_within_its_stated_limits():
    """The gait drive (tasks/gait.py) over 60 random free-space actions: the turn and the
    move errors within the limits the ant's mount states, and no fall in 200 random
    actions that ram the walls."""
    from experiments.checks import robotcheck
    errors, limits = robotcheck.accuracy("ant", 60, seed=1)
    assert limits == {"turn": 0.08, "move": 0.12}
    for key, e in errors.items():
        assert e.max() <= limits[key], (key, e.max())
    assert np.median(errors["turn"]) < 0.03 and np.median(errors["move"]) < 0.06
    r = robotcheck.fuzz("ant", 200, seed=3)
    assert r["falls"] == 0 and r["nan_steps"] == 0 and r["warnings"] == 0


def test_a_fall_of_the_gait_is_a_physics_error():
    from dm_control.rl import control
    env = tasks.load("ant", seed=0)
    try:
        env.reset()
        physics = env.physics
        physics.data.qpos[3:7] = (math.cos(0.4), math.sin(0.4), 0.0, 0.0)  # rolled 46 degrees
        physics.data.qpos[2] = 1.5
        physics.forward()
        with pytest.raises(control.PhysicsError, match="tipped over"):
            env.step([0.0])
    finally:
        env.close()


def test_an_installed_copy_finds_the_shipped_mounts_and_behaviours_by_name(tmp_path):
    """A non-editable install (pip install --no-deps --target, from a copy of the tracked
    files) holds the mounts, the vendored car and the paper's behaviour files as package
    data; from elsewhere, that copy loads the car and finds paper_eq8 by name."""
    import shutil
    import subprocess
    import sys
    source = tmp_path / "source"
    files = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard"],
                           cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    for name in files:
        if (ROOT / name).is_file():
            (source / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / name, source / name)
    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target",
                    str(target), str(source)], check=True, capture_output=True)
    code = ("import tasks, ebrl.behaviour as b\n"
            "assert tasks.__file__.startswith(%r)\n"
            "assert sorted(tasks.MOUNTS) == ['ant', 'car', 'point', 'point_mass']\n"
            "assert tasks.resolve('car').model.is_relative_to(%r)\n"
            "env = tasks.load('car'); env.reset(); env.step([0.0]); env.close()\n"
            "print(b.load('paper_eq8').behaviour, b.load('behaviours/paper_eq9-10.json').behaviour)\n"
            % (str(target), str(target)))
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, env={"PYTHONPATH": str(target), "PATH": "/usr/bin:/bin",
                                          "HOME": str(tmp_path)})
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["eq8", "eq9-10"]
