"""Results on disk (the summary over seeds: experiments.running.aggregate).

DIR/<robot>/<condition>/seed_NNN/ holds config.json (every parameter, versions,
git commit), trials.csv (one row per trial), trace.npz (positions, int16
hundredths of a unit) and run.json, written last and atomically: a run folder
without a complete run.json is unfinished, and a rerun redoes it from scratch.

A run that raised has instead a run.json with status "failed": its parameters, the
error in one line and the traceback (write_failure). It is never averaged, the
report names it, a rerun retries it, and advice() says whether that can help.
"""
import csv
import io
import json
import pathlib
import platform
import re
import subprocess
import sys
import traceback

import numpy as np

from experiments.running import execution, schema
from experiments.running import lock
from experiments.running.disk import (TEST_DISK_FULL, TEST_DISK_FULL_AT,  # noqa: F401
                                      ResultsError, WriteError, atomic_file, atomic_write,
                                      tmp_prefix, write_error)

# -- writing (ResultsError, WriteError and the atomic write: experiments.running.disk) ---
def dumps(obj):
    return json.dumps(obj, indent=2, sort_keys=True) + "\n"


def versions():
    """The packages a run's numbers depend on (numba and llvmlite compile the agent's and
    the tasks' kernels), with the git commit."""
    import dm_control
    import llvmlite
    import mujoco
    import numba
    out = {"python": platform.python_version(), "numpy": np.__version__,
           "mujoco": mujoco.__version__, "dm_control": getattr(dm_control, "__version__", "?"),
           "numba": numba.__version__, "llvmlite": llvmlite.__version__}
    try:
        commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True,
                                cwd=pathlib.Path(__file__).parent, timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10,
                               cwd=pathlib.Path(__file__).parent).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        commit, dirty = "", ""
    out["git_commit"] = (commit + ("+dirty" if dirty else "")) or "unknown"
    out.update(lock.describe())  # the lock file's digest, and whether it is what is installed
    return out


def run_dir(root, spec):
    return pathlib.Path(root) / spec.label / spec.condition / f"seed_{spec.seed:03d}"


def write_run(root, spec, result, versions_info):
    """Writes one run's files; run.json goes last, so it marks the run complete."""
    folder = run_dir(root, spec)
    parameters = spec.parameters()
    atomic_write(folder / "config.json", dumps(dict(parameters, versions=versions_info)))
    ends = result["trial_ends"]
    lengths = execution.trial_lengths(ends)
    rows = io.StringIO()
    w = csv.writer(rows, lineterminator="\n")
    w.writerow(["trial", "steps", "cumulative_steps", "reached"])
    for i, (n, c) in enumerate(zip(lengths, ends)):
        w.writerow([i, int(n), int(c), 1])
    ran = result.get("steps_run", spec.steps)  # a first-trial run stops at its goal
    unfinished = ran - (int(ends[-1]) if len(ends) else 0)
    if unfinished:
        w.writerow([len(ends), unfinished, ran, 0])
    atomic_write(folder / "trials.csv", rows.getvalue())
    buf = io.BytesIO()
    np.savez_compressed(buf, trace=result["trace"], starts=result["starts"],
                        trial_ends=ends, scale=execution.TRACE_SCALE)
    atomic_write(folder / "trace.npz", buf.getvalue())
    run = {"status": "complete", "parameters": parameters,
           "metrics": execution.metrics(ends), "seconds": round(result["seconds"], 3),
           "memory_decisions": result["memory_decisions"]}
    atomic_write(folder / "run.json", dumps(run))
    return run


def error_line(error, limit=300):
    """An exception as one line, 'Type: first line of the message', at most limit chars;
    for one that wraps the run's own error as .cause (Ray's RayTaskError), that error."""
    cause = getattr(error, "cause", None)
    if isinstance(cause, BaseException):
        error = cause
    message = str(error).strip().splitlines()
    line = f"{type(error).__name__}: {message[0]}" if message else type(error).__name__
    return line if len(line) <= limit else line[: limit - 3] + "..."


