"""`ebrl check` says which way each error falls (issue 59, item 2's first part): short of
the command or past it, so a drive too slow or too weak (raise its gains, or time_scale)
is told from one too strong. On the soccer boxhead at the paper's step length, whose
ball cannot roll 2 units in 0.4 s. A robot that turns unstable fails in a line."""
import numpy as np

from experiments.checks import robotcheck
from helpers import ebrl_here
import test_beams
import test_joints


def test_way_by_hand():
    assert robotcheck.way(np.array([-0.1, -0.2, 0.3, 0.0])) == \
        "50% short of the command, 25% past it"


def test_the_boxhead_at_the_papers_step_length_falls_short(tmp_path):
    path = tmp_path / "fast.toml"
    path.write_text(test_beams.BOXHEAD.format(height=-0.2).replace("time_scale = 4.0",
                                                                   "time_scale = 1.0"))
    errors, limits, _, signed = robotcheck.free_space(str(path), 30)
    for key in ("turn", "move"):
        np.testing.assert_array_equal(np.abs(signed[key]), errors[key])
    assert errors["move"].max() > limits["move"]
    assert (signed["move"] < 0).all()   # every move short of its command: too slow
    assert robotcheck.way(signed["move"]) == "100% short of the command, 0% past it"


def test_a_robot_that_turns_unstable_fails_the_check_in_a_line(tmp_path):
    """A simulation that blows up (the tricycle's stiff velocity servos under Euler at 0.01
    s) is a FAIL line of `ebrl check`, exit status 1, not a traceback: a failure the
    search scores robotcheck.UNMEASURED."""
    (tmp_path / "t.xml").write_text(test_joints.TRICYCLE.format(
        actuators='<velocity name="drive" joint="roll" kv="50"/>'
                  '<velocity name="spin" joint="steer" kv="50"/>'))
    path = tmp_path / "t.toml"
    path.write_text(test_joints.TRICYCLE_MOUNT.format(name="t", gains="kp = 20.0\n")
                    .replace('"implicitfast"', '"Euler"').replace("0.002", "0.01"))
    proc = ebrl_here("check", "--robot", path, "--actions", "20", "--accuracy-actions", "10")
    assert proc.returncode == 1 and "Traceback" not in proc.stderr, proc
    assert proc.stdout.splitlines() == [
        f"{path}: free-space actions: unstable simulation at t=0.010 s FAIL",
        f"{path}: 20 random actions: unstable simulation at t=0.010 s FAIL"]
    checked = robotcheck.check(str(path), 20, 10)
    assert not checked.passed and checked.failed == 2
    assert checked.shares == {"free space": robotcheck.UNMEASURED, "fuzz": robotcheck.UNMEASURED}
