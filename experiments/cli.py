"""The `ebrl` command (also `python -m experiments`): robots, run, report, render, bench,
check, sweep, demo."""
import argparse
import os
import pathlib
import sys

from experiments import paper

USAGE_ERROR = 2


class _Parser(argparse.ArgumentParser):
    """Bad arguments: one line on stderr and exit status 2, nothing written."""

    def error(self, message):
        self.exit(USAGE_ERROR, f"{self.prog}: error: {message}\n")


def _fail(message):
    print(f"ebrl: error: {message}", file=sys.stderr)
    return USAGE_ERROR


def parse_seeds(text):
    """'0-49', '7' or '1,3,5' -> sorted list of seeds."""
    seeds = set()
    for part in text.split(","):
        part = part.strip()
        try:
            if "-" in part:
                lo, hi = (int(v) for v in part.split("-", 1))
                if hi < lo:
                    raise argparse.ArgumentTypeError(f"reversed seed range {part!r}")
                seeds.update(range(lo, hi + 1))
            else:
                seeds.add(int(part))
        except ValueError:
            raise argparse.ArgumentTypeError(f"bad seed range {text!r} (use e.g. 0-49)") from None
    if not seeds:
        raise argparse.ArgumentTypeError(f"empty seed range {text!r}")
    if min(seeds) < 0:
        raise argparse.ArgumentTypeError("seeds must be non-negative")
    return sorted(seeds)


def positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"must be positive, got {value}")
    return value


def _choice(valid):
    def check(text):
        if text not in valid:
            raise argparse.ArgumentTypeError(f"unknown {text!r}; valid: {', '.join(valid)}")
        return text
    return check


def robot_list(text):
    """--robot: a registered name, several joined by commas, "paper" (the paper's two
    robots), "all" (every registered robot), or a path to a robot .xml file (with
    --drive)."""
    from tasks.robots import PAPER_ROBOTS, ROBOTS
    if text == "paper":
        return PAPER_ROBOTS
    if text == "all":
        return tuple(ROBOTS)
    if text.lower().endswith(".xml"):
        return (text,)
    names = tuple(n.strip() for n in text.split(","))
    for n in names:
        if n not in ROBOTS:
            raise argparse.ArgumentTypeError(
                f"unknown robot {n!r}; valid: {', '.join(ROBOTS)}, paper, all, "
                "or a path to a robot .xml file with --drive")
    return names


def _robot_args(parser, default):
    from tasks.robots import DRIVES
    parser.add_argument("--robot", type=robot_list, default=robot_list(default),
                        help=f"default: {default} (see 'ebrl robots')")
    parser.add_argument("--drive", type=_choice(tuple(DRIVES)), default=None,
                        help="the drive of a robot given as a file: " + ", ".join(DRIVES))


def _override(text):
    """name=value for an agent parameter (sweeps), e.g. policy_threshold=0.05."""
    import dataclasses

    import ebrl
    name, sep, value = text.partition("=")
    fields = {f.name: f for f in dataclasses.fields(ebrl.Config)}
    if not sep or name not in fields:
        raise argparse.ArgumentTypeError(f"bad --set {text!r}; use NAME=VALUE with NAME one of "
                                         + ", ".join(fields))
    kind = type(getattr(ebrl.Config(), name))
    try:
        return name, kind(value)
    except ValueError:
        raise argparse.ArgumentTypeError(f"bad value for {name}: {value!r}") from None


