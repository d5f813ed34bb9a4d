"""`ebrl check`: a robot's action accuracy and a random-action fuzz
(experiments.checks.robotcheck)."""
from experiments.checks import validate
from experiments.checks import robotcheck
from experiments.commands import arguments
from experiments.commands.common import check_robots, fail


def add_parser(subparsers):
    p = subparsers.add_parser("check", help="a robot's action accuracy and a random-action fuzz")
    arguments.add_robots(p, "all")
    p.add_argument("--actions", type=arguments.up_to(validate.MAX_STEPS), default=100_000,
                   help="random actions of the fuzz (default: %(default)s)")
    p.add_argument("--accuracy-actions", type=arguments.up_to(validate.MAX_STEPS), default=1000,
                   help="free-space actions of the accuracy check (default: %(default)s)")
    arguments.add_room(p)
    p.set_defaults(func=run)


def run(args):
    try:
        check_robots(args)
    except ValueError as e:
        return fail(str(e))
    return robotcheck.main(args.robot, args.actions, args.accuracy_actions, args.drive,
                           args.room)
