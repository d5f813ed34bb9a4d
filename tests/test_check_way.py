"""`ebrl check` says which way each error falls (issue 59, item 2's first part): short of
the command or past it, so a drive too slow or too weak (raise its gains, or time_scale)
is told from one too strong. On the soccer boxhead at the paper's step length, whose
ball cannot roll 2 units in 0.4 s."""
import numpy as np

from experiments.checks import robotcheck
import test_beams


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
