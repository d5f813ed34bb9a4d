"""The room, the robots and the tasks against the paper's Sections 3.1-3.3, in real MuJoCo."""
import math

import numpy as np
import pytest
from absl.testing import absltest
from dm_env import test_utils

import tasks
from tasks import navigation
from tasks.kernels import sensing
from tasks.kernels.two_wheel import away_sign

# The room as the issue states it, written out independently of room.xml:
# field 0..90 x 0..60 units, obstacles as (xmin, xmax, ymin, ymax).
FIELD = (0.0, 90.0, 0.0, 60.0)
OBSTACLES = [(20.0, 30.0, 20.0, 50.0), (50.0, 60.0, 10.0, 20.0), (70.0, 80.0, 30.0, 60.0)]
RADIUS = 1.5
TWO_WHEEL_BEAMS = np.deg2rad([90, 60, 30, 0, -30, -60, -90])
FLOATING_BEAMS = np.deg2rad([0, 45, 90, 135, 180, 225, 270, 315])


def ray_to_box_from_outside(px, py, dx, dy, box):
    """Slab test: distance along (dx, dy) to box, or inf."""
    x0, x1, y0, y1 = box
    tmin, tmax = -np.inf, np.inf
    for p, d, lo, hi in ((px, dx, x0, x1), (py, dy, y0, y1)):
        if abs(d) < 1e-12:
            if not lo <= p <= hi:
                return np.inf
            continue
        t0, t1 = sorted(((lo - p) / d, (hi - p) / d))
        tmin, tmax = max(tmin, t0), min(tmax, t1)
    return tmin if tmax >= tmin and tmin >= 0 else np.inf


def ray_to_field_from_inside(px, py, dx, dy):
    x0, x1, y0, y1 = FIELD
    ts = []
    if dx > 1e-12:
        ts.append((x1 - px) / dx)
    if dx < -1e-12:
        ts.append((x0 - px) / dx)
    if dy > 1e-12:
        ts.append((y1 - py) / dy)
    if dy < -1e-12:
        ts.append((y0 - py) / dy)
    return min(ts)


def expected_codes(x, y, heading, beam_angles):
    codes = []
    for b in beam_angles:
        dx, dy = math.cos(heading + b), math.sin(heading + b)
        t = min([ray_to_field_from_inside(x, y, dx, dy)]
                + [ray_to_box_from_outside(x, y, dx, dy, box) for box in OBSTACLES])
        d = t - RADIUS
        codes.append(0.0 if d > 14.0 else round(255 * (1 - max(d, 0.0) / 14.0)))
    return np.array(codes)


def clearance(x, y):
    """Distance from the centre to the nearest wall or obstacle surface (negative inside)."""
    x0, x1, y0, y1 = FIELD
    dists = [x - x0, x1 - x, y - y0, y1 - y]
    for bx0, bx1, by0, by1 in OBSTACLES:
        ox = max(bx0 - x, 0.0, x - bx1)
        oy = max(by0 - y, 0.0, y - by1)
        inside = bx0 < x < bx1 and by0 < y < by1
        dists.append(-min(x - bx0, bx1 - x, y - by0, by1 - y) if inside else math.hypot(ox, oy))
    return min(dists)


def random_free_pose(rng):
    while True:
        x, y = rng.uniform(0, 90), rng.uniform(0, 60)
        if clearance(x, y) > RADIUS + 0.2:
            return x, y, rng.uniform(-np.pi, np.pi)


def quiet_env(robot, **kw):
    """The paper's base task (the config fields' defaults, not the robot's readings),
    without noise or jitter."""
    return tasks.load(robot, config=tasks.TaskConfig(), sensor_noise=0.0, action_noise=0.0,
                      start_jitter=False, **kw)


@pytest.mark.parametrize("robot,beams", [("two_wheel", TWO_WHEEL_BEAMS), ("floating", FLOATING_BEAMS)])
def test_ranges_match_an_independent_ray_cast(robot, beams):
    env = quiet_env(robot, seed=0)
    env.reset()
    rng = np.random.default_rng(1)
    for _ in range(300):
        x, y, heading = random_free_pose(rng)
        heading = heading if robot == "two_wheel" else 0.0
        env.physics.set_robot_pose(x, y, heading)
        got = env.task.get_observation(env.physics)["range"]
        want = expected_codes(x, y, heading, beams)
        assert np.abs(got - want).max() <= 3, (x, y, heading, got, want)
    env.close()


