"""`ebrl check --tune` (issue 59, item 2; experiments.checks.tune): a mount's time_scale and
gains searched against the check's own limits, the tuned mount written beside the input
and never over a file. Its refusals, each one line before any work; the rewrite of the
mount's text, which changes those values and nothing else; and a small tune of dm_control's
soccer boxhead (tests/test_beams.py's BOXHEAD, from the rolling ball's values) as a real
process, whose file is the same for the same seed and whose measures are `ebrl check`'s on
the file it wrote."""
import os
import re
import time
import tomllib

import pytest

from experiments.checks import tune
from helpers import ebrl, ebrl_here
import test_beams

#: The boxhead mounted with the rolling ball's drive values (docs/adding_a_robot.md's
#: worked example): its moves overshoot the paper's 5% by four times.
BOXHEAD = (test_beams.BOXHEAD.format(height=-0.2)
           .replace("time_scale = 4.0", "time_scale = 2.5           # the ball's")
           .replace("kp = 80.0", "kp = 120.0").replace("kv = 30.0", "kv = 12.0"))


def _boxhead(folder, text=BOXHEAD, name="boxhead.toml"):
    folder.mkdir(exist_ok=True)
    path = folder / name
    path.write_text(text)
    return path


def _snapshot(folder):
    return sorted((str(p.relative_to(folder)), p.read_bytes() if p.is_file() else None)
                  for p in folder.rglob("*"))


def _refused(folder, *args):
    """`ebrl ARGS` in folder: exit 2 within seconds, one line on stderr, nothing on
    stdout, nothing written; the line."""
    before, started = _snapshot(folder), time.perf_counter()
    proc = ebrl_here(*args, cwd=folder)
    assert time.perf_counter() - started < 10.0   # refused before any simulation
    assert proc.returncode == 2, proc
    assert proc.stdout == "" and "Traceback" not in proc.stderr, proc
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(("ebrl: error: ", "ebrl check: error: ")), \
        proc.stderr
    assert _snapshot(folder) == before
    return lines[0]


REFUSALS = [
    (["check", "--tune"], "--tune takes one mount file: --robot FILE.toml"),
    (["check", "--tune", "--robot", "two_wheel,floating"], "--tune takes one mount file"),
    (["check", "--tune", "--robot", "diff_drive"], "'diff_drive' is a registered robot: its "
                                                   "drive values are its entry's in tasks/robots.py"),
    (["check", "--tune", "--robot", "car"], "'car' is a shipped mount"),
    (["check", "--tune", "--robot", "my.xml"], "my.xml is a robot file, not a mount"),
    (["check", "--tune", "--robot", "my.xml", "--drive", "two_wheel"], "not --drive"),
    (["check", "--tune", "--robot", "boxhead.toml", "--trials", "0"], "positive"),
    (["check", "--tune", "--robot", "boxhead.toml", "--trials", "abc"], "not an integer"),
    (["check", "--tune", "--robot", "boxhead.toml", "--trials", "100001"], "at most 100,000"),
    (["check", "--tune", "--robot", "boxhead.toml", "--sampler-seed", "-1"], "at least 0"),
    (["check", "--robot", "boxhead.toml", "--trials", "5"], "--trials is an option of --tune"),
    (["check", "--robot", "boxhead.toml", "--first-pass"], "--first-pass is an option of --tune"),
    (["check", "--tune", "--robot", "missing.toml"], "no mount file at"),
]


@pytest.mark.parametrize("args, message", REFUSALS, ids=[" ".join(a) for a, _ in REFUSALS])
def test_a_bad_tune_is_one_line_before_any_work(tmp_path, args, message):
    _boxhead(tmp_path)
    line = _refused(tmp_path, *args)
    assert message in line, line


def test_a_tune_never_writes_over_a_file(tmp_path):
    """The tuned mount's name taken, by a file or a folder: refused, both left as they are."""
    path = _boxhead(tmp_path)
    (tmp_path / "boxhead.tuned.toml").write_text("mine\n")
    line = _refused(tmp_path, "check", "--tune", "--robot", path)
    assert line == (f"ebrl: error: --tune: {tmp_path}/boxhead.tuned.toml exists (an earlier "
                    "tune's?): move or remove it; --tune never writes over a file"), line
    (tmp_path / "boxhead.tuned.toml").unlink()
    (tmp_path / "boxhead.tuned.toml").mkdir()
    assert "exists" in _refused(tmp_path, "check", "--tune", "--robot", path)


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into a read-only folder")
def test_a_tune_beside_a_mount_in_a_read_only_folder_is_refused(tmp_path):
    path = _boxhead(tmp_path / "ro")
    os.chmod(path.parent, 0o555)
    try:
        assert "cannot write in" in _refused(tmp_path, "check", "--tune", "--robot", path)
    finally:
        os.chmod(path.parent, 0o755)


def _inline_action(text):
    """The mount's [action] table written inline in its top table."""
    head, action = text.split("[action]\n")
    inline = ", ".join(line for line in action.splitlines() if line)
    return head.replace("[bumper]", f"action = {{ {inline} }}\n[bumper]")


