"""`ebrl evolve`: CMA-ES over a robot's intrinsic behaviour, learning or not
(experiments.studies.evolve); an Optuna study, resumable."""
import pathlib

from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import check_robots, fail, finish, open_study, study_storage
from experiments.running import execution, results
from experiments.studies import study
from tasks.robots import resolve


def add_parser(subparsers):
    p = subparsers.add_parser("evolve", help="CMA-ES over a robot's intrinsic behaviour, "
                                             "learning or not (an Optuna study; resumable)")
    arguments.add_robots(p, None, several=False)
    arguments.add_room(p)
    p.add_argument("--population", type=arguments.up_to(validate.MAX_POPULATION), default=8,
                   help="trials per CMA-ES generation (default: %(default)s)")
    p.add_argument("--generations", type=arguments.up_to(validate.MAX_TRIALS), default=30,
                   help="generations the study should hold after the starting genome "
                        "(default: %(default)s); the same command continues a study")
    p.add_argument("--seeds", type=arguments.seeds, default=list(range(1000, 1005)),
                   help="training seeds (default: 1000-1004, outside the protocol's 0-49, "
                        "which stay held out)")
    p.add_argument("--steps", type=arguments.up_to(validate.MAX_STEPS), default=None,
                   help="agent steps per run (default: the robot's budget)")
    p.add_argument("--no-learning", action="store_true",
                   help="evolve the behaviour alone: the memory never acts")
    p.add_argument("--start", type=pathlib.Path, default=None, metavar="FILE",
                   help="the starting genome (default: the paper's rule for the robot)")
    p.add_argument("--space", default="all",
                   help="comma-separated genome fields to evolve (default: all; without "
                        "learning, all but the learning variables)")
    p.add_argument("--storage", default=None,
                   help="an Optuna storage URL or an SQLite file (default: OUT/study.db)")
    p.add_argument("--study", default=None,
                   help="the study's name (default: evolve-ROBOT, evolve-ROBOT-controller "
                        "with --no-learning)")
    arguments.add_sampler_seed(p)
    arguments.add_workers(p)
    arguments.add_backend(p)
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("evolve"))
    arguments.add_no_progress(p)
    p.set_defaults(func=run)


def _check(args):
    """Every argument checked before any work: (problem, storage URL)."""
    from experiments.checks import behaviour_file
    from experiments.studies import evolve
    if args.population < 2:
        raise ValueError("--population must be at least 2 (CMA-ES keeps the better half)")
    import importlib.util
    if importlib.util.find_spec("cmaes") is None:
        raise ValueError("ebrl evolve needs the cmaes package (Optuna's CMA-ES): pip install -e .")
    check_robots(args)
    entry = resolve(args.robot, args.drive)
    if args.start is not None:
        start = behaviour_file.check(args.start, (args.robot,), args.drive)
    else:
        start = evolve.paper_genome(entry)
    names = evolve.fields(start, args.space, learning=not args.no_learning)
    url = study_storage(args)
    problem = evolve.Problem(args.robot, start, names, tuple(args.seeds), args.steps,
                             learning=not args.no_learning, population=args.population,
                             sampler_seed=args.sampler_seed, drive=args.drive, room=args.room)
    return problem, url


def _generations(args, s, problem):
    """The starting genome alone (enqueued by study.load; CMA-ES needs a complete trial to
    know the space), then one batch of --population trials per generation: (trials made,
    failed (name, error))."""
    made, failed = 0, []
    for n_trials, batch in ((1, 1), (1 + args.population * args.generations, args.population)):
        outcome = study.optimize(problem, s, args.out, n_trials, batch=batch,
                                 workers=args.workers, backend=args.backend,
                                 promote=1.0, progress=not args.no_progress)
        made += outcome.made
        failed += [(f"trial {n}", e) for n, e in outcome.failed]
    return made, failed


def run(args):
    try:
        problem, url = _check(args)
    except ValueError as e:
        return fail(str(e))
    from experiments.studies import evolve, study
    label = execution.RunSpec(args.robot, "avoidance", 0, 1, drive=args.drive, room=args.room).label
    name = args.study or evolve.study_name(label, not args.no_learning)
    s, status = open_study(args, url, lambda: study.load(
        name, url, args.out, sampler=problem.sampler(0), first=problem.x0()))
    if s is None:
        return status
    try:
        evolve.check_settings(s, problem)
    except ValueError as e:
        return fail(str(e))
    try:
        made, failed = _generations(args, s, problem)
        path = evolve.write(s, args.out, problem)
    except results.ResultsError as e:
        return fail(str(e))
    print(f"{made} trials made now, {len(s.trials)} in the study {name} ({study.shown(url)})")
    return finish("evolve", path, failed)
