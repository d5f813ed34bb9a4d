"""Robots that keep their own joints and motors (issue 39): root slides added beside a
base's own joints, the gait for any leg listing (the quadruped's legs read from its
model), in real MuJoCo from real files."""
import importlib.resources
import math
import pathlib

import mujoco
import numpy as np
import pytest

import tasks
from helpers import ROOT
from tasks import mount

MOUNTS = ROOT / "models" / "mounts"

#: A cart written for these tests: a disc on its own steering hinge (about z) and a
#: stiff tipping hinge (about x), moved by its own velocity actuators: one pushing at
#: its nose, one turning the steering hinge.
CART = """<mujoco model="cart">
  <compiler angle="radian"/>
  <worldbody>
    <body name="cart" pos="0 0 0.1">
      <joint name="steer" type="hinge" axis="0 0 1"/>
      <joint name="tip" type="hinge" axis="1 0 0" range="-0.05 0.05" limited="true"
             stiffness="50" damping="5"/>
      <geom name="shell" type="cylinder" size="0.15 0.05" mass="1"/>
      <site name="nose" pos="0.1 0 0"/>
    </body>
  </worldbody>
  <actuator>
    <velocity name="push" site="nose" gear="1 0 0 0 0 0" kv="1"/>
    <velocity name="spin" joint="steer" kv="1"/>
  </actuator>
</mujoco>
"""
CART_MOUNT = """name = "cart"
file = "cart.xml"
drive = "two_wheel"
unit = 0.1
base = "cart"
joints = "slides"
[bumper]
geom = "shell"
[beams]
height = 0.0
[action]
kind = "actuators"
forward = "push"
turn = "spin"
"""


def _cart(tmp_path, text=CART_MOUNT, name="cart"):
    (tmp_path / "cart.xml").write_text(CART)
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


def _names(m, kind, count):
    return [mujoco.mj_id2name(m, kind, i) for i in range(count)]


def test_root_slides_beside_the_bases_own_hinges_keep_them_and_their_motors(tmp_path):
    """joints = "slides": slides x and y come first on the base, its own hinges after
    them with their fields, its motors kept; the heading is read from the base's frame
    (not from a hinge), and the cart turns and moves as the two-wheel drive asks."""
    path = _cart(tmp_path)
    m, _ = tasks.compile_robot(tasks.resolve(str(path)))
    base = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "robot/cart")
    own = [j for j in range(m.njnt) if m.jnt_bodyid[j] == base]
    assert [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in own] == [
        "robot/x", "robot/y", "robot/steer", "robot/tip"]
    tip = own[3]
    assert m.jnt_stiffness[tip] == 50 and m.dof_damping[m.jnt_dofadr[tip]] == 5
    assert np.allclose(m.jnt_range[tip], [-0.05, 0.05]) and m.jnt_limited[tip]
    assert _names(m, mujoco.mjtObj.mjOBJ_ACTUATOR, m.nu) == ["robot/push", "robot/spin"]
    env = tasks.load(str(path), seed=0, sensor_noise=0.0, action_noise=0.0, start_jitter=False)
    try:
        env.reset()
        physics = env.physics
        assert physics.body["qyaw"] == -1 and physics.body["free"] == 0
        x0, y0, h0 = physics.robot_pose()
        env.step([0.5])            # turn 0.5 rad clockwise, then move 1 unit
        x1, y1, h1 = physics.robot_pose()
        steer = physics.data.qpos[m.jnt_qposadr[own[2]]]
        assert abs(math.remainder(h1 - h0 + 0.5, 2 * math.pi)) < 0.05
        assert abs(h1 - steer) < 1e-9     # its own hinge about z is its heading here
        assert abs(math.hypot(x1 - x0, y1 - y0) - 1.0) < 0.05
    finally:
        env.close()


def test_root_slides_refusals_are_one_line(tmp_path):
    for i, (text, message) in enumerate((
            (CART_MOUNT.replace('joints = "slides"', 'joints = "free"'),
             "joints: body 'cart' has joints of its own"),
            (CART_MOUNT.replace('joints = "slides"', 'joints = "slides"\ncondim = 3'),
             "condim: joints = slides: its geoms touch nothing"),
            (CART_MOUNT.replace('joints = "slides"', 'joints = "hinged"'),
             "joints: must be one of file, free, planar, slides, slides_z"))):
        path = _cart(tmp_path, text, f"bad{i}")
        with pytest.raises(mount.MountError) as e:
            tasks.load(str(path)).close()
        line = str(e.value)
        assert "\n" not in line and line.startswith(str(path)) and message in line, line


