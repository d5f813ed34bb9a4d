"""The robot registry: every robot the package knows, in one place.

A robot is an MJCF file plus the paper's settings that go with its drive (the action
family of Section 3.3). The drive gives the defaults: its Table 1 column (memory
size), its Section 3.6 step budget, its intrinsic behaviour (Section 3.4) and its
sensor modalities with eq 3's weights; an entry may override any of them, may set
its own timestep and integrator (the room's are the planar robots': 0.05 s, Euler),
and may stretch the seconds an agent step takes (`time_scale`: a real robot
accelerates more gently than the paper's ideal one).

Every command, figure and table takes its robots from `ROBOTS`; `resolve` also
accepts a path to a robot file of the user's, with a drive. This module imports
nothing heavy, so the command line can check names before any work.
"""
import dataclasses
import pathlib
from typing import TYPE_CHECKING

from models import MODEL_DIR, UNIT
from tasks.config import TaskConfig
from tasks.protocols import PROTOCOLS

if TYPE_CHECKING:
    from tasks.mount import Mount

#: The shipped mounts (tasks.mount): third-party robot files, unchanged, by name.
MOUNT_DIR = MODEL_DIR / "mounts"


@dataclasses.dataclass(frozen=True)
class Drive:
    """An action family of Section 3.3 and the paper's settings for its robot."""
    name: str
    table1: str        # Table 1 column: "T" (two wheels robot) or "F" (floating robot)
    budget: int        # Section 3.6: agent steps of learning per run
    avoidance: str     # Section 3.4's intrinsic behaviour, by equation ("eq8", "eq9-10")
    modalities: tuple  # (observation key, eq 3 weight) pairs, in the agent's input order


DRIVES = {
    "two_wheel": Drive("two_wheel", table1="T", budget=30_000, avoidance="eq8",
                       modalities=(("range", 1.0),)),
    "floating": Drive("floating", table1="F", budget=100_000, avoidance="eq9-10",
                      modalities=(("range", 0.7), ("velocity", 0.3))),
}


@dataclasses.dataclass(frozen=True)
class Robot:
    name: str
    model: pathlib.Path           # the robot's MJCF file
    drive: str                    # a key of DRIVES
    #: How the drive's action reaches the body: a name of tasks.realisations.REALISATIONS
    #: (a shipped robot's, by name; a mount's, its action kind's; a robot file's, by the
    #: contract's actuators it has: file_realisation).
    realisation: str = None
    timestep: float = None        # seconds; None keeps the room's 0.05
    integrator: str = None        # None keeps the room's Euler
    time_scale: float = 1.0       # seconds of an agent step over the drive's (a slower robot)
    table1: str = None            # None: the drive's
    budget: int = None
    avoidance: str = None
    modalities: tuple = None
    #: The robot's own readings, (field, value) pairs (a mount's [readings] table), on top
    #: of its protocol's.
    own_readings: tuple = ()
    description: str = ""
    #: Metres per paper unit: the room, the start, the goal and the beams' range scale
    #: with it (models.compose); every distance the task reports stays in paper units.
    unit: float = UNIT
    #: The mount that enters a file not of the naming contract.
    mount: "Mount | None" = None
    #: `ebrl check`'s accuracy limits where the drive's 5% is not asked of the body (a
    #: mount's [check]), as (error, limit) pairs.
    accuracy_limits: tuple = ()
    #: The protocol whose readings the entry takes (a name of tasks.protocols.PROTOCOLS).
    protocol: str = "adopted"
    #: Its readings, (field, value) pairs, sorted: the protocol's for it, then its own
    #: (tasks.protocols.Protocol.readings_for).
    readings: tuple = dataclasses.field(init=False)

    def __post_init__(self):
        if self.drive not in DRIVES:
            raise ValueError(f"unknown drive {self.drive!r}; valid: {', '.join(DRIVES)}")
        d = DRIVES[self.drive]
        for field in ("table1", "budget", "avoidance", "modalities"):
            if getattr(self, field) is None:
                object.__setattr__(self, field, getattr(d, field))
        object.__setattr__(self, "model", pathlib.Path(self.model))
        if self.protocol not in PROTOCOLS:
            raise ValueError(f"unknown protocol {self.protocol!r}; valid: {', '.join(PROTOCOLS)}")
        object.__setattr__(self, "readings", PROTOCOLS[self.protocol].readings_for(
            self.name, self.drive, self.own_readings))
        if self.realisation is None:
            object.__setattr__(self, "realisation", file_realisation(self.model, self.drive))

    def under(self, protocol):
        """This entry under a named protocol (tasks.protocols.PROTOCOLS)."""
        return self if protocol == self.protocol else dataclasses.replace(self, protocol=protocol)

    def task_config(self, **overrides):
        """tasks.TaskConfig with this robot's task readings, then the overrides."""
        return TaskConfig(**(self.task_readings() | overrides))

    def task_readings(self):
        """{TaskConfig field: value} of this robot's readings."""
        fields = {f.name for f in dataclasses.fields(TaskConfig)}
        return {k: v for k, v in self.readings if k in fields}

    def agent_readings(self):
        """{field: value} of this robot's readings that are not the task's (the agent's)."""
        task = self.task_readings()
        return {k: v for k, v in self.readings if k not in task}


