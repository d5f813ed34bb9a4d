"""A mount file read into a Mount: the top table, the bumper, the beams, the action (its
kind's own fields: tasks.mount.kinds), the readings and check tables."""
from __future__ import annotations

import importlib.util
import pathlib

from ebrl.readings import Range
from tasks.mount.fields import Fields, MountError, read
from tasks.mount.frame import FORWARDS
from tasks.mount.kinds import KINDS
from tasks.mount.parsed import Action, Beams, Bumper, Mount
from tasks.mount.spec import BEAMS
from tasks.readings import READING_BY_NAME

#: Joints of the base: its file's, a free joint added, slide x, slide y (and, for the
#: two-wheel drive, hinge yaw) added in place of the base's own, or slides x, y (and z)
#: added beside the base's own joints ("slides": held at its height; "slides_z": resting
#: on the floor by gravity).
JOINTS = ("file", "free", "planar", "slides", "slides_z")
#: What of the file a mount may drop: "world" the geoms of its world body (floor, walls,
#: markers), "lights", "skybox" (its skybox textures), "cameras", "actuators", "tendons",
#: "sensors" (all but the rangefinders the beams name).
DROPS = ("world", "lights", "skybox", "cameras", "actuators", "tendons", "sensors")
OPTIONS = ("timestep", "integrator", "flags")
#: The action kinds each drive takes (every drive has a beams arrangement, BEAMS), in the
#: kinds' registration order.
ACTIONS = {drive: tuple(name for name, kind in KINDS.items() if drive in kind.drives)
           for drive in BEAMS}

#: The top table's numbers: metres per paper unit (the paper's 0.1; the room is scaled by
#: unit / 0.1), MuJoCo's timestep (s) and the registry's time_scale.
UNIT = Range(float, 0.001, 100.0, high_note=" m per paper unit")
TIMESTEP = Range(float, 1e-4, 1.0, high_note=" s")
TIME_SCALE = Range(float, 0.0, 1000.0, low_open=True)

_TOP = {"name", "description", "file", "drive", "unit", "base", "joints", "drop",
        "drop_geoms", "drop_bodies", "keep_options", "timestep", "integrator", "time_scale",
        "condim", "forward", "rest",
        "bumper", "beams", "action", "readings", "check"}
_BUMPER = {"geom", "shape", "radius", "height", "half_length"}
_BEAMS = {"height", "sensors"}
_ACTION = {"kind"}.union(*(kind.keys for kind in KINDS.values()))


def resolve_file(text: str, where: str, mount_path: pathlib.Path) -> pathlib.Path:
    """A robot file named by a path (relative to the mount file) or by package:path."""
    if ":" in text and not pathlib.Path(text).is_absolute() and len(text.split(":", 1)[0]) > 1:
        package, rel = text.split(":", 1)
        try:
            spec = importlib.util.find_spec(package)
        except (ImportError, ValueError):
            spec = None
        if spec is None or not spec.submodule_search_locations:
            raise MountError(f"{mount_path}: {where}: package {package!r} is not installed")
        path = pathlib.Path(next(iter(spec.submodule_search_locations))) / rel
    else:
        path = (mount_path.parent / text).resolve()
    if not path.is_file():
        raise MountError(f"{mount_path}: {where}: no robot file at {path}")
    return path


