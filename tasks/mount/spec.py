"""A mount's edit of the robot file: its MjSpec, loaded from where the file lies and
edited in memory (the file itself is untouched) before models.compose attaches it to the
room. What the action kind adds or maps is its own (tasks.mount.kinds); the helpers it
builds with are here."""
from __future__ import annotations

import math

import models
from tasks.mount import frame as frames
from tasks.mount.fields import fail
from tasks.mount.parsed import Mount

#: The beams' arrangement per drive (Section 3.2): (count, first angle, step) in degrees,
#: counter-clockwise from the heading, leftmost first for the two-wheel robot's seven.
BEAMS = {"two_wheel": (7, 90.0, -30.0), "floating": (8, 0.0, 45.0)}


def robot_spec(mount: Mount):
    """The robot file's MjSpec, edited as the mount says (the file itself is untouched)."""
    spec, base = _load(mount)
    frame = frames.base_frame(mount)
    names = {}
    if mount.base != "base":
        names["base"] = mount.base
    planar = (mount.joints in ("planar", "slides")
              or (mount.joints == "file" and not _has_free(base)))
    beam_names = _drop(mount, spec, names)
    _root_joints(mount, spec, base, frame)
    _bumper(mount, spec, base, planar, names, frame)
    _beams(mount, spec, base, beam_names, frame)
    _robot_frame(mount, spec, base, frame)
    mount.action.edit(mount, spec, base, names)
    _options(mount, spec)
    _rest(mount, spec)
    if names:
        spec.add_text(name=models.NAMES_TEXT,
                      data=" ".join(f"{k}={v}" for k, v in sorted(names.items())))
    return spec


def _robot_frame(mount, spec, base, frame):
    """The site FRAME_SITE on the base with the robot's frame (x forward, z up), where it
    is not the base's own (tasks.navigation reads the pose from it)."""
    if frame.robot is None:
        return
    if spec.site(frames.FRAME_SITE) is not None:
        fail(mount.path, "forward", f"{mount.model} has a site named {frames.FRAME_SITE!r}, the "
                                    "name of the robot's frame a mount adds")
    base.add_site(name=frames.FRAME_SITE, pos=[0, 0, 0], quat=list(frame.robot_quat()),
                  group=5, size=[0.01 * mount.unit / models.UNIT, 0, 0])


def _rest(mount, spec):
    """The rest pose (tasks.mount.frame.rest_values) of the joints the robot keeps, in the
    model's text element models.REST_TEXT (models.rest_qpos reads it)."""
    kept = []
    for name, value in frames.rest_values(mount):
        if spec.joint(name) is None:
            if isinstance(mount.rest, str):
                continue   # a keyframe's joint the mount replaces (its root joints)
            fail(mount.path, f"rest.{name}", f"joint {name!r} is not kept (the mount's "
                                             f"joints = {mount.joints!r} replace it)")
        if any(ch.isspace() or ch == "=" for ch in name):
            fail(mount.path, f"rest.{name}", f"{name!r}: a joint's name with spaces or '=' "
                                             "cannot be recorded")
        kept.append(f"{name}={value!r}")
    if kept:
        spec.add_text(name=models.REST_TEXT, data=" ".join(kept))


def _load(mount):
    """The robot file's MjSpec and its base body."""
    import mujoco
    try:
        spec = mujoco.MjSpec.from_file(str(mount.model))
    except ValueError as e:
        fail(mount.path, "file", f"{mount.model} is not a MuJoCo model: {str(e).splitlines()[0]}")
    base = spec.body(mount.base)
    if base is None or base.name == "world":
        fail(mount.path, "base", f"no body named {mount.base!r} in {mount.model}")
    return spec, base


