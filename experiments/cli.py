"""The `ebrl` command (also `python -m experiments`): robots, run, report, render, bench,
check, sweep, ablate, fit, evolve, demo.

Exit status: 0 done; 1 some runs failed (each recorded in its run.json, named by the
report, retried by a rerun); 2 a bad argument (one line, nothing written), or a results
folder that cannot be written or a lost Ray cluster (one line; finished runs kept, the same
command resumes); 130 Ctrl-C (finished runs kept; the same command resumes), SIGTERM likewise.
"""
import argparse
import os
import pathlib
import signal
import sys
import threading

from experiments import paper
from experiments.checks import validate

USAGE_ERROR = 2
RUNS_FAILED = 1
INTERRUPTED = 130


class _Parser(argparse.ArgumentParser):
    """Bad arguments: one line on stderr and exit status 2, nothing written."""

    def error(self, message):
        self.exit(USAGE_ERROR, f"{self.prog}: error: {message}\n")


def _fail(message, status=USAGE_ERROR):
    print(f"ebrl: error: {message}", file=sys.stderr)
    return status


def robot_list(text):
    """--robot: a registered name, several joined by commas, "paper" (the paper's two
    robots), "all" (every registered robot), or a path to a robot .xml file (with
    --drive). The names come from the registry, tasks/robots.py."""
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


def _robot_args(parser, default, several=True):
    """--robot and --drive, from the registry."""
    from tasks.robots import DRIVES
    if several:
        parser.add_argument("--robot", type=robot_list, default=robot_list(default),
                            help=f"default: {default}; see 'ebrl robots'")
    else:
        parser.add_argument("--robot", type=_one_robot, required=True,
                            help="a registered name (see 'ebrl robots') or a robot .xml file")
    parser.add_argument("--drive", type=_choice(tuple(DRIVES)), default=None,
                        help="the drive of a robot given as a file: " + ", ".join(DRIVES))


def _one_robot(text):
    robots = robot_list(text)
    if len(robots) != 1:
        raise argparse.ArgumentTypeError(f"one robot, got {text!r}")
    return robots[0]


def _argument(check):
    """validate's ValueError as argparse's error (one line, exit status 2)."""
    def wrapped(text):
        try:
            return check(text)
        except ValueError as e:
            raise argparse.ArgumentTypeError(str(e)) from None
    return wrapped


def parse_seeds(text):
    """'0-49', '7' or '1,3,5' -> sorted list of seeds (0 to validate.MAX_SEED, at most
    validate.MAX_SEEDS of them)."""
    return _argument(validate.seeds)(text)


def positive_int(text, maximum=sys.maxsize):
    return _argument(lambda t: validate.integer(t, 1, maximum))(text)


def _up_to(maximum):
    """A positive integer at most maximum, for argparse."""
    return lambda text: positive_int(text, maximum)


def _choice(valid):
    def check(text):
        if text not in valid:
            raise argparse.ArgumentTypeError(f"unknown {text!r}; valid: {', '.join(valid)}")
        return text
    return check


def _override(text):
    """name=value for a field of the agent's config (ebrl.Config) or the task's
    (tasks.TaskConfig), e.g. policy_threshold=0.05 or bump=slide."""
    name, sep, value = text.partition("=")
    kinds = validate.setting_kinds()
    if not sep or name not in kinds:
        raise argparse.ArgumentTypeError(f"bad --set {text!r}; use NAME=VALUE with NAME one of "
                                         + ", ".join(kinds))
    return name, _argument(lambda v: validate.number(kinds[name], name, v))(value)


def _comparison(text):
    """--compare: "condition" (random, then avoidance), "behaviour" (the paper's rule, then
    --behaviour FILE) or NAME=A,B (--set NAME=A, then NAME=B) -> (name, (a, b))."""
    if text == "condition":
        return "condition", paper.CONDITIONS
    if text == "behaviour":
        return "behaviour", ("hand-coded", "evolved")
    name, sep, values = text.partition("=")
    kinds = validate.setting_kinds()
    parts = values.split(",")
    if not sep or name not in kinds or len(parts) != 2:
        raise argparse.ArgumentTypeError(
            f"bad --compare {text!r}; use condition, behaviour, or NAME=A,B with NAME one of "
            + ", ".join(kinds))
    a, b = (_argument(lambda v: validate.number(kinds[name], name, v))(p) for p in parts)
    if a == b:
        raise argparse.ArgumentTypeError(f"--compare {text!r} compares a value with itself")
    return name, (a, b)


