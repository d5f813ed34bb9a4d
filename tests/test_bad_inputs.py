"""The newer surfaces' bad inputs (issue 50): mount values out of their ranges, a robot
too wide for a map's corridors with --set, a random maze's seed past labmaze's range, a
map with a byte-order mark, repeated values; each exit status 2 and one line naming the
problem (the file and the field for a mount), in this process (helpers.ebrl_here),
before any work: nothing written. The worker's side (an error raised in a worker) is
the slow test at the end."""
import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

from helpers import ROOT, ebrl_here
from models import rooms
from tasks import mount
from tasks.realisations import gait_parameters as gait

ANT = (ROOT / "models" / "mounts" / "ant.toml").read_text()

#: (what the ant's mount has, what the bad mount has instead, the line's field and words)
MOUNT_CASES = [
    ("control_substeps = 1", "control_substeps = 0",
     "action.gait.control_substeps: must be at least 1, got 0"),
    ("control_substeps = 1", "control_substeps = 1000000000000",
     "action.gait.control_substeps: must be at most 1000, got 1000000000000"),
    ("control_substeps = 1", "control_substeps = 1.5",
     "action.gait.control_substeps: must be an integer, got 1.5"),
    ("frequency = 1.0", "frequency = -1.0", "action.gait.frequency: must be positive, got -1.0"),
    ("frequency = 1.0", "frequency = 1.0\nkp = -15.0", "action.gait.kp: must be positive, got -15.0"),
    ("frequency = 1.0", "frequency = 1.0\nkd = -1", "action.gait.kd: must be non-negative, got -1"),
    ("frequency = 1.0", "frequency = 1.0\nmax_tilt = 270.0",
     "action.gait.max_tilt: must be at most 180 degrees, got 270.0"),
    ("frequency = 1.0", "frequency = nan", "action.gait.frequency: must be a finite number, got nan"),
    ("unit = 0.4", "unit = 1e-300", "unit: must be at least 0.001, got 1e-300"),
    ("unit = 0.4", "unit = 1e300", "unit: must be at most 100 m per paper unit, got 1e+300"),
    ("timestep = 0.02", "timestep = 1e-300", "timestep: must be at least 0.0001, got 1e-300"),
    ("falls = 0", "falls = -1", "check.falls: must be non-negative, got -1"),
    ("[check]", "[readings]\nno_such = 1\n\n[check]", "readings.no_such: unknown key; valid: "),
    ("[check]", "[readings]\nradius = -1.0\n\n[check]", "readings.radius: must be positive, got -1.0"),
    ("[check]", "[readings]\nradius = 9.0\n\n[check]", "readings.radius: must be at most 5 units"),
    ("[check]", '[readings]\nblocked_move = "sideways"\n\n[check]',
     "readings.blocked_move: must be one of stop, refuse, got 'sideways'"),
    ("[check]", '[readings]\npolicy_threshold = "high"\n\n[check]',
     "readings.policy_threshold: must be a finite number, got 'high'"),
    ('description = "', 'description = 3\n#', "description: must be a string, got 3"),
]


def _mount(tmp_path, have, instead):
    assert have in ANT, have
    path = tmp_path / "bad_ant.toml"
    path.write_text(ANT.replace(have, instead, 1))
    return path


@pytest.mark.parametrize("have, instead, said", MOUNT_CASES, ids=[c[1] for c in MOUNT_CASES])
def test_a_mount_value_out_of_its_range_is_refused_naming_file_and_field(tmp_path, have,
                                                                       instead, said):
    path = _mount(tmp_path, have, instead)
    with pytest.raises(mount.MountError) as e:
        mount.parse(path)
    assert str(e.value).startswith(f"{path}: {said}"), str(e.value)
    out = tmp_path / "out"
    proc = ebrl_here("run", "--robot", path, "--seeds", "0", "--steps", "5", "--out", out)
    assert proc.returncode == 2 and not out.exists()
    assert proc.stderr.strip().splitlines() == [f"ebrl: error: {e.value}"]


def test_every_gait_parameter_has_a_range_its_default_is_in():
    assert set(gait.RANGES) == set(gait.PARAMETERS)
    for name, value in gait.PARAMETERS.items():
        assert gait.RANGES[name].problem(value) is None, name


def test_a_mount_of_good_values_still_parses_as_before(tmp_path):
    path = _mount(tmp_path, "[check]", '[readings]\nradius = 1.5\nbump = "stop"\n\n[check]')
    m = mount.parse(path)
    assert m.readings == (("bump", "stop"), ("radius", 1.5)) and m.unit == 0.4


