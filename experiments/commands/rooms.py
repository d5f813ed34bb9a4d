"""`ebrl rooms`: the shipped maps (models/maps/), each with its size and shortest path;
with --show NAME|FILE, one map's text (and random:WxH:SEED's maze)."""
from experiments.commands import arguments
from models import rooms


def add_parser(subparsers):
    p = subparsers.add_parser("rooms", help="list the shipped maps (rooms); --show one")
    p.add_argument("--show", type=arguments.room, default=False, metavar="NAME|FILE",
                   help="print one room's map: a shipped map, random:WxH:SEED or a map file")
    p.set_defaults(func=run)


def run(args):
    if args.show is not False:
        m = rooms.load(rooms.DEFAULT if args.show is None else args.show)
        print(m.text(), end="")
        return 0
    print(f"{'room':<10} {'cells':>7} {'cell':>5} {'walls':>6} {'shortest':>9}  description")
    for name, description in rooms.MAPS.items():
        m = rooms.load(name)
        print(f"{name:<10} {f'{m.width}x{m.height}':>7} {m.cell:>5g} {len(rooms.merged_walls(m)):>6} "
              f"{m.shortest_cells():>9}  {description}")
    print("\nrandom:WxH:SEED  a labmaze.RandomMaze of W x H cells (3..31), drawn by its seed; "
          "a map file: docs/rooms.md ('*' wall, ' ' free, one 'P' start, one 'G' goal)."
          "\nwalls: the merged inner wall boxes; shortest: the fewest cell moves from P to G.")
    return 0