ROBOTS = {r.name: r for r in (
    Robot("two_wheel", MODEL_DIR / "two_wheel.xml", "two_wheel", "servos",
          description="the paper's two-wheel robot as a planar base (slide x, y, hinge yaw)"),
    Robot("floating", MODEL_DIR / "floating.xml", "floating", "thrusters",
          description="the paper's floating robot as a planar puck (slide x, y)"),
    Robot("diff_drive", MODEL_DIR / "diff_drive.xml", "two_wheel", "wheels", timestep=0.025,
          integrator="Euler", time_scale=2.5,
          description="a 3D differential-drive robot: free chassis, two wheels, casters"),
    Robot("hovercraft", MODEL_DIR / "hovercraft.xml", "floating", "thrusters", timestep=0.025,
          integrator="implicitfast",
          description="a 3D hovercraft on a free joint, gliding on skids under gravity"),
)}

#: The paper's two robots, in the order its Section 3.6 reports them.
PAPER_ROBOTS = ("two_wheel", "floating")


def resolve(robot, drive=None):
    """A Robot from a registered name, or from a path to an MJCF file with a drive.

    A registered name with a drive is refused unless the drive is the robot's own. A
    shipped mount's name (MOUNTS) or a path to a mount file (.toml) gives its entry."""
    if isinstance(robot, Robot):
        return robot
    if robot in ROBOTS:
        entry = ROBOTS[robot]
        if drive is not None and drive != entry.drive:
            raise ValueError(f"robot {robot!r} has the {entry.drive} drive, not {drive!r}")
        return entry
    path = pathlib.Path(robot)
    if robot in MOUNTS or path.suffix.lower() == ".toml":
        if drive is not None:
            raise ValueError(f"robot {robot!r} is a mount: its drive is in the mount, not --drive")
        return _mounted(str(MOUNTS.get(robot, path)))
    if path.suffix.lower() != ".xml":
        raise ValueError(f"unknown robot {robot!r}; valid: {', '.join(ROBOTS)}, "
                         f"{', '.join(MOUNTS)}, a mount file (.toml), "
                         "or a path to a robot .xml file with --drive")
    if not path.is_file():
        raise ValueError(f"no robot file at {path}")
    if drive is None:
        raise ValueError(f"robot file {path} needs a drive: one of {', '.join(DRIVES)}")
    if drive not in DRIVES:
        raise ValueError(f"unknown drive {drive!r}; valid: {', '.join(DRIVES)}")
    return Robot(str(path), path.resolve(), drive, **file_options(path))


#: The shipped mounts by name: models/mounts/<name>.toml.
MOUNTS = {p.stem: p for p in sorted(MOUNT_DIR.glob("*.toml"))}


def _mounted(path):
    """The entry of a mount file (tasks.mount), parsed once per process and path;
    MountError on a bad mount."""
    key = str(pathlib.Path(path).resolve())
    if key not in _MOUNTED:
        from tasks import mount
        _MOUNTED[key] = mount_entry(mount.parse(path))
    return _MOUNTED[key]


def mount_entry(m):
    """The registry entry of a parsed mount (tasks.mount.Mount)."""
    return Robot(m.name, m.model, m.drive, m.action.realisation(m.drive),
                 unit=m.unit, time_scale=m.time_scale,
                 own_readings=m.readings, accuracy_limits=m.check,
                 description=m.description or f"mounted from {m.file}",
                 mount=m, **_mount_options(m))


def _mount_options(mount):
    """The registry's timestep and integrator for a mount: its own fields, else the file's
    <option> where keep_options names them, else the room's (None)."""
    own = file_options(mount.model)
    out = {k: own[k] for k in ("timestep", "integrator") if k in mount.keep_options and k in own}
    if mount.timestep is not None:
        out["timestep"] = mount.timestep
    if mount.integrator is not None:
        out["integrator"] = mount.integrator
    return out


_MOUNTED = {}


def file_realisation(path, drive):
    """The realisation of a robot file of the naming contract (docs/adding_a_robot.md), by
    the contract's actuators it declares: the floating drive's thrusters; for the
    two_wheel drive, wheels where it has ``left_wheel``, else servos (``forward``,
    ``turn``; a file with neither is refused when loaded, naming both)."""
    if drive == "floating":
        return "thrusters"
    import xml.etree.ElementTree as ElementTree
    try:
        root = ElementTree.parse(path).getroot()
    except (OSError, ElementTree.ParseError):
        return "servos"   # models.compose names what is wrong with the file
    actuators = root.find("actuator")
    names = {a.get("name") for a in actuators} if actuators is not None else set()
    return "wheels" if "left_wheel" in names else "servos"


def file_options(path):
    """The timestep and integrator of a robot file's own <option>, if it gives them (a
    robot file run as a file brings its own; a registered one has them in its entry)."""
    import xml.etree.ElementTree as ElementTree
    try:
        option = ElementTree.parse(path).getroot().find("option")
    except ElementTree.ParseError as e:
        raise ValueError(f"{path} is not an XML file: {e}") from None
    if option is None:
        return {}
    out = {}
    if "timestep" in option.attrib:
        try:
            out["timestep"] = float(option.attrib["timestep"])
        except ValueError:
            raise ValueError(f"{path}: bad <option timestep={option.attrib['timestep']!r}>") from None
        if not out["timestep"] > 0:
            raise ValueError(f"{path}: <option timestep> must be positive")
    if "integrator" in option.attrib:
        out["integrator"] = option.attrib["integrator"]
    return out