def build_parser():
    from experiments.running.protocol import AGENTS
    p = _Parser(prog="ebrl", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)

    sub.add_parser("robots", help="list the registered robots")

    r = sub.add_parser("run", help="run the protocol (skips runs already on disk)")
    _robot_args(r, "paper")
    r.add_argument("--condition", type=_choice(paper.CONDITIONS + ("all",)), default="all")
    r.add_argument("--seeds", type=parse_seeds, default=list(range(paper.SEEDS)),
                   help=f"e.g. 0-49 (default), 3, or 1,4,9; seeds 0 to {validate.MAX_SEED:,}, "
                        f"at most {validate.MAX_SEEDS:,} of them")
    r.add_argument("--steps", type=_up_to(validate.MAX_STEPS), default=None,
                   help="agent steps per run (default: the robot's budget, 'ebrl robots'; "
                        f"at most {validate.MAX_STEPS:,})")
    r.add_argument("--workers", type=_up_to(validate.MAX_WORKERS), default=os.cpu_count() or 1)
    r.add_argument("--backend", type=_choice(("local", "ray")), default="local")
    r.add_argument("--agent", type=_choice(AGENTS), default="ebrl",
                   help="the learner: " + ", ".join(AGENTS) + " (default: ebrl, the paper's)")
    r.add_argument("--out", type=pathlib.Path, default=pathlib.Path("results"))
    r.add_argument("--set", type=_override, action="append", default=[], metavar="NAME=VALUE",
                   help="change an agent parameter from Table 1's (for sweeps)")
    r.add_argument("--behaviour", type=pathlib.Path, default=None, metavar="FILE",
                   help="an intrinsic behaviour genome (JSON, ebrl.behaviour), e.g. "
                        "behaviours/paper_eq8.json or one `ebrl evolve` saved")
    r.add_argument("--first-trial", action="store_true",
                   help="end each run at its first goal (or its budget): its first trial, "
                        "bit for bit a full run's, in folders ROBOT.first_trial/")
    r.add_argument("--no-progress", action="store_true")

    rep = sub.add_parser("report", help="rebuild summary.json, REPORT.md and figures")
    rep.add_argument("dir", type=pathlib.Path)
    rep.add_argument("--results", type=pathlib.Path, default=None, metavar="RESULTS.md",
                     help="also regenerate the tables of this page (between its markers), "
                          "copy the figures to --figures and summary.json beside it")
    rep.add_argument("--figures", type=pathlib.Path, default=pathlib.Path("docs/figures"))

    from experiments.outputs.rendering import PATH_STYLES
    v = sub.add_parser("render", help="an offscreen MP4 of one run, or of two side by side")
    _robot_args(v, None, several=False)
    v.add_argument("--camera", default="top",
                   help="top (default), perspective, follow (a perspective camera that "
                        "tracks the robot), or a camera of the robot's file (chase)")
    v.add_argument("--condition", type=_choice(paper.CONDITIONS), default=None,
                   help="required, unless --compare condition")
    v.add_argument("--seed", type=_argument(lambda t: validate.integer(t, 0, validate.MAX_SEED)),
                   required=True)
    v.add_argument("--steps", type=_up_to(validate.MAX_STEPS), default=3000)
    v.add_argument("--set", type=_override, action="append", default=[], metavar="NAME=VALUE",
                   help="change a parameter of the agent or the task, as ebrl run does")
    v.add_argument("--compare", type=_comparison, default=None,
                   metavar="condition|behaviour|NAME=A,B",
                   help="two runs side by side, the same seed and the same steps: random "
                        "and avoidance, or --set NAME=A and NAME=B")
    v.add_argument("--beams", action=argparse.BooleanOptionalAction, default=True,
                   help="each rangefinder beam to what it hits, shaded by its reading")
    v.add_argument("--path", type=_choice(PATH_STYLES), default=PATH_STYLES[0],
                   help="the trial's path coloured by who chose each step, with a legend "
                        "(decider, the default), in one colour (plain), or none")
    v.add_argument("--caption", action=argparse.BooleanOptionalAction, default=True,
                   help="a line of text: step, trial, goals, who chose the action")
    v.add_argument("--out", type=pathlib.Path, required=True)
    v.add_argument("--behaviour", type=pathlib.Path, default=None, metavar="FILE",
                   help="an intrinsic behaviour genome (JSON), as `ebrl run --behaviour`")

    b = sub.add_parser("bench", help="microseconds per agent step, by part")
    b.add_argument("--robot", type=robot_list, default=robot_list("all"),
                   help="default: every registered robot")
    b.add_argument("--steps", type=_up_to(validate.MAX_BENCH_STEPS), default=2000,
                   help="timed steps per block")
    b.add_argument("--blocks", type=_up_to(validate.MAX_BENCH_BLOCKS), default=5,
                   help="medians over this many blocks")

    c = sub.add_parser("check", help="a robot's action accuracy and a random-action fuzz")
    _robot_args(c, "all")
    c.add_argument("--actions", type=_up_to(validate.MAX_STEPS), default=100_000,
                   help="random actions of the fuzz (default: %(default)s)")
    c.add_argument("--accuracy-actions", type=_up_to(validate.MAX_STEPS), default=1000,
                   help="free-space actions of the accuracy check (default: %(default)s)")

    w = sub.add_parser("sweep", help="the protocol at several values of one agent parameter")
    w.add_argument("--param", default="policy_threshold")
    w.add_argument("--values", default="0,0.01,0.05,0.1,0.2",
                   help="comma-separated values (default: %(default)s)")
    _robot_args(w, "paper")
    w.add_argument("--condition", type=_choice(paper.CONDITIONS + ("all",)), default="all")
    w.add_argument("--seeds", type=parse_seeds, default=list(range(20)))
    w.add_argument("--steps", type=_up_to(validate.MAX_STEPS), default=None)
    w.add_argument("--workers", type=_up_to(validate.MAX_WORKERS), default=os.cpu_count() or 1)
    w.add_argument("--agent", type=_choice(AGENTS), default="ebrl")
    w.add_argument("--out", type=pathlib.Path, default=pathlib.Path("sweeps"))
    w.add_argument("--baseline", type=pathlib.Path, default=None,
                   help="a run folder (e.g. results) whose runs at the default value join the "
                        "table, for the same robots, conditions, seeds and budgets")
    w.add_argument("--no-progress", action="store_true")

    a = sub.add_parser("ablate", help="the readings ablation: one reading changed at a time")
    _robot_args(a, "paper")
    a.add_argument("--seeds", type=parse_seeds, default=list(range(10)))
    a.add_argument("--steps", type=_up_to(validate.MAX_STEPS), default=None)
    a.add_argument("--readings", default="all",
                   help="comma-separated reading names (default: all of them)")
    a.add_argument("--combo", action="append", default=[], metavar="NAME=VALUE,NAME=VALUE",
                   help="a cell with several readings changed together (repeatable)")
    a.add_argument("--workers", type=_up_to(validate.MAX_WORKERS), default=os.cpu_count() or 1)
    a.add_argument("--out", type=pathlib.Path, default=pathlib.Path("ablation"))
    a.add_argument("--baseline", type=pathlib.Path, default=None,
                   help="a run folder (e.g. results) whose default runs are the default cell")
    a.add_argument("--results", type=pathlib.Path, default=None, metavar="RESULTS.md",
                   help="also regenerate this page's Ablation block")
    a.add_argument("--no-progress", action="store_true")

    f = sub.add_parser("fit", help="search the paper's unwritten readings against its table "
                                   "(an Optuna study; resumable)")
    f.add_argument("--trials", type=_up_to(MAX_TRIALS), default=150,
                   help="finished trials the study should hold (default: %(default)s); the "
                        "same command continues a study")
    f.add_argument("--seeds", type=parse_seeds, default=[0, 1],
                   help="every trial's seeds (default: 0-1)")
    f.add_argument("--promote-seeds", type=parse_seeds, default=None,
                   help="a promoted trial's seeds, including --seeds (default: 0-5; with "
                        "--stage first-trial, --seeds)")
    f.add_argument("--promote", type=_argument(lambda t: validate.fraction(t, "--promote")),
                   default=0.1, help="the share of trials promoted (default: %(default)s)")
    f.add_argument("--batch", type=_up_to(64), default=4,
                   help="trials asked and run together (default: %(default)s)")
    f.add_argument("--stage", type=_choice(("table", "first-trial")), default="table",  # fit.STAGES
                   help="table: the readings against Section 3.6's table (default); "
                        "first-trial: stage 1, one drive's physics and fallback readings "
                        "against the paper's first-trial distributions (--robot; 64 or "
                        "more --seeds), FIT_first_trial_DRIVE.md")
    f.add_argument("--robot", type=_choice(("two_wheel", "floating")), default=None,
                   help="--stage first-trial: the drive's robot to fit")
    f.add_argument("--space", default="all",
                   help="comma-separated readings to search (default: all; see FIT.md)")
    f.add_argument("--steps", type=_up_to(validate.MAX_STEPS), default=None,
                   help="agent steps per run (default: each robot's budget)")
    f.add_argument("--storage", default=None,
                   help="an Optuna storage URL (postgresql://..., mysql://...) or an SQLite "
                        "file (default: OUT/study.db)")
    f.add_argument("--study", default=None, help="the study's name (default: fit)")
    f.add_argument("--sampler-seed", type=_argument(lambda t: validate.integer(t, 0, 2**31 - 1)),
                   default=0)
    f.add_argument("--validate", type=parse_seeds, default=None, metavar="SEEDS",
                   help="then run the best trial (or --trial) and the defaults on these "
                        "seeds, which the search must not use (e.g. 100-149)")
    f.add_argument("--trial", type=_argument(lambda t: validate.integer(t, 0, 10**9)),
                   default=None, help="the trial --validate runs (default: the best)")
    f.add_argument("--workers", type=_up_to(validate.MAX_WORKERS), default=os.cpu_count() or 1)
    f.add_argument("--backend", type=_choice(("local", "ray")), default="local")
    f.add_argument("--out", type=pathlib.Path, default=pathlib.Path("fit"))
    f.add_argument("--results", type=pathlib.Path, default=None, metavar="RESULTS.md",
                   help="also regenerate this page's Search block")
    f.add_argument("--figures", type=pathlib.Path, default=pathlib.Path("docs/figures"))
    f.add_argument("--no-progress", action="store_true")

    e = sub.add_parser("evolve", help="CMA-ES over a robot's intrinsic behaviour, learning "
                                      "or not (an Optuna study; resumable)")
    _robot_args(e, None, several=False)
    e.add_argument("--population", type=_up_to(MAX_POPULATION), default=8,
                   help="trials per CMA-ES generation (default: %(default)s)")
    e.add_argument("--generations", type=_up_to(MAX_TRIALS), default=30,
                   help="generations the study should hold after the starting genome "
                        "(default: %(default)s); the same command continues a study")
    e.add_argument("--seeds", type=parse_seeds, default=list(range(1000, 1005)),
                   help="training seeds (default: 1000-1004, outside the protocol's 0-49, "
                        "which stay held out)")
    e.add_argument("--steps", type=_up_to(validate.MAX_STEPS), default=None,
                   help="agent steps per run (default: the robot's budget)")
    e.add_argument("--no-learning", action="store_true",
                   help="evolve the behaviour alone: the memory never acts")
    e.add_argument("--start", type=pathlib.Path, default=None, metavar="FILE",
                   help="the starting genome (default: the paper's rule for the robot)")
    e.add_argument("--space", default="all",
                   help="comma-separated genome fields to evolve (default: all; without "
                        "learning, all but the learning variables)")
    e.add_argument("--storage", default=None,
                   help="an Optuna storage URL or an SQLite file (default: OUT/study.db)")
    e.add_argument("--study", default=None,
                   help="the study's name (default: evolve-ROBOT, evolve-ROBOT-controller "
                        "with --no-learning)")
    e.add_argument("--sampler-seed", type=_argument(lambda t: validate.integer(t, 0, 2**31 - 1)),
                   default=0)
    e.add_argument("--workers", type=_up_to(validate.MAX_WORKERS), default=os.cpu_count() or 1)
    e.add_argument("--backend", type=_choice(("local", "ray")), default="local")
    e.add_argument("--out", type=pathlib.Path, default=pathlib.Path("evolve"))
    e.add_argument("--no-progress", action="store_true")

    er = sub.add_parser("evolve-report", help="EVOLVE.md: the paper's intrinsic behaviours "
                                              "against the evolved ones (README)")
    er.add_argument("--evolve", type=pathlib.Path, default=pathlib.Path("evolve"),
                    help="`ebrl evolve`'s --out (default: %(default)s)")
    er.add_argument("--hand", type=pathlib.Path, default=pathlib.Path("results"),
                    help="the protocol's runs, the paper's rules (default: %(default)s)")
    er.add_argument("--evolved", type=pathlib.Path, default=pathlib.Path("evolved"),
                    help="the evolved genomes' runs: learner/, controller/, alone_*/, "
                         "transfer/ (default: %(default)s)")
    er.add_argument("--out", type=pathlib.Path, default=pathlib.Path("EVOLVE.md"))
    er.add_argument("--figures", type=pathlib.Path, default=pathlib.Path("docs/figures"))
    er.add_argument("--results", type=pathlib.Path, default=None, metavar="RESULTS.md",
                    help="also regenerate this page's 'Evolved intrinsic behaviours' block")

    d = sub.add_parser("demo", help="a quick protocol, its report and one video")
    d.add_argument("--out", type=pathlib.Path, default=pathlib.Path("demo_results"))
    d.add_argument("--workers", type=_up_to(validate.MAX_WORKERS), default=os.cpu_count() or 1)
    return p


