"""Any robot file, unchanged (issue 49): actuators read by what they do, the file's own
frame and signs honoured (a rotated or tilted base, a forward axis, a hinge about -z),
never a run outside the room, a rest pose. On small robot files written here."""
import math
import re

import mujoco
import pytest
from dm_control.rl import control

import tasks
from experiments.running import execution, results, runner
import test_joints
from helpers import ROOT, ebrl_here
from tasks import actuators, mount, placement

#: A disc on its own steering hinge (its axis {steer}), a nose site along +x (or +y), a
#: limited antenna hinge resting at 0 outside its range, a keyframe that puts it inside;
#: the disc's orientation and position in its file: {orient}; an ancestor around it:
#: {open} ... {close}.
CART = """<mujoco model="cart">
  <compiler angle="radian"/>
  <worldbody>
    {open}
    <body name="cart" pos="0.3 -0.2 0.1" {orient}>
      <joint name="steer" type="hinge" axis="{steer}"/>
      <geom name="shell" type="cylinder" size="0.15 0.05" mass="1"/>
      <site name="nose" pos="{nose}"/>
      <body name="mast" pos="0 0 0.05">
        <joint name="antenna" type="hinge" axis="0 1 0" range="0.5 1.0" limited="true"
               stiffness="1" damping="1"/>
        <geom name="rod" type="capsule" size="0.005 0.02" mass="0.001"/>
      </body>
    </body>
    {close}
  </worldbody>
  <actuator>
    <velocity name="push" site="nose" gear="{gear}" kv="1"/>
    <velocity name="spin" joint="steer" kv="1"/>
  </actuator>
  <keyframe>
    <key name="stand" qpos="0 0.7"/>
  </keyframe>
</mujoco>
"""
CART_MOUNT = """file = "cart.xml"
drive = "two_wheel"
unit = 0.1
base = "cart"
joints = "{joints}"
{extra}
[bumper]
shape = "sphere"
radius = 0.15
[beams]
height = {beams}
[action]
kind = "{kind}"
{action}
"""
QUARTER = math.pi / 2
#: The ways a file turns its base a quarter turn about z: on the base, or on an
#: ancestor (a body, a frame).
TURNS = {
    "quat": ("", f'quat="{math.cos(QUARTER / 2)} 0 0 {math.sin(QUARTER / 2)}"', ""),
    "euler": ("", f'euler="0 0 {QUARTER}"', ""),
    "axisangle": ("", f'axisangle="0 0 1 {QUARTER}"', ""),
    "xyaxes": ("", 'xyaxes="0 1 0 -1 0 0"', ""),
    "ancestor body": (f'<body name="holder" euler="0 0 {QUARTER}">', "", "</body>"),
    "ancestor frame": (f'<frame euler="0 0 {QUARTER}">', "", "</frame>"),
}


def _cart(tmp_path, turn=("", "", ""), steer="0 0 1", nose="0.1 0 0", gear="1 0 0 0 0 0",
          joints="slides", kind="servos", action="", extra="", beams=0.0):
    """The cart's file and a mount of it in tmp_path; returns the mount's path."""
    opened, orient, close = turn
    (tmp_path / "cart.xml").write_text(CART.format(open=opened, orient=orient, close=close,
                                                   steer=steer, nose=nose, gear=gear))
    path = tmp_path / "cart.toml"
    path.write_text(CART_MOUNT.format(joints=joints, kind=kind, action=action, extra=extra,
                                      beams=beams))
    return path


def _quiet(path):
    env = tasks.load(str(path), seed=0, sensor_noise=0.0, action_noise=0.0, start_jitter=False)
    env.reset()
    return env


def _turns_and_moves(env):
    """The robot starts at the room's start facing its heading; a = -0.5 turns it 0.5 rad
    counter-clockwise and moves it 1 unit along its new heading; a = 0 moves it 2."""
    physics = env.physics
    x, y, heading = physics.robot_pose()
    assert (x, y, heading) == pytest.approx(physics.start, abs=1e-6)
    env.step([-0.5])
    x1, y1, h1 = physics.robot_pose()
    assert math.remainder(h1 - heading, 2 * math.pi) == pytest.approx(0.5, abs=0.03)
    assert math.hypot(x1 - x, y1 - y) == pytest.approx(1.0, abs=0.05)
    assert math.atan2(y1 - y, x1 - x) == pytest.approx(h1, abs=0.05)
    env.step([0.0])
    x2, y2, _ = physics.robot_pose()
    assert math.hypot(x2 - x1, y2 - y1) == pytest.approx(2.0, abs=0.05)