def build_parser():
    from tasks.robots import DRIVES
    p = _Parser(prog="ebrl", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    sub.add_parser("robots", help="list the registered robots")

    r = sub.add_parser("run", help="run the protocol (skips runs already on disk)")
    _robot_args(r, "paper")
    r.add_argument("--condition", type=_choice(paper.CONDITIONS + ("all",)), default="all")
    r.add_argument("--seeds", type=parse_seeds, default=list(range(paper.SEEDS)),
                   help="e.g. 0-49 (default), 3, or 1,4,9")
    r.add_argument("--steps", type=positive_int, default=None,
                   help="agent steps per run (default: the robot's budget, 'ebrl robots')")
    r.add_argument("--workers", type=positive_int, default=os.cpu_count() or 1)
    r.add_argument("--backend", type=_choice(("local", "ray")), default="local")
    r.add_argument("--out", type=pathlib.Path, default=pathlib.Path("results"))
    r.add_argument("--set", type=_override, action="append", default=[], metavar="NAME=VALUE",
                   help="change an agent parameter from Table 1's (for sweeps)")
    r.add_argument("--no-progress", action="store_true")

    rep = sub.add_parser("report", help="rebuild summary.json, REPORT.md and figures")
    rep.add_argument("dir", type=pathlib.Path)
    rep.add_argument("--results", type=pathlib.Path, default=None, metavar="RESULTS.md",
                     help="also regenerate the tables of this page (between its markers), "
                          "copy the figures to --figures and summary.json beside it")
    rep.add_argument("--figures", type=pathlib.Path, default=pathlib.Path("docs/figures"))

    v = sub.add_parser("render", help="an offscreen MP4 of one run")
    v.add_argument("--robot", required=True, help="a registered name or a robot .xml file")
    v.add_argument("--drive", default=None, help="the drive of a robot given as a file")
    v.add_argument("--camera", default="top",
                   help="top (default), perspective, or a camera of the robot's file")
    v.add_argument("--condition", type=_choice(paper.CONDITIONS), required=True)
    v.add_argument("--seed", type=int, required=True)
    v.add_argument("--steps", type=positive_int, default=3000)
    v.add_argument("--out", type=pathlib.Path, required=True)

    b = sub.add_parser("bench", help="microseconds per agent step, by part")
    b.add_argument("--robot", type=robot_list, default=robot_list("all"),
                   help="default: every registered robot")
    b.add_argument("--steps", type=positive_int, default=2000, help="timed steps per block")
    b.add_argument("--blocks", type=positive_int, default=5, help="medians over this many blocks")

    c = sub.add_parser("check", help="a robot's action accuracy and a random-action fuzz")
    c.add_argument("--robot", type=robot_list, default=robot_list("all"),
                   help="default: every registered robot")
    c.add_argument("--drive", type=_choice(tuple(DRIVES)), default=None,
                   help="the drive of a robot given as a file")
    c.add_argument("--actions", type=positive_int, default=100_000,
                   help="random actions of the fuzz (default: %(default)s)")
    c.add_argument("--accuracy-actions", type=positive_int, default=1000,
                   help="free-space actions of the accuracy check (default: %(default)s)")

    w = sub.add_parser("sweep", help="the protocol at several values of one agent parameter")
    w.add_argument("--param", default="policy_threshold")
    w.add_argument("--values", default="0,0.01,0.05,0.1,0.2",
                   help="comma-separated values (default: %(default)s)")
    _robot_args(w, "paper")
    w.add_argument("--condition", type=_choice(paper.CONDITIONS + ("all",)), default="all")
    w.add_argument("--seeds", type=parse_seeds, default=list(range(20)))
    w.add_argument("--steps", type=positive_int, default=None)
    w.add_argument("--workers", type=positive_int, default=os.cpu_count() or 1)
    w.add_argument("--out", type=pathlib.Path, default=pathlib.Path("sweeps"))
    w.add_argument("--baseline", type=pathlib.Path, default=None,
                   help="a run folder (e.g. results) whose runs at the default value join the "
                        "table, for the same robots, conditions, seeds and budgets")
    w.add_argument("--no-progress", action="store_true")

    d = sub.add_parser("demo", help="a quick protocol, its report and one video")
    d.add_argument("--out", type=pathlib.Path, default=pathlib.Path("demo_results"))
    d.add_argument("--workers", type=positive_int, default=os.cpu_count() or 1)
    return p


def _plan(args, overrides=()):
    """The specs that --robot, --condition, --seeds and --steps select."""
    from experiments import runner
    conditions = paper.CONDITIONS if args.condition == "all" else (args.condition,)
    return runner.plan(args.robot, conditions, args.seeds, args.steps, overrides, args.drive)


def _check_robots(args):
    """Loads each robot's model once (a user's file can lack a part): ValueError if not."""
    import tasks
    for robot in args.robot:
        tasks.load(robot, drive=args.drive).close()


def cmd_robots(args):
    from tasks.robots import ROBOTS
    print(f"{'robot':<12} {'drive':<10} {'Table 1':<8} {'budget':>8}  {'avoidance':<9} description")
    for r in ROBOTS.values():
        print(f"{r.name:<12} {r.drive:<10} {r.table1:<8} {r.budget:>8,}  {r.avoidance:<9} "
              f"{r.description}")
    return 0


def cmd_run(args):
    from experiments import report, results, runner
    try:
        _check_robots(args)
        specs = _plan(args, args.set)
    except ValueError as e:
        return _fail(str(e))
    try:
        ran = runner.run(specs, args.out, workers=args.workers, backend=args.backend,
                         progress=not args.no_progress)
        path = report.build(args.out)
    except results.ResultsError as e:
        return _fail(str(e))
    print(f"{ran} runs made, {len(specs) - ran} already on disk; report: {path}")
    return 0


def cmd_report(args):
    from experiments import report, results
    if not args.dir.is_dir():
        return _fail(f"no results folder at {args.dir}")
    try:
        path = report.build(args.dir)
        if args.results is not None:
            print(f"published: {report.publish(args.dir, args.results, args.figures)}")
    except results.ResultsError as e:
        return _fail(str(e))
    print(f"report: {path}")
    return 0


def cmd_render(args):
    from experiments import protocol, rendering
    if args.out.suffix.lower() != ".mp4":
        return _fail(f"--out must end in .mp4, got {args.out}")
    if not args.out.parent.is_dir():
        return _fail(f"no folder {args.out.parent} for --out")
    spec = protocol.RunSpec(args.robot, args.condition, args.seed, args.steps,
                            drive=args.drive)
    try:
        spec.entry
        rendering.ensure_backend()
        rendering.check_camera(spec, args.camera)
    except (ValueError, rendering.RenderingError) as e:
        return _fail(str(e))
    result = rendering.record(spec, args.out, camera=args.camera)
    print(f"video: {args.out} ({len(result['trial_ends'])} goals in {args.steps} steps)")
    return 0


def cmd_check(args):
    from experiments import robotcheck
    try:
        _check_robots(args)
    except ValueError as e:
        return _fail(str(e))
    return robotcheck.main(args.robot, args.actions, args.accuracy_actions, args.drive)


def cmd_bench(args):
    from experiments import bench
    bench.main(args.steps, args.blocks, args.robot)
    return 0


def cmd_sweep(args):
    import ebrl
    from experiments import report, results, runner
    try:
        values = [_override(f"{args.param}={v}") for v in args.values.split(",") if v.strip()]
    except argparse.ArgumentTypeError as e:
        return _fail(str(e))
    if not values:
        return _fail("--values is empty")
    try:
        _check_robots(args)
    except ValueError as e:
        return _fail(str(e))
    plans = [(args.out / f"{args.param}_{v}", _plan(args, [(n, v)])) for n, v in values]
    try:
        baseline = None
        if args.baseline is not None:  # the default's runs, checked before running any
            specs = _plan(args)
            if runner.pending(args.baseline, specs):
                raise results.ResultsError(f"{args.baseline} lacks some of these runs at the "
                                           f"default {args.param}; run them there first")
            baseline = results.load_runs(args.baseline, specs)
        for folder, specs in plans:  # refuse damaged or mismatched folders before running any
            runner.pending(folder, specs)
        for folder, specs in plans:
            runner.run(specs, folder, workers=args.workers, progress=not args.no_progress)
            report.build(folder)
        rows = [(v, results.load_runs(f)) for (_, v), (f, _) in zip(values, plans)]
        if baseline is not None:
            default = getattr(ebrl.Config(), args.param)
            rows = sorted(rows + [(default, baseline)], key=lambda row: row[0])
            rows = [(f"{v} (default, {args.baseline})" if runs is baseline else v, runs)
                    for v, runs in rows]
        path = report.sweep_table(args.out, args.param, rows)
    except results.ResultsError as e:
        return _fail(str(e))
    print(f"sweep: {path}")
    return 0


DEMO_SEEDS = 6
DEMO_VIDEO_STEPS = 3_000


def cmd_demo(args):
    """A quick protocol: the paper's robots, 6 seeds at a fifth of their budgets (at least
    10,000 steps), then the report and one video."""
    from experiments import protocol, rendering, report, results, runner
    from tasks.robots import PAPER_ROBOTS, ROBOTS
    budgets = {r: max(10_000, ROBOTS[r].budget // 5) for r in PAPER_ROBOTS}
    specs = runner.plan(tuple(budgets), paper.CONDITIONS, range(DEMO_SEEDS), budgets)
    print(f"demo: {len(specs)} runs ({DEMO_SEEDS} seeds x 2 robots x 2 conditions), budgets "
          + ", ".join(f"{k} {v:,} steps" for k, v in budgets.items()) + f" -> {args.out}/")
    try:
        runner.run(specs, args.out, workers=args.workers)
        path = report.build(args.out)
        rendering.ensure_backend()
    except (results.ResultsError, rendering.RenderingError) as e:
        return _fail(str(e))
    robot = PAPER_ROBOTS[0]
    video = args.out / f"{robot}_avoidance_seed000.mp4"
    rendering.record(protocol.RunSpec(robot, "avoidance", 0, DEMO_VIDEO_STEPS), video)
    print(f"report:  {path}\nfigures: {args.out / 'figures'}/\nvideo:   {video}")
    return 0


def main(argv=None):
    args = build_parser().parse_args(argv)
    try:
        return {"robots": cmd_robots, "run": cmd_run, "report": cmd_report, "render": cmd_render,
                "bench": cmd_bench, "check": cmd_check, "sweep": cmd_sweep, "demo": cmd_demo}[args.command](args)
    except KeyboardInterrupt:
        print("ebrl: interrupted; finished runs are kept, rerun to resume", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