def parse(path: str | pathlib.Path, text: str | None = None) -> Mount:
    """The Mount of a mount file; MountError on any bad field (the file is not compiled
    here: `check` does that). text: the file's text, for a mount not yet written at path
    (`ebrl check --tune`'s candidates; its robot file is found beside path as ever)."""
    path = pathlib.Path(path).resolve()   # every error names it so (FILE: FIELD: problem)
    data = read(path, text)
    fields = Fields(path)
    drive, model, joints = _parse_top(fields, data)
    bumper = _parse_bumper(fields, data)
    beams = _parse_beams(fields, data, drive)
    action = _parse_action(fields, data, drive, joints)
    readings, check = _parse_tables(fields, data, drive)
    integrator = _parse_integrator(fields, data)
    text, ranged, names = fields.text, fields.ranged, fields.names
    return Mount(path=path, name=text(data, "name", "name", path.stem),
                 file=data["file"], model=model, drive=drive,
                 unit=ranged(data, "unit", "unit", UNIT, 0.1), base=text(data, "base", "base"),
                 joints=joints, drop=names(data, "drop", "drop", DROPS),
                 drop_geoms=names(data, "drop_geoms", "drop_geoms"),
                 drop_bodies=names(data, "drop_bodies", "drop_bodies"),
                 keep_options=names(data, "keep_options", "keep_options", OPTIONS),
                 bumper=bumper, beams=beams, action=action,
                 timestep=ranged(data, "timestep", "timestep", TIMESTEP), integrator=integrator,
                 time_scale=ranged(data, "time_scale", "time_scale", TIME_SCALE, 1.0),
                 condim=_parse_condim(fields, data, joints),
                 forward=_parse_forward(fields, data, drive), rest=_parse_rest(fields, data),
                 readings=readings, check=check,
                 description=_description(fields, data))


def _description(fields, data):
    v = data.get("description", "")
    if not isinstance(v, str):
        fields.fail("description", f"must be a string, got {v!r}")
    return v


def _parse_top(fields, data):
    """The top table's keys, its required fields, the drive, the robot file (resolved)
    and the joints."""
    fail = fields.fail
    fields.table(data, _TOP, "")
    for key in ("file", "drive", "base"):
        if key not in data:
            fail(key, "missing (required)")
    drive = fields.text(data, "drive", "drive")
    if drive not in ACTIONS:
        fail("drive", f"unknown drive {drive!r}; valid: {', '.join(ACTIONS)}")
    model = resolve_file(fields.text(data, "file", "file"), "file", fields.path)
    joints = data.get("joints", "file")
    if joints not in JOINTS:
        fail("joints", f"must be one of {', '.join(JOINTS)}, got {joints!r}")
    return drive, model, joints


def _parse_bumper(fields, data) -> Bumper:
    """The bumper: the file's geom, or a shape added."""
    fail, number = fields.fail, fields.number
    bumper = fields.table(data.get("bumper", {}), _BUMPER, "bumper")
    if "geom" in bumper:
        if set(bumper) - {"geom"}:
            fail("bumper", "a file's geom (geom) or an added shape (shape, radius, height), not both")
        return Bumper(geom=fields.text(bumper, "geom", "bumper.geom"))
    if "shape" in bumper:
        shape = bumper["shape"]
        if shape not in ("sphere", "capsule"):
            fail("bumper.shape", f"must be sphere or capsule, got {shape!r}")
        if "radius" not in bumper:
            fail("bumper.radius", "missing (required with shape)")
        return Bumper(shape=shape, radius=number(bumper, "radius", "bumper.radius"),
                      height=number(bumper, "height", "bumper.height", 0.0, positive=False),
                      half_length=number(bumper, "half_length", "bumper.half_length", 0.0,
                                         positive=False))
    fail("bumper", "missing: geom = a geom of the file, or shape, radius, height")


def _parse_beams(fields, data, drive) -> Beams:
    """The beams: added at a height, or the file's rangefinders by name."""
    fail = fields.fail
    beams = fields.table(data.get("beams", {}), _BEAMS, "beams")
    if "sensors" in beams:
        if "height" in beams:
            fail("beams", "the file's rangefinders (sensors) or added beams (height), not both")
        listed = fields.names(beams, "sensors", "beams.sensors")
        count = BEAMS[drive][0]
        if len(listed) != count:
            fail("beams.sensors", f"the {drive} drive needs {count} rangefinders, got {len(listed)}")
        return Beams(sensors=listed)
    if "height" in beams:
        return Beams(height=fields.number(beams, "height", "beams.height", positive=False))
    fail("beams", "missing: height = the added beams' height above the base (m), "
                  "or sensors = the file's rangefinders in order")


