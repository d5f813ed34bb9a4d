"""`ebrl multiverse`: the protocol in every universe of a resolution-V design over the open
readings (experiments.studies.multiverse), then MULTIVERSE.md, multiverse.csv and a
specification curve per claim (experiments.outputs.multiverse, multiverse_report)."""
import datetime
import pathlib
import time

from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import check_backend, fail, finish

#: The multiverse's own seeds (docs/seeds.md): 20 per universe, named before any run.
SEEDS = list(range(11000, 11020))


def add_parser(subparsers):
    p = subparsers.add_parser(
        "multiverse", help="the protocol in every combination of the readings the text "
                           "allows (a resolution-V design), a specification curve per claim")
    p.add_argument("--factors", default="all",
                   help="comma-separated factor keys (default: all; the others stay plain; "
                        "docs/interpretation.md, \"The multiverse\")")
    p.add_argument("--universes", type=arguments.up_to(), default=None, metavar="K",
                   help="run the first K universes of the design (default: all; the first "
                        "is the literal protocol), and the current protocol where it is not "
                        "among them")
    p.add_argument("--seeds", type=arguments.seeds, default=SEEDS,
                   help="seeds per universe (default: 11000-11019, docs/seeds.md)")
    p.add_argument("--steps", type=arguments.up_to(validate.MAX_STEPS), default=None,
                   help="agent steps per run, a cap for quick checks (default: the paper's "
                        "budgets)")
    arguments.add_workers(p)
    arguments.add_backend(p)
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("multiverse"))
    p.add_argument("--bench", action="store_true",
                   help="also measure the cost of a step (ebrl bench's fused loop) for the "
                        "report's floor (OUT/bench.json)")
    arguments.add_no_progress(p)
    p.set_defaults(func=run)


def _check(args):
    """Every argument checked before any work: (the chosen factors, the universes)."""
    from experiments.checks.validate import agent_configs
    from experiments.studies import multiverse
    from tasks.robots import PAPER_ROBOTS
    validate.output_folder(args.out, "--out")
    check_backend(args.backend)
    keys = None if args.factors == "all" else \
        [k.strip() for k in args.factors.split(",") if k.strip()]
    chosen = multiverse.select(keys)
    design = multiverse.design_for(chosen)
    if args.universes is not None and args.universes > design.runs:
        raise ValueError(f"--universes must be at most {design.runs}, the design's universes "
                         f"({design.name()}), got {args.universes}")
    for robot in PAPER_ROBOTS:  # each level's readings as a run's configs take them
        for factor in multiverse.factors():
            lv = multiverse.levels(factor, robot)
            for values in (lv.plain, lv.alternative):
                agent_configs((robot,), tuple(sorted(values.items())))
    return chosen, multiverse.universes(chosen, args.universes)


def _timing(out, started, seconds, ran, args):
    """OUT/timing.json: every call's wall time and runs (ran: runner.Ran; None for a call
    stopped before its runs were done), appended."""
    from experiments.running import results, schema
    path = out / "timing.json"
    sessions = results.read_bookkeeping(path, schema.check_timing) or []
    counts = ({"interrupted": True} if ran is None else
              {"runs_made": ran.made, "on_disk": ran.on_disk, "failed": len(ran.failed)})
    sessions.append({"started": started, "seconds": round(seconds, 1), **counts,
                     "workers": args.workers, "backend": args.backend})
    results.atomic_write(path, results.dumps(sessions))
    return sessions


def _bench(out, measure):
    """OUT/bench.json: ebrl bench's measure per paper robot, made now (measure) or before."""
    import functools

    from experiments.running import results, schema
    from tasks.robots import PAPER_ROBOTS
    path = out / "bench.json"
    check = functools.partial(schema.check_bench, robots=PAPER_ROBOTS)
    if measure:
        from experiments.checks import bench
        from tasks.kernels.bindings import stage_timers_off
        with stage_timers_off():
            rows = {r: bench.measure(r, 1000, 3) for r in PAPER_ROBOTS}
        results.atomic_write(path, results.dumps(rows))
    return results.read_bookkeeping(path, check)


def _report(args, chosen, design, universes, seconds_made):
    """Collects what is on disk and writes the table, the figures and MULTIVERSE.md."""
    from experiments.outputs import multiverse as mv
    from experiments.outputs import multiverse_report as mr
    from experiments.running import results
    from experiments.studies import multiverse
    out = args.out
    data, failed, seconds, commits = multiverse.collect(out, universes, args.seeds, args.steps)
    records = {name: mv.universe_record(runs) for name, runs in data.items()}
    factor_list = multiverse.factors()
    analysis = mv.analyse(factor_list, chosen, universes, records)
    results.atomic_write(out / "multiverse.csv", mv.table(factor_list, universes, records))
    figures = {}
    for claim in mv.CLAIMS:
        path = mr.spec_curve(claim, factor_list, chosen, universes, records,
                             out / "figures" / f"spec_{claim.key}.png")
        if path is not None:
            figures[claim.key] = f"figures/{path.name}"
    specs = multiverse.plan(out, universes, args.seeds, args.steps)
    steps_by_robot = {}
    for s in specs:
        steps_by_robot[s.robot] = steps_by_robot.get(s.robot, 0) + s.steps
    ctx = mr.Context(factor_list, chosen, design, universes, records, analysis, args.seeds,
                     args.steps, len(specs), seconds, commits, seconds_made,
                     _bench(out, args.bench), steps_by_robot, figures, failed)
    results.atomic_write(out / "multiverse.json", results.dumps({
        "design": {"name": design.name(), "generators": list(design.generators),
                   "resolution": design.resolution, "factors": [f.key for f in chosen],
                   "matrix": design.matrix.tolist()},
        "universes": {u.name: {"row": u.row, "marks": list(u.marks), "codes": u.codes,
                               "claims": (records[u.name] or {}).get("claims")}
                      for u in universes},
        "analysis": analysis}))
    return mr.write(out, ctx), failed


def run(args):
    try:
        chosen, (design, universes) = _check(args)
    except ValueError as e:
        return fail(str(e))
    from experiments.running import results, schema
    from experiments.studies import multiverse
    try:  # what is on disk, before any work: a refusal writes nothing (no timing entry)
        multiverse.check_on_disk(args.out, universes, args.seeds, args.steps)
    except results.ResultsError as e:
        return fail(str(e))
    args.out.mkdir(exist_ok=True)
    results.read_bookkeeping(args.out / "timing.json", schema.check_timing)  # a damaged
    _bench(args.out, False)  # timing.json or bench.json is set aside now, named, made again
    started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    clock = time.perf_counter()
    try:
        try:
            ran = multiverse.run(args.out, universes, args.seeds, args.steps, args.workers,
                                 args.backend, not args.no_progress)
        except BaseException:  # Ctrl-C, a kill, a lost cluster: its wall time still counts
            _timing(args.out, started, time.perf_counter() - clock, None, args)
            raise
        sessions = _timing(args.out, started, time.perf_counter() - clock, ran, args)
        path, failed = _report(args, chosen, design, universes, sessions)
    except results.ResultsError as e:
        return fail(str(e))
    return finish("multiverse", path, failed)
