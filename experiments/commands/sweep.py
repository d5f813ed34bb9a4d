"""`ebrl sweep`: the protocol at several values of one agent or task setting, each value in
its own folder, then one table (optionally beside a baseline folder's runs at the default)."""
import argparse
import pathlib

from experiments.checks import validate
from experiments.commands import arguments
from experiments.commands.common import (check_agent, check_robots, fail, finish, plan,
                                          selected_robots)
from experiments.running import settings
from experiments.running import results, runner
from experiments.running.learners import AGENTS
from tasks.robots import resolve


def add_parser(subparsers):
    p = subparsers.add_parser("sweep",
                              help="the protocol at several values of one agent parameter")
    p.add_argument("--param", default="policy_threshold")
    p.add_argument("--values", default="0,0.01,0.05,0.1,0.2",
                   help="comma-separated values (default: %(default)s)")
    arguments.add_robots(p, "paper")
    arguments.add_room(p)
    arguments.add_condition(p)
    p.add_argument("--seeds", type=arguments.seeds, default=list(range(20)))
    p.add_argument("--steps", type=arguments.up_to(validate.MAX_STEPS), default=None)
    arguments.add_workers(p)
    p.add_argument("--agent", type=arguments.choice(AGENTS), default="ebrl")
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("sweeps"))
    p.add_argument("--baseline", type=pathlib.Path, default=None,
                   help="a run folder (e.g. results) whose runs at the default value join the "
                        "table, for the same robots, conditions, seeds and budgets")
    arguments.add_no_progress(p)
    p.set_defaults(func=run)


def _values(args):
    """--param and --values as (name, value) pairs, each value distinct and accepted by
    ebrl.Config for the selected robots."""
    fields = list(settings.kinds())
    if args.param not in fields:
        raise ValueError(f"unknown --param {args.param!r}; one of {', '.join(fields)}")
    try:
        values = [arguments.override(f"{args.param}={v.strip()}") for v in args.values.split(",")
                  if v.strip()]
    except argparse.ArgumentTypeError as e:
        raise ValueError(str(e)) from None
    if not values:
        raise ValueError("--values is empty")
    seen = [v for _, v in values]
    repeated = next((v for v in seen if seen.count(v) > 1), None)
    if repeated is not None:
        raise ValueError(f"--values gives {args.param}={repeated} more than once")
    for value in values:
        check_agent(args, [value])
    return values


def _check(args):
    """Every argument checked before any work: the (name, value) pairs."""
    check_robots(args)
    values = _values(args)
    validate.output_folder(args.out, "--out")
    if args.baseline is not None:
        validate.results_folder(args.baseline, "--baseline")
    return values


def _baseline(args):
    """The baseline folder's runs at the default value (None without --baseline), refused
    before running any when some are missing."""
    if args.baseline is None:
        return None
    specs = plan(args)
    if runner.pending(args.baseline, specs, mend=False):  # a folder this command only reads
        raise results.ResultsError(f"{args.baseline} lacks some of these runs at the "
                                   f"default {args.param}; run them there first")
    return results.load_runs(args.baseline, specs)


def _with_baseline(args, rows, baseline):
    """The table's rows with the baseline's in its place: by value at the robots' shared
    default, else first."""
    default = settings.default(
        args.param, [resolve(r, args.drive) for r in selected_robots(args)])
    if default is None:  # the robots' defaults differ: the baseline first
        rows = [("the robots' own", baseline)] + rows
    else:
        rows = sorted(rows + [(default, baseline)], key=lambda row: row[0])
    return [(f"{v} (default, {args.baseline})" if runs is baseline else v, runs)
            for v, runs in rows]


def _sweep(args, values):
    """Runs every value's folder: (the table's path or None, the failed (name, error))."""
    from experiments.outputs import report
    plans = [(args.out / f"{args.param}_{v}", plan(args, [(n, v)])) for n, v in values]
    baseline = _baseline(args)  # the default's runs, checked before running any
    for folder, specs in plans:  # refuse mismatched folders, set damaged runs aside, first
        runner.pending(folder, specs)
    # Every value's runs on one worker pool, value after value (a pool's start costs
    # about as much as a short value's runs); each run in its value's folder.
    where = {spec: folder for folder, specs in plans for spec in specs}
    ran = runner.run(list(where), where.__getitem__, workers=args.workers,
                     progress=not args.no_progress)
    failed = [(f"{where[s].name}/{s.name}", e) for s, e in ran.failed]
    rows = []
    for ((_, v), (folder, specs)) in zip(values, plans):
        if len(runner.pending(folder, specs)) < len(specs):  # a complete run to report
            report.build(folder)
            rows.append((v, results.load_runs(folder)))
    if baseline is not None:
        rows = _with_baseline(args, rows, baseline)
    path = report.sweep_table(args.out, args.param, rows, failed) if rows else None
    return path, failed


def run(args):
    try:
        values = _check(args)
    except ValueError as e:
        return fail(str(e))
    try:
        path, failed = _sweep(args, values)
    except results.ResultsError as e:
        return fail(str(e))
    return finish("sweep", path, failed)
