"""Beams see the room, never the robot (issue 59, tasks.beams): a beam whose nearest hit at
the start is one of the robot's own geoms is refused at load in one line naming the beam
and the geom; `ebrl check` fails beams over the walls' top and beams that read nearer
than any wall in free space. On dm_control's soccer boxhead (its eyes are geoms of a
child body of the head) and on the paper's two-wheel robot edited here."""
import re

import mujoco
import numpy as np
import pytest

import tasks
from experiments.checks import robotcheck
from helpers import ROOT, ebrl, ebrl_here
from models import rooms
from tasks import beams

#: dm_control's soccer boxhead (tests/mounts/boxhead.toml, the mount `make test` warms),
#: its beams at {height} m above the head's centre.
BOXHEAD = (ROOT / "tests" / "mounts" / "boxhead.toml").read_text().replace(
    "\nheight = -0.2\n", "\nheight = {height}\n")
assert "{height}" in BOXHEAD


def _boxhead(tmp_path, height):
    path = tmp_path / "boxhead.toml"
    path.write_text(BOXHEAD.format(height=height))
    return path


def _two_wheel(tmp_path, edit):
    """The paper's two-wheel robot file, edited, beside the test."""
    path = tmp_path / "my_two_wheel.xml"
    path.write_text(edit((ROOT / "models" / "two_wheel.xml").read_text()))
    return path


def test_beams_that_hit_the_boxheads_own_eyes_are_refused_at_load_naming_beam_and_geom(tmp_path):
    """The issue's blind robot: beams at the head's centre cross its eyes (geoms of the
    child body egocentric_camera, which the rangefinder does not ignore)."""
    path = _boxhead(tmp_path, 0.0)
    with pytest.raises(tasks.navigation.ContractError) as refused:
        tasks.load(str(path), seed=0)
    line = str(refused.value)
    assert "\n" not in line and line.startswith(f"{path.resolve()}: beams.height: "), line
    for beam, eye in (("range_0", "eye_l"), ("range_2", "eye_l"), ("range_4", "eye_r"),
                      ("range_6", "eye_r")):
        assert f"'{beam}' (its geom '{eye}'," in line, line
    assert "'range_3'" not in line   # the middle beam passes between the eyes
    proc = ebrl_here("check", "--robot", path, "--actions", "10", "--accuracy-actions", "5")
    assert proc.returncode == 2 and proc.stdout == "", proc
    assert proc.stderr.strip().splitlines() == [f"ebrl: error: {line}"]


def test_the_check_casts_the_rangefinders_own_ray():
    """What tasks.beams.ray finds is what the rangefinder reads, bit for bit, for every
    registered robot and shipped mount, at the start; and none of them reads itself."""
    for name in (*tasks.ROBOTS, *tasks.MOUNTS):
        env = tasks.load(name, seed=0, start_jitter=False)
        try:
            physics = env.physics
            m, d = physics.model.ptr, physics.data.ptr
            physics.set_robot_pose(*physics.start)
            read = physics.ranges() + physics.robot_radius
            cast = [beams.ray(m, d, s)[0] / physics.unit for s in beams.beam_sensors(m)]
            cast = np.where(np.asarray(cast) < 0, np.inf, cast)
            np.testing.assert_allclose(read, cast, rtol=1e-12, err_msg=name)
            assert beams.self_hits(physics) == [], name
            assert all(0.0 < h.origin < rooms.WALL_HEIGHT and 0.0 < h.end < rooms.WALL_HEIGHT
                       for h in beams.heights(physics, env.task.config.sensor_range)), name
        finally:
            env.close()