def test_the_quadrupeds_legs_read_from_its_model():
    """dm_control's suite quadruped, legs listed by joint: each leg's yaw swings its foot
    (its hip points diagonally, so the swing's forward share is +-cos 45 degrees and
    every leg's turning share is the same), its pitch lifts it (a negative pitch raises
    the foot), diagonal legs share a phase; the twelve position servos' controls per
    radian are the file's tendon coefficients (lift 0.5 and extend 0.25 per radian of
    pitch, yaw 1 per radian of yaw), none at rest."""
    from tasks.kernels.gait import LIFT, SWING
    file = pathlib.Path(str(importlib.resources.files("dm_control") / "suite/quadruped.xml"))
    assert tasks.resolve("quadruped").model.resolve() == file.resolve()
    env = tasks.load("quadruped", seed=0)
    try:
        p = env.physics
        m = p.model.ptr
        assert list(p._role) == [SWING, LIFT] * 4 and list(p._leg) == [0, 0, 1, 1, 2, 2, 3, 3]
        names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in p._joints]
        assert names[:2] == ["robot/yaw_front_left", "robot/pitch_front_left"]
        c = math.cos(math.pi / 4)
        assert np.allclose(p._forward_share, [c, -c, -c, c], atol=1e-6)
        assert np.allclose(p._turn_share, -1.0, atol=1e-6)
        assert list(p._lift_sign[1::2]) == [-1.0] * 4 and list(p._lift_sign[0::2]) == [0.0] * 4
        assert list(p._offset) == [0.0, 0.5, 0.0, 0.5]
        assert (p._acts == -1).all() and len(p._servos) == 12
        servos = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in p._servos]
        gain = {name.removeprefix("robot/"): row for name, row in zip(servos, p._servo_gain)}
        for leg, side in enumerate(("front_left", "front_right", "back_right", "back_left")):
            expected = {"yaw": (2 * leg, 1.0), "lift": (2 * leg + 1, 0.5),
                        "extend": (2 * leg + 1, 0.25)}
            for act, (column, value) in expected.items():
                row = np.zeros(8)
                row[column] = value
                assert np.allclose(gain[f"{act}_{side}"], row, atol=1e-6), (act, side)
        assert np.allclose(p._servo_rest, 0.0)
        assert list(p._servo_lo[:3]) == [-1.0, -1.0, -0.8] and list(p._servo_hi[:3]) == [1.0, 1.1, 0.8]
    finally:
        env.close()


def test_a_gait_listing_the_ant_by_hand_is_its_mount():
    """The Ant's mount is a listing of four legs, a swing and a lift each; its torque
    motors are driven by PD (one motor on each listed joint), no servo."""
    ant = mount.parse(MOUNTS / "ant.toml")
    assert ant.action.legs == tuple((f"{s}_hip", (f"{s}_ankle",), ()) for s in (
        "front_left", "front_right", "back_right", "back_left"))
    env = tasks.load("ant", seed=0)
    try:
        p = env.physics
        assert len(p._servos) == 0 and (p._acts >= 0).all()
        m = p.model.ptr
        assert [m.actuator_trnid[a, 0] for a in p._acts] == list(p._joints)
    finally:
        env.close()


BAD_LEGS = [
    ('[[action.legs]]\nswing = "front_left_hip"\n', "action.legs[4].lift: missing"),
    ('[[action.legs]]\nswing = "front_left_hip"\nlift = "front_left_ankle"\n',
     "action.legs[4].swing: joint 'front_left_hip' is listed twice"),
    ('[[action.legs]]\nswing = "nose"\nlift = "tail"\n',
     "action.legs[4].swing: no joint named 'nose' in"),
    ('[[action.legs]]\nswing = ["a", "b"]\nlift = "c"\n', "action.legs[4].swing: one joint"),
    ('[[action.legs]]\nswing = "a"\nlift = "c"\nknee = "d"\n', "action.legs[4].knee: unknown key"),
]


@pytest.mark.parametrize("extra, message", BAD_LEGS)
def test_a_bad_leg_listing_is_one_line(tmp_path, extra, message):
    ant = pathlib.Path(str(importlib.resources.files("dm_control") / "third_party/ant/ant.xml"))
    text = (MOUNTS / "ant.toml").read_text().replace(
        '"dm_control:third_party/ant/ant.xml"', f'"{ant}"')
    text = text.replace("[action.gait]", extra + "\n[action.gait]")
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(mount.MountError) as e:
        tasks.load(str(path)).close()
    line = str(e.value)
    assert "\n" not in line and line.startswith(str(path)) and message in line, line


