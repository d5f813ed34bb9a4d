"""`ebrl render`: an offscreen MP4 of one run, or of two side by side (--compare)."""
import argparse
import pathlib

from experiments import paper
from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import check_agent, check_behaviour, check_robots, fail
from experiments.outputs import rendering
from experiments.outputs.rendering import PATH_STYLES
from experiments.running import settings
from experiments.running import execution


def comparison(text):
    """--compare: "condition" (random, then avoidance), "behaviour" (the paper's rule, then
    --behaviour FILE) or NAME=A,B (--set NAME=A, then NAME=B) -> (name, (a, b))."""
    if text == "condition":
        return "condition", paper.CONDITIONS
    if text == "behaviour":
        return "behaviour", ("hand-coded", "evolved")
    name, sep, values = text.partition("=")
    kinds = settings.kinds()
    parts = values.split(",")
    if not sep or name not in kinds or len(parts) != 2:
        raise argparse.ArgumentTypeError(
            f"bad --compare {text!r}; use condition, behaviour, or NAME=A,B with NAME one of "
            + ", ".join(kinds))
    a, b = (arguments.setting_value(kinds, name, p) for p in parts)
    if a == b:
        raise argparse.ArgumentTypeError(f"--compare {text!r} compares a value with itself")
    return name, (a, b)


def add_parser(subparsers):
    p = subparsers.add_parser("render", help="an offscreen MP4 of one run, or of two side by side")
    arguments.add_robots(p, None, several=False)
    arguments.add_room(p)
    p.add_argument("--camera", default="top",
                   help="top (default), perspective, follow (a perspective camera that "
                        "tracks the robot), or a camera of the robot's file (chase)")
    arguments.add_condition(p, every=False, default=None,
                            also="; required, unless --compare condition")
    p.add_argument("--seed", type=arguments.between(0, validate.MAX_SEED), required=True)
    p.add_argument("--steps", type=arguments.up_to(validate.MAX_STEPS), default=3000)
    p.add_argument("--set", type=arguments.override, action="append", default=[],
                   metavar="NAME=VALUE",
                   help="change a parameter of the agent or the task, as ebrl run does")
    p.add_argument("--compare", type=comparison, default=None,
                   metavar="condition|behaviour|NAME=A,B",
                   help="two runs side by side, the same seed and the same steps: random "
                        "and avoidance, or --set NAME=A and NAME=B")
    p.add_argument("--beams", action=argparse.BooleanOptionalAction, default=True,
                   help="each rangefinder beam to what it hits, shaded by its reading")
    p.add_argument("--path", type=arguments.choice(PATH_STYLES), default=PATH_STYLES[0],
                   help="the trial's path coloured by who chose each step, with a legend "
                        "(decider, the default), in one colour (plain), or none")
    p.add_argument("--caption", action=argparse.BooleanOptionalAction, default=True,
                   help="a line of text: step, trial, goals, who chose the action")
    p.add_argument("--out", type=pathlib.Path, required=True)
    p.add_argument("--behaviour", type=pathlib.Path, default=None, metavar="FILE",
                   help="an intrinsic behaviour genome (JSON), as `ebrl run --behaviour`")
    p.set_defaults(func=run)


def _variants(args):
    """(label, condition, --set pairs) of the run to render, or of the two to compare."""
    pairs = list(args.set)
    if args.compare is not None and args.compare[0] == "condition":
        if args.condition is not None:
            raise ValueError("--compare condition runs both conditions: drop --condition")
        return [(c, c, pairs) for c in args.compare[1]]
    if args.condition is None:
        raise ValueError("--condition is required (unless --compare condition)")
    if args.compare is None:
        return [(args.condition, args.condition, pairs)]
    name, values = args.compare
    if name == "behaviour":  # the paper's rule (no genome), then --behaviour's
        if args.behaviour is None:
            raise ValueError("--compare behaviour needs --behaviour FILE (the one set beside "
                             "the paper's rule)")
        return [(f"{values[0]} (paper)", args.condition, pairs),
                (f"{values[1]} ({args.behaviour.stem})", args.condition, pairs)]
    if name in dict(pairs):
        raise ValueError(f"--compare {name} is also given with --set")
    return [(f"{name}={v}", args.condition, pairs + [(name, v)]) for v in values]


def _check(args):
    """Every argument checked before any work: (variants, the --behaviour genome)."""
    validate.output_file(args.out, "--out", suffix=".mp4")
    check_robots(args)
    variants = _variants(args)
    for _, _, pairs in variants:
        check_agent(args, pairs)
    return variants, check_behaviour(args, args.set)


def _specs(args, variants, genome):
    """One RunSpec per variant; with --compare behaviour, the first runs the paper's rule."""
    paper_first = args.compare is not None and args.compare[0] == "behaviour"
    return [execution.RunSpec(args.robot, condition, args.seed, args.steps, tuple(sorted(pairs)),
                             drive=args.drive,
                             behaviour=None if paper_first and i == 0 else genome,
                             room=args.room)
            for i, (_, condition, pairs) in enumerate(variants)]


def run(args):
    try:
        variants, genome = _check(args)
    except ValueError as e:
        return fail(str(e))
    specs = _specs(args, variants, genome)
    labels = [label for label, _, _ in variants]
    try:
        rendering.ensure_backend()
        rendering.check_camera(specs[0], args.camera)
    except rendering.RenderingError as e:
        return fail(str(e))
    options = dict(camera=args.camera, beams=args.beams, path_style=args.path,
                   caption=args.caption)
    if len(specs) == 1:
        results = [rendering.record(specs[0], args.out, label=labels[0], **options)]
    else:
        results = rendering.record_compare(specs, labels, args.out, **options)
    goals = ", ".join(f"{len(r['trial_ends'])} goals ({label})"
                      for r, label in zip(results, labels))
    print(f"video: {args.out} ({goals} in {args.steps} steps)")
    return 0
