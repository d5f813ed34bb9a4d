"""`ebrl robots`: the registered robots, their budgets and the readings each one sets,
then the mounted robot files."""


def add_parser(subparsers):
    parser = subparsers.add_parser("robots", help="list the registered robots")
    parser.set_defaults(func=run)


def run(args):
    from tasks.readings import READING_BY_NAME, applies
    from tasks.robots import MOUNTS, ROBOTS, resolve
    print(f"{'robot':<12} {'drive':<10} {'Table 1':<8} {'budget':>8}  {'avoidance':<9} description")
    for r in ROBOTS.values():
        print(f"{r.name:<12} {r.drive:<10} {r.table1:<8} {r.budget:>8,}  {r.avoidance:<9} "
              f"{r.description}")
    print("\nReadings of what the paper leaves open, where the robot's protocol sets one that acts "
          "on it (docs/interpretation.md; --set overrides):")
    for r in ROBOTS.values():
        text = ", ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}"
                         for k, v in r.readings if applies(READING_BY_NAME[k], r))
        print(f"{r.name:<12} {text or 'none: the literal protocol'}")
    print("\nMounted robot files, unchanged (models/mounts/*.toml; docs/adding_a_robot.md):")
    for name in MOUNTS:
        r = resolve(name)
        print(f"{r.name:<12} {r.drive:<10} {r.table1:<8} {r.budget:>8,}  {r.avoidance:<9} "
              f"{r.description} ({r.unit:.3g} m per unit)")
    return 0