def _drop(mount, spec, names):
    """Deletes what the mount drops, and what the drive's own elements replace; returns
    the names of the file's rangefinders the beams read."""
    drop = set(mount.drop) | mount.action.drops   # the drive's own actuators replace the file's
    if mount.joints == "planar":
        drop |= {"actuators", "tendons"}   # they may act on the joints replaced
    mount.action.check_file(mount, spec, drop, names)
    for field, find in (("drop_bodies", spec.body), ("drop_geoms", spec.geom)):
        for name in getattr(mount, field):
            element = find(name)
            if element is None:
                fail(mount.path, field, f"no {field[5:-1]} named {name!r} in {mount.model}")
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
    beam_names = mount.beams.sensors
    for name in beam_names:
        sensor = by_name(spec.sensors, name)
        if sensor is None or sensor.type != mujoco.mjtSensor.mjSENS_RANGEFINDER:
            fail(mount.path, "beams.sensors", f"no rangefinder named {name!r} in {mount.model}")
    for sensor in list(spec.sensors):
        is_beam = sensor.type == mujoco.mjtSensor.mjSENS_RANGEFINDER
        if ("sensors" in drop or is_beam) and sensor.name not in beam_names:
            spec.delete(sensor)   # only the beams the mount names (or adds) are read
    return beam_names


def _root_joints(mount, spec, base, frame):
    """The base's joints: slides x, y (and hinge yaw) in place of its own for "planar",
    a free joint added for "free". Added slides and hinges follow the room's axes
    whatever the base's rotation in its file (frame: tasks.mount.frame.BaseFrame)."""
    import mujoco
    if mount.joints == "planar":
        for joint in list(base.joints):
            spec.delete(joint)
        plain_joint(base, "x", mujoco.mjtJoint.mjJNT_SLIDE, frame.world_axis(0))
        plain_joint(base, "y", mujoco.mjtJoint.mjJNT_SLIDE, frame.world_axis(1))
        if mount.drive == "two_wheel":
            plain_joint(base, "yaw", mujoco.mjtJoint.mjJNT_HINGE, frame.world_axis(2))
    elif mount.joints == "free":
        own = list(base.joints)
        if any(j.type == mujoco.mjtJoint.mjJNT_FREE for j in own):
            fail(mount.path, "joints", f"body {mount.base!r} has a free joint of its own: "
                                       "joints = \"file\"")
        if own:
            fail(mount.path, "joints", f"body {mount.base!r} has joints of its own "
                                       f"({_listed(own)}), so no free joint can be added: "
                                       f"{fitting_joints(mount, spec, base)}")
        base.add_freejoint(name="root")
    elif mount.joints in ("slides", "slides_z"):
        _slides_beside(mount, spec, base, frame)
    else:   # "file": the base's own must place it (tasks.placement.base_joints)
        own = list(base.joints)
        slides = [j for j in own if j.type == mujoco.mjtJoint.mjJNT_SLIDE]
        if not any(j.type == mujoco.mjtJoint.mjJNT_FREE for j in own) and len(slides) < 2:
            has = f"its own: {_listed(own)}" if own else "it has none"
            fail(mount.path, "joints", f"body {mount.base!r} has no free joint and no slides "
                                       f"along x and y to move it in the room ({has}): "
                                       f"{fitting_joints(mount, spec, base)}")


#: The joints value that fits a base, and what it does: with joints of its own, and
#: (Action.on_floor) moved through the floor or not.
FITTING = {(True, True): ("slides_z", "adds slides x, y and z beside them (a robot that rolls "
                                      "or walks on the floor, resting on it by gravity)"),
           (True, False): ("slides", "adds slides x and y beside them (the base held at its "
                                     "height: a planar robot)"),
           (False, True): ("free", "adds a free joint (a robot that stands on the floor)"),
           (False, False): ("planar", "adds slides x and y (and a hinge about z): a planar "
                                      "robot")}


def fitting_joints(mount, spec, base):
    """'joints = "VALUE" adds ...': the joints value that fits the base (FITTING), by its
    own joints and whether the action moves it through the floor."""
    value, does = FITTING[bool(list(base.joints)), mount.action.on_floor(spec)]
    return f"joints = \"{value}\" {does}"


