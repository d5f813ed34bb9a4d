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
    p.add_argument("--section", default=None, metavar="NAME",
                   help="with --results: write this folder's tables into the page's block "
                        "named NAME (its own markers, made at the end where missing) and "
                        "summary-NAME.json beside it, the main block untouched")
    p.add_argument("--literal", type=pathlib.Path, default=None, metavar="DIR",
                   help="with --results: the literal protocol's results folder (its "
                        "summary.json); writes the headline (the paper, the literal protocol "
                        "and this folder's) into the page and the README.md beside it")
    p.set_defaults(func=run)


def _check(args):
    validate.results_folder(args.dir, writable=True)
    validate.output_folder(args.dir / "figures", "the figures folder")
    arguments.check_results(args)
    if args.section is not None and (args.results is None or args.literal is not None):
        raise ValueError("--section needs --results, and is not for the headline (--literal)")
    if args.section is not None and not args.section.strip():
        raise ValueError("--section: give the block a name")
    if args.literal is not None:
        if args.results is None:
            raise ValueError("--literal needs --results (the page its headline goes in)")
        if not (args.literal / "summary.json").is_file():
            raise ValueError(f"--literal {args.literal}: no summary.json there (make it with "
                             f"`ebrl report {args.literal}`)")


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
            page = report.publish(args.dir, args.results, args.figures, args.section)
            print(f"published: {page}")
        if args.literal is not None:
            for page in _headline(args):
                print(f"headline: {page}")
        failed = results.failed_runs(args.dir)
    except results.ResultsError as e:
        return fail(str(e))
    print(f"report: {path}")
    if failed:
        return fail(failed_line(sorted(failed.items()), "failed and not averaged")
                    + "; " + results.advice(failed.values(), "rerun `ebrl run`"), RUNS_FAILED)
    return 0


def _headline(args):
    """The headline from this folder's and the literal folder's summary.json, written into
    the page and its README (experiments.outputs.headline); the literal summary kept
    beside the page."""
    import json

    from experiments.outputs import headline
    from experiments.running import results
    literal = (args.literal / "summary.json").read_bytes()
    results.atomic_write(args.results.parent / headline.LITERAL_SUMMARY, literal)
    current = json.loads((args.dir / "summary.json").read_text())
    return headline.publish(args.results, current, json.loads(literal))

