"""`ebrl bench`: microseconds per agent step, by part (experiments.ops.bench). It takes
the robots `ebrl run` takes: registered names, a mount, or a robot .xml file with --drive."""
from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import check_robots, fail, selected_robots


def add_parser(subparsers):
    p = subparsers.add_parser("bench", help="microseconds per agent step, by part")
    arguments.add_robots(p, "all")
    p.add_argument("--steps", type=arguments.up_to(validate.MAX_BENCH_STEPS), default=2000,
                   help="timed steps per block")
    p.add_argument("--blocks", type=arguments.up_to(validate.MAX_BENCH_BLOCKS), default=5,
                   help="medians over this many blocks")
    arguments.add_room(p)
    p.set_defaults(func=run)


def run(args):
    try:
        check_robots(args)  # a robot file without --drive, or a bad one: one line
    except ValueError as e:
        return fail(str(e))
    from experiments.ops import bench
    bench.main(args.steps, args.blocks, selected_robots(args), args.room, args.drive)
    return 0
