"""`ebrl fit`: an Optuna study of the paper's unwritten readings against its table
(experiments.studies.fit); resumable, and optionally the best trial validated on held-out
seeds."""
import pathlib

from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import check_room, fail, finish, open_study, study_storage
from experiments.running import results
from experiments.running.execution import ROOM_MARK
from models.rooms import tag


def add_parser(subparsers):
    p = subparsers.add_parser("fit", help="search the paper's unwritten readings against its "
                                          "table (an Optuna study; resumable)")
    p.add_argument("--trials", type=arguments.up_to(validate.MAX_TRIALS), default=150,
                   help="finished trials the study should hold (default: %(default)s); the "
                        "same command continues a study")
    p.add_argument("--seeds", type=arguments.seeds, default=[0, 1],
                   help="every trial's seeds (default: 0-1)")
    p.add_argument("--promote-seeds", type=arguments.seeds, default=None,
                   help="a promoted trial's seeds, including --seeds (default: 0-5; with "
                        "--stage first-trial, --seeds)")
    p.add_argument("--promote", default=0.1,
                   type=arguments.argument(lambda t: validate.fraction(t, "--promote")),
                   help="the share of trials promoted (default: %(default)s)")
    p.add_argument("--batch", type=arguments.up_to(64), default=4,
                   help="trials asked and run together (default: %(default)s)")
    p.add_argument("--stage", type=arguments.choice(("table", "first-trial")), default="table",
                   help="table: the readings against Section 3.6's table (default); "
                        "first-trial: stage 1, one drive's physics and fallback readings "
                        "against the paper's first-trial distributions (--robot; 64 or "
                        "more --seeds), FIT_first_trial_DRIVE.md")
    p.add_argument("--robot", type=arguments.choice(("two_wheel", "floating")), default=None,
                   help="--stage first-trial: the drive's robot to fit: two_wheel or floating "
                        "(the paper's two)")
    p.add_argument("--space", default="all",
                   help="comma-separated readings to search (default: all; see FIT.md)")
    p.add_argument("--steps", type=arguments.up_to(validate.MAX_STEPS), default=None,
                   help="agent steps per run (default: each robot's budget)")
    p.add_argument("--storage", default=None,
                   help="an Optuna storage URL (postgresql://..., mysql://...) or an SQLite "
                        "file (default: OUT/study.db)")
    p.add_argument("--study", default=None, help="the study's name (default: fit)")
    arguments.add_room(p)
    arguments.add_sampler_seed(p)
    p.add_argument("--validate", type=arguments.seeds, default=None, metavar="SEEDS",
                   help="then run the best trial (or --trial) and the defaults on these "
                        "seeds, which the search must not use (e.g. 100-149)")
    p.add_argument("--trial", type=arguments.between(0, 10**9), default=None,
                   help="the trial --validate runs (default: the best)")
    arguments.add_workers(p)
    arguments.add_backend(p)
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("fit"))
    arguments.add_results(p, "this page's Search block")
    arguments.add_no_progress(p)
    p.set_defaults(func=run)


def _check(args):
    """Every argument checked before any work: (space names, storage URL); for --stage
    first-trial, ((space names, rungs), storage URL)."""
    from experiments.studies import fit
    check_room(fit.ROBOTS if args.robot is None else (args.robot,), args.room)
    if args.stage == "first-trial":
        from experiments.studies import first_trials
        names, rungs = first_trials.check_args(args.robot, args.space, args.seeds,
                                               args.promote_seeds, args.validate)
        if args.trial is not None and args.validate is None:
            raise ValueError("--trial chooses the trial --validate runs; give --validate too")
        return (names, rungs), study_storage(args)
    if args.robot is not None:
        raise ValueError("--robot is for --stage first-trial (the table's fit runs both robots)")
    if args.promote_seeds is None:
        args.promote_seeds = list(range(6))
    names = tuple(fit.PARAMETER_BY_NAME) if args.space == "all" else \
        tuple(n.strip() for n in args.space.split(",") if n.strip())
    unknown = [n for n in names if n not in fit.PARAMETER_BY_NAME]
    if unknown or not names:
        raise ValueError(f"unknown reading {unknown[0] if unknown else args.space!r} in --space; "
                         f"valid: {', '.join(fit.PARAMETER_BY_NAME)}")
    validate.once(names, "--space")
    if not set(args.seeds) <= set(args.promote_seeds):
        raise ValueError("--promote-seeds must include every seed of --seeds")
    if args.validate is not None and set(args.validate) & set(args.promote_seeds):
        raise ValueError("--validate seeds must be seeds the search never uses (not in "
                         "--seeds or --promote-seeds)")
    if args.trial is not None and args.validate is None:
        raise ValueError("--trial chooses the trial --validate runs; give --validate too")
    from experiments.studies import fit
    arguments.check_results(args, (fit.FIT_BEGIN, fit.FIT_END))
    return names, study_storage(args)


