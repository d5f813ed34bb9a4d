"""`ebrl run`: the protocol, the runs not already on disk, then the report."""
import pathlib

from experiments import paper
from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import (check_agent, check_backend, check_behaviour,
                                          check_robots, fail, plan, report_if_any,
                                          run_summary)
from experiments.running import results, runner
from experiments.running.learners import AGENTS


def add_parser(subparsers):
    p = subparsers.add_parser("run", help="run the protocol (skips runs already on disk)")
    arguments.add_robots(p, "paper")
    arguments.add_room(p)
    arguments.add_condition(p)
    p.add_argument("--seeds", type=arguments.seeds, default=list(range(paper.SEEDS)),
                   help=f"e.g. 0-49 (default), 3, or 1,4,9; seeds 0 to {validate.MAX_SEED:,}, "
                        f"at most {validate.MAX_SEEDS:,} of them")
    p.add_argument("--steps", type=arguments.up_to(validate.MAX_STEPS), default=None,
                   help="agent steps per run (default: the robot's budget, 'ebrl robots'; "
                        f"at most {validate.MAX_STEPS:,})")
    arguments.add_workers(p)
    arguments.add_backend(p)
    p.add_argument("--agent", type=arguments.choice(AGENTS), default="ebrl",
                   help="the learner: " + ", ".join(AGENTS) + " (default: ebrl, the paper's)")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("results"))
    p.add_argument("--set", type=arguments.override, action="append", default=[],
                   metavar="NAME=VALUE",
                   help="change an agent parameter from Table 1's (for sweeps)")
    p.add_argument("--behaviour", type=pathlib.Path, default=None, metavar="FILE",
                   help="an intrinsic behaviour genome (JSON, ebrl.behaviour), e.g. "
                        "behaviours/paper_eq8.json or one `ebrl evolve` saved")
    p.add_argument("--first-trial", action="store_true",
                   help="end each run at its first goal (or its budget): its first trial, "
                        "bit for bit a full run's, in folders ROBOT.first_trial/")
    arguments.add_protocol(p)
    arguments.add_no_progress(p)
    p.set_defaults(func=run)


def run(args):
    try:
        validate.output_folder(args.out, "--out")
        check_robots(args)
        check_agent(args, args.set)
        check_backend(args.backend)
        genome = check_behaviour(args, args.set)
    except ValueError as e:
        return fail(str(e))
    specs = plan(args, args.set)
    if genome is not None:
        import dataclasses
        specs = [dataclasses.replace(s, behaviour=genome) for s in specs]
    try:
        ran = runner.run(specs, args.out, workers=args.workers, backend=args.backend,
                         progress=not args.no_progress)
        path = report_if_any(args.out, ran)
    except results.ResultsError as e:
        return fail(str(e))
    return run_summary(ran, path)