def test_touching_reads_255_and_nothing_reads_0():
    env = quiet_env("floating", seed=0)
    env.reset()
    env.physics.set_robot_pose(RADIUS, 30.0)  # touching the west wall, open space elsewhere
    codes = env.task.get_observation(env.physics)["range"]
    assert codes[4] == 255  # W
    assert codes[0] == 0 and codes[2] == 0  # E and N see nothing within 14 units
    env.close()


def step_pose(env, action):
    before = env.physics.robot_pose()
    env.step(action)
    return before, env.physics.robot_pose()


def test_two_wheel_free_space_action_semantics():
    env = quiet_env("two_wheel", seed=0)
    env.reset()
    for action, turn, move in [(0.0, 0.0, 2.0), (1.0, -1.0, 0.0), (-0.4, 0.4, 1.2),
                               (0.25, -0.25, 1.5), (-1.0, 1.0, 0.0)]:
        env.physics.set_robot_pose(45.0, 30.0, 0.3)  # the middle of the room, nothing near
        (x0, y0, h0), (x1, y1, h1) = step_pose(env, [action])
        assert abs((h1 - h0) - turn) < 0.05, (action, h1 - h0)
        heading = h0 + turn
        ahead = (x1 - x0) * math.cos(heading) + (y1 - y0) * math.sin(heading)
        aside = -(x1 - x0) * math.sin(heading) + (y1 - y0) * math.cos(heading)
        assert abs(ahead - move) < 0.15 and abs(aside) < 0.15, (action, ahead, aside)
    env.close()


def test_two_wheel_blocked_move_becomes_a_right_turn():
    env = quiet_env("two_wheel", seed=0)
    env.reset()
    # Facing the east face of the west block (x = 20) from 0.5 units away.
    env.physics.set_robot_pose(20.0 - RADIUS - 0.5, 35.0, 0.0)
    (x0, _, h0), (x1, _, h1) = step_pose(env, [0.0])
    assert x1 - x0 < 0.6  # moved at most the gap
    # The 1.5 units that did not happen became 0.75 rad of turn, to the right (a = 0).
    assert abs((h1 - h0) + 0.75) < 0.1, h1 - h0
    # A commanded left turn keeps its direction for the leftover.
    env.physics.set_robot_pose(20.0 - RADIUS - 0.05, 35.0, 0.1)
    (_, _, h0), (_, _, h1) = step_pose(env, [-0.1])
    assert h1 - h0 > 0.1 + 0.5, h1 - h0
    env.close()


def _blocked(blocked_move, leftover_turn, compiled=True):
    """Two blocked steps, noise off: a = 0 facing the west block's east face (x = 20)
    from 0.5 units; a = 0.1 (0.1 rad right, then 1.8 units) at heading 0.5 from there."""
    env = quiet_env("two_wheel", seed=0, blocked_move=blocked_move,
                    leftover_turn=leftover_turn)
    env.compiled = compiled
    env.reset()
    poses = []
    for heading, action in ((0.0, 0.0), (0.5, 0.1)):
        env.physics.set_robot_pose(20.0 - RADIUS - 0.5, 35.0, heading)
        poses.append(step_pose(env, [action])[1])
    env.close()
    return poses


@pytest.mark.parametrize("compiled", [True, False])
def test_a_refused_move_turns_all_of_it(compiled):
    """blocked_move "refuse": the robot stays where the turn left it, and the whole move
    is turned at 1 rad per 2 units: a = 0 turns 2 / 2 = 1 rad right; a = 0.1 turns 0.1,
    then 1.8 / 2 = 0.9 rad right ("commanded") or left ("away": the block is nearer on
    the right at heading 0.4): 0.4 - 0.9 = -0.5 and 0.4 + 0.9 = 1.3."""
    (p, q), (_, r) = _blocked("refuse", "commanded", compiled), _blocked("refuse", "away", compiled)
    x0 = 20.0 - RADIUS - 0.5
    assert abs(p[0] - x0) < 1e-9 and abs(p[1] - 35.0) < 1e-9 and abs(p[2] + 1.0) < 1e-9
    assert abs(q[0] - x0) < 1e-9 and abs(q[1] - 35.0) < 1e-9 and abs(q[2] + 0.5) < 1e-9
    assert abs(r[0] - x0) < 1e-9 and abs(r[1] - 35.0) < 1e-9 and abs(r[2] - 1.3) < 1e-9