class _NoTrial(Exception):
    """--validate (or --trial) names no complete trial: one line, exit status 2."""


def _validate(args, s, problem, names):
    """--validate: the chosen trial and the defaults on held-out seeds; the failed runs."""
    from experiments.studies import fit, study
    best = study.best_trials(s, 1) if args.trial is None else \
        [t for t in s.trials if t.number == args.trial and "rungs" in t.user_attrs]
    if not best:
        raise _NoTrial(f"no complete trial {'to validate' if args.trial is None else args.trial}")
    params = {k: v for k, v in best[0].params.items() if k in names}
    _, lost = fit.validate_best(problem, params, args.out, args.validate, args.workers,
                                args.backend, not args.no_progress)
    return [(spec.name, e) for spec, e in lost]


def _search(args, s, problem, names):
    """The study's trials (the defaults first: study.load enqueued them), then --validate and the pages: (the
    optimize outcome, the study page's path, the failed (name, error))."""
    from experiments.studies import fit, study
    outcome = study.optimize(problem, s, args.out, args.trials, batch=args.batch,
                             workers=args.workers, backend=args.backend,
                             promote=args.promote, progress=not args.no_progress)
    failed = [(f"trial {n}", e) for n, e in outcome.failed]
    if args.validate is not None:
        failed += _validate(args, s, problem, names)
    path = fit.write(s, args.out, names)
    if args.results is not None:
        print(f"published: {fit.publish(s, args.out, names, args.results, args.figures)}")
    return outcome, path, failed


def _in_room(name, room):
    """A study's default name: with "@<room>" in a room other than the paper's."""
    return name if room is None else f"{name}{ROOM_MARK}{tag(room)}"


def run(args):
    try:
        names, url = _check(args)
    except ValueError as e:
        return fail(str(e))
    if args.stage == "first-trial":
        return _first_trial(args, *names, url)
    from experiments.studies import fit, study
    rungs = (tuple(args.seeds),) if args.seeds == args.promote_seeds else \
        (tuple(args.seeds), tuple(args.promote_seeds))
    problem = fit.Problem(names=names, rungs=rungs, steps=args.steps, room=args.room)
    s, status = open_study(args, url, lambda: study.load(
        args.study or _in_room(fit.STUDY_NAME, args.room), url, args.out, args.sampler_seed,
        first={n: fit.default(n) for n in names}))  # the defaults: trial 0
    if s is None:
        return status
    try:
        outcome, path, failed = _search(args, s, problem, names)
    except (results.ResultsError, _NoTrial) as e:
        return fail(str(e))
    print(f"{outcome.made} trials made now, {outcome.total} in the study ({study.shown(url)})")
    return finish("fit", path, failed)


def _first_trial(args, names, rungs, url):
    """`ebrl fit --stage first-trial` after its checks (experiments.studies.first_trials)."""
    from experiments.studies import first_trials, study
    problem = first_trials.Problem(args.robot, names, rungs, args.steps, room=args.room)
    name = args.study or _in_room(f"first_trial_{args.robot}", args.room)
    s, status = open_study(args, url, lambda: study.load(
        name, url, args.out, args.sampler_seed, first=problem.defaults()))
    if s is None:
        return status
    try:
        outcome, path, failed = first_trials.fit(
            problem, s, args.out, args.trials, batch=args.batch, workers=args.workers,
            backend=args.backend, promote=args.promote, progress=not args.no_progress,
            validate_seeds=args.validate, trial=args.trial)
    except (results.ResultsError, ValueError) as e:
        return fail(str(e))
    print(f"{outcome.made} trials made now, {outcome.total} in the study ({study.shown(url)})")
    return finish("fit", path, failed)
