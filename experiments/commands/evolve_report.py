"""`ebrl evolve-report`: EVOLVE.md, the paper's intrinsic behaviours against the evolved
ones (experiments.studies.evolved)."""
import pathlib

from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import fail
from experiments.running import results


def add_parser(subparsers):
    p = subparsers.add_parser("evolve-report", help="EVOLVE.md: the paper's intrinsic "
                                                    "behaviours against the evolved ones (README)")
    p.add_argument("--evolve", type=pathlib.Path, default=pathlib.Path("evolve"),
                   help="`ebrl evolve`'s --out (default: %(default)s)")
    p.add_argument("--hand", type=pathlib.Path, default=pathlib.Path("results"),
                   help="the protocol's runs, the paper's rules (default: %(default)s)")
    p.add_argument("--evolved", type=pathlib.Path, default=pathlib.Path("evolved"),
                   help="the evolved genomes' runs: learner/, controller/, alone_*/, "
                        "transfer/ (default: %(default)s)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("EVOLVE.md"))
    arguments.add_results(p, "this page's 'Evolved intrinsic behaviours' block")
    p.set_defaults(func=run)


def _check(args):
    validate.results_folder(args.hand, "--hand")
    for folder, what in ((args.evolve, "--evolve"), (args.evolved, "--evolved")):
        if not folder.is_dir():
            raise ValueError(f"{what}: no folder at {folder}")
    validate.output_file(args.out, "--out")
    validate.output_folder(args.figures, "--figures")
    from experiments.studies import evolved
    arguments.check_results(args, (evolved.BEGIN, evolved.END))


def run(args):
    try:
        _check(args)
    except ValueError as e:
        return fail(str(e))
    from experiments.studies import evolved
    try:
        path = evolved.write(args.evolve, args.hand, args.evolved, args.out, args.figures,
                             args.results)
    except results.ResultsError as e:
        return fail(str(e))
    print(f"evolve report: {path}" + (f"; published: {args.results}" if args.results else ""))
    return 0
