"""Mounts: an unchanged robot file entered into the room by a small TOML file.

A robot file of the naming contract (docs/adding_a_robot.md: a body ``base``, a geom
``hull``, rangefinders, the drive's actuators) needs no mount. Any other file does: its
mount says which body is the base, its root joints, its bumper, its beams, how the
drive's action reaches it and what of the file to drop. The file is read where it lies
(a path beside the mount, or ``package:path`` inside an installed package, resolved at
load time, never copied) and edited only in memory, as an MjSpec, before it is attached
to the room (models.compose). What the mount adds carries the contract's names; what it
names of the file is mapped in the model's text element models.NAMES_TEXT, which
tasks.navigation reads, so a mounted model is as self-describing as a contract file.

    name = "point"                      # default: the mount file's stem
    description = "..."
    file = "gymnasium:envs/mujoco/assets/point.xml"
    drive = "two_wheel"                 # a key of ACTIONS (tasks.robots.DRIVES)
    unit = 0.3333333333333333           # metres per paper unit (default 0.1)
    base = "torso"                      # the body whose frame is the robot's pose
    joints = "file"                     # "file" (the base's own), "free", "planar"
    drop = ["world", "lights", "skybox", "actuators"]
    keep_options = []                   # of the file's <option>: timestep, integrator, flags
    time_scale = 1.0                    # also timestep, integrator: the registry's fields
    [bumper]                            # geom = "a geom of the file", or an added shape:
    geom = "pointbody"                  # shape = "sphere" | "capsule", radius, height (m)
    [beams]                             # height = 0.5 (added, the drive's arrangement), or
    height = 0.5                        # sensors = [the file's rangefinders, in order]
    [action]
    kind = "servos"                     # servos, actuators, wheels, wheel_motors,
                                        # thrusters, gait
    [readings]                          # TaskConfig or agent fields (Robot.readings)

Every error is one line, ``<mount file>: <field>: <what is wrong>`` (MountError).
"""
import dataclasses
import importlib.util
import math
import pathlib
import tomllib

#: Joints of the base: its file's, a free joint added, or slide x, slide y (and, for the
#: two-wheel drive, hinge yaw) added in place of the base's own.
JOINTS = ("file", "free", "planar")
#: What of the file a mount may drop: "world" the geoms of its world body (floor, walls,
#: markers), "lights", "skybox" (its skybox textures), "cameras", "actuators", "tendons",
#: "sensors" (all but the rangefinders the beams name).
DROPS = ("world", "lights", "skybox", "cameras", "actuators", "tendons", "sensors")
OPTIONS = ("timestep", "integrator", "flags")
#: How the drive's action reaches the robot, by drive.
ACTIONS = {"two_wheel": ("servos", "actuators", "wheels", "wheel_motors", "gait"),
           "floating": ("thrusters", "actuators")}
#: The contract's actuator names an "actuators" action maps, by drive.
ACTUATOR_ROLES = {"two_wheel": ("forward", "turn", "grip"), "floating": ("thrust_x", "thrust_y")}
REQUIRED_ROLES = {"two_wheel": ("forward", "turn"), "floating": ("thrust_x", "thrust_y")}
#: The beams' arrangement per drive (Section 3.2): (count, first angle, step) in degrees,
#: counter-clockwise from the heading, leftmost first for the two-wheel robot's seven.
BEAMS = {"two_wheel": (7, 90.0, -30.0), "floating": (8, 0.0, 45.0)}

_TOP = {"name", "description", "file", "drive", "unit", "base", "joints", "drop",
        "drop_geoms", "drop_bodies", "keep_options", "timestep", "integrator", "time_scale",
        "bumper", "beams", "action", "readings", "check"}
_BUMPER = {"geom", "shape", "radius", "height", "half_length"}
_BEAMS = {"height", "sensors"}
_ACTION = {"kind", "forward", "turn", "grip", "thrust_x", "thrust_y", "left", "right", "gait",
           "kp", "kv", "force", "motors", *(f"{j}_{i}" for j in ("hip", "ankle") for i in range(4))}


class MountError(ValueError):
    """A bad mount: one line naming the mount file and the field."""