def _listed(joints):
    """The joints' names and types, as an error lists them."""
    import mujoco
    kinds = {mujoco.mjtJoint.mjJNT_HINGE: "a hinge", mujoco.mjtJoint.mjJNT_SLIDE: "a slide",
             mujoco.mjtJoint.mjJNT_BALL: "a ball joint", mujoco.mjtJoint.mjJNT_FREE: "free"}
    return ", ".join(f"{j.name!r}, {kinds[j.type]}" for j in joints)


#: A joint's fields an MjSpec copy keeps (every field of MjsJoint but its identity).
JOINT_FIELDS = ("type", "name", "pos", "axis", "ref", "align", "stiffness", "springref",
                "springdamper", "limited", "range", "margin", "solref_limit", "solimp_limit",
                "actfrclimited", "actfrcrange", "actgravcomp", "armature", "damping",
                "frictionloss", "solref_friction", "solimp_friction", "group", "userdata")


def _slides_beside(mount, spec, base, frame):
    """Slides x and y (and z, for "slides_z": a base resting on the floor by gravity)
    added at the base before its own joints, which are kept with every motor, tendon and
    equality on them (MuJoCo applies a body's joints in order: the slides first move the
    base, its own joints then turn it about their axes)."""
    import mujoco
    own = list(base.joints)
    for j in own:
        if j.type == mujoco.mjtJoint.mjJNT_FREE:
            fail(mount.path, "joints", f"body {mount.base!r} has a free joint: joints = \"file\"")
        if j.name in ("x", "y", "z"):
            fail(mount.path, "joints", f"body {mount.base!r} has a joint named {j.name!r}, "
                                       "the name of an added slide")
    kept = [{f: getattr(j, f) for f in JOINT_FIELDS} for j in own]
    for j in own:
        spec.delete(j)
    for i, name in enumerate(("x", "y", "z") if mount.joints == "slides_z" else ("x", "y")):
        plain_joint(base, name, mujoco.mjtJoint.mjJNT_SLIDE, frame.world_axis(i))
    for fields in kept:
        base.add_joint(**fields)


# The room's contact bits (models/__init__.py): the bumper 2 / 1 touches walls only;
# a planar robot's other geoms touch nothing; a free robot's touch the walls and the
# floor (0 / 5), never the bumper or each other.
def _bumper(mount, spec, base, planar, names, frame):
    """The bumper (the file's geom, or a shape added) and the room's contact bits."""
    geom = mount.bumper.geom
    hull = _file_bumper(mount, spec, names) if geom is not None else None
    contract = geom == "hull" and mount.base == "base"
    if not contract:   # a contract file keeps its own bits; a mounted one gets the room's
        for body in _bodies(base):
            for g in body.geoms:
                if g is hull:
                    continue
                g.contype, g.conaffinity = (0, 0) if planar else (0, 5)
                if mount.condim is not None:
                    g.condim = mount.condim
    if hull is None:
        hull = _added_bumper(mount, base, planar, frame)
    if not contract:
        hull.contype, hull.conaffinity, hull.condim = 2, 1, 1
        hull.solref = [0.02, 1]
        hull.solimp = [0.99, 0.999, 0.001, 0.5, 2]


def _file_bumper(mount, spec, names):
    """The file's geom the bumper names: a sphere, cylinder or capsule on the base."""
    import mujoco
    name = mount.bumper.geom
    hull = spec.geom(name)
    if hull is None:
        fail(mount.path, "bumper.geom", f"no geom named {name!r} in {mount.model}")
    if hull.type not in (mujoco.mjtGeom.mjGEOM_SPHERE, mujoco.mjtGeom.mjGEOM_CYLINDER,
                         mujoco.mjtGeom.mjGEOM_CAPSULE):
        fail(mount.path, "bumper.geom", f"geom {name!r} must be a sphere, cylinder "
                                        "or capsule (its radius is the robot's)")
    if _owner(spec, hull) != mount.base:
        fail(mount.path, "bumper.geom", f"geom {name!r} is not on the base body "
                                        f"{mount.base!r}")
    if name != "hull":
        names["hull"] = name
    return hull


