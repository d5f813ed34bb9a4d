"""`ebrl multiverse`: the protocol in every universe of a resolution-V design over the open
readings (experiments.studies.multiverse), then MULTIVERSE.md, multiverse.csv and a
specification curve per claim (experiments.outputs.multiverse, multiverse_report).

Each finished run leaves its record in the records folder (--records; experiments.studies.
multiverse_records), which is what the analysis reads and what a resume skips: a fresh
clone given the committed records (docs/data/multiverse) makes only the runs they lack,
or none (--report-only). The records are read and checked before any work."""
import pathlib

from experiments.checks import validate
from experiments.checks.validate import agent_configs
from experiments.commands import arguments
from experiments.commands.common import check_backend, fail, finish
from experiments.running import results, schema
from experiments.studies import multiverse, multiverse_records, multiverse_records as kept
from experiments.studies.multiverse_records import key
from tasks.robots import PAPER_ROBOTS

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
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("multiverse"),
                   help="the report, the table, the figures and the run folders (default: "
                        "multiverse)")
    p.add_argument("--records", type=pathlib.Path, default=None, metavar="DIR",
                   help="the runs' records, read first (a run recorded there is not made "
                        "again) and appended to (default: OUT/records; the committed "
                        "study's: docs/data/multiverse)")
    p.add_argument("--report-only", action="store_true",
                   help="make no run: the report from the records alone")
    p.add_argument("--bench", action="store_true",
                   help="also measure the cost of a step (ebrl bench's fused loop) for the "
                        "report's floor (OUT/bench.json)")
    arguments.add_results(p, "the page's section \"How much the conclusions depend on the "
                             "open details\" (between its markers), its figures copied")
    arguments.add_no_progress(p)
    p.set_defaults(func=run)


def _check(args):
    """Every argument checked before any work: (the chosen factors, the universes)."""
    validate.output_folder(args.out, "--out")
    if args.records is not None and not args.report_only:
        validate.output_folder(args.records, "--records")
    check_backend(args.backend)
    from experiments.outputs.multiverse_report import BLOCK
    arguments.check_results(args, BLOCK)
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


def _bench(out, measure):
    """OUT/bench.json: ebrl bench's measure per paper robot, made now (measure) or before."""
    import functools

    path = out / "bench.json"
    check = functools.partial(schema.check_bench, robots=PAPER_ROBOTS)
    if measure:
        from experiments.ops import bench
        from tasks.kernels.bindings import stage_timers_off
        with stage_timers_off():
            rows = {r: bench.measure(r, 1000, 3) for r in PAPER_ROBOTS}
        results.atomic_write(path, results.dumps(rows))
    return results.read_bookkeeping(path, check)


def _records(args, chosen, universes):
    """(the records folder, the plan's specs, its Store, {spec: record} of the recorded
    ones): every record file read and checked against this call (RecordsError)."""
    folder = args.records if args.records is not None else args.out / "records"
    store = multiverse_records.Store(folder, multiverse_records.identity(chosen, args.steps))
    specs = multiverse.plan(universes, args.seeds, args.steps)
    return folder, specs, store, store.match(specs)


def _levels(chosen):
    return {f.key: {r: [multiverse.levels(f, r).plain, multiverse.levels(f, r).alternative]
                    for r in PAPER_ROBOTS} for f in multiverse.factors()}