@dataclasses.dataclass(frozen=True)
class Mount:
    path: pathlib.Path          # the mount file
    name: str
    file: str                   # the robot file as written ("package:path" or a path)
    model: pathlib.Path         # the robot file, resolved
    drive: str
    unit: float
    base: str
    joints: str
    drop: tuple
    drop_geoms: tuple
    drop_bodies: tuple
    keep_options: tuple
    bumper: tuple               # ("geom", name) or (shape, radius, height, half_length)
    beams: tuple                # ("add", height) or ("sensors", name, ...)
    action: tuple               # (kind, (role, name) pairs...)
    #: (parameter, value) pairs of the action: the gait's (tasks.gait), the wheel servos'
    gait: tuple = ()
    timestep: float = None
    integrator: str = None
    time_scale: float = 1.0
    readings: tuple = ()
    description: str = ""
    #: `ebrl check`'s accuracy limits where the drive's 5% is not reached, as (error,
    #: limit) pairs ("turn" rad, "move" units, "velocity_x", "velocity_y" units/step).
    check: tuple = ()


def resolve_file(text, where, mount_path):
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


def parse(path):
    """The Mount of a mount file; MountError on any bad field (the file is not compiled
    here: `check` does that)."""
    path = pathlib.Path(path)
    data = _read(path)
    fields = _Fields(path)
    drive, model, joints = _parse_top(fields, data)
    bumper = _parse_bumper(fields, data)
    beams = _parse_beams(fields, data, drive)
    action, gait = _parse_action(fields, data, drive, joints)
    readings, check = _parse_tables(fields, data, drive)
    integrator = _parse_integrator(fields, data)
    text, number, names = fields.text, fields.number, fields.names
    return Mount(path=path.resolve(), name=text(data, "name", "name", path.stem),
                 file=data["file"], model=model, drive=drive,
                 unit=number(data, "unit", "unit", 0.1), base=text(data, "base", "base"),
                 joints=joints, drop=names(data, "drop", "drop", DROPS),
                 drop_geoms=names(data, "drop_geoms", "drop_geoms"),
                 drop_bodies=names(data, "drop_bodies", "drop_bodies"),
                 keep_options=names(data, "keep_options", "keep_options", OPTIONS),
                 bumper=bumper, beams=beams, action=action, gait=gait,
                 timestep=number(data, "timestep", "timestep"), integrator=integrator,
                 time_scale=number(data, "time_scale", "time_scale", 1.0),
                 readings=readings, check=check,
                 description=str(data.get("description", "")))


def _read(path):
    """The mount file's TOML as a dict."""
    if not path.is_file():
        raise MountError(f"no mount file at {path}")
    try:
        return tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise MountError(f"{path}: not a TOML file: {e}") from None


