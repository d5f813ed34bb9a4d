"""`ebrl report`: summary.json, REPORT.md and the figures of a results folder, rebuilt;
with --results, the tables of a page such as RESULTS.md too."""
import pathlib

from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import RUNS_FAILED, fail, failed_line


def add_parser(subparsers):
    p = subparsers.add_parser("report", help="rebuild summary.json, REPORT.md and figures")
    p.add_argument("dir", type=pathlib.Path)
    arguments.add_results(p, "the tables of this page (between its markers), copy the "
                             "figures to --figures and summary.json beside it")
    from models import rooms
    p.add_argument("--room", type=arguments.room, default=False, metavar="NAME|FILE",
                   help="only the runs in this room (default: every room's runs, each "
                        f"robot's rows in its own room; {rooms.DEFAULT}: the paper's)")
    p.set_defaults(func=run)


def _check(args):
    validate.results_folder(args.dir, writable=True)
    validate.output_folder(args.dir / "figures", "the figures folder")
    arguments.check_results(args)


def run(args):
    try:
        _check(args)
    except ValueError as e:
        return fail(str(e))
    from experiments.outputs import report
    from experiments.running import results
    try:
        path = report.build(args.dir, args.room)
        if args.results is not None:
            print(f"published: {report.publish(args.dir, args.results, args.figures)}")
        failed = results.failed_runs(args.dir)
    except results.ResultsError as e:
        return fail(str(e))
    print(f"report: {path}")
    if failed:
        return fail(failed_line(sorted(failed.items()), "failed and not averaged")
                    + "; " + results.advice(failed.values(), "rerun `ebrl run`"), RUNS_FAILED)
    return 0