def _selected_robots(args):
    return args.robot if isinstance(args.robot, tuple) else (args.robot,)


def _check_robots(args):
    """Registered robots are known; a robot file is loaded once here, so a missing part
    (the naming contract, docs/adding_a_robot.md) is one line before any run."""
    from tasks.robots import ROBOTS, resolve
    for robot in _selected_robots(args):
        resolve(robot, args.drive)
        if robot not in ROBOTS:
            import tasks
            tasks.load(robot, drive=args.drive).close()


def _check_agent(args, overrides):
    """--set values (or a sweep's): each name once, and a config that ebrl.Config accepts
    for every selected robot, checked here rather than in the workers."""
    names = [name for name, _ in overrides]
    twice = next((name for name in names if names.count(name) > 1), None)
    if twice is not None:
        raise ValueError(f"--set {twice} is given more than once")
    validate.agent_configs(_selected_robots(args), overrides, args.drive,
                           getattr(args, "agent", "ebrl"))


def _check_behaviour(args, overrides=()):
    """--behaviour FILE: the genome for the selected robots (None without it)."""
    if args.behaviour is None:
        return None
    from experiments.studies import evolve
    return evolve.check_genome(args.behaviour, _selected_robots(args), args.drive, overrides)


def _check_backend(backend):
    import importlib.util
    if backend == "ray" and importlib.util.find_spec("ray") is None:
        raise ValueError("--backend ray needs Ray: pip install -e '.[ray]'")