#: The kinds of failure a run's record can hold, first match first: (kind, whether its
#: one-line error is of it, what to do; RERUN stands for the command to rerun). A rerun
#: is suggested alone only where it can help: a run is computed the same way whenever
#: it runs (same seed, same result), so a run that raised raises again.
_NATIVE_CRASH = ("SIGSEGV", "SIGBUS", "SIGABRT", "SIGILL", "SIGFPE")
FAILURE_KINDS = (
    ("crashed", lambda e: e.startswith("WorkerDied:") and any(s in e for s in _NATIVE_CRASH),
     "a crash in native code, which a rerun repeats (same seed, same computation): "
     "reinstall the project and its libraries (pip install --force-reinstall -e .), "
     "then RERUN"),
    ("killed", lambda e: e.startswith("WorkerDied:"),
     "RERUN to retry the runs whose worker was killed or died (out of memory: fewer "
     "--workers)"),
    ("library", lambda e: e.startswith(("ImportError:", "OSError:"))
     and ("cannot open shared object file" in e or "Library not loaded" in e),
     "a system library is missing (the error names it): install it, then RERUN"),
    ("install", lambda e: e.startswith(("ModuleNotFoundError:", "ImportError:")),
     "the install is damaged or incomplete: reinstall it (pip install -e .), then RERUN"),
    ("robot", lambda e: e.startswith(("MountError:", "ContractError:")) or "XML Error" in e,
     "the robot file is bad (the error says where): fix it, then RERUN"),
    ("memory", lambda e: e.split(":")[0].endswith("MemoryError"),  # numpy's _ArrayMemoryError
     "out of memory: RERUN with fewer --workers, or with smaller --set sizes"),
    ("left the room", lambda e: e.startswith("PhysicsError: the robot left the room"),
     "the robot went through a wall and off the room's floor, which a rerun repeats (same "
     "seed, same computation): its contacts with the walls are too soft or its steps too "
     "long for its speed (`ebrl check` measures how deep it goes into a wall)"),
    ("raised", lambda e: True,
     "a rerun raises the same again (same seed, same result): each run.json holds its "
     "traceback"),
)


def failure_kind(error):
    """The kind (FAILURE_KINDS) of a failed run's one-line error, alone or after its run
    folder's name ("two_wheel/random/seed_000: WorkerDied: ...", as a study's trial
    holds it)."""
    error = re.sub(r"^[\w.-]+/[\w.-]+/seed_\d+: ", "", error)
    return next(kind for kind, test, _ in FAILURE_KINDS if test(error))


def advice(errors, rerun="rerun the same command"):
    """What to do about failed runs with these one-line errors: each kind's advice once,
    in FAILURE_KINDS' order, joined by '; '."""
    kinds = {failure_kind(e) for e in errors}
    return "; ".join(text.replace("RERUN", rerun) for kind, _, text in FAILURE_KINDS
                     if kind in kinds)


def write_failure(root, spec, error):
    """Records a run that raised error: run.json with status "failed", the run's
    parameters, the error in one line and its traceback (the worker's, when it came
    from one), and for a worker process that died, the signal that ended it ("signal":
    "SIGSEGV") or its exit status. Returns the one-line error."""
    line = error_line(error)
    record = {"status": "failed", "parameters": spec.parameters(), "error": line,
              "traceback": "".join(traceback.format_exception(error))}
    for key in ("signal", "exit_status"):  # a worker process that died (worker.WorkerDied)
        if getattr(error, key, None) is not None:
            record[key] = getattr(error, key)
    atomic_write(run_dir(root, spec) / "run.json", dumps(record))
    return line


# -- reading -----------------------------------------------------------------------
class DamagedRun(ResultsError):
    """A run folder whose files cannot be read (cut short, overwritten, edited): .folder
    and .reason (schema.Damaged's). A report skips it and names it; a rerun sets its files
    aside (schema.set_aside) and makes it again."""

    def __init__(self, folder, reason):
        super().__init__(f"{folder}: damaged run: {reason}")
        self.folder, self.reason = pathlib.Path(folder), reason