def test_the_gait_refuses_a_joint_no_actuator_moves(tmp_path):
    """The quadruped's knee is moved only through tendons that pull its pitch and ankle
    too; a yaw on a joint no actuator moves is fine (held), a lift on one is not."""
    file = pathlib.Path(str(importlib.resources.files("dm_control") / "suite/quadruped.xml"))
    text = (MOUNTS / "quadruped.toml").read_text().replace(
        '"dm_control:suite/quadruped.xml"', f'"{file}"').replace(
        'lift = "pitch_front_left"', 'lift = "pitch_front_left"\nyaw = "root"')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(mount.MountError, match="action.legs.0..yaw: joint .root. is not a hinge or a slide"):
        tasks.load(str(path)).close()


#: A tricycle-like cart written for these tests: a disc on its own steering hinge (about
#: z) carried by one wheel under its centre (its own hinge "roll" about y) and two
#: frictionless skids; root slides x, y and z are added beside the steering hinge. Its
#: actuators, by kind: ACTUATORS.
TRICYCLE = """<mujoco model="tricycle">
  <compiler angle="radian"/>
  <worldbody>
    <body name="cart" pos="0 0 0.1">
      <joint name="steer" type="hinge" axis="0 0 1" damping="0.01"/>
      <geom name="shell" type="cylinder" size="0.15 0.03" mass="1"/>
      <geom name="skid_front" type="sphere" size="0.03" pos="0.1 0 -0.07" condim="1" mass="0.01"/>
      <geom name="skid_back" type="sphere" size="0.03" pos="-0.1 0 -0.07" condim="1" mass="0.01"/>
      <body name="wheel" pos="0 0 -0.05">
        <joint name="roll" type="hinge" axis="0 1 0" damping="0.001"/>
        <geom name="tyre" type="cylinder" size="0.05 0.01" euler="1.5707963267948966 0 0"
              condim="3" friction="1" mass="0.1"/>
      </body>
    </body>
  </worldbody>
  <tendon>
    <fixed name="sum"><joint joint="roll" coef="1"/><joint joint="steer" coef="1"/></fixed>
    <fixed name="difference"><joint joint="roll" coef="1"/><joint joint="steer" coef="-1"/></fixed>
  </tendon>
  <actuator>
{actuators}
  </actuator>
</mujoco>
"""
ACTUATORS = {
    "torque": '<motor name="drive" joint="roll" ctrlrange="-1 1"/>'
              '<motor name="spin" joint="steer" ctrlrange="-1 1"/>',
    "mixed": '<motor name="a" tendon="sum" ctrlrange="-1 1"/>'
             '<motor name="b" tendon="difference" ctrlrange="-1 1"/>',
    "position": '<position name="drive" joint="roll" kp="2" kv="0.05"/>'
                '<position name="spin" joint="steer" kp="2" kv="0.2"/>',
    "velocity": '<velocity name="drive" joint="roll" kv="0.2"/>'
                '<velocity name="spin" joint="steer" kv="0.5"/>',
}
GAINS = {"torque": "kp = 2.0\nkv = 0.1\n", "mixed": "kp = 2.0\nkv = 0.1\n", "position": "",
         "velocity": "kp = 20.0\n"}
TRICYCLE_MOUNT = """name = "{name}"
file = "{name}.xml"
drive = "two_wheel"
unit = 0.1
base = "cart"
joints = "slides_z"
timestep = 0.002
integrator = "implicitfast"
time_scale = 2.5
[bumper]
geom = "shell"
[beams]
height = 0.05
[action]
kind = "joint_motors"
forward = "roll"
turn = "steer"
{gains}"""


def _tricycle(folder, kind, name=None, mount=None):
    name = name or f"tricycle_{kind}"
    (folder / f"{name}.xml").write_text(TRICYCLE.format(actuators=ACTUATORS[kind]))
    path = folder / f"{name}.toml"
    path.write_text(mount or TRICYCLE_MOUNT.format(name=name, gains=GAINS[kind]))
    return path