def test_a_leftover_turn_away_mirrors_the_commanded_one():
    """blocked_move "stop": the same move stops at the same place either way and the same
    rest is turned; at heading 0.4 (a = 0.1) the block is nearer on the right, so "away"
    turns it left by what "commanded" turns right: 0.4 + t and 0.4 - t. At a = 0 facing
    the face head-on the beams either side read alike (a tie): both turn right."""
    (p1, q1), (p2, q2) = _blocked("stop", "commanded"), _blocked("stop", "away")
    assert q1[:2] == q2[:2] and abs((q2[2] - 0.4) + (q1[2] - 0.4)) < 1e-12
    assert q1[2] < 0.4 - 0.3 and q2[2] > 0.4 + 0.3
    assert p1 == p2 and p1[2] < -0.5


def test_away_sign_by_hand():
    inf = np.inf
    assert away_sign(np.array([3.0, inf, inf, 1.0, inf, 5.0, inf]), 1.0) == -1.0
    assert away_sign(np.array([inf, 6.0, inf, 0.0, 2.0, inf, inf]), -1.0) == 1.0
    assert away_sign(np.array([2.0, inf, inf, 0.0, inf, inf, 2.0]), 1.0) == 1.0
    assert away_sign(np.full(7, inf), -1.0) == -1.0  # nothing seen: commanded


def test_floating_thrust_and_coast():
    env = quiet_env("floating", seed=0)
    env.reset()
    env.physics.set_robot_pose(10.0, 5.0)
    env.step([1.0, -0.5])
    np.testing.assert_allclose(env.physics.robot_velocity(), [0.2, -0.1], atol=1e-9)
    x0, y0, _ = env.physics.robot_pose()
    for _ in range(10):
        ts = env.step([0.0, 0.0])
    np.testing.assert_allclose(ts.observation["velocity"], [0.2, -0.1], rtol=0.01)
    x1, y1, _ = env.physics.robot_pose()
    np.testing.assert_allclose([x1 - x0, y1 - y0], [2.0, -1.0], rtol=0.01)
    env.close()


@pytest.mark.parametrize("vx,vy,slide", [(0.0, -0.4, (0.0, 0.0)), (0.4, -0.4, (0.0, 0.02)),
                                          (0.4, -0.1, (0.2, 0.35))])
def test_floating_bump_stops_the_motion_into_the_wall(vx, vy, slide):
    """The bumper grips (friction 1): the wall takes the speed into it and as much along
    it, so a head-on or 45-degree bump stops the puck and a shallow one slides on slower;
    at most a small rebound is left."""
    env = quiet_env("floating", seed=0, bump="grip")
    env.reset()
    env.physics.set_robot_pose(40.0, 3.0)
    for _ in range(2):  # two thrusts build the velocity, then the puck coasts into the wall
        env.step([vx / 0.4, vy / 0.4])
    for _ in range(25):
        env.step([0.0, 0.0])
    got_vx, got_vy = env.physics.robot_velocity()
    assert 0.0 <= got_vy < 0.25 * abs(vy)
    assert slide[0] - 1e-3 <= got_vx <= slide[1] + 1e-3
    env.close()


@pytest.mark.parametrize("robot", ["two_wheel", "floating"])
def test_no_robot_ever_ends_inside_an_obstacle(robot):
    env = tasks.load(robot, seed=3)
    env.reset()
    rng = np.random.default_rng(0)
    dim = env.action_spec().shape[0]
    worst = np.inf
    for i in range(3000):
        # Random actions with a bias, so the robot keeps ramming walls.
        action = np.clip(rng.normal(0.0, 0.5, dim) + (0.6 if robot == "floating" else 0.0), -1, 1)
        if robot == "floating" and i % 300 == 0:
            action = -action
        if env.step(action).last():
            env.reset()
        x, y, _ = env.physics.robot_pose()
        worst = min(worst, clearance(x, y))
    radius = env.physics.robot_radius  # the robot's (its readings' radius, tasks.robots)
    assert worst > radius - 0.3, worst  # the body may sink by a fraction of a unit, no more
    env.close()