@pytest.mark.parametrize("edit, field", [
    (lambda t: t.replace("kp = 120.0", "kp = [120.0,\n      120.0]"), "action.kp"),
    (_inline_action, "action.kp"),
])
def test_a_mount_whose_values_are_not_one_to_a_line_is_refused(tmp_path, edit, field):
    """--tune writes each value on its own line: a mount it cannot rewrite so (a list over
    two lines, an inline [action] table) is one line naming the field, before any work."""
    path = _boxhead(tmp_path, edit(BOXHEAD))
    tomllib.loads(path.read_text())   # a good TOML file all the same
    line = _refused(tmp_path, "check", "--tune", "--robot", path)
    assert line.startswith(f"ebrl: error: {path}: {field}: "), line


def test_the_rewrite_changes_the_values_and_nothing_else(tmp_path):
    """Lines that give a value are rewritten, their comments kept; a value the mount does
    not give is added to its table; every other line is as it was."""
    text = BOXHEAD.replace("time_scale = 2.5           # the ball's\n", "")
    fields = {"time_scale": 4.12, "kp": [83.4, 152.0], "kv": [31.0, 0.5]}
    out = tune.rewrite(text, tmp_path / "b.toml", fields, header="# tuned")
    data = tomllib.loads(out)
    assert data["time_scale"] == 4.12 and data["action"]["kp"] == [83.4, 152.0]
    assert out.startswith("# tuned\n")
    assert "time_scale = 4.12\n[bumper]" in out   # after the top table's last key
    assert "kp = [83.4, 152.0]\nkv = [31.0, 0.5]\n" in out
    kept = BOXHEAD.replace("time_scale = 2.5 ", "time_scale = 4.12 ")
    assert tune.rewrite(BOXHEAD, tmp_path / "b.toml", {"time_scale": 4.12}) == kept
    commented = BOXHEAD.replace("kp = 120.0", "kp = 120.0   # N m per rad")
    assert "kp = [1.0, 2.0]   # N m per rad\n" in tune.rewrite(
        commented, tmp_path / "b.toml", {"kp": [1.0, 2.0]})


def test_open_values_are_time_scale_and_a_gain_per_joint(tmp_path):
    from tasks import mount
    m = mount.parse(_boxhead(tmp_path))
    assert tune.open_values(m) == {"time_scale": 2.5, "kp_forward": 120.0, "kp_turn": 120.0,
                                   "kv_forward": 12.0, "kv_turn": 12.0}
    values = dict(tune.open_values(m), kp_turn=150.0)
    assert tune.fields_of(m, values) == {"time_scale": 2.5, "kp": [120.0, 150.0],
                                         "kv": [12.0, 12.0]}


#: A tune small enough for the slow tier: two trials (the mount as it is, one sampled),
#: each over 10 free-space and 20 random actions.
SMALL = ("--trials", "2", "--actions", "20", "--accuracy-actions", "10", "--no-progress")


def _measures(lines):
    """The check's lines without the robot's name and the fuzz's seconds."""
    return [re.sub(r" in \d+ s:", ":", line.split(": ", 1)[1]) for line in lines]


@pytest.mark.slow
def test_a_small_tune_of_the_boxhead_writes_its_values_beside_the_mount(tmp_path):
    """The tune as a user runs it (a process of its own): the tuned mount beside the
    input, the input unchanged byte for byte, the check's measures at the values found
    those of `ebrl check` on the written file, and the same seed the same file."""
    path = _boxhead(tmp_path / "a")
    proc = ebrl("check", "--tune", "--robot", path, *SMALL)
    assert proc.returncode in (0, 1), proc.stdout + proc.stderr
    out = tmp_path / "a" / "boxhead.tuned.toml"
    assert sorted(p.name for p in out.parent.iterdir()) == ["boxhead.toml", "boxhead.tuned.toml"]
    assert path.read_text() == BOXHEAD
    lines = proc.stdout.splitlines()
    assert lines[0].startswith(f"{path}: as it is (time_scale 2.5, kp [120.0, 120.0], kv "
                               "[12.0, 12.0]): worst move at "), lines[0]
    assert lines[0].endswith(" FAIL")
    assert lines[1].startswith(f"{path}: 2 trials (sampler seed 0; each 10 free-space and 20 "
                               "random actions) in "), lines[1]
    reported = [line for line in lines if line.startswith(f"{out}: ")]
    assert len(reported) == 5, proc.stdout
    assert lines[-1].startswith(f"{path}: wrote {out}" if proc.returncode == 0 else
                                f"{path}: no trial passed; the nearest written to {out}")

    data = tomllib.loads(out.read_text())
    found = f"time_scale {data['time_scale']!r}, kp {data['action']['kp']}, kv {data['action']['kv']}"
    assert f", {found}, worst " in lines[1], (found, lines[1])
    # the check on the written file, and the same tune again, in this process: the same
    # measures and the same file as the user's process gave
    again = ebrl_here("check", "--robot", out, "--actions", "20", "--accuracy-actions", "10")
    assert again.returncode == proc.returncode, again.stdout + again.stderr
    assert _measures(again.stdout.splitlines()) == _measures(reported)

    same = ebrl_here("check", "--tune", "--robot", _boxhead(tmp_path / "b"), *SMALL)
    assert same.returncode == proc.returncode, same.stdout + same.stderr
    assert (tmp_path / "b" / "boxhead.tuned.toml").read_bytes() == out.read_bytes()