def _report_if_any(folder, ran):
    """Rebuilds the report unless every run of this command failed and none is on disk."""
    from experiments.outputs import report
    return report.build(folder) if ran.made or ran.on_disk else None


def _failed_line(failed, what="failed"):
    """'N runs failed: a, b, c and K more (first error: ...)' for (name, error) pairs."""
    names = [name for name, _ in failed]
    shown = ", ".join(names[:5]) + (f" and {len(names) - 5} more" if len(names) > 5 else "")
    if len(names) == 1:
        return f"1 run {what}: {shown} ({failed[0][1]})"
    return f"{len(names)} runs {what}: {shown} (first error: {failed[0][1]})"


def _run_summary(ran, path):
    """The command's last line: on stdout when every run is done, else on stderr with the
    failed runs named, and exit status 1."""
    report = f"report: {path}" if path is not None else "no report (no complete run)"
    line = f"{ran.made} runs made, {ran.on_disk} already on disk; {report}"
    if not ran.failed:
        print(line)
        return 0
    return _fail(f"{_failed_line([(s.name, e) for s, e in ran.failed])}; recorded in "
                 f"run.json, not averaged; {line}; rerun the same command to retry",
                 RUNS_FAILED)


def _plan(args, overrides=()):
    """The specs that --robot, --condition, --seeds and --steps select."""
    from experiments.running import runner
    conditions = paper.CONDITIONS if args.condition == "all" else (args.condition,)
    return runner.plan(_selected_robots(args), conditions, args.seeds, args.steps, overrides,
                       args.drive, getattr(args, "agent", "ebrl"),
                       getattr(args, "first_trial", False))


