"""Mount errors in one style (issue 59, item 3): ``FILE: FIELD: problem``, FILE the mount
file's full path however it was named, whether the mount is refused when read
(tasks.mount.parsing), when its file is edited (tasks.mount.spec) or when the robot is
loaded into the room (a ContractError naming its field, tasks.load); a value wrong for
this robot names the one that fits. On dm_control's soccer boxhead and Ant, as `ebrl
check` sees them, from a folder beside the mount (a relative path)."""
import pytest

import tasks
from tasks import mount
import test_beams
import test_frames
from helpers import ROOT, ebrl_here


def _refused(tmp_path, name, text):
    """`ebrl check --robot err/NAME.toml`, run in tmp_path: (its one stderr line, the
    mount's full path)."""
    folder = tmp_path / "err"
    folder.mkdir(exist_ok=True)
    (folder / f"{name}.toml").write_text(text)
    proc = ebrl_here("check", "--robot", f"err/{name}.toml", "--actions", "5",
                     "--accuracy-actions", "5", cwd=tmp_path)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and proc.stdout == "", proc
    return lines[0], folder.resolve() / f"{name}.toml"


BOXHEAD = test_beams.BOXHEAD.format(height=-0.2)

#: (name, the mount's text, its field, a piece of the problem): one case of each stage.
CASES = [
    ("badfile", BOXHEAD.replace("boxhead.xml", "boxhead2.xml"), "file",
     "no robot file at "),                                             # read
    ("bump", BOXHEAD.replace('shape = "sphere"\nradius = 0.45\nheight = -0.65',
                             'geom = "nose"'), "bumper.geom", "no geom named 'nose'"),  # edited
    ("forward", BOXHEAD.replace('base = "head_body"', 'base = "head_body"\nforward = "y"'),
     "forward", "across its forward axis (1.00, 0.00): forward = \"x\" or \"-x\", the "
                "base's axis it moves along"),                          # loaded
    ("eyes", test_beams.BOXHEAD.format(height=0.0), "beams.height",
     "beams 'range_0' (its geom 'eye_l', "),                            # loaded
    ("dim", BOXHEAD.replace('joints = "slides_z"', 'joints = "slides"\ncondim = 9'),
     "condim", "must be one of 1, 3, 4, 6, got 9"),                    # read
]


@pytest.mark.parametrize("name, text, field, problem", CASES)
def test_every_mount_error_is_file_field_problem(tmp_path, name, text, field, problem):
    line, path = _refused(tmp_path, name, text)
    prefix = f"ebrl: error: {path}: {field}: "
    assert line.startswith(prefix) and problem in line, line
    assert "mount " not in line[:len(prefix)]


def test_joints_file_on_the_boxhead_names_the_field_and_slides_z(tmp_path):
    """The issue's boxhead: its head has only its steering hinge. joints = "file" named no
    field; joints = "free" suggested "file" or "slides", both wrong for a robot that
    rolls on the floor: both now name joints and slides_z."""
    slides_z = ('joints = "slides_z" adds slides x, y and z beside them (a robot that rolls '
                'or walks on the floor, resting on it by gravity)')
    line, path = _refused(tmp_path, "file", BOXHEAD.replace('"slides_z"', '"file"'))
    assert line == (f"ebrl: error: {path}: joints: body 'head_body' has no free joint and no "
                    "slides along x and y to move it in the room (its own: 'steer', a "
                    f"hinge): {slides_z}")
    line, path = _refused(tmp_path, "free", BOXHEAD.replace('"slides_z"', '"free"'))
    assert line == (f"ebrl: error: {path}: joints: body 'head_body' has joints of its own "
                    f"('steer', a hinge), so no free joint can be added: {slides_z}")


def test_the_joints_that_fit_follow_the_base_and_the_action(tmp_path):
    """A base with no joints, walked by a gait (dm_control's Ant): "free"; a base with a
    hinge of its own, pushed by servos added (the cart of test_frames): "slides"."""
    ant = (ROOT / "models" / "mounts" / "ant.toml").read_text()
    line, _ = _refused(tmp_path, "ant", ant.replace('joints = "free"', 'joints = "file"'))
    assert line.endswith("joints: body 'torso' has no free joint and no slides along x and y "
                         "to move it in the room (it has none): joints = \"free\" adds a free "
                         "joint (a robot that stands on the floor)"), line
    path = test_frames._cart(tmp_path, joints="file")
    with pytest.raises(mount.MountError) as refused:
        tasks.load(str(path), seed=0)
    assert str(refused.value) == (
        f"{path}: joints: body 'cart' has no free joint and no slides along x and y to move "
        "it in the room (its own: 'steer', a hinge): joints = \"slides\" adds slides x and y "
        "beside them (the base held at its height: a planar robot)")


def _docs():
    return (ROOT / "docs" / "adding_a_robot.md").read_text()


def _docs_block(marker):
    """docs/adding_a_robot.md's TOML block that holds `marker`."""
    blocks = [b.split("```", 1)[0] for b in _docs().split("```toml\n")[1:]]
    return next(b for b in blocks if marker in b)


def test_the_docs_boxhead_is_the_one_tested_here():
    """docs/adding_a_robot.md's boxhead (beams see the room) is test_beams' at -0.2 m,
    which `ebrl check` passes (test_beams), but for its comments."""
    docs = _docs_block("boxhead.xml")
    strip = lambda text: [line.split("#")[0].rstrip() for line in text.splitlines()  # noqa: E731
                          if line.split("#")[0].strip()]
    assert strip(docs) == strip(BOXHEAD)


@pytest.mark.parametrize("name, text", [
    ("my_boxhead", test_beams.BOXHEAD.format(height=0.0)),
    ("my_boxhead", BOXHEAD.replace('"slides_z"', '"free"')),
    ("my_ball", None),
])
def test_the_docs_quote_the_lines_the_commands_print(tmp_path, name, text):
    """Each refusal docs/adding_a_robot.md quotes for the boxhead and the rolling ball is
    the line `ebrl check` prints, but for the folder (/home/me in the docs)."""
    if text is None:   # the docs' rolling ball without its forward = "y"
        text = _docs_block("jumping_ball_with_head.xml").replace('forward = "y"', "")
    line, path = _refused(tmp_path, name, text)
    quoted = line.replace(str(path), f"/home/me/{name}.toml")
    assert quoted in _docs().splitlines(), quoted