@pytest.mark.parametrize("kind", ["torque", "position", "velocity"])
def test_joint_motors_drive_a_robots_own_actuators_on_named_joints(tmp_path, kind):
    """The tricycle rolls on its wheel's hinge and steers on its base's hinge, through
    its own torque motors, position servos or velocity servos (none added, none dropped):
    random free-space actions within the drive's 5% (`ebrl check`'s accuracy)."""
    from experiments.checks import robotcheck
    path = _tricycle(tmp_path, kind)
    m, _ = tasks.compile_robot(tasks.resolve(str(path)))
    assert _names(m, mujoco.mjtObj.mjOBJ_ACTUATOR, m.nu) == ["robot/drive", "robot/spin"]
    errors, limits = robotcheck.accuracy(str(path), 12, seed=2)
    for key, e in errors.items():
        assert e.max() <= limits[key], (kind, key, e.max())


def test_the_joint_controllers_solve_by_hand(tmp_path):
    """Each controller's controls, from a record set by hand (tasks.kernels.plan.controls):
    torque motors on tendons roll + steer and roll - steer give the PD torques
    tau = kp (target - q) - kv dq with controls ((tau_roll + tau_steer) / 2,
    (tau_roll - tau_steer) / 2), clipped to +-1; position servos on the joints hold the
    targets; velocity servos command kp (target - q)."""
    from tasks.kernels import plan as joints
    q, dq, target = np.array([0.3, -0.2]), np.array([0.5, 1.0]), np.array([0.5, 0.1])
    for kind in ("mixed", "position", "velocity"):
        env = tasks.load(str(_tricycle(tmp_path, kind)), seed=0)
        try:
            env.reset()
            p = env.physics
            parts = p.parts       # the record's fields (its arrays are the record's)
            assert parts["mode"] == {"mixed": joints.TORQUE, "position": joints.POSITION,
                                     "velocity": joints.VELOCITY}[kind]
            p.data.qpos[parts["joint_q"]] = q
            p.data.qvel[parts["joint_dof"]] = dq
            parts["target"][:] = target
            joints.controls(p.record)
            if kind == "mixed":
                tau = 2.0 * (target - q) - 0.1 * dq            # (0.35, 0.5)
                expected = np.clip([(tau[0] + tau[1]) / 2, (tau[0] - tau[1]) / 2], -1, 1)
            elif kind == "position":
                expected = target                              # rest 0, lengths 0
            else:
                expected = 20.0 * (target - q)                 # (4, 6)
            got = parts["controls"]
            assert np.allclose(got, expected, atol=1e-9), (kind, got, expected)
        finally:
            env.close()


def test_joint_motors_gains_per_joint(tmp_path):
    """kp and kv as [forward's, turn's]: torque motors on tendons roll + steer and roll -
    steer give tau_j = kp_j (target_j - q_j) - kv_j dq_j (the controls as in the test
    above); one number is both joints' gain, bit for bit the same run as [k, k]."""
    from tasks.kernels import plan as joints
    q, dq, target = np.array([0.3, -0.2]), np.array([0.5, 1.0]), np.array([0.5, 0.1])
    text = TRICYCLE_MOUNT.format(name="tricycle_mixed", gains="kp = [2.0, 3.0]\nkv = [0.1, 0.2]\n")
    env = tasks.load(str(_tricycle(tmp_path, "mixed", mount=text)), seed=0)
    try:
        env.reset()
        parts = env.physics.parts
        assert list(parts["kp"]) == [2.0, 3.0] and list(parts["kv"]) == [0.1, 0.2]
        env.physics.data.qpos[parts["joint_q"]] = q
        env.physics.data.qvel[parts["joint_dof"]] = dq
        parts["target"][:] = target
        joints.controls(env.physics.record)
        tau = np.array([2.0, 3.0]) * (target - q) - np.array([0.1, 0.2]) * dq
        expected = np.clip([(tau[0] + tau[1]) / 2, (tau[0] - tau[1]) / 2], -1, 1)
        assert np.allclose(parts["controls"], expected, atol=1e-9), (parts["controls"], expected)
    finally:
        env.close()
    runs = []
    for gains in ("kp = 2.0\nkv = 0.1\n", "kp = [2.0, 2.0]\nkv = [0.1, 0.1]\n"):
        folder = tmp_path / str(len(runs))
        folder.mkdir()
        text = TRICYCLE_MOUNT.format(name="tricycle_torque", gains=gains)
        env = tasks.load(str(_tricycle(folder, "torque", mount=text)), seed=1)
        try:
            env.reset()
            rng = np.random.default_rng(2)
            runs.append([env.step(rng.uniform(-1, 1, 1)) and env.physics.data.qpos.copy()
                         for _ in range(10)])
        finally:
            env.close()
    assert all(np.array_equal(a, b) for a, b in zip(*runs))


