"""The `ebrl` command (also `python -m experiments`): run, report, render, bench, demo."""
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
    p = _Parser(prog="ebrl", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    r = sub.add_parser("run", help="run the protocol (skips runs already on disk)")
    r.add_argument("--robot", type=_choice(paper.ROBOTS + ("all",)), default="all")
    r.add_argument("--condition", type=_choice(paper.CONDITIONS + ("all",)), default="all")
    r.add_argument("--seeds", type=parse_seeds, default=list(range(paper.SEEDS)),
                   help="e.g. 0-49 (default), 3, or 1,4,9")
    r.add_argument("--steps", type=positive_int, default=None,
                   help="agent steps per run (default: the paper's, "
                        + ", ".join(f"{k} {v:,}" for k, v in paper.BUDGETS.items()) + ")")
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
    v.add_argument("--robot", type=_choice(paper.ROBOTS), required=True)
    v.add_argument("--condition", type=_choice(paper.CONDITIONS), required=True)
    v.add_argument("--seed", type=int, required=True)
    v.add_argument("--steps", type=positive_int, default=3000)
    v.add_argument("--out", type=pathlib.Path, required=True)

    b = sub.add_parser("bench", help="microseconds per agent step, by part")
    b.add_argument("--steps", type=positive_int, default=2000, help="timed steps per block")
    b.add_argument("--blocks", type=positive_int, default=5, help="medians over this many blocks")

    w = sub.add_parser("sweep", help="the protocol at several values of one agent parameter")
    w.add_argument("--param", default="policy_threshold")
    w.add_argument("--values", default="0,0.01,0.05,0.1,0.2",
                   help="comma-separated values (default: %(default)s)")
    w.add_argument("--robot", type=_choice(paper.ROBOTS + ("all",)), default="all")
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
    robots = paper.ROBOTS if args.robot == "all" else (args.robot,)
    conditions = paper.CONDITIONS if args.condition == "all" else (args.condition,)
    return runner.plan(robots, conditions, args.seeds, args.steps or paper.BUDGETS, overrides)


def cmd_run(args):
    from experiments import report, results, runner
    specs = _plan(args, args.set)
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
    try:
        rendering.ensure_backend()
    except rendering.RenderingError as e:
        return _fail(str(e))
    spec = protocol.RunSpec(args.robot, args.condition, args.seed, args.steps)
    result = rendering.record(spec, args.out)
    print(f"video: {args.out} ({len(result['trial_ends'])} goals in {args.steps} steps)")
    return 0


def cmd_bench(args):
    from experiments import bench
    bench.main(args.steps, args.blocks)
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


DEMO_BUDGETS = {"two_wheel": 10_000, "floating": 20_000}
DEMO_SEEDS = 6
DEMO_VIDEO_STEPS = 3_000


def cmd_demo(args):
    """A quick protocol: 6 seeds at a third / a fifth of the paper's budgets, then the
    report and one video."""
    from experiments import protocol, rendering, report, results, runner
    budgets = DEMO_BUDGETS
    specs = runner.plan(paper.ROBOTS, paper.CONDITIONS, range(DEMO_SEEDS), budgets)
    print(f"demo: {len(specs)} runs ({DEMO_SEEDS} seeds x 2 robots x 2 conditions), budgets "
          + ", ".join(f"{k} {v:,} steps" for k, v in budgets.items()) + f" -> {args.out}/")
    try:
        runner.run(specs, args.out, workers=args.workers)
        path = report.build(args.out)
        rendering.ensure_backend()
    except (results.ResultsError, rendering.RenderingError) as e:
        return _fail(str(e))
    video = args.out / "two_wheel_avoidance_seed000.mp4"
    rendering.record(protocol.RunSpec("two_wheel", "avoidance", 0, DEMO_VIDEO_STEPS), video)
    print(f"report:  {path}\nfigures: {args.out / 'figures'}/\nvideo:   {video}")
    return 0


def main(argv=None):
    args = build_parser().parse_args(argv)
    try:
        return {"run": cmd_run, "report": cmd_report, "render": cmd_render,
                "bench": cmd_bench, "sweep": cmd_sweep, "demo": cmd_demo}[args.command](args)
    except KeyboardInterrupt:
        print("ebrl: interrupted; finished runs are kept, rerun to resume", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
