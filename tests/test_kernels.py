"""The tasks' compiled step (tasks.kernels.env_step.step) against dm_control's hooks (which call
the drives' same kernels one hook at a time, drawing from the RandomState), step for step."""
import contextlib

import mujoco
import numpy as np
import pytest

import tasks
from tasks.kernels import bindings
from tasks.kernels.thrusters import hull_normal


def _pair(robot, **fields):
    compiled, hooks = tasks.load(robot, seed=7, **fields), tasks.load(robot, seed=7, **fields)
    hooks.compiled = False
    return compiled, hooks


def test_each_realisation_is_one_row_whose_entries_resolve():
    """tasks.realisations.REALISATIONS reaches every part of a realisation: its Physics
    (whose record is the row's), its record (whose module holds its kernels: the family's
    PHASES, or a floating drive's act and velocity), its mount kind (of its name, running
    on it) and its Task class; tasks.kernels.env_step names no realisation."""
    import inspect

    from tasks.kernels import env_step, two_wheel
    from tasks.realisations import REALISATIONS
    for name, row in REALISATIONS.items():
        assert row.name == name and row.physics_class().Record is row.record_class()
        kernels = row.kernels()
        assert kernels.__name__ == f"tasks.kernels.{name}"
        if row.drive == "two_wheel":
            assert len(kernels.PHASES) == 5 and all(hasattr(f, "py_func") for f in kernels.PHASES)
            assert kernels.PHASES[0] is kernels.turn and kernels.PHASES[1] is kernels.move
        else:
            assert hasattr(kernels.act, "py_func") and hasattr(kernels.velocity, "py_func")
        kind = row.kind_class()
        assert kind.name == name and row.drive in kind.drives
        assert issubclass(row.task_class(), tasks.navigation.Navigation)
    source = inspect.getsource(env_step)
    assert not [name for name in REALISATIONS if f"{name}." in source or f"{name}_" in source]
    assert list(inspect.signature(two_wheel.act).parameters) == ["s", "a", "u"]


@pytest.mark.parametrize("robot,fields", [
    ("two_wheel", {}),
    ("two_wheel", {"sensor_noise": 0.0, "action_noise": 0.0}),
    ("diff_drive", {}),  # wheels under servos (WheelsPhysics)
    ("two_wheel", {"leftover_turn": "commanded"}),
    ("two_wheel", {"blocked_move": "refuse", "leftover_turn": "away"}),
    ("diff_drive", {"blocked_move": "refuse"}),  # a wheels' state undone
    ("hovercraft", {"bump": "bounce"}),  # a free joint's velocity dofs
    ("floating", {}),  # bump "stop"
    ("floating", {"bump": "bounce"}),
    ("floating", {"bump": "stop", "velocity_code": "none"}),
    ("floating", {"thrust": "clipped", "bump": "slide"}),
    ("floating", {"thrust": "demand", "action_noise": 0.0}),
    ("floating", {"velocity_noise": 0.1, "velocity_code": "code"}),
    ("floating", {"velocity_code": "code", "sensor_noise": 0.0}),
    ("floating", {"velocity_noise": 0.05, "wall_friction": 0.3}),
    ("point", {}),
    ("point_mass", {}),
])
@pytest.mark.slow
def test_the_compiled_step_is_the_hooks_step_for_step(robot, fields):
    compiled, hooks = _pair(robot, **fields)
    assert compiled.steps_compiled and not hooks.steps_compiled
    dim = compiled.action_spec().shape[0]
    rng = np.random.default_rng(3)
    compiled.reset(), hooks.reset()
    goals = 0
    for i in range(600):
        # out-of-range demands (clipped); after step 300, straight into the goal
        action = rng.uniform(-1.3, 1.3, dim)
        if 300 < i < 310:
            action = np.array([0.0] if dim == 1 else [1.0, 0.0])
        a, b = compiled.step(action), hooks.step(action)
        assert a.step_type == b.step_type and a.reward == b.reward and a.discount == b.discount
        assert a.observation.keys() == b.observation.keys()
        for key in a.observation:
            assert a.observation[key].tobytes() == b.observation[key].tobytes(), (i, key)
        assert compiled.physics.robot_pose() == hooks.physics.robot_pose()
        assert compiled.physics.substeps == hooks.physics.substeps
        goals += a.reward or 0.0
        if i == 300:  # a goal step: both placed next to it, then driven in
            for env in (compiled, hooks):
                lo, hi = env.physics.goal_box
                env.physics.set_robot_pose(lo[0] - 0.5, (lo[1] + hi[1]) / 2, 0.0)
    assert goals >= 1
    compiled.close(), hooks.close()


