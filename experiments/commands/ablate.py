"""`ebrl ablate`: the readings ablation, one reading changed at a time (and --combo cells
with several changed together), then ABLATION.md."""
import argparse
import pathlib

from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import check_agent, check_robots, fail, finish, selected_robots
from experiments.running import results


def add_parser(subparsers):
    p = subparsers.add_parser("ablate",
                              help="the readings ablation: one reading changed at a time")
    arguments.add_robots(p, "paper")
    arguments.add_room(p)
    p.add_argument("--seeds", type=arguments.seeds, default=list(range(10)))
    p.add_argument("--steps", type=arguments.up_to(validate.MAX_STEPS), default=None)
    p.add_argument("--readings", default="all",
                   help="comma-separated reading names (default: all of them)")
    p.add_argument("--combo", action="append", default=[], metavar="NAME=VALUE,NAME=VALUE",
                   help="a cell with several readings changed together (repeatable)")
    arguments.add_workers(p)
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("ablation"))
    p.add_argument("--baseline", type=pathlib.Path, default=None,
                   help="a run folder (e.g. results) whose default runs are the default cell")
    arguments.add_results(p, "this page's Ablation block", figures=False)
    arguments.add_no_progress(p)
    p.set_defaults(func=run)


def _readings(args):
    """--readings as the ablation's readings."""
    from experiments.studies import ablation
    names = [r.name for r in ablation.READINGS] if args.readings == "all" else \
        [n.strip() for n in args.readings.split(",") if n.strip()]
    unknown = [n for n in names if n not in ablation.ABLATED_BY_NAME]
    if unknown or not names:
        raise ValueError(f"unknown reading {unknown[0] if unknown else args.readings!r}; "
                         f"valid: {', '.join(ablation.ABLATED_BY_NAME)}")
    validate.once(names, "--readings")
    return [ablation.ABLATED_BY_NAME[n] for n in names]


def _combos(args):
    """--combo cells as lists of (name, value), each accepted for the selected robots."""
    combos = []
    for text in args.combo:
        combo = [arguments.argument(arguments.override)(part.strip())
                 for part in text.split(",")]
        check_agent(args, combo)
        combos.append(combo)
    validate.once([" ".join(f"{n}={v}" for n, v in sorted(c)) for c in combos], "--combo")
    return combos


def _check(args):
    """Every argument checked before any work: (readings, combos)."""
    check_robots(args)
    readings = _readings(args)
    combos = _combos(args)
    for r in readings:  # each value accepted for the selected robots
        for value in r.values:
            check_agent(args, [(r.name, value)])
    validate.output_folder(args.out, "--out")
    if args.baseline is not None:
        validate.results_folder(args.baseline, "--baseline")
    from experiments.studies import ablation
    arguments.check_results(args, (ablation.ABLATION_BEGIN, ablation.ABLATION_END))
    return readings, combos


def run(args):
    try:
        readings, combos = _check(args)
    except (ValueError, argparse.ArgumentTypeError) as e:
        return fail(str(e))
    from experiments.studies import ablation
    try:
        cell_runs, failed = ablation.run(args.out, selected_robots(args), args.seeds,
                                         args.steps, readings, combos, args.baseline,
                                         args.workers, not args.no_progress, args.room)
        path = ablation.write(args.out, ablation.summarize(cell_runs), failed)
        if args.results is not None:
            print(f"published: {ablation.publish(args.out, args.results)}")
    except results.ResultsError as e:
        return fail(str(e))
    return finish("ablation", path, failed)