def _parse_action(fields, data, drive, joints) -> Action:
    """The action: its kind's record, parsed by the kind."""
    fail = fields.fail
    table = fields.table(data.get("action", {}), _ACTION, "action")
    name = table.get("kind")
    if name not in ACTIONS[drive]:
        fail("action.kind", f"the {drive} drive takes one of {', '.join(ACTIONS[drive])}, "
                            f"got {name!r}")
    action = KINDS[name].parse(fields, table, drive)
    # (a [action.gait] table is not refused for the other kinds: it is ignored)
    extra = set(table) - {"kind", "gait"} - action.claimed()
    if extra:
        fail(f"action.{sorted(extra)[0]}", f"not a field of action kind {name!r}")
    action.check_joints(fields, joints)
    return action


def _parse_tables(fields, data, drive):
    """Mount.readings and Mount.check, from the readings and check tables."""
    fail = fields.fail
    readings = fields.table(data.get("readings", {}), set(READING_BY_NAME), "readings")
    for k, v in readings.items():  # each through the readings' registry (tasks.readings)
        try:
            READING_BY_NAME[k].check(v)
        except ValueError as e:
            fail(f"readings.{k}", str(e).removeprefix(f"{k} "))
    check = data.get("check", {})
    if not isinstance(check, dict):
        fail("check", "must be a table")
    valid = ("turn", "move", "falls") if drive == "two_wheel" else ("velocity_x", "velocity_y")
    for k in check:
        if k not in valid:
            fail(f"check.{k}", f"unknown key; valid: {', '.join(valid)}")
        fields.ranged(check, k, f"check.{k}", FALLS if k == "falls" else Range(float, 0.0, low_open=True))
    return (tuple(sorted(readings.items())),
            tuple(sorted((k, float(v)) for k, v in check.items())))


#: [check]'s falls: a count of falls allowed in `ebrl check`'s fuzz.
FALLS = Range(int, 0)


def _parse_integrator(fields, data):
    """The integrator field, one of models.INTEGRATORS, or None."""
    integrator = data.get("integrator")
    if integrator is not None:
        import models
        if integrator not in models.INTEGRATORS:
            fields.fail("integrator", f"unknown integrator {integrator!r}; valid: "
                                      f"{', '.join(models.INTEGRATORS)}")
    return integrator


#: A free robot's geoms' contact dimensionality on the floor (MuJoCo's condim values).
CONDIMS = (1, 3, 4, 6)


def _parse_condim(fields, data, joints):
    """The condim field: the robot's geoms' contact dimensionality (None: the file's)."""
    if "condim" not in data:
        return None
    v = data["condim"]
    if isinstance(v, bool) or v not in CONDIMS:
        fields.fail("condim", f"must be one of {', '.join(map(str, CONDIMS))}, got {v!r}")
    if joints in ("planar", "slides"):
        fields.fail("condim", f"joints = {joints}: its geoms touch nothing (condim is for "
                              "a robot that stands on the floor)")
    return int(v)


def _parse_forward(fields, data, drive):
    """The forward field: the base's axis the robot moves along (FORWARDS; default x)."""
    v = data.get("forward", "x")
    if not isinstance(v, str) or v not in FORWARDS:
        fields.fail("forward", f"must be one of {', '.join(FORWARDS)}, got {v!r}")
    if v != "x" and drive != "two_wheel":
        fields.fail("forward", f"the {drive} drive has no forward axis (its beams and "
                               "thrusts follow the room's axes)")
    return v


def _parse_rest(fields, data):
    """The rest field: a keyframe's name of the file, or a table of joint = value (rad
    for a hinge, m for a slide); None: the file's qpos0 (tasks.mount.frame.rest_values
    checks it against the file)."""
    if "rest" not in data:
        return None
    v = data["rest"]
    if isinstance(v, str):
        if not v:
            fields.fail("rest", "must be a keyframe's name or a table of joint = value")
        return v
    if not isinstance(v, dict) or not v:
        fields.fail("rest", "must be a keyframe's name or a table of joint = value")
    for name in v:
        fields.number(v, name, f"rest.{name}", positive=False)
    return tuple(sorted((name, float(value)) for name, value in v.items()))