def test_start_jitter_stays_within_bounds_and_spreads():
    env = tasks.load("two_wheel", seed=7)
    poses = []
    for _ in range(300):
        env.reset()
        poses.append(env.physics.robot_pose())
    start = (5.0, 35.0, 0.0)  # Section 3.1: 5 from the left, 25 below the top, heading right
    assert env.physics.start == start
    poses = np.array(poses) - np.array(start)
    bounds = [3.0, 3.0, np.deg2rad(15)]
    for k in range(3):
        assert np.abs(poses[:, k]).max() <= bounds[k] + 1e-9
        assert poses[:, k].min() < -0.8 * bounds[k] and poses[:, k].max() > 0.8 * bounds[k]
        assert abs(poses[:, k].mean()) < 0.15 * bounds[k]
    env.close()
    still = tasks.load("two_wheel", seed=7, start_jitter=False)
    still.reset()
    assert still.physics.robot_pose() == pytest.approx(start)
    still.close()


@pytest.mark.parametrize("robot,action", [("two_wheel", [0.0]), ("floating", [0.0, 1.0])])
def test_goal_gives_reward_one_and_last(robot, action):
    env = quiet_env(robot, seed=0)
    env.reset()
    env.physics.set_robot_pose(85.0, 47.0, math.pi / 2)  # 3 units below the goal, facing it
    ts = env.step(action)
    assert ts.reward == 0.0 and ts.mid()
    for _ in range(5):
        ts = env.step(action)
        if ts.last():
            break
    assert ts.last() and ts.reward == 1.0 and ts.discount == 0.0
    assert env.step(action).first()  # the next step starts a new trial
    env.close()


@pytest.mark.parametrize("robot", ["two_wheel", "floating"])
def test_same_seed_same_trajectory(robot):
    def trajectory(seed):
        env = tasks.load(robot, seed=seed)
        env.reset()
        rng = np.random.default_rng(0)
        out = []
        for _ in range(200):
            ts = env.step(np.clip(rng.normal(0, 0.5, env.action_spec().shape), -1, 1))
            out.append(np.concatenate([env.physics.robot_pose(), ts.observation["range"]]))
        env.close()
        return np.array(out)
    a, b, c = trajectory(5), trajectory(5), trajectory(6)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_bad_robot_and_bad_actions():
    with pytest.raises(ValueError, match="two_wheel.*floating|floating.*two_wheel"):
        tasks.load("tricycle")
    env = quiet_env("two_wheel", seed=0)
    env.reset()
    for bad in ([np.nan], [np.inf], [0.1, 0.2], [[0.1]]):
        with pytest.raises(ValueError):
            env.step(bad)
    env.physics.set_robot_pose(45.0, 30.0, 0.0)
    env.step([7.0])  # clipped to 1: a pure right turn of 1 rad
    assert env.physics.robot_pose()[2] == pytest.approx(-1.0, abs=0.05)
    env.close()
    env = quiet_env("floating", seed=0)
    env.reset()
    with pytest.raises(ValueError, match="shape"):
        env.step([0.1])
    env.close()


@pytest.mark.parametrize("robot", ["two_wheel", "floating"])
def test_observations_match_their_specs(robot):
    env = tasks.load(robot, seed=0)
    ts = env.reset()
    spec = env.observation_spec()
    assert set(ts.observation) == set(spec)
    assert spec["range"].shape == ((7,) if robot == "two_wheel" else (8,))
    for _ in range(50):
        ts = env.step(np.zeros(env.action_spec().shape))
        for k, s in spec.items():
            s.validate(ts.observation[k])
            assert ts.observation[k].dtype == np.float64
        assert np.all((ts.observation["range"] >= 0) & (ts.observation["range"] <= 255))
    aspec = env.action_spec()
    assert aspec.shape == ((1,) if robot == "two_wheel" else (2,))
    assert np.all(aspec.minimum == -1) and np.all(aspec.maximum == 1)
    env.close()


class _Contract:
    robot = None

    def make_object_under_test(self):
        return tasks.load(self.robot, seed=0)

    def make_action_sequence(self):
        # Wander, then drive into the goal so the LAST/FIRST contract is exercised.
        for _ in range(10):
            yield self.make_action()
        self.environment.physics.set_robot_pose(85.0, 49.0, math.pi / 2)
        for _ in range(6):
            yield np.array([0.0] if self.robot == "two_wheel" else [0.0, 1.0])
        for _ in range(5):
            yield self.make_action()