@pytest.mark.parametrize("way", sorted(TURNS))
def test_a_base_turned_in_its_file_starts_at_the_start_facing_its_heading(tmp_path, way):
    """A base a quarter turn about z in its file (on itself or an ancestor) and away from
    its file's origin: the slides the mount adds follow the room's axes, the robot
    stands at the start facing the start heading, and turns and moves as the drive asks."""
    env = _quiet(_cart(tmp_path, TURNS[way]))
    try:
        _turns_and_moves(env)
    finally:
        env.close()


def test_a_base_tilted_in_its_file_is_read_from_an_upright_frame(tmp_path):
    """A base whose z axis is horizontal in its file (zaxis="0 -1 0": a y-up file standing
    upright in the world): joints = "planar" adds slides and a yaw hinge along the
    room's axes, the mount adds the robot's upright frame (the site ebrl_frame), from
    which the pose is read; it stands at the start, turns and moves. Its beams 0.1 m up:
    tilted, the antenna (a child body's geom) lies across the plane of beams at the
    base's centre, and a beam that reads the robot itself is refused (tasks.beams)."""
    path = _cart(tmp_path, ("", 'zaxis="0 -1 0"', ""), joints="planar", beams=0.1)
    m, _ = tasks.compile_robot(tasks.resolve(str(path)))
    assert mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, "robot/ebrl_frame") >= 0
    env = _quiet(path)
    try:
        _turns_and_moves(env)
        assert math.degrees(env.physics.tilt()) < 1e-6
    finally:
        env.close()


@pytest.mark.parametrize("kind", ["servos", "actuators"])
def test_a_turn_hinge_about_minus_z_turns_the_right_way(tmp_path, kind):
    """The steering hinge turns about -z: the servos added on it (kind servos) or the
    file's own servo on it (kind actuators) turn the robot counter-clockwise for a < 0."""
    action = 'forward = "push"\nturn = "spin"' if kind == "actuators" else ""
    env = _quiet(_cart(tmp_path, steer="0 0 -1", kind=kind, action=action))
    try:
        _turns_and_moves(env)
    finally:
        env.close()


def test_a_forward_axis_of_plus_y_is_the_heading_the_beams_and_the_servos(tmp_path):
    """forward = "y": the robot's nose is its base's +y; it starts facing the start
    heading with it, its middle beam looks along it, and it moves along it."""
    path = _cart(tmp_path, nose="0 0.1 0", extra='forward = "y"')
    env = _quiet(path)
    try:
        physics = env.physics
        site = mujoco.mj_name2id(physics.model.ptr, mujoco.mjtObj.mjOBJ_SITE, "robot/range_3")
        beam = physics.data.site_xmat[site].reshape(3, 3)[:, 2]   # a rangefinder's z axis
        h = physics.start[2]
        assert beam == pytest.approx([math.cos(h), math.sin(h), 0.0], abs=1e-9)
        cart = mujoco.mj_name2id(physics.model.ptr, mujoco.mjtObj.mjOBJ_BODY, "robot/cart")
        assert physics.data.xmat[cart].reshape(3, 3)[:, 1] == pytest.approx(
            [math.cos(h), math.sin(h), 0.0], abs=1e-9)   # the base's +y ahead
        _turns_and_moves(env)
    finally:
        env.close()


#: The tricycle of tests/test_joints.py, its steering hinge about -z, its two drives
#: <general> actuators that act as torque motors (affine bias all zeros), the roll's of
#: a negative gear (as dm_control's jumping ball's).
TRICYCLE = test_joints.TRICYCLE.replace(
    '<joint name="steer" type="hinge" axis="0 0 1"', '<joint name="steer" type="hinge" axis="0 0 -1"'
).replace('<joint name="roll" type="hinge" axis="0 1 0"', '<joint name="roll" type="hinge" axis="{roll}"')
GENERALS = ('<general name="drive" joint="roll" ctrlrange="-1 1" gear="-1" biastype="affine" '
            'biasprm="0"/>\n<general name="spin" joint="steer" ctrlrange="-1 1" {spin}/>')