class _Fields:
    """The field checks of one mount file: each fails with MountError naming it."""

    def __init__(self, path):
        self.path = path

    def fail(self, field, message):
        raise MountError(f"{self.path}: {field}: {message}")

    def table(self, d, keys, where):
        if not isinstance(d, dict):
            self.fail(where, "must be a table")
        for k in d:
            if k not in keys:
                self.fail(f"{where}.{k}" if where else k,
                          f"unknown key; valid: {', '.join(sorted(keys))}")
        return d

    def text(self, d, key, where, default=None):
        v = d.get(key, default)
        if v is default and default is None and key not in d:
            return None
        if not isinstance(v, str) or not v:
            self.fail(where, "must be a non-empty string")
        return v

    def number(self, d, key, where, default=None, positive=True):
        if key not in d:
            return default
        v = d[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            self.fail(where, f"must be a number, got {v!r}")
        if positive and v <= 0:
            self.fail(where, f"must be positive, got {v!r}")
        return float(v)

    def names(self, d, key, where, valid=None):
        v = d.get(key, [])
        if not isinstance(v, list) or not all(isinstance(x, str) and x for x in v):
            self.fail(where, "must be a list of strings")
        if valid is not None:
            for x in v:
                if x not in valid:
                    self.fail(where, f"unknown {x!r}; valid: {', '.join(valid)}")
        return tuple(v)


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


def _parse_bumper(fields, data):
    """Mount.bumper: ("geom", name) or (shape, radius, height, half_length)."""
    fail, number = fields.fail, fields.number
    bumper = fields.table(data.get("bumper", {}), _BUMPER, "bumper")
    if "geom" in bumper:
        if set(bumper) - {"geom"}:
            fail("bumper", "a file's geom (geom) or an added shape (shape, radius, height), not both")
        return ("geom", fields.text(bumper, "geom", "bumper.geom"))
    if "shape" in bumper:
        shape = bumper["shape"]
        if shape not in ("sphere", "capsule"):
            fail("bumper.shape", f"must be sphere or capsule, got {shape!r}")
        if "radius" not in bumper:
            fail("bumper.radius", "missing (required with shape)")
        return (shape, number(bumper, "radius", "bumper.radius"),
                number(bumper, "height", "bumper.height", 0.0, positive=False),
                number(bumper, "half_length", "bumper.half_length", 0.0, positive=False))
    fail("bumper", "missing: geom = a geom of the file, or shape, radius, height")


def _parse_beams(fields, data, drive):
    """Mount.beams: ("add", height) or ("sensors", name, ...)."""
    fail = fields.fail
    beams = fields.table(data.get("beams", {}), _BEAMS, "beams")
    if "sensors" in beams:
        if "height" in beams:
            fail("beams", "the file's rangefinders (sensors) or added beams (height), not both")
        listed = fields.names(beams, "sensors", "beams.sensors")
        count = BEAMS[drive][0]
        if len(listed) != count:
            fail("beams.sensors", f"the {drive} drive needs {count} rangefinders, got {len(listed)}")
        return ("sensors", *listed)
    if "height" in beams:
        return ("add", fields.number(beams, "height", "beams.height", positive=False))
    fail("beams", "missing: height = the added beams' height above the base (m), "
                  "or sensors = the file's rangefinders in order")


def _parse_action(fields, data, drive, joints):
    """Mount.action (kind, (role, name) pairs...) and Mount.gait."""
    fail = fields.fail
    action = fields.table(data.get("action", {}), _ACTION, "action")
    kind = action.get("kind")
    if kind not in ACTIONS[drive]:
        fail("action.kind", f"the {drive} drive takes one of {', '.join(ACTIONS[drive])}, "
                            f"got {kind!r}")
    roles = ()
    gait = ()
    if kind == "actuators":
        roles = _actuator_roles(fields, action, drive)
    elif kind == "wheels":
        roles, gait = _wheel_roles(fields, action)
    elif kind == "wheel_motors":
        roles, gait = _wheel_motor_roles(fields, action)
    elif kind == "gait":
        roles, gait = _gait_roles(fields, action)
    listed = {"motors"} if kind == "wheel_motors" else set()
    extra = (set(action) - {"kind", "gait"} - listed - {r for r, _ in roles}
             - {k for k, _ in gait})
    if extra:
        fail(f"action.{sorted(extra)[0]}", f"not a field of action kind {kind!r}")
    if kind == "servos" and joints == "free":
        fail("action.kind", "servos drive planar joints (joints = file or planar), not a free joint")
    if kind == "wheel_motors" and joints == "planar":
        fail("joints", "wheel_motors roll the file's wheels on a free base (joints = file or "
                       "free); planar replaces the base's joints and drops the file's motors")
    return (kind, *roles), gait


def _actuator_roles(fields, action, drive):
    """An "actuators" action's (role, the file's actuator) pairs."""
    for role in REQUIRED_ROLES[drive]:
        if role not in action:
            fields.fail(f"action.{role}", "missing: the file's actuator for it")
    return tuple((r, fields.text(action, r, f"action.{r}")) for r in ACTUATOR_ROLES[drive]
                 if r in action)


def _wheel_joints(fields, action):
    """The (role, the file's wheel joint) pairs of a "wheels" or "wheel_motors" action."""
    from tasks.two_wheel import WHEEL_JOINTS
    for role in WHEEL_JOINTS:
        if role not in action:
            fields.fail(f"action.{role}", "missing: the file's wheel joint")
    return tuple((r, fields.text(action, r, f"action.{r}")) for r in WHEEL_JOINTS)


def _wheel_roles(fields, action):
    """A "wheels" action's (role, the file's wheel joint) pairs and its servos' gains."""
    roles = _wheel_joints(fields, action)
    # the wheel servos' gains: diff_drive.xml's unless given (kp N m/rad, kv N m s/rad,
    # force the servo's torque limit, N m)
    gains = tuple((k, fields.number(action, k, f"action.{k}", d))
                  for k, d in (("kp", 2.0), ("kv", 0.05), ("force", 0.12)))
    return roles, gains


def _wheel_motor_roles(fields, action):
    """A "wheel_motors" action's (role, name) pairs, the file's wheel joints ("left",
    "right") and its motors (tasks.two_wheel.MOTOR_ROLE: "motor_0", ...), and its PD
    gains (kp N m/rad, kv N m s/rad: required, a robot's own)."""
    from tasks.two_wheel import MOTOR_ROLE
    fail = fields.fail
    roles = _wheel_joints(fields, action)
    if "motors" not in action:
        fail("action.motors", "missing: the file's motors that turn the wheels, as a list")
    motors = fields.names(action, "motors", "action.motors")
    if len(motors) < 2 or len(set(motors)) != len(motors):
        fail("action.motors", f"needs two or more different motors of the file, got {list(motors)}")
    for k in ("kp", "kv"):
        if k not in action:
            fail(f"action.{k}", "missing: the PD gain on the wheel angles (a robot's own)")
    roles += tuple((MOTOR_ROLE.format(k), name) for k, name in enumerate(motors))
    gains = tuple((k, fields.number(action, k, f"action.{k}", positive=k == "kp"))
                  for k in ("kp", "kv"))
    if dict(gains)["kv"] < 0:
        fail("action.kv", f"must not be negative, got {dict(gains)['kv']!r}")
    return roles, gains


def _gait_roles(fields, action):
    """A "gait" action's (role, the file's motor) pairs and its gait's parameters."""
    fail = fields.fail
    roles = tuple((r, fields.text(action, r, f"action.{r}")) for r in
                  (f"{j}_{i}" for j in ("hip", "ankle") for i in range(4)) if r in action)
    g = action.get("gait", {})
    if not isinstance(g, dict):
        fail("action.gait", "must be a table")
    from tasks import gait as gait_module
    for k, v in g.items():
        if k not in gait_module.PARAMETERS:
            fail(f"action.gait.{k}", f"unknown key; valid: {', '.join(gait_module.PARAMETERS)}")
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            fail(f"action.gait.{k}", f"must be a number, got {v!r}")
    return roles, tuple(sorted((k, float(v)) for k, v in g.items()))


def _parse_tables(fields, data, drive):
    """Mount.readings and Mount.check, from the readings and check tables."""
    fail = fields.fail
    readings = data.get("readings", {})
    if not isinstance(readings, dict):
        fail("readings", "must be a table")
    check = data.get("check", {})
    if not isinstance(check, dict):
        fail("check", "must be a table")
    valid = ("turn", "move", "falls") if drive == "two_wheel" else ("velocity_x", "velocity_y")
    for k in check:
        if k not in valid:
            fail(f"check.{k}", f"unknown key; valid: {', '.join(valid)}")
        fields.number(check, k, f"check.{k}", positive=k != "falls")
    return (tuple(sorted(readings.items())),
            tuple(sorted((k, float(v)) for k, v in check.items())))


def _parse_integrator(fields, data):
    """The integrator field, one of models.INTEGRATORS, or None."""
    integrator = data.get("integrator")
    if integrator is not None:
        import models
        if integrator not in models.INTEGRATORS:
            fields.fail("integrator", f"unknown integrator {integrator!r}; valid: "
                                      f"{', '.join(models.INTEGRATORS)}")
    return integrator


def _fail(mount, field, message):
    raise MountError(f"{mount.path}: {field}: {message}")


def _by_name(items, name):
    return next((x for x in items if x.name == name), None)


def _file_actuator(mount, spec, field, name):
    """The file's actuator `name`, or the mount's one-line error at `field`."""
    actuator = _by_name(spec.actuators, name)
    if actuator is None:
        _fail(mount, field, f"no actuator named {name!r} in {mount.model}")
    return actuator


def robot_spec(mount):
    """The robot file's MjSpec, edited as the mount says (the file itself is untouched)."""
    import models
    spec, base = _load(mount)
    names = {}
    if mount.base != "base":
        names["base"] = mount.base
    planar = mount.joints == "planar" or (mount.joints == "file" and not _has_free(base))
    beam_names = _drop(mount, spec, names)
    _root_joints(mount, spec, base)
    _bumper(mount, spec, base, planar, names)
    _beams(mount, spec, base, beam_names)
    _drive_actuators(mount, spec, base, names)
    _options(mount, spec)
    if names:
        spec.add_text(name=models.NAMES_TEXT,
                      data=" ".join(f"{k}={v}" for k, v in sorted(names.items())))
    return spec


def _load(mount):
    """The robot file's MjSpec and its base body."""
    import mujoco
    try:
        spec = mujoco.MjSpec.from_file(str(mount.model))
    except ValueError as e:
        _fail(mount, "file", f"{mount.model} is not a MuJoCo model: {str(e).splitlines()[0]}")
    base = spec.body(mount.base)
    if base is None or base.name == "world":
        _fail(mount, "base", f"no body named {mount.base!r} in {mount.model}")
    return spec, base


def _drop(mount, spec, names):
    """Deletes what the mount drops, and what the drive's own elements replace; returns
    the names of the file's rangefinders the beams read."""
    kind = mount.action[0]
    drop = set(mount.drop)
    if kind in ("servos", "thrusters", "wheels"):
        drop |= {"actuators"}      # the drive's own actuators replace the file's
    if mount.joints == "planar":
        drop |= {"actuators", "tendons"}   # they may act on the joints replaced
    if kind == "wheel_motors":
        _check_wheel_motors(mount, spec, drop)
    if kind == "actuators":
        for role, name in mount.action[1:]:
            _file_actuator(mount, spec, f"action.{role}", name)
            if name != role:
                names[role] = name
    for field, find in (("drop_bodies", spec.body), ("drop_geoms", spec.geom)):
        for name in getattr(mount, field):
            element = find(name)
            if element is None:
                _fail(mount, field, f"no {field[5:-1]} named {name!r} in {mount.model}")
            spec.delete(element)
    _drop_categories(spec, drop)
    return _drop_sensors(mount, spec, drop)


def _drop_categories(spec, drop):
    """Deletes every element of the categories in drop (but sensors: _drop_sensors)."""
    import mujoco
    skybox = mujoco.mjtTexture.mjTEXTURE_SKYBOX
    elements = {"world": lambda: spec.worldbody.geoms, "lights": lambda: spec.lights,
                "cameras": lambda: spec.cameras, "actuators": lambda: spec.actuators,
                "tendons": lambda: spec.tendons,
                "skybox": lambda: [x for x in spec.textures if x.type == skybox]}
    for category, listed in elements.items():
        if category in drop:
            for element in list(listed()):
                spec.delete(element)


def _drop_sensors(mount, spec, drop):
    """Deletes every rangefinder the beams do not name (every sensor, with "sensors" in
    drop); returns the names of those they do."""
    import mujoco
    beam_names = mount.beams[1:] if mount.beams[0] == "sensors" else ()
    for name in beam_names:
        sensor = _by_name(spec.sensors, name)
        if sensor is None or sensor.type != mujoco.mjtSensor.mjSENS_RANGEFINDER:
            _fail(mount, "beams.sensors", f"no rangefinder named {name!r} in {mount.model}")
    for sensor in list(spec.sensors):
        is_beam = sensor.type == mujoco.mjtSensor.mjSENS_RANGEFINDER
        if ("sensors" in drop or is_beam) and sensor.name not in beam_names:
            spec.delete(sensor)   # only the beams the mount names (or adds) are read
    return beam_names


def _root_joints(mount, spec, base):
    """The base's joints: slides x, y (and hinge yaw) in place of its own for "planar",
    a free joint added for "free"."""
    import mujoco
    if mount.joints == "planar":
        for joint in list(base.joints):
            spec.delete(joint)
        _plain_joint(base, "x", mujoco.mjtJoint.mjJNT_SLIDE, [1, 0, 0])
        _plain_joint(base, "y", mujoco.mjtJoint.mjJNT_SLIDE, [0, 1, 0])
        if mount.drive == "two_wheel":
            _plain_joint(base, "yaw", mujoco.mjtJoint.mjJNT_HINGE, [0, 0, 1])
    elif mount.joints == "free":
        if list(base.joints):
            _fail(mount, "joints", f"body {mount.base!r} has joints of its own: joints = \"file\"")
        base.add_freejoint(name="root")


# The room's contact bits (models/__init__.py): the bumper 2 / 1 touches walls only;
# a planar robot's other geoms touch nothing; a free robot's touch the walls and the
# floor (0 / 5), never the bumper or each other.
def _bumper(mount, spec, base, planar, names):
    """The bumper (the file's geom, or a shape added) and the room's contact bits."""
    hull = _file_bumper(mount, spec, names) if mount.bumper[0] == "geom" else None
    contract = mount.bumper[0] == "geom" and mount.bumper[1] == "hull" and mount.base == "base"
    if not contract:   # a contract file keeps its own bits; a mounted one gets the room's
        for body in _bodies(base):
            for geom in body.geoms:
                if geom is hull:
                    continue
                geom.contype, geom.conaffinity = (0, 0) if planar else (0, 5)
    if hull is None:
        hull = _added_bumper(mount, base, planar)
    if not contract:
        hull.contype, hull.conaffinity, hull.condim = 2, 1, 1
        hull.solref = [0.02, 1]
        hull.solimp = [0.99, 0.999, 0.001, 0.5, 2]


def _file_bumper(mount, spec, names):
    """The file's geom the bumper names: a sphere, cylinder or capsule on the base."""
    import mujoco
    hull = spec.geom(mount.bumper[1])
    if hull is None:
        _fail(mount, "bumper.geom", f"no geom named {mount.bumper[1]!r} in {mount.model}")
    if hull.type not in (mujoco.mjtGeom.mjGEOM_SPHERE, mujoco.mjtGeom.mjGEOM_CYLINDER,
                         mujoco.mjtGeom.mjGEOM_CAPSULE):
        _fail(mount, "bumper.geom", f"geom {mount.bumper[1]!r} must be a sphere, cylinder "
                                     "or capsule (its radius is the robot's)")
    if _owner(spec, hull) != mount.base:
        _fail(mount, "bumper.geom", f"geom {mount.bumper[1]!r} is not on the base body "
                                     f"{mount.base!r}")
    if mount.bumper[1] != "hull":
        names["hull"] = mount.bumper[1]
    return hull


def _added_bumper(mount, base, planar):
    """The bumper's shape added to the base as the geom hull (massless on a free base)."""
    import mujoco
    shape, radius, height, half = mount.bumper
    hull = base.add_geom(name="hull", pos=[0, 0, height], group=3,
                         type=(mujoco.mjtGeom.mjGEOM_SPHERE if shape == "sphere"
                               else mujoco.mjtGeom.mjGEOM_CAPSULE),
                         size=[radius, half, 0], mass=0 if not planar else 1,
                         rgba=[0.2, 0.35, 0.8, 0.15])
    if not planar:
        hull.mass = 0.0
        hull.density = 0.0
    return hull


def _beams(mount, spec, base, beam_names):
    """The drive's beams added to the base, or the file's rangefinders in the mount's
    order."""
    import mujoco

    import models
    if mount.beams[0] == "add":
        count, first, step = BEAMS[mount.drive]
        for i in range(count):
            angle = math.radians(first + i * step)
            site = base.add_site(name=f"range_{i}", pos=[0, 0, mount.beams[1]],
                                 zaxis=[math.cos(angle), math.sin(angle), 0], group=4,
                                 size=[0.01 * mount.unit / models.UNIT, 0, 0],
                                 rgba=[1, 0.2, 0.2, 1])
            _rangefinder(spec, f"range_{i}", site.name)
    elif list(beam_names) != [s.name for s in spec.sensors
                              if s.type == mujoco.mjtSensor.mjSENS_RANGEFINDER]:
        # re-declared one after another, in the mount's order (tasks.navigation reads
        # the rangefinders as one block)
        sites = {}
        for name in beam_names:
            sensor = _by_name(spec.sensors, name)
            sites[name] = sensor.objname
            spec.delete(sensor)
        for name in beam_names:
            _rangefinder(spec, name, sites[name])


def _drive_actuators(mount, spec, base, names):
    """The actuators of the mount's action kind (an "actuators" action uses the file's,
    named in _drop)."""
    kind = mount.action[0]
    if kind == "servos":
        _servos(mount, spec, base)
    elif kind == "thrusters":
        _thrusters(mount, spec, base)
    elif kind == "wheels":
        _wheels(mount, spec)
    elif kind == "gait":
        _check_gait(mount, spec)
    if kind in ("gait", "wheel_motors"):   # the file's joints and motors, by role
        names.update((role, name) for role, name in mount.action[1:] if role != name)


def _servos(mount, spec, base):
    """two_wheel.xml's servos: kv is set at load time (tasks.two_wheel.Physics)."""
    import mujoco
    base.add_site(name="drive")
    _actuator(spec, "forward", mujoco.mjtTrn.mjTRN_SITE, "drive",
              [1, 0, 0, 0, 0, 0]).set_to_velocity(kv=1)
    _actuator(spec, "grip", mujoco.mjtTrn.mjTRN_SITE, "drive",
              [0, 1, 0, 0, 0, 0]).set_to_velocity(kv=1)
    yaw = "yaw" if mount.joints == "planar" else _yaw_joint(mount, base)
    _actuator(spec, "turn", mujoco.mjtTrn.mjTRN_JOINT, yaw).set_to_velocity(kv=1)


def _thrusters(mount, spec, base):
    """The floating drive's motors on the base's slides x and y."""
    import mujoco
    joints = ("x", "y") if mount.joints == "planar" else _slides(mount, base)
    for role, joint in zip(("thrust_x", "thrust_y"), joints):
        _actuator(spec, role, mujoco.mjtTrn.mjTRN_JOINT, joint).set_to_motor()


def _wheels(mount, spec):
    """diff_drive.xml's integrated-velocity servos on the file's wheel joints
    (tasks.two_wheel.WheelPhysics)."""
    import mujoco
    for role, joint in mount.action[1:]:
        if spec.joint(joint) is None:
            _fail(mount, f"action.{role}", f"no joint named {joint!r} in {mount.model}")
        act = _actuator(spec, f"{role}_wheel", mujoco.mjtTrn.mjTRN_JOINT, joint)
        gains = dict(mount.gait)
        act.set_to_intvelocity(kp=gains["kp"], kv=gains["kv"])
        act.forcerange = [-gains["force"], gains["force"]]
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.actrange, act.actlimited = [-1e6, 1e6], mujoco.mjtLimited.mjLIMITED_TRUE


def _options(mount, spec):
    """The room's flags (unless the mount keeps the file's) and gravity."""
    import mujoco

    import models
    room = mujoco.MjSpec.from_file(str(models.ROOM_FILE))
    keep = set(mount.keep_options)
    if "flags" not in keep:
        spec.option.disableflags = room.option.disableflags
        spec.option.enableflags = room.option.enableflags
    spec.option.gravity = room.option.gravity


# What a mount adds is set in full here: the file's <default> would otherwise reach it
# (point_mass.xml's joints default to limited and damped, its motors to gear 0.1).
def _plain_joint(body, name, kind, axis):
    import mujoco
    return body.add_joint(name=name, type=kind, axis=axis, limited=mujoco.mjtLimited.mjLIMITED_FALSE,
                          damping=0.0, stiffness=0.0, armature=0.0, frictionloss=0.0,
                          pos=[0, 0, 0], ref=0.0, springref=0.0,
                          actfrclimited=mujoco.mjtLimited.mjLIMITED_FALSE)


def _actuator(spec, name, trntype, target, gear=(1, 0, 0, 0, 0, 0)):
    import mujoco
    off = mujoco.mjtLimited.mjLIMITED_FALSE
    return spec.add_actuator(name=name, trntype=trntype, target=target, gear=list(gear),
                             ctrllimited=off, forcelimited=off, actlimited=off)


def _rangefinder(spec, name, site):
    """A rangefinder on a site, reading the distance (as the XML's default data="dist")."""
    import mujoco
    sensor = spec.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_RANGEFINDER,
                             objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site)
    sensor.intprm[0] = 1
    return sensor