def _added_bumper(mount, base, planar, frame):
    """The bumper's shape added to the base as the geom hull (massless on a free base),
    upright in the robot's frame."""
    import mujoco
    bumper = mount.bumper
    hull = base.add_geom(name="hull", pos=frame.in_base([0, 0, bumper.height]), group=3,
                         type=(mujoco.mjtGeom.mjGEOM_SPHERE if bumper.shape == "sphere"
                               else mujoco.mjtGeom.mjGEOM_CAPSULE),
                         size=[bumper.radius, bumper.half_length, 0], mass=0 if not planar else 1,
                         rgba=[0.2, 0.35, 0.8, 0.15])
    if frame.robot is not None:
        hull.quat = list(frame.robot_quat())
    if not planar:
        hull.mass = 0.0
        hull.density = 0.0
    return hull


def _beams(mount, spec, base, beam_names, frame):
    """The drive's beams added to the base (in the robot's frame), or the file's
    rangefinders in the mount's order."""
    import mujoco

    if mount.beams.added:
        count, first, step = BEAMS[mount.drive]
        for i in range(count):
            angle = math.radians(first + i * step)
            site = base.add_site(name=f"range_{i}", pos=frame.in_base([0, 0, mount.beams.height]),
                                 zaxis=frame.in_base([math.cos(angle), math.sin(angle), 0]),
                                 group=4,
                                 size=[0.01 * mount.unit / models.UNIT, 0, 0],
                                 rgba=[1, 0.2, 0.2, 1])
            _rangefinder(spec, f"range_{i}", site.name)
    elif list(beam_names) != [s.name for s in spec.sensors
                              if s.type == mujoco.mjtSensor.mjSENS_RANGEFINDER]:
        # re-declared one after another, in the mount's order (tasks.navigation reads
        # the rangefinders as one block)
        sites = {}
        for name in beam_names:
            sensor = by_name(spec.sensors, name)
            sites[name] = sensor.objname
            spec.delete(sensor)
        for name in beam_names:
            _rangefinder(spec, name, sites[name])


def _options(mount, spec):
    """The room's flags (unless the mount keeps the file's) and gravity."""
    room = models.room_spec()
    keep = set(mount.keep_options)
    if "flags" not in keep:
        spec.option.disableflags = room.option.disableflags
        spec.option.enableflags = room.option.enableflags
    spec.option.gravity = room.option.gravity
    # the room's camera clipping (a file's own would conflict with it at the attach)
    spec.visual.map.znear, spec.visual.map.zfar = room.visual.map.znear, room.visual.map.zfar


# What a mount adds is set in full here: the file's <default> would otherwise reach it
# (point_mass.xml's joints default to limited and damped, its motors to gear 0.1).
def plain_joint(body, name, kind, axis):
    """A joint added to body with none of the file's defaults."""
    import mujoco
    return body.add_joint(name=name, type=kind, axis=axis, limited=mujoco.mjtLimited.mjLIMITED_FALSE,
                          damping=0.0, stiffness=0.0, armature=0.0, frictionloss=0.0,
                          pos=[0, 0, 0], ref=0.0, springref=0.0,
                          actfrclimited=mujoco.mjtLimited.mjLIMITED_FALSE)


def actuator(spec, name, trntype, target, gear=(1, 0, 0, 0, 0, 0)):
    """An actuator added to spec with none of the file's defaults (unlimited)."""
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


def by_name(items, name):
    """The element of items named `name`, or None."""
    return next((x for x in items if x.name == name), None)


def file_actuator(mount, spec, field, name):
    """The file's actuator `name`, or the mount's one-line error at `field`."""
    found = by_name(spec.actuators, name)
    if found is None:
        fail(mount.path, field, f"no actuator named {name!r} in {mount.model}")
    return found


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