TORQUE = 'biastype="affine" biasprm="0 0 0"'


def _tricycle(tmp_path, spin=TORQUE, roll="0 1 0", extra="", fork=False):
    """The tricycle and its mount; fork: its steering hinge on a fork that holds the wheel
    (not on the base, which cannot then face the start heading), the base a quarter turn
    about z in its file."""
    text = TRICYCLE.replace("{actuators}", GENERALS.format(spin=spin)).replace("{roll}", roll)
    if fork:
        text = text.replace('<body name="cart" pos="0 0 0.1">', '<body name="cart" pos="0 0 0.1" '
                            'euler="0 0 1.5707963">').replace(
            '<joint name="steer" type="hinge" axis="0 0 -1" damping="0.01"/>', "").replace(
            '<body name="wheel" pos="0 0 -0.05">', '<body name="wheel" pos="0 0 -0.05">\n'
            '        <joint name="steer" type="hinge" axis="0 0 1" damping="0.01"/>')
    (tmp_path / "tricycle.xml").write_text(text)
    path = tmp_path / "tricycle.toml"
    path.write_text(test_joints.TRICYCLE_MOUNT.format(name="tricycle", gains=test_joints.GAINS["torque"])
                    .replace('joints = "slides_z"\n', f'joints = "slides_z"\n{extra}\n'))
    return path


def test_general_actuators_of_zero_bias_drive_their_joints_as_torque_motors(tmp_path):
    """<general> actuators with an affine bias of zeros are torque motors
    (tasks.actuators.kind), one of a negative gear; joint_motors drives them, the steering
    hinge about -z turning the robot the right way."""
    path = _tricycle(tmp_path)
    m, _ = tasks.compile_robot(tasks.resolve(str(path)))
    assert [actuators.model_kind(m, a) for a in range(m.nu)] == ["torque motors"] * 2
    env = _quiet(path)
    try:
        _turns_and_moves(env)
    finally:
        env.close()


