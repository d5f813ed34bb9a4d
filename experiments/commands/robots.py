"""`ebrl robots`: the registered robots, their budgets and the readings each one sets."""


def add_parser(subparsers):
    parser = subparsers.add_parser("robots", help="list the registered robots")
    parser.set_defaults(func=run)


def run(args):
    from tasks.robots import ROBOTS
    print(f"{'robot':<12} {'drive':<10} {'Table 1':<8} {'budget':>8}  {'avoidance':<9} description")
    for r in ROBOTS.values():
        print(f"{r.name:<12} {r.drive:<10} {r.table1:<8} {r.budget:>8,}  {r.avoidance:<9} "
              f"{r.description}")
    print("\nReadings of what the paper leaves open (docs/interpretation.md; --set overrides):")
    for r in ROBOTS.values():
        text = ", ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}"
                         for k, v in r.readings)
        print(f"{r.name:<12} {text or 'none: the config fields defaults'}")
    return 0