def cmd_robots(args):
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


def cmd_run(args):
    try:
        validate.output_folder(args.out, "--out")
        _check_robots(args)
        _check_agent(args, args.set)
        _check_backend(args.backend)
        genome = _check_behaviour(args, args.set)
    except ValueError as e:
        return _fail(str(e))
    from experiments.running import results, runner
    specs = _plan(args, args.set)
    if genome is not None:
        import dataclasses
        specs = [dataclasses.replace(s, behaviour=genome) for s in specs]
    try:
        ran = runner.run(specs, args.out, workers=args.workers, backend=args.backend,
                         progress=not args.no_progress)
        path = _report_if_any(args.out, ran)
    except results.ResultsError as e:
        return _fail(str(e))
    return _run_summary(ran, path)


def cmd_report(args):
    try:
        validate.results_folder(args.dir, writable=True)
        validate.output_folder(args.dir / "figures", "the figures folder")
        if args.results is not None:
            validate.output_file(args.results, "--results")
            validate.output_folder(args.figures, "--figures")
    except ValueError as e:
        return _fail(str(e))
    from experiments.outputs import report
    from experiments.running import results
    try:
        path = report.build(args.dir)
        if args.results is not None:
            print(f"published: {report.publish(args.dir, args.results, args.figures)}")
        failed = results.failed_runs(args.dir)
    except results.ResultsError as e:
        return _fail(str(e))
    print(f"report: {path}")
    if failed:
        return _fail(_failed_line(sorted(failed.items()), "failed and not averaged")
                     + "; rerun `ebrl run` to retry", RUNS_FAILED)
    return 0


def cmd_evolve_report(args):
    try:
        validate.results_folder(args.hand, "--hand")
        for folder, what in ((args.evolve, "--evolve"), (args.evolved, "--evolved")):
            if not folder.is_dir():
                raise ValueError(f"{what}: no folder at {folder}")
        validate.output_file(args.out, "--out")
        validate.output_folder(args.figures, "--figures")
        if args.results is not None:
            validate.output_file(args.results, "--results")
    except ValueError as e:
        return _fail(str(e))
    from experiments.studies import evolved
    from experiments.running import results
    try:
        path = evolved.write(args.evolve, args.hand, args.evolved, args.out, args.figures,
                             args.results)
    except results.ResultsError as e:
        return _fail(str(e))
    print(f"evolve report: {path}" + (f"; published: {args.results}" if args.results else ""))
    return 0


def _render_variants(args):
    """(label, condition, --set pairs) of the run to render, or of the two to compare."""
    pairs = list(args.set)
    if args.compare is not None and args.compare[0] == "condition":
        if args.condition is not None:
            raise ValueError("--compare condition runs both conditions: drop --condition")
        return [(c, c, pairs) for c in args.compare[1]]
    if args.condition is None:
        raise ValueError("--condition is required (unless --compare condition)")
    if args.compare is None:
        return [(args.condition, args.condition, pairs)]
    name, values = args.compare
    if name == "behaviour":  # the paper's rule (no genome), then --behaviour's
        if args.behaviour is None:
            raise ValueError("--compare behaviour needs --behaviour FILE (the one set beside "
                             "the paper's rule)")
        return [(f"{values[0]} (paper)", args.condition, pairs),
                (f"{values[1]} ({args.behaviour.stem})", args.condition, pairs)]
    if name in dict(pairs):
        raise ValueError(f"--compare {name} is also given with --set")
    return [(f"{name}={v}", args.condition, pairs + [(name, v)]) for v in values]


def cmd_render(args):
    try:
        validate.output_file(args.out, "--out", suffix=".mp4")
        _check_robots(args)
        variants = _render_variants(args)
        for _, _, pairs in variants:
            _check_agent(args, pairs)
        genome = _check_behaviour(args, args.set)
    except ValueError as e:
        return _fail(str(e))
    from experiments.running import protocol
    from experiments.outputs import rendering
    paper_first = args.compare is not None and args.compare[0] == "behaviour"
    specs = [protocol.RunSpec(args.robot, condition, args.seed, args.steps, tuple(sorted(pairs)),
                              drive=args.drive,
                              behaviour=None if paper_first and i == 0 else genome)
             for i, (_, condition, pairs) in enumerate(variants)]
    labels = [label for label, _, _ in variants]
    try:
        rendering.ensure_backend()
        rendering.check_camera(specs[0], args.camera)
    except rendering.RenderingError as e:
        return _fail(str(e))
    options = dict(camera=args.camera, beams=args.beams, path_style=args.path,
                   caption=args.caption)
    if len(specs) == 1:
        results = [rendering.record(specs[0], args.out, label=labels[0], **options)]
    else:
        results = rendering.record_compare(specs, labels, args.out, **options)
    goals = ", ".join(f"{len(r['trial_ends'])} goals ({label})" for r, label in zip(results, labels))
    print(f"video: {args.out} ({goals} in {args.steps} steps)")
    return 0