def test_each_actuator_kind_and_the_term_that_makes_one_none(tmp_path):
    """tasks.actuators.kind by gain, bias and dyn, whatever the element; for one of no
    kind, why_other names the term."""
    xml = """<mujoco><worldbody><body><joint name="j" type="hinge"/><geom size="0.1"/>
      </body></worldbody><actuator>
      <motor joint="j"/>
      <general joint="j" biastype="affine" biasprm="0 0 0"/>
      <general joint="j" gainprm="3" biastype="affine" biasprm="0 -3 -1"/>
      <general joint="j" gainprm="2" biastype="affine" biasprm="0 0 -2"/>
      <general joint="j" gainprm="100" biastype="affine" biasprm="0 -50 0"/>
      <general joint="j" gainprm="2" biastype="affine" biasprm="0 0 -1"/>
      <general joint="j" biastype="affine" biasprm="1 0 0"/>
      <general joint="j" dyntype="filter" dynprm="0.1"/>
      <general joint="j" gaintype="affine" gainprm="1 0 1"/>
      <general joint="j" gainprm="0"/>
      </actuator></mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    kinds = [actuators.model_kind(m, a) for a in range(m.nu)]
    assert kinds == ["torque motors", "torque motors", "position servos", "velocity servos"] \
        + [None] * 6
    why = [actuators.model_why_other(m, a) for a in range(m.nu)]
    assert why[:4] == [None] * 4
    assert [w.split(":")[0] for w in why[4:]] == ["bias", "bias", "bias", "dyn", "gain", "gain"]
    assert "is not -gain (-100)" in why[4] and "filter" in why[7] and "affine" in why[8]


#: Mounts of the cart and the tricycle that cannot be honoured, and the field each
#: one line names.
REFUSED = [
    ("cart", {"extra": 'forward = "z"'}, "forward: axis z of body 'cart' points up"),
    ("cart", {"extra": 'forward = "sideways"'}, "forward: must be one of x, y, z"),
    ("cart", {"extra": "forward = [1]"}, "forward: must be one of x, y, z, -x, -y, -z, got [1]"),
    ("cart", {"extra": '[rest]\nantenna = "up"'}, "rest.antenna: must be a number, got 'up'"),
    ("tricycle", {"spin": 'gainprm="100" biastype="affine" biasprm="0 -50 0"'},
     "action.kind: joint_motors need the joints' actuators to act as torque motors, "
     "position servos or velocity servos; 'spin' is none: bias: its length term"),
    ("tricycle", {"roll": "1 0 0"}, "forward: joint 'roll' moves the robot along"),
    ("tricycle", {"extra": 'forward = "y"'}, "forward: joint 'roll' moves the robot along"),
    ("cart", {"kind": "actuators", "action": 'forward = "push"\nturn = "spin"',
              "steer": "1 0 0"},
     'a planar two_wheel base needs a hinge about z (a mount\'s joints = "planar" adds one)'),
    ("tricycle", {"fork": True}, "no hinge about z (or -z) to face the start heading"),
]


@pytest.mark.parametrize("robot, edits, message", REFUSED)
def test_what_cannot_be_honoured_is_refused_in_one_line_naming_the_field(tmp_path, robot,
                                                                         edits, message):
    """A forward axis that stands up, a <general> that is no servo, a forward joint that
    rolls across the forward axis, a robot that cannot face the start heading: one line
    at load, naming the field that fixes it."""
    path = (_cart if robot == "cart" else _tricycle)(tmp_path, **edits)
    with pytest.raises((mount.MountError, ValueError)) as refused:
        tasks.load(str(path), seed=0)
    line = str(refused.value)
    assert message in line and "\n" not in line, line


def test_a_refusal_on_the_command_line_is_one_line_and_exit_2(tmp_path):
    path = _cart(tmp_path, extra='forward = "z"')
    proc = ebrl_here("check", "--robot", path, "--actions", "10")
    assert proc.returncode == 2, proc
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "forward: axis z" in lines[0], proc.stderr


def test_a_start_outside_the_rooms_free_space_is_refused_at_load():
    """tasks.placement.check_start: the robot placed at a start inside an obstacle (the
    paper's room's west block) is refused in one line."""
    env = tasks.load("two_wheel", seed=0)
    try:
        physics = env.physics
        physics.start = (25.0, 35.0, 0.0)
        with pytest.raises(tasks.navigation.ContractError) as refused:
            placement.check_start(physics)
        assert "outside the room's free space" in str(refused.value)
        assert "\n" not in str(refused.value)
    finally:
        env.close()


def _ghost(tmp_path):
    """The paper's two-wheel robot whose bumper touches nothing: it goes through walls."""
    text = (ROOT / "models" / "two_wheel.xml").read_text()
    hull = text[text.index('<geom name="hull"'):]
    hull = hull[:hull.index(">") + 1]
    assert 'contype="2"' in hull and 'conaffinity="1"' in hull
    ghost = tmp_path / "ghost.xml"
    ghost.write_text(text.replace(hull, hull.replace('contype="2"', 'contype="0"')
                                  .replace('conaffinity="1"', 'conaffinity="0"')))
    return ghost


def test_a_robot_that_leaves_the_room_raises(tmp_path):
    """Driven straight east from the start through the walls, the ghost leaves the room's
    floor within 45 steps: a PhysicsError that says so (the status OUTSIDE of
    tasks.kernels.env_step.step), not a silent run."""
    env = tasks.load(str(_ghost(tmp_path)), drive="two_wheel", seed=0, sensor_noise=0.0,
                     action_noise=0.0, start_jitter=False)
    try:
        env.reset()
        with pytest.raises(control.PhysicsError, match="the robot left the room"):
            for _ in range(50):
                env.step([0.0])
        x, _, _ = env.physics.robot_pose()
        assert x > 90.0
    finally:
        env.close()


