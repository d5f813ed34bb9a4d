"""`ebrl bench`: microseconds per agent step, by part (experiments.checks.bench)."""
from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import check_room, fail


def add_parser(subparsers):
    p = subparsers.add_parser("bench", help="microseconds per agent step, by part")
    p.add_argument("--robot", type=arguments.robot_list, default=arguments.robot_list("all"),
                   metavar="NAME[,NAME...]|FILE",
                   help=arguments.robot_help(True, "all", xml=False))
    p.add_argument("--steps", type=arguments.up_to(validate.MAX_BENCH_STEPS), default=2000,
                   help="timed steps per block")
    p.add_argument("--blocks", type=arguments.up_to(validate.MAX_BENCH_BLOCKS), default=5,
                   help="medians over this many blocks")
    arguments.add_room(p)
    p.set_defaults(func=run)


def run(args):
    try:
        check_room(args.robot, args.room)
    except ValueError as e:
        return fail(str(e))
    from experiments.checks import bench
    bench.main(args.steps, args.blocks, args.robot, args.room)
    return 0