def test_the_compiled_step_refuses_what_the_hooks_refuse():
    compiled, hooks = _pair("two_wheel")
    compiled.reset(), hooks.reset()
    for bad in ([np.nan], [np.inf], [0.1, 0.2]):
        with pytest.raises(ValueError) as e1:
            compiled.step(bad)
        with pytest.raises(ValueError) as e2:
            hooks.step(bad)
        assert str(e1.value) == str(e2.value)
    # a 0-d action is the one-dimensional drive's action
    a, b = compiled.step(np.float64(0.25)), hooks.step(np.float64(0.25))
    assert a.observation["range"].tobytes() == b.observation["range"].tobytes()
    compiled.close(), hooks.close()


def test_the_struct_views_are_the_fields_they_name():
    env = tasks.load("two_wheel", seed=0)
    m, d = env.physics.model.ptr, env.physics.data.ptr
    flags = bindings.disable_flags(m)
    assert flags[0] == m.opt.disableflags
    flags[0] ^= int(mujoco.mjtDisableBit.mjDSBL_WARMSTART)
    assert flags[0] == m.opt.disableflags
    flags[0] ^= int(mujoco.mjtDisableBit.mjDSBL_WARMSTART)
    count = bindings.warning_count(d, mujoco.mjtWarning.mjWARN_BADQACC)
    d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number = 3
    assert count[0] == 3
    d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number = 0
    env.close()


def test_the_contact_views_read_mujocos_contacts():
    env = tasks.load("floating", seed=0, bump="grip")
    physics = env.physics
    d = physics.data.ptr
    ncon = bindings.contact_count(d)
    floats, ints, layout = bindings.contact_views(d)
    hull_id = physics.hull
    env.reset()
    # the puck pressed into the west wall, then into the south-west corner
    for x, y in ((physics.robot_radius - 0.2, 30.0),
                 (physics.robot_radius - 0.2, physics.robot_radius - 0.2)):
        physics.set_robot_pose(x, y)
        assert d.ncon >= 1 and ncon[0] == d.ncon
        normal = np.zeros(2)
        assert hull_normal(ncon, floats, ints, layout, hull_id,
                                   normal)
        for k in range(d.ncon):
            c = d.contact[k]
            f = k * layout[0] + layout[1]
            assert floats[f: f + 9].tolist() == c.frame.tolist()
            assert ints[k * layout[2] + layout[3]] == c.geom1
            assert ints[k * layout[2] + layout[4]] == c.geom2
        hull = [k for k in range(d.ncon) if hull_id in d.contact[k].geom][0]
        sign = -1.0 if d.contact[hull].geom1 == hull_id else 1.0
        assert normal.tolist() == (sign * d.contact[hull].frame[:2]).tolist()
        assert normal[0] > 0.5  # from the wall into the robot: east
    # nothing touched: no normal
    physics.set_robot_pose(*physics.start[:2])
    assert d.ncon == 0 and not hull_normal(ncon, floats, ints, layout,
                                                   hull_id, np.zeros(2))
    env.close()


@pytest.mark.parametrize("robot", ["two_wheel", "floating"])
def test_stage_timers_off_changes_nothing_but_the_timers(robot):
    """MuJoCo's timer callback (set by the mujoco package) fills mjData.timer and nothing
    else: with it off the same steps give the same state bit for bit, the timers do not
    advance, and the callback is back after the block."""
    before = bindings.TIMER_CALLBACK.value
    assert before is not None  # the mujoco package sets one at import
    runs = []
    for off in (False, True):
        env = tasks.load(robot, seed=5)
        env.reset()
        rng = np.random.default_rng(1)
        position = env.physics.data.timer[mujoco.mjtTimer.mjTIMER_POSITION]  # mj_step1's
        start = position.duration
        with bindings.stage_timers_off() if off else contextlib.nullcontext():
            if off:
                assert bindings.TIMER_CALLBACK.value is None
            obs = [env.step(rng.uniform(-1, 1, env.action_spec().shape)).observation
                   for _ in range(200)]
        timed = position.duration - start
        runs.append((obs, env.physics.data.qpos.tobytes(), env.physics.data.qvel.tobytes(),
                     env.physics.robot_pose(), timed))
        env.close()
    assert bindings.TIMER_CALLBACK.value == before
    (obs_on, *state_on, timed_on), (obs_off, *state_off, timed_off) = runs
    assert state_on == state_off
    for a, b in zip(obs_on, obs_off):
        assert a.keys() == b.keys() and all(a[k].tobytes() == b[k].tobytes() for k in a)
    assert timed_on > 0 and timed_off == 0