def warn(message):
    """One warning line on stderr, as the commands' (ebrl: warning: ...)."""
    print(f"ebrl: warning: {message}", file=sys.stderr, flush=True)


def read_run_json(path):
    """The run.json at path, checked against its schema (experiments.running.schema:
    required keys, types, finite numbers), or DamagedRun naming its folder."""
    path = pathlib.Path(path)
    try:
        return schema.read_record(path)
    except schema.Damaged as e:
        raise DamagedRun(path.parent, str(e)) from None


class DamagedFile(ResultsError):
    """A file the tool wrote and reads back (summary.json, a multiverse folder's
    bench.json, a fit's validation.json) that cannot be read or is not of its kind's
    shape: the message names the file and what is wrong (schema.read_json)."""


def read_file(path, check):
    """The JSON file at path checked by check (schema.check_summary, check_bench,
    check_validation): the one reader of the files the tool reads back; DamagedFile naming
    the file when it cannot be read or is not of its shape."""
    try:
        return schema.read_json(path, check)
    except schema.Damaged as e:
        raise DamagedFile(str(e)) from None


def read_bookkeeping(path, check):
    """A study folder's bookkeeping file (bench.json, validation.json) read through
    read_file: its value, or None when there is none; a damaged one is moved aside to
    PATH.damaged-<time> (schema.move_aside, never deleted) with one warning line naming
    it, and the caller makes it again."""
    path = pathlib.Path(path)
    if not path.exists():
        return None
    try:
        return read_file(path, check)
    except DamagedFile as e:
        try:
            aside = schema.move_aside(path)
        except OSError as error:
            raise write_error(path, error) from error
        warn(f"{e}; moved aside to {aside.name} (kept), the command goes on as if it "
             "were missing")
        return None


def read_summary(path):
    """A summary.json (ebrl report's), checked (schema.check_summary); DamagedFile if not."""
    return read_file(path, schema.check_summary)


def read_run(folder, root=None):
    """The run record of a run folder, every file of it checked: run.json's schema, and
    for a complete run trace.npz, trials.csv and config.json readable and agreeing with
    it (and, given root, the record naming its folder). DamagedRun when any is not; the
    one reader of run folders every command uses."""
    folder = pathlib.Path(folder)
    run = read_run_json(folder / "run.json")
    try:
        if root is not None:
            schema.check_place(folder, root, run)
        schema.check_files(folder, run)
    except schema.Damaged as e:
        raise DamagedRun(folder, str(e)) from None
    return run


def examine(root, spec):
    """(state, detail) of spec's run under root: ("done", record) for a matching complete
    run, ("failed", record) for a failed one (it runs again), ("missing", None) for none
    (or an unfinished one), ("damaged", DamagedRun) for a run folder that cannot be read.

    Raises ResultsError when the folder holds a complete run made with other parameters
    (never overwritten: use another --out), naming the parameters that differ."""
    folder = run_dir(root, spec)
    if not (folder / "run.json").exists():
        return "missing", None
    try:
        run = read_run(folder, root)
    except DamagedRun as e:
        return "damaged", e
    if run["status"] == "failed":
        return "failed", run
    asked = json.loads(json.dumps(spec.parameters()))
    if run["parameters"] != asked:
        raise ResultsError(f"{folder / 'run.json'} holds a run made with other parameters "
                           f"({schema.differences(run['parameters'], asked)}); use another "
                           "--out")
    return "done", run


def existing(root, spec, mend=False):
    """'done' if a matching complete run is on disk, 'failed' if a failed one is (it
    runs again), 'missing' if it must run, 'damaged' if its folder cannot be read; with
    mend, a damaged folder's files are set aside (set_aside) and it is 'missing'.

    Raises ResultsError when the folder holds a complete run made with other parameters
    (never overwritten: use another --out)."""
    state, detail = examine(root, spec)
    if state == "damaged" and mend:
        set_aside(detail)
        return "missing"
    return state


