"""What several commands share beyond their arguments: the exit codes and the one-line
failure, the checks made before any work (the robots, the agent's settings, a behaviour
file, the backend, a study's storage), the runs a command plans, and its last line.
"""
import pathlib
import sys

import tasks
from experiments import paper
from experiments.checks import validate
from experiments.running import results, runner
from experiments.studies import study
from tasks.robots import ROBOTS, resolve

USAGE_ERROR = 2
RUNS_FAILED = 1
INTERRUPTED = 130


def fail(message, status=USAGE_ERROR):
    print(f"ebrl: error: {message}", file=sys.stderr)
    return status


def selected_robots(args):
    return args.robot if isinstance(args.robot, tuple) else (args.robot,)


def check_robots(args):
    """Registered robots are known; a robot file is loaded once here, so a missing part
    (the naming contract, docs/adding_a_robot.md) is one line before any run; in a room
    other than the paper's (--room), every robot is composed into it, so a corridor
    narrower than a robot is one line too (models.rooms.check_fits)."""
    room = getattr(args, "room", None)
    for robot in selected_robots(args):
        resolve(robot, args.drive)
        if robot not in ROBOTS:
            import tasks
            tasks.load(robot, drive=args.drive, room=room).close()
        else:
            check_room((robot,), room)


def check_room(robots, room, drive=None, overrides=()):
    """Each robot composed into the room (--room; None: the paper's, nothing to check)
    with the task fields of overrides (--set radius=...): models.rooms.MapError, one
    line, when a corridor is narrower than a robot. Compiled through tasks.compiled_model,
    once per process and model: the runs' parameters (their model's digest) read the same
    compile."""
    if room is None:
        return
    import dataclasses

    fields = {f.name for f in dataclasses.fields(tasks.TaskConfig)}
    task = {k: v for k, v in overrides if k in fields}
    for robot in robots:
        entry = resolve(robot, drive)
        tasks.compiled_model(entry, entry.task_config(**task), room)


def check_agent(args, overrides):
    """--set values (or a sweep's): each name once, a config that ebrl.Config accepts
    for every selected robot, and a robot that still fits the room's corridors (--set
    radius), checked here rather than in the workers."""
    names = [name for name, _ in overrides]
    twice = next((name for name in names if names.count(name) > 1), None)
    if twice is not None:
        raise ValueError(f"--set {twice} is given more than once")
    validate.agent_configs(selected_robots(args), overrides, args.drive,
                           getattr(args, "agent", "ebrl"), getattr(args, "steps", None))
    if overrides:  # a task field (radius) against the room's corridors
        check_room(selected_robots(args), getattr(args, "room", None), args.drive, overrides)


def check_behaviour(args, overrides=()):
    """--behaviour FILE: the genome for the selected robots (None without it)."""
    if args.behaviour is None:
        return None
    from experiments.checks import behaviour_file  # the simulator, past the light checks
    return behaviour_file.check(args.behaviour, selected_robots(args), args.drive, overrides)


def check_backend(backend):
    import importlib.util
    if backend == "ray" and importlib.util.find_spec("ray") is None:
        raise ValueError("--backend ray needs Ray: pip install -e '.[ray]'")


def _storage_url(args):
    """--storage as an Optuna URL (checked: a writable SQLite file's folder, or a URL)."""
    url = study.storage_url(args.storage, args.out)
    if args.storage is None:
        pass  # OUT/study.db: --out is checked by the caller
    elif url.startswith("sqlite:///"):
        path = validate.output_file(pathlib.Path(url[len("sqlite:///"):]), "--storage")
        _sqlite_or_new(path, args.storage)
    else:
        import sqlalchemy.engine
        try:
            sqlalchemy.engine.make_url(url)
        except Exception as e:  # sqlalchemy's ArgumentError: not a URL
            raise ValueError(f"bad --storage {args.storage!r}: {e}") from None
    return url


#: The first bytes of every SQLite database file (an empty file is a new database too).
SQLITE_HEADER = b"SQLite format 3\x00"