def _has_free(body):
    import mujoco
    return any(j.type == mujoco.mjtJoint.mjJNT_FREE for j in body.joints)


def _bodies(body):
    yield body
    for child in body.bodies:
        yield from _bodies(child)


def _owner(spec, geom):
    for body in _bodies(spec.worldbody):
        if any(g is geom or (g.name and g.name == geom.name) for g in body.geoms):
            return body.name
    return None


def _yaw_joint(mount, base):
    import mujoco
    for j in base.joints:
        if j.type == mujoco.mjtJoint.mjJNT_HINGE and tuple(j.axis) == (0, 0, 1):
            return j.name
    _fail(mount, "action.kind", f"servos turn a hinge about z on {mount.base!r}; it has none "
                                "(joints = \"planar\" adds one)")


def _slides(mount, base):
    import mujoco
    out = {}
    for j in base.joints:
        if j.type == mujoco.mjtJoint.mjJNT_SLIDE:
            out[tuple(j.axis)] = j.name
    if (1, 0, 0) not in out or (0, 1, 0) not in out:
        _fail(mount, "action.kind", f"thrusters push slides along x and y on {mount.base!r}; "
                                    "it has none (joints = \"planar\" adds them)")
    return out[(1, 0, 0)], out[(0, 1, 0)]