def set_aside(damaged):
    """Moves a damaged run's files (a DamagedRun) into its folder's damaged-<time>/
    subfolder, never deleting them, with one warning line; its run is then made again."""
    try:
        aside = schema.set_aside(damaged.folder)
    except OSError as e:
        raise write_error(damaged.folder / "run.json", e) from e
    warn(f"{damaged}; its files moved to {aside}, the run is made again")
    return aside


def _scan(root, paths):
    """(complete runs, failed runs, damaged runs) of the run.json paths under root: run
    folder name -> record, for the damaged ones -> DamagedRun."""
    complete, failed, damaged = {}, {}, {}
    for path in paths:
        name = path.parent.relative_to(root).as_posix()
        try:
            run = read_run(path.parent, root)
        except DamagedRun as e:
            damaged[name] = e
            continue
        (failed if run["status"] == "failed" else complete)[name] = run
    return complete, failed, damaged


def load_runs(root, specs=None, room=False, damaged=None):
    """Every complete run under root (or only those of specs), as
    (robot, condition, seed) -> run.json dict. Failed runs are left out (see
    failed_runs). room: only the runs in that room (None: the paper's; False: all). A
    run's robot (its label) names its room, so runs in different rooms never share a key
    (execution.RunSpec.label). A damaged run folder (read_run) is skipped with one
    warning line naming it; damaged, a dict, receives them (run folder name ->
    DamagedRun)."""
    root = pathlib.Path(root)
    if not root.is_dir():
        raise ResultsError(f"no results folder at {root}")
    paths = (sorted(root.glob("*/*/seed_*/run.json")) if specs is None
             else [run_dir(root, spec) / "run.json" for spec in specs])
    missing = [p for p in paths if not p.exists()]
    if specs is not None and missing:  # runs asked for by name: each must be on disk
        raise ResultsError(f"no run at {missing[0]}"
                           + (f" (and {len(missing) - 1} more)" if len(missing) > 1 else ""))
    complete, failed, broken = _scan(root, [p for p in paths if p.exists()])
    for error in broken.values():
        warn(f"{error}; skipped (`ebrl run` moves its files aside and makes it again)")
    if damaged is not None:
        damaged.update(broken)
    runs = {}
    for run in complete.values():
        p = run["parameters"]
        if room is not False and p.get("room") != room:
            continue
        runs[(p["robot"], p["condition"], p["seed"])] = run
    if not runs:
        errors = [run["error"] for run in failed.values()]
        raise ResultsError(f"no complete runs under {root}"
                           + ("" if room is False else f" in room {room or 'sutton'}")
                           + (f" ({len(errors)} failed: {advice(errors, 'rerun `ebrl run`')})"
                              if errors else "")
                           + (f" ({len(broken)} damaged, skipped)" if broken else ""))
    return runs


def failed_runs(root):
    """The failed runs under root, as run folder name (robot/condition/seed_NNN) -> the
    one-line error recorded in its run.json (damaged folders left out: load_runs names
    them)."""
    root = pathlib.Path(root)
    failed = {}
    for path in sorted(root.glob("*/*/seed_*/run.json")):
        try:
            run = read_run_json(path)
        except DamagedRun:
            continue
        if run["status"] == "failed":
            failed[path.parent.relative_to(root).as_posix()] = run["error"]
    return failed


def load_trace(root, robot, condition, seed):
    """(positions, starts, trial ends) of a run's trace.npz, positions in units;
    DamagedRun when it cannot be read (read_run checks it first)."""
    folder = pathlib.Path(root) / robot / condition / f"seed_{seed:03d}"
    try:
        with np.load(folder / "trace.npz") as z:
            scale = float(z["scale"])
            return z["trace"] / scale, z["starts"] / scale, z["trial_ends"]
    except Exception as e:  # changed since it was checked: zipfile's, zlib's, numpy's errors
        raise DamagedRun(folder, f"trace.npz cannot be read ({type(e).__name__})") from None


def trial_paths(trace, starts, trial_ends):
    """The path of each completed trial, as (n, 2) arrays in units."""
    paths, begin = [], 1
    for i, end in enumerate(trial_ends):
        paths.append(np.vstack([starts[i], trace[begin:end + 1]]))
        begin = end + 1
    return paths
