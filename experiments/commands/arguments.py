"""The argument types and options several commands share: --robot and --drive from the
registry, seeds, bounded integers, choices, --set NAME=VALUE, --workers, --backend,
--no-progress, --sampler-seed, and --results with --figures. A bad value is argparse's
one-line error (exit status 2), the message from experiments.checks.validate.
"""
import argparse
import os
import pathlib
import sys

from ebrl.config import CONDITIONS
from experiments.checks import validate
from experiments.running import settings
from models import rooms
from tasks.protocols import PROTOCOL_VERSION, PROTOCOLS
from tasks.robots import DRIVES, MOUNTS, PAPER_ROBOTS, ROBOTS


def robot_list(text):
    """--robot: a registered name, several joined by commas, "paper" (the paper's two
    robots), "all" (every registered robot), or a path to a robot .xml file (with
    --drive), or a mount (a shipped mount's name, or a .toml file: tasks/mount/). The
    names come from the registry, tasks/robots.py."""
    if text == "paper":
        return PAPER_ROBOTS
    if text == "all":
        return tuple(ROBOTS)
    if text.lower().endswith((".xml", ".toml")) or text in MOUNTS:
        return (text,)
    names = tuple(n.strip() for n in text.split(","))
    argument(lambda _: validate.once(names, "robot"))(text)
    for n in names:
        if n not in ROBOTS and n not in MOUNTS:
            raise argparse.ArgumentTypeError(
                f"unknown robot {n!r}; valid: {', '.join(ROBOTS)}, paper, all, "
                f"{', '.join(MOUNTS)}, a mount file (.toml), "
                "or a path to a robot .xml file with --drive")
    return names


def _one_robot(text):
    robots = robot_list(text)
    if len(robots) != 1:
        raise argparse.ArgumentTypeError(f"one robot, got {text!r}")
    return robots[0]


def robot_help(several, default, xml=True):
    """What --robot takes, as robot_list reads it: the registered robots, the shipped
    mounts, a mount file, (xml) a robot file with --drive and (several) lists."""
    takes = (f"a registered robot ({', '.join(ROBOTS)}), a shipped mount ({', '.join(MOUNTS)}; "
             "'ebrl robots' lists both), a mount file (.toml: docs/adding_a_robot.md)"
             + (" or a robot file of the naming contract (.xml, with --drive)" if xml else ""))
    if several:
        takes += ("; several names joined by commas, 'paper' (the paper's two) or 'all' "
                  f"(every registered robot); default: {default}")
    return takes


def add_robots(parser, default, several=True):
    """--robot and --drive, from the registry; the help lists what --robot takes."""
    takes = robot_help(several, default)
    if several:
        parser.add_argument("--robot", type=robot_list, default=robot_list(default),
                            metavar="NAME[,NAME...]|FILE", help=takes)
    else:
        parser.add_argument("--robot", type=_one_robot, required=True, metavar="NAME|FILE",
                            help=takes)
    parser.add_argument("--drive", type=choice(tuple(DRIVES)), default=None,
                        help="the drive of a robot given as a .xml file: " + ", ".join(DRIVES))


def add_condition(parser, every=True, default="all", also=""):
    """--condition: one of the paper's conditions (ebrl.config.CONDITIONS), or (every)
    "all"; its help lists the values."""
    values = CONDITIONS + (("all",) if every else ())
    what = {"random": "the intrinsic behaviour a random walk",
            "avoidance": "the intrinsic behaviour Section 3.4's obstacle avoidance"}
    listed = "; ".join(f"{c}: {what[c]}" for c in CONDITIONS)
    parser.add_argument("--condition", type=choice(values), default=default,
                        metavar="{" + ",".join(values) + "}",
                        help=f"the paper's condition (Section 3.6): {listed}"
                             + ("; all: both" if every else "")
                             + (f"; default: {default}" if default is not None else "")
                             + also)


def argument(check):
    """validate's ValueError as argparse's error (one line, exit status 2)."""
    def wrapped(text):
        try:
            return check(text)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None
    return wrapped