def physics_class(mount):
    """The Physics class of the mount's drive and action kind."""
    from tasks import floating, two_wheel
    kind = mount.action[0]
    if mount.drive == "floating":
        return floating.Physics
    if kind == "gait":
        from tasks import gait
        return gait.physics_class(mount)
    if kind == "wheel_motors":
        return two_wheel.motor_wheel_physics(mount)
    return two_wheel.WheelPhysics if kind == "wheels" else two_wheel.Physics


def _check_gait(mount, spec):
    """The file's motors a gait mount names: 4 hips and 4 ankles (tasks.gait.LEGS)."""
    from tasks.gait import LEGS
    roles = dict(mount.action[1:])
    for role in [f"hip_{i}" for i in range(LEGS)] + [f"ankle_{i}" for i in range(LEGS)]:
        name = roles.get(role)
        if name is None:
            _fail(mount, f"action.{role}", "missing: the file's motor for it")
        _file_actuator(mount, spec, f"action.{role}", name)


def _check_wheel_motors(mount, spec, drop):
    """The file's wheel hinges and motors a wheel_motors mount names (before the drop:
    its motors and their tendons are kept)."""
    import mujoco

    from tasks.two_wheel import WHEEL_JOINTS
    if "actuators" in drop:
        _fail(mount, "drop", "wheel_motors turn the wheels through the file's motors: "
                             "do not drop its actuators")
    for role, name in mount.action[1:]:
        field = f"action.{role}" if role in WHEEL_JOINTS else "action.motors"
        if role != name and any(ch.isspace() for ch in name):   # models.NAMES_TEXT's pairs
            _fail(mount, field, f"{name!r}: a name with spaces cannot be mapped")
        if role in WHEEL_JOINTS:
            joint = spec.joint(name)
            if joint is None:
                _fail(mount, field, f"no joint named {name!r} in {mount.model}")
            if joint.type != mujoco.mjtJoint.mjJNT_HINGE:
                _fail(mount, field, f"joint {name!r} is not a hinge (a wheel's joint)")
            continue
        motor = _file_actuator(mount, spec, field, name)
        if motor.trntype == mujoco.mjtTrn.mjTRN_TENDON and "tendons" in drop:
            _fail(mount, "drop", f"motor {name!r} pulls a tendon of the file: do not drop "
                                 "its tendons")
