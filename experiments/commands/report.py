"""`ebrl report`: summary.json, REPORT.md and the figures of a results folder, rebuilt;
with --results, the tables of a page such as RESULTS.md too."""
import pathlib

from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import RUNS_FAILED, fail, failed_line
from experiments.running import results
from models import rooms


def add_parser(subparsers):
    p = subparsers.add_parser("report", help="rebuild summary.json, REPORT.md and figures")
    p.add_argument("dir", type=pathlib.Path)
    arguments.add_results(p, "the tables of this page (between its markers), copy the "
                             "figures to --figures and summary.json beside it")
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
    from experiments.outputs import headline
    from experiments.outputs import report as outputs
    if args.section is not None and (args.results is None or args.literal is not None):
        raise ValueError("--section needs --results, and is not for the headline (--literal)")
    if args.section is not None:
        outputs.check_section(args.section)
    arguments.check_results(args, outputs.markers(args.section))
    if args.section is not None:
        outputs.check_section_clash(args.results, args.section)
    if args.literal is not None:
        if args.results is None:
            raise ValueError("--literal needs --results (the page its headline goes in)")
        summary = args.literal / "summary.json"
        if not summary.is_file():
            raise ValueError(f"--literal {args.literal}: no summary.json there (make it with "
                             f"`ebrl report {args.literal}`)")
        headline.check(args.results)
        from experiments.running import results
        try:
            literal = results.read_summary(summary)
            headline.table(literal, literal)  # the headline can be made from it
        except results.DamagedFile as e:
            raise ValueError(f"--literal {args.literal}: {e}") from None
        except (KeyError, IndexError, TypeError, ValueError, AttributeError) as e:
            raise ValueError(f"--literal {args.literal}: {summary} cannot give the headline "
                             f"({results.error_line(e, 160)}); remake it with `ebrl report "
                             f"{args.literal}`") from None


def run(args):
    try:
        _check(args)
    except ValueError as e:
        return fail(str(e))
    from experiments.outputs import report
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
    from experiments.outputs import headline
    path = args.literal / "summary.json"
    literal = path.read_bytes()
    parsed = results.read_summary(path)
    current = results.read_summary(args.dir / "summary.json")
    results.atomic_write(args.results.parent / headline.LITERAL_SUMMARY, literal)
    return headline.publish(args.results, current, parsed)