def seeds(text):
    """'0-49', '7' or '1,3,5' -> sorted list of seeds (0 to validate.MAX_SEED, at most
    validate.MAX_SEEDS of them)."""
    return argument(validate.seeds)(text)


def between(lo, hi):
    """An integer from lo to hi (inclusive), for argparse."""
    return argument(lambda text: validate.integer(text, lo, hi))


def up_to(maximum=sys.maxsize):
    """A positive integer at most maximum, for argparse."""
    return between(1, maximum)


def choice(valid):
    def check(text):
        if text not in valid:
            raise argparse.ArgumentTypeError(f"unknown {text!r}; valid: {', '.join(valid)}")
        return text
    return check


def setting_value(kinds, name, text):
    """text as the value of the setting name (of kinds, settings.kinds()), for argparse: a
    reading's value checked against its registry entry here (settings.check)."""
    return argument(lambda v: settings.check(name, validate.number(kinds[name], name, v)))(text)


def override(text):
    """name=value for a field of the agent's config (ebrl.Config) or the task's
    (tasks.TaskConfig), e.g. policy_threshold=0.05 or bump=slide."""
    name, sep, value = text.partition("=")
    kinds = settings.kinds()
    if not sep or name not in kinds:
        raise argparse.ArgumentTypeError(f"bad --set {text!r}; use NAME=VALUE with NAME one of "
                                         + ", ".join(kinds))
    return name, setting_value(kinds, name, value)


def room(text):
    """--room: a shipped map's name ('ebrl rooms'), random:WxH:SEED or a map file, read
    and checked here (models.rooms.MapError: one line naming the file); the paper's
    `sutton` is None."""
    try:
        rooms.load(text)
    except rooms.MapError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    return None if text == rooms.DEFAULT else text


def add_room(parser):
    parser.add_argument("--room", type=room, default=None, metavar="NAME|FILE",
                        help=f"the room: a shipped map ({', '.join(rooms.MAPS)}; 'ebrl rooms'), "
                             "random:WxH:SEED (a labmaze maze of W x H cells) or a map file "
                             f"(docs/rooms.md); default: {rooms.DEFAULT}, the paper's")


def add_workers(parser):
    parser.add_argument("--workers", type=up_to(validate.MAX_WORKERS),
                        default=os.cpu_count() or 1)


def add_backend(parser):
    parser.add_argument("--backend", type=choice(("local", "ray")), default="local")


def add_protocol(parser):
    parser.add_argument("--protocol", type=choice(PROTOCOLS), default="adopted",
                        help=f"the readings (tasks/protocols.py): adopted (protocol "
                             f"{PROTOCOL_VERSION}'s) or literal (the paper as written, "
                             "docs/interpretation.md); default: adopted")


def add_no_progress(parser):
    parser.add_argument("--no-progress", action="store_true")


def add_sampler_seed(parser):
    parser.add_argument("--sampler-seed", type=between(0, 2**31 - 1), default=0)


FIGURES = pathlib.Path("docs/figures")


def add_results(parser, what, figures=True):
    """--results RESULTS.md (also regenerate `what` on that page) and, with figures,
    --figures (where the page's figures are copied; default docs/figures)."""
    parser.add_argument("--results", type=pathlib.Path, default=None, metavar="RESULTS.md",
                        help=f"also regenerate {what}")
    if figures:
        parser.add_argument("--figures", type=pathlib.Path, default=FIGURES,
                            help="where the page's figures go (default: %(default)s)")


def check_results(args, *blocks):
    """add_results' options writable, and the page's blocks (each a (begin, end) pair of
    markers) well formed where it has them, before any work starts (ValueError
    otherwise: experiments.outputs.page.PageError, one line naming the page and the
    line)."""
    if args.results is not None:
        validate.output_file(args.results, "--results")
        if hasattr(args, "figures"):
            validate.output_folder(args.figures, "--figures")
        from experiments.outputs import page
        for begin, end in blocks:
            page.check(args.results, begin, end, "--results")