class TwoWheelContractTest(_Contract, test_utils.EnvironmentTestMixin, absltest.TestCase):
    robot = "two_wheel"


class FloatingContractTest(_Contract, test_utils.EnvironmentTestMixin, absltest.TestCase):
    robot = "floating"


def test_compiled_sensing_equals_the_numpy_formula_bit_for_bit():
    """Section 3.2 as numpy writes it, against the compiled loops the task runs."""
    rng = np.random.default_rng(0)
    raw = np.concatenate([rng.uniform(0.0, 2.0, 5000), [-1.0, 0.15, 0.149, 1.55, 1.4 + 0.15]])
    radius = 1.5
    distance = raw * (1.0 / 0.1)
    distance -= radius
    distance[raw < 0.0] = np.inf
    code = np.maximum(distance, 0.0)
    code *= -255 / 14.0
    code += 255
    np.rint(code, out=code)
    np.maximum(code, 0.0, out=code)
    noise = rng.normal(0.0, 12.75, size=code.shape)
    noisy = np.minimum(np.maximum(code + noise, 0.0), 255)
    got = sensing.surface_distances(raw, 1.0 / 0.1, radius)
    assert got.tobytes() == distance.tobytes()
    assert navigation.encode_range(got).tobytes() == code.tobytes()
    assert navigation.encode_range(got, noise).tobytes() == noisy.tobytes()


def _bump(robot, bump, vx, vy):
    env = tasks.load(robot, seed=0, config=tasks.TaskConfig(), start_jitter=False,
                     sensor_noise=0.0, action_noise=0.0, bump=bump)
    env.reset()
    env.physics.set_robot_pose(40.0, 3.0)  # 1.5 units above the south wall
    for _ in range(2):
        env.step([vx / 0.4, vy / 0.4])
    for _ in range(25):
        env.step([0.0, 0.0])
    v, pose = env.physics.robot_velocity(), env.physics.robot_pose()
    env.close()
    return v, pose


@pytest.mark.parametrize("robot", ["floating", "hovercraft"])
def test_bump_readings_do_what_they_name(robot):
    # stop: the velocity is zero at the wall, and the bumper rests on it (y = radius).
    v, (_, y, _) = _bump(robot, "stop", 0.4, -0.4)
    assert np.allclose(v, 0.0, atol=1e-12) and 1.5 <= y < 1.5 + 0.1
    # slide: frictionless walls keep the motion along the wall.
    v, _ = _bump(robot, "slide", 0.4, -0.4)
    assert v[0] == pytest.approx(0.4, abs=0.01) and 0 <= v[1] < 0.1
    # bounce: the velocity mirrored off the wall, elastically.
    v, _ = _bump(robot, "bounce", 0.0, -0.4)
    np.testing.assert_allclose(v, [0.0, 0.4], atol=1e-6)
    v, _ = _bump(robot, "bounce", 0.4, -0.1)
    np.testing.assert_allclose(v, [0.4, 0.1], atol=1e-6)


def test_radius_changes_the_body_and_the_readings():
    def ranges(**kw):
        env = quiet_env("two_wheel", **kw)
        env.reset()
        env.physics.set_robot_pose(45.0, 30.0, 0.0)
        out = env.physics.ranges(), env.physics.robot_radius
        env.close()
        return out
    (r15, rad15), (r25, rad25) = ranges(), ranges(radius=2.5)
    assert rad15 == pytest.approx(1.5) and rad25 == pytest.approx(2.5)
    np.testing.assert_allclose(r15 - r25, 1.0, atol=1e-9)  # readings from the surface


@pytest.mark.parametrize("field,value,message", [
    ("bump", "wobble", "bump must be one of"), ("radius", 0.0, "radius must be positive"),
    ("radius", 7.0, "at most 5"), ("sensor_noise", float("nan"), "finite"),
    ("action_noise", 1.0, "below 1"), ("start_jitter", "yes", "true or false"),
    ("blocked_move", "bounce", "blocked_move must be one of stop, refuse"),
    ("leftover_turn", "left", "leftover_turn must be one of commanded, away"),
])
@pytest.mark.slow
def test_task_config_refuses_bad_values(field, value, message):
    with pytest.raises(ValueError, match=message):
        tasks.TaskConfig(**{field: value})
