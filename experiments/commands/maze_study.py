"""`ebrl maze-study`: both paper robots, both conditions, in random mazes of several
sizes (experiments.studies.mazes), then MAZES.md and its figure."""
import argparse
import pathlib

from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import fail, finish
from experiments.running import results
from experiments.studies import mazes
from models import rooms


def sizes(text):
    """'9x6,15x15,21x21' -> ((9, 6), (15, 15), (21, 21))."""
    out = []
    for part in text.split(","):
        w, sep, h = part.strip().partition("x")
        if not (sep and w.isdigit() and h.isdigit()):
            raise argparse.ArgumentTypeError(f"bad size {part!r}; use WxH, e.g. 9x6,15x15,21x21")
        lo, hi = rooms.RANDOM_SIZES
        if not (lo <= int(w) <= hi and lo <= int(h) <= hi):
            raise argparse.ArgumentTypeError(f"size {part!r}: sides must be {lo}..{hi} cells")
        out.append((int(w), int(h)))
    if len(set(out)) < len(out):
        again = next(s for k, s in enumerate(out) if s in out[:k])
        raise argparse.ArgumentTypeError(f"size {again[0]}x{again[1]} is given more than once")
    return tuple(out)


def add_parser(subparsers):
    p = subparsers.add_parser("maze-study",
                              help="both robots, both conditions, in random mazes of several sizes")
    p.add_argument("--sizes", type=sizes, default=mazes.SIZES, metavar="WxH,...",
                   help="maze sizes in cells (default: 9x6,15x15,21x21)")
    p.add_argument("--mazes", type=arguments.up_to(100), default=3, help="mazes per size")
    p.add_argument("--seeds", type=arguments.up_to(100), default=2, help="seeds per maze")
    p.add_argument("--steps-per-cell", type=arguments.up_to(100_000), default=mazes.STEPS_PER_CELL,
                   help="the budget: agent steps per cell of the maze's shortest path "
                        "(default: %(default)s)")
    arguments.add_workers(p)
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("mazes"))
    arguments.add_results(p, "this page's maze-study block")
    arguments.add_no_progress(p)
    p.set_defaults(func=run)


def run(args):
    try:
        validate.output_folder(args.out, "--out")
        arguments.check_results(args, (mazes.BEGIN, mazes.END))
        specs = mazes.plan(args.sizes, args.mazes, args.seeds, args.steps_per_cell)
    except (ValueError, rooms.MapError) as e:
        return fail(str(e))
    total = sum(s.steps for s in specs)
    print(f"{len(specs)} runs, {total:,} agent steps in all")
    try:
        ran = mazes.run(args.out, specs, args.workers, not args.no_progress)
        path = mazes.write(args.out, specs, args.sizes, args.mazes, args.seeds,
                           args.steps_per_cell)
        if args.results is not None:
            print(f"published: {mazes.publish(args.out, args.results, args.figures)}")
    except results.ResultsError as e:
        return fail(str(e))
    return finish("maze study", path, [(s.name, e) for s, e in ran.failed])