def cmd_bench(args):
    from experiments.checks import bench
    bench.main(args.steps, args.blocks, args.robot)
    return 0


def cmd_check(args):
    try:
        _check_robots(args)
    except ValueError as e:
        return _fail(str(e))
    from experiments.checks import robotcheck
    return robotcheck.main(args.robot, args.actions, args.accuracy_actions, args.drive)


def _sweep_values(args):
    """--param and --values as (name, value) pairs, each value distinct and accepted by
    ebrl.Config for the selected robots."""
    fields = list(validate.setting_kinds())
    if args.param not in fields:
        raise ValueError(f"unknown --param {args.param!r}; one of {', '.join(fields)}")
    try:
        values = [_override(f"{args.param}={v.strip()}") for v in args.values.split(",")
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
        _check_agent(args, [value])
    return values


def cmd_sweep(args):
    try:
        _check_robots(args)
        values = _sweep_values(args)
        validate.output_folder(args.out, "--out")
        if args.baseline is not None:
            validate.results_folder(args.baseline, "--baseline")
    except ValueError as e:
        return _fail(str(e))
    from experiments.outputs import report
    from experiments.running import results, runner
    plans = [(args.out / f"{args.param}_{v}", _plan(args, [(n, v)])) for n, v in values]
    failed = []
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
        rows = []
        for ((_, v), (folder, specs)) in zip(values, plans):
            ran = runner.run(specs, folder, workers=args.workers, progress=not args.no_progress)
            failed += [(f"{folder.name}/{s.name}", e) for s, e in ran.failed]
            if _report_if_any(folder, ran) is not None:
                rows.append((v, results.load_runs(folder)))
        if baseline is not None:
            from tasks.robots import resolve
            default = validate.setting_default(
                args.param, [resolve(r, args.drive) for r in _selected_robots(args)])
            if default is None:  # the robots' defaults differ: the baseline first
                rows = [("the robots' own", baseline)] + rows
            else:
                rows = sorted(rows + [(default, baseline)], key=lambda row: row[0])
            rows = [(f"{v} (default, {args.baseline})" if runs is baseline else v, runs)
                    for v, runs in rows]
        path = report.sweep_table(args.out, args.param, rows, failed) if rows else None
    except results.ResultsError as e:
        return _fail(str(e))
    return _finish("sweep", path, failed)


def _finish(what, path, failed):
    """The last line of a command that runs many folders: what it wrote, or (exit 1) the
    failed (name, error) runs."""
    if failed:
        return _fail(f"{_failed_line(failed)}; recorded in run.json, not averaged; "
                     f"{what}: {path}; rerun the same command to retry", RUNS_FAILED)
    print(f"{what}: {path}")
    return 0


DEMO_SEEDS = 6
DEMO_VIDEO_STEPS = 3_000


def cmd_ablate(args):
    from experiments.studies import ablation
    try:
        _check_robots(args)
        names = [r.name for r in ablation.READINGS] if args.readings == "all" else \
            [n.strip() for n in args.readings.split(",") if n.strip()]
        unknown = [n for n in names if n not in ablation.BY_NAME]
        if unknown or not names:
            raise ValueError(f"unknown reading {unknown[0] if unknown else args.readings!r}; "
                             f"valid: {', '.join(ablation.BY_NAME)}")
        combos = []
        for text in args.combo:
            combo = [_argument(lambda t: _override(t))(part.strip()) for part in text.split(",")]
            _check_agent(args, combo)
            combos.append(combo)
        for r in (ablation.BY_NAME[n] for n in names):
            for value in r.values:
                _check_agent(args, [(r.name, value)])
        validate.output_folder(args.out, "--out")
        if args.baseline is not None:
            validate.results_folder(args.baseline, "--baseline")
        if args.results is not None:
            validate.output_file(args.results, "--results")
    except (ValueError, argparse.ArgumentTypeError) as e:
        return _fail(str(e))
    from experiments.running import results
    readings = [ablation.BY_NAME[n] for n in names]
    try:
        cell_runs, failed = ablation.run(args.out, _selected_robots(args), args.seeds,
                                         args.steps, readings, combos, args.baseline,
                                         args.workers, not args.no_progress)
        path = ablation.write(args.out, ablation.summarize(cell_runs), failed)
        if args.results is not None:
            print(f"published: {ablation.publish(args.out, args.results)}")
    except results.ResultsError as e:
        return _fail(str(e))
    return _finish("ablation", path, failed)


MAX_TRIALS = 100_000
MAX_POPULATION = 1_000


def _storage_url(args):
    """--storage as an Optuna URL (checked: a writable SQLite file's folder, or a URL)."""
    from experiments.studies import study
    url = study.storage_url(args.storage, args.out)
    if args.storage is None:
        pass  # OUT/study.db: --out is checked by the caller
    elif url.startswith("sqlite:///"):
        validate.output_file(pathlib.Path(url[len("sqlite:///"):]), "--storage")
    else:
        import sqlalchemy.engine
        try:
            sqlalchemy.engine.make_url(url)
        except Exception as e:  # sqlalchemy's ArgumentError: not a URL
            raise ValueError(f"bad --storage {args.storage!r}: {e}") from None
    return url


def _fit_args(args):
    """Every `ebrl fit` argument checked before any work: (space names, storage URL)."""
    from experiments.studies import fit
    if args.stage == "first-trial":
        from experiments.studies import first_trials
        names, rungs = first_trials.check_args(args.robot, args.space, args.seeds,
                                               args.promote_seeds, args.validate)
        if args.trial is not None and args.validate is None:
            raise ValueError("--trial chooses the trial --validate runs; give --validate too")
        return (names, rungs), _study_storage(args)
    if args.robot is not None:
        raise ValueError("--robot is for --stage first-trial (the table's fit runs both robots)")
    if args.promote_seeds is None:
        args.promote_seeds = list(range(6))
    names = tuple(fit.BY_NAME) if args.space == "all" else \
        tuple(n.strip() for n in args.space.split(",") if n.strip())
    unknown = [n for n in names if n not in fit.BY_NAME]
    if unknown or not names:
        raise ValueError(f"unknown reading {unknown[0] if unknown else args.space!r} in --space; "
                         f"valid: {', '.join(fit.BY_NAME)}")
    if not set(args.seeds) <= set(args.promote_seeds):
        raise ValueError("--promote-seeds must include every seed of --seeds")
    if args.validate is not None and set(args.validate) & set(args.promote_seeds):
        raise ValueError("--validate seeds must be seeds the search never uses (not in "
                         "--seeds or --promote-seeds)")
    if args.trial is not None and args.validate is None:
        raise ValueError("--trial chooses the trial --validate runs; give --validate too")
    if args.results is not None:
        validate.output_file(args.results, "--results")
        validate.output_folder(args.figures, "--figures")
    return names, _study_storage(args)


def _study_storage(args):
    """A study command's --out, --backend and storage, checked: the storage URL."""
    validate.output_folder(args.out, "--out")
    _check_backend(args.backend)
    return _storage_url(args)


def cmd_fit(args):
    try:
        names, url = _fit_args(args)
    except ValueError as e:
        return _fail(str(e))
    from experiments.studies import fit, study
    from experiments.running import results
    if args.stage == "first-trial":
        return _fit_first_trial(args, *names, url)
    rungs = (tuple(args.seeds),) if args.seeds == args.promote_seeds else \
        (tuple(args.seeds), tuple(args.promote_seeds))
    problem = fit.Problem(names=names, rungs=rungs, steps=args.steps)
    args.out.mkdir(parents=True, exist_ok=True)
    try:
        s = study.load(args.study or fit.STUDY_NAME, url, args.out, args.sampler_seed)
    except Exception as e:  # a storage that cannot be opened: one line
        return _fail(f"cannot open the study storage {url}: {results.error_line(e)}")
    try:
        if not s.get_trials(deepcopy=False):  # the defaults first, as trial 0
            s.enqueue_trial({n: fit.default(n) for n in names})
        outcome = study.optimize(problem, s, args.out, args.trials, batch=args.batch,
                                 workers=args.workers, backend=args.backend,
                                 promote=args.promote, progress=not args.no_progress)
        failed = [(f"trial {n}", e) for n, e in outcome.failed]
        if args.validate is not None:
            best = study.best_trials(s, 1) if args.trial is None else \
                [t for t in s.trials if t.number == args.trial and "rungs" in t.user_attrs]
            if not best:
                return _fail(f"no complete trial {'to validate' if args.trial is None else args.trial}")
            params = {k: v for k, v in best[0].params.items() if k in names}
            _, lost = fit.validate_best(problem, params, args.out, args.validate, args.workers,
                                        args.backend, not args.no_progress)
            failed += [(s_.name, e) for s_, e in lost]
        path = fit.write(s, args.out, names)
        if args.results is not None:
            print(f"published: {fit.publish(s, args.out, names, args.results, args.figures)}")
    except results.ResultsError as e:
        return _fail(str(e))
    print(f"{outcome.made} trials made now, {outcome.total} in the study ({url})")
    return _finish("fit", path, failed)


def _fit_first_trial(args, names, rungs, url):
    """`ebrl fit --stage first-trial` after its checks (experiments.studies.first_trials)."""
    from experiments.running import results
    from experiments.studies import first_trials, study
    problem = first_trials.Problem(args.robot, names, rungs, args.steps)
    args.out.mkdir(parents=True, exist_ok=True)
    name = args.study or f"first_trial_{args.robot}"
    try:
        s = study.load(name, url, args.out, args.sampler_seed)
    except Exception as e:  # a storage that cannot be opened: one line
        return _fail(f"cannot open the study storage {url}: {results.error_line(e)}")
    try:
        outcome, path, failed = first_trials.fit(
            problem, s, args.out, args.trials, batch=args.batch, workers=args.workers,
            backend=args.backend, promote=args.promote, progress=not args.no_progress,
            validate_seeds=args.validate, trial=args.trial)
    except (results.ResultsError, ValueError) as e:
        return _fail(str(e))
    print(f"{outcome.made} trials made now, {outcome.total} in the study ({url})")
    return _finish("fit", path, failed)


def _evolve_args(args):
    """Every `ebrl evolve` argument checked before any work: (problem, storage URL)."""
    from experiments.studies import evolve
    from tasks.robots import resolve
    if args.population < 2:
        raise ValueError("--population must be at least 2 (CMA-ES keeps the better half)")
    import importlib.util
    if importlib.util.find_spec("cmaes") is None:
        raise ValueError("ebrl evolve needs the cmaes package (Optuna's CMA-ES): pip install -e .")
    _check_robots(args)
    entry = resolve(args.robot, args.drive)
    if args.start is not None:
        start = evolve.check_genome(args.start, (args.robot,), args.drive)
    else:
        start = evolve.paper_genome(entry)
    names = evolve.fields(start, args.space, learning=not args.no_learning)
    url = _study_storage(args)
    problem = evolve.Problem(args.robot, start, names, tuple(args.seeds), args.steps,
                             learning=not args.no_learning, population=args.population,
                             sampler_seed=args.sampler_seed, drive=args.drive)
    return problem, url


def cmd_evolve(args):
    try:
        problem, url = _evolve_args(args)
    except ValueError as e:
        return _fail(str(e))
    from experiments.studies import evolve, study
    from experiments.running import protocol, results
    label = protocol.RunSpec(args.robot, "avoidance", 0, 1, drive=args.drive).label
    name = args.study or evolve.study_name(label, not args.no_learning)
    args.out.mkdir(parents=True, exist_ok=True)
    try:
        s = study.load(name, url, args.out, sampler=problem.sampler(0))
    except Exception as e:  # a storage that cannot be opened: one line
        return _fail(f"cannot open the study storage {url}: {results.error_line(e)}")
    try:
        evolve.check_settings(s, problem)
    except ValueError as e:
        return _fail(str(e))
    made, failed = 0, []
    try:
        if not s.get_trials(deepcopy=False):  # the starting genome first, alone
            s.enqueue_trial(problem.x0())
        # The starting genome alone (CMA-ES needs a complete trial to know the space), then
        # one batch of --population trials per generation.
        for n_trials, batch in ((1, 1), (1 + args.population * args.generations, args.population)):
            outcome = study.optimize(problem, s, args.out, n_trials, batch=batch,
                                     workers=args.workers, backend=args.backend,
                                     promote=1.0, progress=not args.no_progress)
            made += outcome.made
            failed += [(f"trial {n}", e) for n, e in outcome.failed]
        path = evolve.write(s, args.out, problem)
    except results.ResultsError as e:
        return _fail(str(e))
    print(f"{made} trials made now, {len(s.trials)} in the study {name} ({url})")
    return _finish("evolve", path, failed)


def cmd_demo(args):
    """A quick protocol: the paper's robots, 6 seeds at a fifth of their budgets (at least
    10,000 steps), then the report and one video."""
    try:
        validate.output_folder(args.out, "--out")
    except ValueError as e:
        return _fail(str(e))
    from experiments.running import protocol, results, runner
    from experiments.outputs import rendering
    from tasks.robots import PAPER_ROBOTS, ROBOTS
    budgets = {r: max(10_000, ROBOTS[r].budget // 5) for r in PAPER_ROBOTS}
    specs = runner.plan(PAPER_ROBOTS, paper.CONDITIONS, range(DEMO_SEEDS), budgets)
    print(f"demo: {len(specs)} runs ({DEMO_SEEDS} seeds x 2 robots x 2 conditions), budgets "
          + ", ".join(f"{k} {v:,} steps" for k, v in budgets.items()) + f" -> {args.out}/")
    try:
        ran = runner.run(specs, args.out, workers=args.workers)
        path = _report_if_any(args.out, ran)
        if ran.failed:
            return _run_summary(ran, path)
        rendering.ensure_backend()
    except (results.ResultsError, rendering.RenderingError) as e:
        return _fail(str(e))
    robot = PAPER_ROBOTS[0]
    video = args.out / f"{robot}_avoidance_seed000.mp4"
    rendering.record(protocol.RunSpec(robot, "avoidance", 0, DEMO_VIDEO_STEPS), video)
    print(f"report:  {path}\nfigures: {args.out / 'figures'}/\nvideo:   {video}")
    return 0


def _terminated(signum, frame):
    """SIGTERM (a `kill`, a scheduler's stop) as Ctrl-C: the runner then stops its workers
    instead of leaving them to finish their runs as orphans."""
    raise KeyboardInterrupt


def main(argv=None):
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _terminated)
    try:
        args = build_parser().parse_args(argv)
        return {"robots": cmd_robots, "run": cmd_run, "report": cmd_report,
                "render": cmd_render, "bench": cmd_bench, "check": cmd_check,
                "sweep": cmd_sweep, "ablate": cmd_ablate, "fit": cmd_fit, "evolve": cmd_evolve,
                "evolve-report": cmd_evolve_report, "demo": cmd_demo}[args.command](args)
    except KeyboardInterrupt:
        print("ebrl: interrupted; finished runs are kept, rerun to resume", file=sys.stderr)
        return INTERRUPTED
    except OSError as e:  # a disk that fills, a folder removed, a lost Ray cluster, say
        where = f": {e.filename}" if e.filename else ""
        status = _fail(f"{e.strerror or e}{where}")
        if getattr(e, "exit_now", False):  # a lost Ray cluster: Ray's exit would wait on it
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(status)
        return status


if __name__ == "__main__":
    sys.exit(main())