def test_a_contract_files_beam_through_its_own_child_body_is_refused(tmp_path):
    """A flag on a child body of the base, in front of the middle beam: refused, naming
    the robot file, the beam and the geom (a robot file has no mount field to name)."""
    flag = ('<body name="mast" pos="0.3 0 0"><geom name="flag" type="box" '
            'size="0.02 0.05 0.05" contype="0" conaffinity="0" mass="0.01"/></body>\n'
            '      <site name="drive"')
    path = _two_wheel(tmp_path, lambda t: t.replace('<site name="drive"', flag, 1))
    with pytest.raises(tasks.navigation.ContractError) as refused:
        tasks.load(str(path), drive="two_wheel", seed=0)
    line = str(refused.value)
    assert line.startswith(f"robot file {path}: beam 'range_3' (its geom 'flag', "), line
    assert re.search(r"'flag', 2\.\d\d units away\) hits the robot itself", line), line
    assert "'range_2'" not in line and "\n" not in line


def test_the_check_fails_beams_over_the_walls(tmp_path):
    """The boxhead's beams 0.3 m above its head (1.3 m, 4.33 units, over the 3-unit walls):
    loaded (they hit nothing of the robot), failed by `ebrl check`, each beam named."""
    path = _boxhead(tmp_path, 0.3)
    tasks.load(str(path), seed=0).close()
    proc = ebrl_here("check", "--robot", path, "--actions", "10", "--accuracy-actions", "5")
    assert proc.returncode == 1, proc
    failed = [line for line in proc.stdout.splitlines() if line.endswith("FAIL")]
    assert len(failed) == 1, proc.stdout
    assert failed[0].startswith(f"{path}: beams outside the walls' height (0 to 3 units) at "
                                "the start: range_0 (4.33 to 4.33), "), failed[0]
    assert "range_6 (4.33 to 4.33) units above the floor" in failed[0]


def test_the_check_fails_a_beam_that_reads_the_floor_in_open_space(tmp_path):
    """The middle beam tilted down hits the floor 2 units ahead: nearer than any wall in
    free space, and under the floor at the end of its range: both named, and no other
    beam."""
    path = _two_wheel(tmp_path, lambda t: t.replace('name="range_3" class="beam" zaxis="1 0 0"',
                                                    'name="range_3" class="beam" zaxis="1 0 -0.5"'))
    errors, limits, seen, _ = robotcheck.free_space(str(path), 20, drive="two_wheel")
    assert seen["range_3"][0] == 20 and seen["range_3"][1] > 2.0, seen
    assert all(seen[f"range_{i}"] == (0, 0.0) for i in (0, 1, 2, 4, 5, 6)), seen
    heights, wall = robotcheck.beam_heights(str(path), "two_wheel")
    lines, failed = robotcheck.beam_lines("my", 20, seen, heights, wall)
    assert failed == 2, lines
    assert lines[0].startswith("my: beams outside the walls' height (0 to 3 units) at the "
                               "start: range_3 (1.00 to -5.26) units") and lines[0].endswith("FAIL")
    assert lines[1].startswith("my: beams that read nearer than any wall after 20 free-space "
                               "actions: range_3 (20 times, up to ") and lines[1].endswith("FAIL")


@pytest.mark.slow
def test_a_boxhead_whose_beams_see_the_room_passes_the_check(tmp_path):
    """The boxhead's beams 0.2 m under its head's centre (2.67 units above the floor:
    under the eyes, over the ball and its arms) see the room: `ebrl check`, a process of
    its own, passes, beams included."""
    path = _boxhead(tmp_path, -0.2)
    proc = ebrl("check", "--robot", path, "--actions", "300", "--accuracy-actions", "100")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert f"{path}: beams at the start 2.67 to 2.67 units above the floor, under the " \
           "walls' top (3 units) ok" in proc.stdout
    assert f"{path}: beams after 100 free-space actions: no reading nearer than the " \
           "nearest wall ok" in proc.stdout


def test_robot_bodies_are_the_base_tree_not_the_room():
    """tasks.beams.robot_bodies: the two-wheel robot's bodies, none of the room's."""
    env = tasks.load("two_wheel", seed=0)
    try:
        m = env.physics.model.ptr
        base = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "robot/base")
        bodies = beams.robot_bodies(m, base)
        assert base in bodies
        assert all(mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b).startswith("robot/")
                   for b in bodies)
    finally:
        env.close()