def _make(args, chosen, specs, made, folder):
    """Runs what no record holds (a complete run folder under OUT/runs without a record
    gives its record first), each run's record appended as it is written; returns
    runner.Ran."""
    writer = kept.Writer(folder, kept.identity(chosen, args.steps), _levels(chosen),
                         args.workers, args.backend)
    kept.seal_left(folder)

    def keep(spec, record):
        writer.add(record)
        made[spec] = record

    ran = None
    try:
        todo = [s for s in specs if s not in made]
        for spec in todo:  # a run made before records were kept, or killed before its record
            root = multiverse.root_of(args.out, spec)
            if results.existing(root, spec) == "done":
                run = results.read_run_json(results.run_dir(root, spec) / "run.json")
                record = kept.from_folder(root, spec, run)
                keep(spec, dict(record, at=round(writer.at(), 1)))
        ran = multiverse.run(
            args.out, [s for s in todo if s not in made], args.workers, args.backend,
            not args.no_progress,
            written=lambda spec, run, result: keep(spec, kept.record_of(
                spec, result["trial_ends"], result["memory_decisions"], result["seconds"],
                writer.at())))
    finally:  # Ctrl-C, a kill, a lost cluster: the records so far are sealed, kept
        writer.close(ran.made if ran else writer.count, interrupted=ran is None)
    return ran


def _report(args, chosen, design, universes, folder, specs, store, made):
    """The table, the figures and MULTIVERSE.md from the records (made: {spec: record})."""
    from experiments.outputs import multiverse as mv
    from experiments.outputs import multiverse_report as mr
    out = args.out
    data = multiverse.gather(universes, args.seeds, args.steps, made)
    records = {(name, d): mv.universe_record(runs, d)
               for name, runs in data.items() for d in mv.DEFINITIONS}
    factor_list = multiverse.factors()
    analysis = mv.analyse(factor_list, chosen, universes, records)
    results.atomic_write(out / "multiverse.csv", mv.table(factor_list, universes, records))
    figures = {}
    for claim in mv.CLAIMS:
        path = mr.spec_curve(claim, factor_list, chosen, universes, records,
                             out / "figures" / f"spec_{claim.key}.png")
        if path is not None:
            figures[claim.key] = f"figures/{path.name}"
    steps_by_robot = {}
    for s in specs:
        steps_by_robot[s.robot] = steps_by_robot.get(s.robot, 0) + s.steps
    failed = [] if args.report_only else multiverse.failed(out, [s for s in specs
                                                                 if s not in made])
    matched = {key(s) for s in made}
    ctx = mr.Context(factor_list, chosen, design, universes, records, analysis, args.seeds,
                     args.steps, len(specs), [float(r["seconds"]) for r in made.values()],
                     store.commits(matched), store.timing(matched), _bench(out, args.bench),
                     steps_by_robot,
                     figures, failed, str(folder), sum(k not in matched for k in store.runs))
    results.atomic_write(out / "multiverse.json", results.dumps({
        "design": {"name": design.name(), "generators": list(design.generators),
                   "resolution": design.resolution, "factors": [f.key for f in chosen],
                   "matrix": design.matrix.tolist()},
        "universes": {u.name: {"row": u.row, "marks": list(u.marks), "codes": u.codes,
                               "claims": {d: (records[(u.name, d)] or {}).get("claims")
                                          for d in mv.DEFINITIONS}}
                      for u in universes},
        "analysis": mv.analysis_json(analysis, mv.keys(factor_list, chosen))}))
    path = mr.write(out, ctx)
    if args.results is not None:
        mr.publish(out, path.read_text(), args.results, args.figures)
    return path, failed


def run(args):
    try:
        chosen, (design, universes) = _check(args)
        folder, specs, store, made = _records(args, chosen, universes)
        if not args.report_only:  # the run folders the records lack, before any work: a
            multiverse.check_on_disk(args.out, [s for s in specs if s not in made])  # refused
    except (ValueError, results.ResultsError) as e:  # resume touches nothing
        return fail(str(e))
    if args.report_only and not store.files:
        return fail(f"--report-only: no records at {folder}")
    args.out.mkdir(exist_ok=True)
    try:
        _bench(args.out, False)  # a damaged bench.json is set aside now, named, made again
        if not args.report_only:
            _make(args, chosen, specs, made, folder)
            store = type(store)(folder, store.ident)  # this session's records and end too
        path, failed = _report(args, chosen, design, universes, folder, specs, store, made)
    except results.ResultsError as e:
        return fail(str(e))
    return finish("multiverse", path, failed)