@pytest.mark.slow
def test_a_run_whose_robot_leaves_the_room_is_a_failed_run(tmp_path):
    """The run (the compiled loop) of the ghost raises; recorded as a failed
    run of the kind "left the room", named, never averaged."""
    spec = execution.RunSpec(str(_ghost(tmp_path)), "random", 0, 20_000, drive="two_wheel")
    with pytest.raises(control.PhysicsError, match="the robot left the room") as raised:
        execution.execute(spec)
    out = tmp_path / "out"
    line = results.write_failure(out, spec, raised.value)
    assert results.failure_kind(line) == "left the room"
    assert results.failed_runs(out) == {f"{spec.label}/random/seed_000": line}
    assert "went through a wall" in results.advice([line])
    assert runner.pending(out, [spec]) == [spec]   # not done: a rerun retries it


def test_a_rest_pose_from_a_keyframe_or_a_table_checked_against_the_ranges(tmp_path):
    """rest = "stand" (a keyframe of the file) or a [rest] table: the robot is placed with
    its antenna there (qpos0, the joints' reference, unchanged); a rest outside the
    joint's range, a keyframe not in the file, a joint not in it: one line each."""
    for i, (extra, antenna) in enumerate((('rest = "stand"', 0.7), ("[rest]\nantenna = 0.8", 0.8))):
        (tmp_path / str(i)).mkdir()   # a mount file is read once per path and process
        env = _quiet(_cart(tmp_path / str(i), extra=extra))
        try:
            m = env.physics.model.ptr
            j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, "robot/antenna")
            assert env.physics.data.qpos[m.jnt_qposadr[j]] == antenna
            assert m.qpos0[m.jnt_qposadr[j]] == 0.0
        finally:
            env.close()
    for extra, message in (("[rest]\nantenna = 2.0", "rest.antenna: joint 'antenna' rests "
                                                     "at 2 rad, outside its range [0.5, 1] rad"),
                           ('rest = "sit"', "rest: no keyframe named 'sit'"),
                           ("[rest]\nwheel = 0.1", "rest.wheel: no hinge or slide named 'wheel'")):
        folder = tmp_path / message[:8].replace(".", "_").replace(":", "")
        folder.mkdir()
        with pytest.raises(mount.MountError, match=re.escape(message)):
            tasks.load(str(_cart(folder, extra=extra)), seed=0)


def test_a_gaits_joints_resting_outside_their_ranges_ask_for_a_rest(tmp_path):
    """Gymnasium's ant.xml's qpos0 has its ankles at 0, outside their 30-70 degree
    ranges: its mount without a rest is refused in one line that names the field."""
    text = (ROOT / "models" / "mounts" / "gym_ant.toml").read_text()
    start, end = text.index("[rest]"), text.index("[bumper]")
    path = tmp_path / "no_rest.toml"
    path.write_text(text[:start] + text[end:])
    with pytest.raises(mount.MountError) as refused:
        mount.robot_spec(mount.parse(path))
    assert "rest: joint 'hip_1'" not in str(refused.value)
    assert "rest: joint 'ankle_1' rests at 0 rad in the file's qpos0" in str(refused.value)


def _docs_mount(tmp_path, marker):
    """The TOML block of docs/adding_a_robot.md that holds `marker`, as a mount file."""
    text = (ROOT / "docs" / "adding_a_robot.md").read_text()
    blocks = [b.split("```", 1)[0] for b in text.split("```toml\n")[1:]]
    path = tmp_path / "example.toml"
    path.write_text(next(b for b in blocks if marker in b))
    return path


@pytest.mark.slow
def test_the_docs_rolling_ball_drives_itself_within_the_papers_accuracy(tmp_path):
    """docs/adding_a_robot.md's worked example: dm_control's jumping ball with a head
    (its base rotated in its file, forward its +y, its steering hinge about -z, its drive
    a <general> of zero bias and a negative gear), on its own actuators, within the
    paper's 5%."""
    from experiments.checks import robotcheck
    path = _docs_mount(tmp_path, "jumping_ball_with_head.xml")
    errors, limits = robotcheck.accuracy(str(path), 20)
    for key, e in errors.items():
        assert e.max() <= limits[key], (key, e.max())
