"""`ebrl demo`: a quick protocol (the paper's robots, 6 seeds at a fifth of their budgets,
at least 10,000 steps), then its report and one video."""
import pathlib

from experiments import paper
from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import fail, report_if_any, run_summary
from experiments.outputs import rendering
from experiments.running import execution, results, runner
from tasks.robots import PAPER_ROBOTS, ROBOTS

SEEDS = 6
VIDEO_STEPS = 3_000


def add_parser(subparsers):
    p = subparsers.add_parser("demo", help="a quick protocol, its report and one video")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("demo_results"))
    arguments.add_workers(p)
    p.set_defaults(func=run)


def run(args):
    try:
        validate.output_folder(args.out, "--out")
    except ValueError as e:
        return fail(str(e))
    budgets = {r: max(10_000, ROBOTS[r].budget // 5) for r in PAPER_ROBOTS}
    specs = runner.plan(PAPER_ROBOTS, paper.CONDITIONS, range(SEEDS), budgets)
    print(f"demo: {len(specs)} runs ({SEEDS} seeds x 2 robots x 2 conditions), budgets "
          + ", ".join(f"{k} {v:,} steps" for k, v in budgets.items()) + f" -> {args.out}/")
    try:
        ran = runner.run(specs, args.out, workers=args.workers)
        path = report_if_any(args.out, ran)
        if ran.failed:
            return run_summary(ran, path)
        rendering.ensure_backend()
    except (results.ResultsError, rendering.RenderingError) as e:
        return fail(str(e))
    robot = PAPER_ROBOTS[0]
    video = args.out / f"{robot}_avoidance_seed000.mp4"
    rendering.record(execution.RunSpec(robot, "avoidance", 0, VIDEO_STEPS), video)
    print(f"report:  {path}\nfigures: {args.out / 'figures'}/\nvideo:   {video}")
    return 0