def _one_line(proc, said):
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and said in lines[0] and lines[0].startswith("ebrl"), proc.stderr
    assert "Traceback" not in proc.stderr


def test_a_robot_set_wider_than_the_corridors_is_refused_before_any_run(tmp_path):
    room = tmp_path / "narrow.txt"
    room.write_text("# cell 6\n*******\n*P   G*\n*******\n")
    out = tmp_path / "out"
    proc = ebrl_here("run", "--robot", "two_wheel", "--room", room, "--set", "radius=4",
                     "--seeds", "0", "--steps", "5", "--out", out)
    _one_line(proc, f"{room}: corridors of 6 units are narrower than the robot (8 units across)")
    assert not out.exists()


@pytest.mark.parametrize("args, said", [
    (["maze-study", "--sizes", "3x3,3x3"], "size 3x3 is given more than once"),
    (["maze-study", "--sizes", "3x3, 5x5,3x3"], "size 3x3 is given more than once"),
    (["run", "--seeds", "0-9,5"], "seed 5 is given more than once in '0-9,5'"),
    (["run", "--seeds", "3,3"], "seed 3 is given more than once"),
    (["run", "--robot", "two_wheel,two_wheel"], "robot two_wheel is given more than once"),
    (["ablate", "--readings", "bump,bump"], "--readings bump is given more than once"),
    (["ablate", "--combo", "bump=stop", "--combo", "bump=stop"], "--combo bump=stop is given more"),
    (["fit", "--space", "bump,bump"], "--space bump is given more than once"),
    (["rooms", "--show", "random:3x3:2147483648"],
     "random:3x3:2147483648: the seed must be 0..2147483647 (labmaze's seeds are 32-bit)"),
    (["run", "--room", "random:3x3:99999999999999999999"], "the seed must be 0..2147483647"),
])
def test_repeated_values_and_a_seed_past_labmaze_are_one_line(tmp_path, args, said):
    _one_line(ebrl_here(*args, cwd=tmp_path), said)
    assert list(tmp_path.iterdir()) == []


def test_a_map_with_a_byte_order_mark_is_read_as_without(tmp_path):
    plain = "# cell 10\n*****\n*P G*\n*****\n"
    path = tmp_path / "bom.txt"
    path.write_bytes(b"\xef\xbb\xbf" + plain.encode())
    assert rooms.load(str(path)).rows == rooms.parse(plain, "plain").rows
    proc = ebrl_here("rooms", "--show", path)
    assert proc.returncode == 0 and proc.stdout == plain
    path.write_bytes(b"\xff\xfe" + plain.encode("utf-16-le"))
    _one_line(ebrl_here("rooms", "--show", path), f"{path}: not a UTF-8 text file")


@pytest.mark.slow
def test_a_bad_input_met_in_a_worker_is_our_one_line_not_a_remote_traceback(tmp_path):
    """A map that turns bad once the driver has checked it (rewritten while the run waits,
    EBRL_TEST_HOLD): the worker raises MapError; the command ends as the driver's check
    would have, one line and exit status 2, nothing recorded as a failed run."""
    room = tmp_path / "room.txt"
    room.write_text("# cell 10\n*******\n*P   G*\n*******\n")
    hold = tmp_path / "hold"
    hold.touch()
    env = dict(os.environ, EBRL_TEST_HOLD=str(hold), PYTHONPATH=str(ROOT))
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [sys.executable, "-m", "experiments", "run", "--robot", "two_wheel", "--condition",
         "avoidance", "--seeds", "0", "--steps", "20", "--room", str(room), "--workers", "1",
         "--out", str(out), "--no-progress"],
        cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while not list(tmp_path.glob("hold.local.*")):
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.1)
        room.write_text("# cell 2\n*******\n*P   G*\n*******\n")
        hold.unlink()
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            proc.communicate()
    assert proc.returncode == 2, stderr
    assert "Traceback" not in stderr and "_RemoteTraceback" not in stderr
    assert stderr.strip().splitlines()[-1] == (
        f"ebrl: error: {room}: corridors of 2 units are narrower than the robot "
        f"({2 * _two_wheel_radius():.3g} units across); set '# cell N' larger")
    assert not list(pathlib.Path(out).rglob("run.json"))


def _two_wheel_radius():
    """The adopted protocol's two-wheel radius (tasks.protocols), the one the run uses."""
    from tasks.protocols import ADOPTED
    return dict(ADOPTED.robots["two_wheel"])["radius"]