BAD_JOINT_MOTORS = [
    ("torque", GAINS["torque"].replace("kv = 0.1\n", ""), "action.kv: missing: the torque motors' gain"),
    ("position", "kp = 3.0\n", "action.kp: not a gain of position servos"),
    ("velocity", "", "action.kp: missing: the velocity servos' gain"),
    ("torque", GAINS["torque"] + "kd = 1.0\n", "action.kd: unknown key"),
    ("position", "kv = 0.1\n", "action.kv: not a gain of position servos"),
    ("torque", "kp = [2.0]\nkv = 0.1\n", "action.kp: one number for both joints, or a list "
                                         "of 2, one per joint (forward, turn), got 1"),
    ("torque", "kp = [2.0, -1.0]\nkv = 0.1\n", "action.kp[1]: must be positive, got -1.0"),
    ("torque", 'kp = 2.0\nkv = [0.1, "a"]\n', "action.kv[1]: must be a number, got 'a'"),
    ("torque", "kp = 2.0\nkv = [-0.1, 0.1]\n", "action.kv[0]: must not be negative, got -0.1"),
    ("position", "kp = [2.0, 3.0]\n", "action.kp: not a gain of position servos"),
]


@pytest.mark.parametrize("kind, gains, message", BAD_JOINT_MOTORS)
def test_a_bad_joint_motors_mount_is_one_line(tmp_path, kind, gains, message):
    name = f"bad_{kind}"
    mount_text = TRICYCLE_MOUNT.format(name=name, gains=gains)
    path = _tricycle(tmp_path, kind, name, mount_text)
    with pytest.raises(mount.MountError) as e:
        tasks.load(str(path)).close()
    line = str(e.value)
    assert "\n" not in line and line.startswith(str(path)) and message in line, line


def test_joint_motors_refuse_joints_no_actuator_moves_and_mixed_kinds(tmp_path):
    cases = (
        (TRICYCLE_MOUNT.replace('forward = "roll"', 'forward = "wheel"'),
         "action.forward: no joint named 'wheel' in"),
        (TRICYCLE_MOUNT.replace('joints = "slides_z"', 'joints = "planar"'),
         "joints: joint_motors drive the file's own joints"),
    )
    for i, (text, message) in enumerate(cases):
        name = f"bad{i}"
        path = _tricycle(tmp_path, "torque", name, text.format(name=name, gains=GAINS["torque"]))
        with pytest.raises(mount.MountError, match=message.replace("(", r"\(")):
            tasks.load(str(path)).close()
    (tmp_path / "mix.xml").write_text(TRICYCLE.format(
        actuators='<motor name="drive" joint="roll"/><velocity name="spin" joint="steer" kv="1"/>'))
    path = tmp_path / "mix.toml"
    path.write_text(TRICYCLE_MOUNT.format(name="mix", gains=GAINS["torque"]))
    with pytest.raises(mount.MountError, match="action.kind: joint_motors need the joints' "
                                               "actuators all torque motors"):
        tasks.load(str(path)).close()


@pytest.mark.slow
def test_joint_motors_and_the_quadrupeds_gait_run_the_same_fused_or_not(tmp_path):
    """The protocol's compiled stretches (experiments.running.fused) run the joint motors'
    realisation and the quadruped's servo gait as the step-by-step loop does."""
    from experiments.running import execution
    for robot, steps in ((str(_tricycle(tmp_path, "mixed")), 40), ("quadruped", 6)):
        spec = execution.RunSpec(robot, "avoidance", 0, steps)
        a, b = execution.execute(spec, fused=False), execution.execute(spec)
        for key in ("trial_ends", "trace", "starts"):
            assert np.array_equal(a[key], b[key]), (robot, key)


def test_joint_motors_compiled_step_is_the_hooks_step_a_refused_move_too(tmp_path):
    """dm_control's hooks (env.compiled = False) and the compiled step give the same
    states, with blocked_move = "refuse" (a refused move puts the targets back:
    motors.keep and back), the tricycle started against the east wall."""
    path = str(_tricycle(tmp_path, "torque"))
    states = []
    for compiled in (False, True):
        env = tasks.load(path, seed=3, blocked_move="refuse")
        env.compiled = compiled
        rng = np.random.default_rng(4)
        env.reset()
        env.physics.set_robot_pose(90.0 - 2.0, 30.0, 0.0)
        out = []
        for _ in range(20):
            env.step(rng.uniform(-0.3, 0.3, 1))
            out.append(env.physics.data.qpos.tobytes() + env.physics.data.qvel.tobytes())
        states.append(out)
        env.close()
    assert states[0] == states[1]
