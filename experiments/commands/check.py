"""`ebrl check`: a robot's action accuracy and a random-action fuzz
(experiments.checks.robotcheck); with --tune, a mount's drive values searched against
them (experiments.checks.tune)."""
import pathlib

from experiments.checks import validate
from experiments.checks import robotcheck, tune
from experiments.commands import arguments
from experiments.commands.common import INTERRUPTED, check_robots, fail, selected_robots

#: The options that only --tune takes.
TUNE_ONLY = ("trials", "sampler_seed", "first_pass", "no_progress")


def add_parser(subparsers):
    p = subparsers.add_parser("check", help="a robot's action accuracy and a random-action fuzz; "
                                            "with --tune, a mount's gains found by them")
    arguments.add_robots(p, "all")
    p.add_argument("--actions", type=arguments.up_to(validate.MAX_STEPS), default=None,
                   help=f"random actions of the fuzz (default: {robotcheck.ACTIONS}; with "
                        f"--tune, each trial's: {tune.ACTIONS})")
    p.add_argument("--accuracy-actions", type=arguments.up_to(validate.MAX_STEPS), default=None,
                   help="free-space actions of the accuracy check (default: "
                        f"{robotcheck.ACCURACY_ACTIONS}; with --tune, each trial's: "
                        f"{tune.ACCURACY_ACTIONS})")
    arguments.add_room(p)
    p.add_argument("--tune", action="store_true",
                   help="search the mount's time_scale and its action's gains (kp, kv; one "
                        "per joint for joint_motors) with Optuna against the check's own "
                        "limits, and write them to NAME.tuned.toml beside the mount (never "
                        "over a file); one mount file (.toml) as --robot")
    p.add_argument("--trials", type=arguments.up_to(validate.MAX_TRIALS), default=None,
                   help=f"--tune: trials of the search, the mount as it is first (default: "
                        f"{tune.TRIALS})")
    p.add_argument("--sampler-seed", type=arguments.between(0, 2**31 - 1), default=None,
                   help="--tune: the TPE sampler's seed; the same seed, trials and counts "
                        "write the same file (default: 0)")
    p.add_argument("--first-pass", action="store_true",
                   help="--tune: stop after the first trials whose values pass (default: run "
                        "every trial and keep, of the values whose measures stay under half "
                        "their limits, those of the shortest time_scale)")
    p.add_argument("--no-progress", action="store_true", help="--tune: no progress bar")
    p.set_defaults(func=run)


def run(args):
    try:
        if args.tune:
            _check_tune(args)
        else:
            given = next((o for o in TUNE_ONLY if getattr(args, o) not in (None, False)), None)
            if given is not None:
                raise ValueError(f"--{given.replace('_', '-')} is an option of --tune")
        check_robots(args)
    except ValueError as e:
        return fail(str(e))
    if args.tune:
        try:
            return tune.main(pathlib.Path(args.robot[0]), args.trials or tune.TRIALS,
                             args.sampler_seed or 0, args.actions or tune.ACTIONS,
                             args.accuracy_actions or tune.ACCURACY_ACTIONS, args.room,
                             args.first_pass, not args.no_progress)
        except KeyboardInterrupt:   # written only at the end: nothing to resume
            return fail("interrupted; nothing written (a tune starts again when rerun)",
                        INTERRUPTED)
    return robotcheck.main(args.robot, args.actions or robotcheck.ACTIONS,
                           args.accuracy_actions or robotcheck.ACCURACY_ACTIONS, args.drive,
                           args.room)


def _check_tune(args):
    """--tune's robot: one mount file (tune.check_args), no --drive."""
    robots = selected_robots(args)
    if len(robots) != 1:
        raise ValueError("--tune takes one mount file: --robot FILE.toml")
    if args.drive is not None:
        raise ValueError("--tune takes a mount file, whose drive is in the mount, not --drive")
    tune.check_args(robots[0], tune.output_path(robots[0]))