def _sqlite_or_new(path, given):
    """An SQLite file --storage names: a database, an empty file or none; ValueError (one
    line) for a file that is something else, which is never opened (nor a lock made
    beside it)."""
    try:
        with open(path, "rb") as f:
            head = f.read(len(SQLITE_HEADER))
    except FileNotFoundError:
        return
    except OSError as e:
        raise ValueError(f"--storage {given}: cannot be read ({e.strerror or e})") from None
    if head and head != SQLITE_HEADER:
        raise ValueError(f"--storage {given}: not an SQLite database (it does not start "
                         "with SQLite's header); the file is left as it is: give a new file, "
                         "a study's database or a URL")


def _storage_files(url):
    """The files opening an SQLite storage may make: the database and its lock beside it."""
    if not str(url).startswith("sqlite:///"):
        return []
    path = pathlib.Path(str(url)[len("sqlite:///"):].split("?")[0])
    return [path, path.with_name(path.name + ".lock")]


def open_study(args, url, load):
    """The study load() opens, with --out made first: (study, None); or, when the storage
    cannot be opened, (None, the exit status of its one line) with what this call made
    (--out, a new database file and its lock) removed again: a refusal writes nothing."""
    made = [p for p in (args.out, *_storage_files(url)) if not p.exists()]
    args.out.mkdir(parents=True, exist_ok=True)
    try:
        return load(), None
    except Exception as e:  # a storage that cannot be opened: one line
        for path in reversed(made):
            try:
                path.rmdir() if path.is_dir() else path.unlink(missing_ok=True)
            except OSError:  # a folder something else wrote into: kept
                pass
        return None, fail(study.hide(f"cannot open the study storage {url}: "
                                     f"{results.error_line(e)}", url))


def study_storage(args):
    """A study command's --out, --backend and storage, checked: the storage URL."""
    validate.output_folder(args.out, "--out")
    check_backend(args.backend)
    return _storage_url(args)


def plan(args, overrides=()):
    """The specs that --robot, --condition, --seeds and --steps select."""
    conditions = paper.CONDITIONS if args.condition == "all" else (args.condition,)
    return runner.plan(selected_robots(args), conditions, args.seeds, args.steps, overrides,
                       args.drive, getattr(args, "agent", "ebrl"),
                       getattr(args, "first_trial", False),
                       protocol=getattr(args, "protocol", "adopted"),
                       room=getattr(args, "room", None))


def report_if_any(folder, ran):
    """Rebuilds the report unless every run of this command failed and none is on disk."""
    from experiments.outputs import report
    return report.build(folder) if ran.made or ran.on_disk else None


def failed_line(failed, what="failed"):
    """'N runs failed: a, b, c and K more (first error: ...)' for (name, error) pairs."""
    names = [name for name, _ in failed]
    shown = ", ".join(names[:5]) + (f" and {len(names) - 5} more" if len(names) > 5 else "")
    if len(names) == 1:
        return f"1 run {what}: {shown} ({failed[0][1]})"
    return f"{len(names)} runs {what}: {shown} (first error: {failed[0][1]})"


def run_summary(ran, path):
    """The command's last line: on stdout when every run is done, else on stderr with the
    failed runs named, and exit status 1."""
    report = f"report: {path}" if path is not None else "no report (no complete run)"
    line = f"{ran.made} runs made, {ran.on_disk} already on disk; {report}"
    if not ran.failed:
        print(line)
        return 0
    return fail(f"{failed_line([(s.name, e) for s, e in ran.failed])}; recorded in "
                f"run.json, not averaged; {line}; {results.advice(e for _, e in ran.failed)}",
                RUNS_FAILED)


def finish(what, path, failed):
    """The last line of a command that runs many folders: what it wrote, or (exit 1) the
    failed (name, error) runs."""
    if failed:
        from experiments.running import results
        return fail(f"{failed_line(failed)}; recorded in run.json, not averaged; "
                    f"{what}: {path}; {results.advice(e for _, e in failed)}", RUNS_FAILED)
    print(f"{what}: {path}")
    return 0
