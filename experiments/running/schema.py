"""What a run folder must hold to be read: run.json's schema (its keys, their types, every
number finite), and for a complete run its other files (trace.npz, trials.csv,
config.json) readable and agreeing with it; the parameters that differ between two runs;
and a damaged folder's files set aside.

Each check raises Damaged with what is wrong in a few words ("metrics.goals is NaN",
"trace.npz cannot be read (BadZipFile: File is not a zip file)");
experiments.running.results names the folder (results.DamagedRun), skips the run in a
report and makes it again in a rerun. Nothing here imports more than numpy.
"""
import csv
import datetime
import json
import math
import os
import pathlib

import numpy as np

#: The header of trials.csv (results.write_run).
TRIALS_HEADER = ["trial", "steps", "cumulative_steps", "reached"]
#: The subfolder of a run folder that a damaged run's files are moved into.
DAMAGED_PREFIX = "damaged-"


class Damaged(ValueError):
    """A run record or file that cannot be read; the message says what is wrong."""


def _name(value):
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else "infinite"
    return {dict: "an object", list: "a list", str: "a string", type(None): "null",
            int: "an integer", float: "a number"}.get(type(value), type(value).__name__)


def _nonfinite(value, where=""):
    """(dotted key, value) of the first non-finite number in a JSON value, or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return where, value
    items = (value.items() if isinstance(value, dict)
             else enumerate(value) if isinstance(value, list) else ())
    for key, item in items:
        found = _nonfinite(item, f"{where}.{key}" if where else str(key))
        if found:
            return found
    return None


def _integer(d, key, where, low=0, optional=False, none=False):
    """d[key] an integer at least low (None where none; absent where optional)."""
    if key not in d:
        if optional:
            return None
        raise Damaged(f"{where}{key} is missing")
    v = d[key]
    if v is None and none:
        return None
    if isinstance(v, bool) or not isinstance(v, int):
        raise Damaged(f"{where}{key} is {_name(v)}, not an integer")
    if v < low:
        raise Damaged(f"{where}{key} is {v}, below {low}")
    return v


def _typed(d, key, where, kinds, what, optional=True):
    if key not in d:
        if optional:
            return None
        raise Damaged(f"{where}{key} is missing")
    v, kinds = d[key], kinds if isinstance(kinds, tuple) else (kinds,)
    if (isinstance(v, bool) and bool not in kinds) or not isinstance(v, kinds):
        raise Damaged(f"{where}{key} is {_name(v)}, not {what}")
    return v


def check_record(run):
    """run.json's content (json.loads'), checked against its schema; Damaged if not."""
    if not isinstance(run, dict):
        raise Damaged(f"it holds {_name(run)}, not a run record")
    bad = _nonfinite(run)
    if bad:
        raise Damaged(f"{bad[0]} is {_name(bad[1])}, not a finite number")
    status = run.get("status")
    if status not in ("complete", "failed"):
        raise Damaged(f"status is {status!r}, not 'complete' or 'failed'")
    p = _typed(run, "parameters", "", dict, "an object", optional=False)
    for key in ("robot", "condition"):
        if not _typed(p, key, "parameters.", str, "a string", optional=False):
            raise Damaged(f"parameters.{key} is empty")
    _integer(p, "seed", "parameters.")
    _integer(p, "steps", "parameters.", low=1)
    for key in ("drive", "learner", "room", "protocol", "model_sha256"):
        _typed(p, key, "parameters.", str, "a string")
    for key in ("agent", "task"):
        _typed(p, key, "parameters.", dict, "an object")
    _typed(p, "first_trial", "parameters.", bool, "true or false")
    _integer(p, "protocol_version", "parameters.", optional=True)
    if status == "failed":
        _typed(run, "error", "", str, "a string", optional=False)
        _typed(run, "traceback", "", str, "a string")
        return run
    m = _typed(run, "metrics", "", dict, "an object", optional=False)
    goals = _integer(m, "goals", "metrics.")
    for key in ("first_trial_steps", "last_trial_steps", "min_trial_steps"):
        _integer(m, key, "metrics.", low=1, optional=key != "first_trial_steps", none=True)
    per_trial = _typed(m, "steps_per_trial", "metrics.", (int, float, type(None)), "a number",
                       optional=False)
    if (goals == 0) != (m["first_trial_steps"] is None) or (goals == 0) != (per_trial is None):
        raise Damaged(f"metrics disagree: {goals} goals, first_trial_steps "
                      f"{m['first_trial_steps']}, steps_per_trial {per_trial}")
    if goals and m["first_trial_steps"] > p["steps"]:
        raise Damaged(f"metrics.first_trial_steps {m['first_trial_steps']} is past the "
                      f"run's {p['steps']} steps")
    _integer(run, "memory_decisions", "")
    seconds = _typed(run, "seconds", "", (int, float), "a number")
    if seconds is not None and seconds < 0:
        raise Damaged(f"seconds is {seconds}, below 0")
    return run


def _json(path):
    """The JSON value of the file at path; Damaged naming the file when it cannot be read
    or is not JSON."""
    path = pathlib.Path(path)
    try:
        return json.loads(path.read_bytes().decode("utf-8"))
    except FileNotFoundError:
        raise Damaged(f"{path.name} is missing") from None
    except OSError as e:
        raise Damaged(f"{path.name} cannot be read ({e.strerror or e})") from None
    except (UnicodeDecodeError, ValueError, RecursionError) as e:  # JSONDecodeError too
        raise Damaged(f"{path.name} is not JSON ({type(e).__name__})") from None


def read_record(path):
    """The run record at path, checked (check_record); Damaged when it cannot be read."""
    run = _json(path)
    try:
        return check_record(run)
    except Damaged as e:
        raise Damaged(f"run.json: {e}") from None


def _trace(folder, run):
    """trace.npz readable, its arrays of the shapes results.write_run gives them and its
    trial ends the record's goals."""
    path = pathlib.Path(folder) / "trace.npz"
    try:
        with np.load(path) as z:
            arrays = {k: z[k] for k in ("trace", "starts", "trial_ends", "scale")}
    except FileNotFoundError:
        raise Damaged("trace.npz is missing") from None
    except KeyError as e:
        raise Damaged(f"trace.npz lacks the array {e}") from None
    except Exception as e:  # a file cut short or overwritten: zipfile's, zlib's, numpy's errors
        said = str(e).strip().splitlines()[0][:120] if str(e).strip() else ""
        raise Damaged(f"trace.npz cannot be read ({type(e).__name__}"
                      f"{': ' + said if said else ''})") from None
    trace, starts, ends, scale = (arrays[k] for k in ("trace", "starts", "trial_ends", "scale"))
    goals, steps = run["metrics"]["goals"], run["parameters"]["steps"]
    for name, a in (("trace", trace), ("starts", starts)):
        if a.ndim != 2 or a.shape[1] != 2 or a.dtype.kind not in "iu" or not len(a):
            raise Damaged(f"trace.npz: {name} is {a.dtype} {a.shape}, not rows of two integers")
    if ends.ndim != 1 or ends.dtype.kind not in "iu":
        raise Damaged(f"trace.npz: trial_ends is {ends.dtype} {ends.shape}, not integers")
    if scale.shape != () or scale.dtype.kind != "f" or not (np.isfinite(scale) and scale > 0):
        raise Damaged(f"trace.npz: scale is {scale!r}, not a positive number")
    if len(trace) - 1 > steps:
        raise Damaged(f"trace.npz holds {len(trace) - 1} steps, more than the run's {steps}")
    if len(ends) != goals:
        raise Damaged(f"trace.npz holds {len(ends)} trial ends, run.json {goals} goals")
    if len(ends) and (ends[0] < 1 or ends[-1] > len(trace) - 1 or np.any(np.diff(ends) <= 0)):
        raise Damaged("trace.npz: its trial ends are not steps of the trace in order")
    if len(starts) < len(ends):
        raise Damaged(f"trace.npz holds {len(starts)} starts for {len(ends)} trials")


def _trials(folder, run):
    """trials.csv readable: its header, integer rows, a reached row per goal."""
    path = pathlib.Path(folder) / "trials.csv"
    try:
        rows = list(csv.reader(path.read_bytes().decode("utf-8").splitlines()))
    except FileNotFoundError:
        raise Damaged("trials.csv is missing") from None
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise Damaged(f"trials.csv cannot be read ({type(e).__name__})") from None
    if not rows or rows[0] != TRIALS_HEADER:
        raise Damaged(f"trials.csv does not start with {','.join(TRIALS_HEADER)}")
    for number, row in enumerate(rows[1:], 2):
        if len(row) != 4 or not all(x.isdigit() for x in row):
            raise Damaged(f"trials.csv: line {number} is not four whole numbers")
    reached = sum(row[3] == "1" for row in rows[1:])
    if reached != run["metrics"]["goals"]:
        raise Damaged(f"trials.csv holds {reached} reached trials, run.json "
                      f"{run['metrics']['goals']} goals")


def _config(folder):
    config = _json(pathlib.Path(folder) / "config.json")
    if not isinstance(config, dict):
        raise Damaged(f"config.json holds {_name(config)}, not an object")


def check_files(folder, run):
    """A complete run's other files readable and agreeing with its record run: Damaged
    if not. (A failed run has its run.json alone.)"""
    if run["status"] == "complete":
        _trace(folder, run)
        _trials(folder, run)
        _config(folder)


def check_place(folder, root, run):
    """The record names the folder it lies in (robot/condition/seed_NNN under root), as
    the readers find its trace by its parameters."""
    p = run["parameters"]
    want = pathlib.Path(p["robot"]) / p["condition"] / f"seed_{p['seed']:03d}"
    try:
        here = pathlib.Path(folder).relative_to(root)
    except ValueError:
        return
    if here != want:
        raise Damaged(f"run.json names the folder {want.as_posix()}")


#: A parameter's value when a run's parameters leave it out (execution.RunSpec.parameters
#: writes protocol and room only when they are not the default).
_ABSENT = {"protocol": "adopted", "room": "sutton", "learner": "ebrl", "first_trial": False}
#: The order differences are listed in: what a person changed first, the model's digest
#: (which any change to the robot or the room changes) last.
_FIRST = ("protocol", "protocol_version", "room", "robot_file", "mount_file", "learner",
          "steps", "first_trial", "behaviour")


def differences(on_disk, asked, limit=5):
    """The parameters that differ between a run's record and the run asked for, as
    "protocol: literal on disk, adopted asked; task.radius: 2.5 on disk, 4 asked" (the
    agent's and the task's fields one by one), at most limit of them."""
    def flat(p):
        out = {}
        for k, v in p.items():
            if isinstance(v, dict) and k in ("agent", "task"):
                out.update({f"{k}.{f}": x for f, x in v.items()})
            else:
                out[k] = v
        return out

    a, b = flat(on_disk), flat(asked)
    keys = [k for k in sorted(set(a) | set(b))
            if a.get(k, _ABSENT.get(k)) != b.get(k, _ABSENT.get(k))]
    keys.sort(key=lambda k: (k == "model_sha256", _FIRST.index(k) if k in _FIRST
                             else len(_FIRST) + k.startswith(("agent.", "task.")), k))
    if len(keys) > 1 and "model_sha256" in keys:
        keys.remove("model_sha256")  # explained by the others

    def show(p, k):
        v = p.get(k, _ABSENT.get(k))
        text = "none" if v is None else json.dumps(v) if isinstance(v, (dict, list)) else str(v)
        return text if len(text) <= 40 else text[:37] + "..."

    shown = [f"{k}: {show(a, k)} on disk, {show(b, k)} asked" for k in keys[:limit]]
    more = f"; and {len(keys) - limit} more" if len(keys) > limit else ""
    return "; ".join(shown) + more if shown else "none"


def set_aside(folder):
    """Moves a damaged run's files into a new subfolder damaged-<UTC time>/ of its folder
    (run.json first, so a move cut short leaves an unfinished run, never a complete one
    without its files); returns the subfolder. Earlier damaged-* subfolders stay."""
    folder = pathlib.Path(folder)
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    aside, n = folder / f"{DAMAGED_PREFIX}{stamp}", 1
    while aside.exists():
        n += 1
        aside = folder / f"{DAMAGED_PREFIX}{stamp}-{n}"
    aside.mkdir()
    files = sorted((p for p in folder.iterdir() if p.is_file() or p.is_symlink()),
                   key=lambda p: p.name != "run.json")
    for path in files:
        os.replace(path, aside / path.name)
    return aside


# -- the other files the tool writes and reads back ----------------------------------
# Each kind's check takes the file's JSON value and raises Damaged saying what is wrong;
# read_json names the file. A run folder's files are read above (read_record,
# check_files); a behaviour genome by ebrl.behaviour.load.

def _list_of_objects(d, key, where):
    v = _typed(d, key, where, list, "a list", optional=False)
    for i, item in enumerate(v):
        if not isinstance(item, dict):
            raise Damaged(f"{where}{key}[{i}] is {_name(item)}, not an object")
    return v


def check_summary(summary):
    """summary.json (ebrl report's): the keys its readers (the page's tables, the
    headline) take, of their types."""
    if not isinstance(summary, dict):
        raise Damaged(f"it holds {_name(summary)}, not a summary")
    for i, g in enumerate(_list_of_objects(summary, "groups", "")):
        where = f"groups[{i}]."
        for key in ("robot", "condition"):
            _typed(g, key, where, str, "a string", optional=False)
        _integer(g, "seeds", where)
        for key in ("first_trial_steps", "steps_per_trial", "goals"):
            _typed(g, key, where, dict, "an object", optional=False)
    prov = _typed(summary, "provenance", "", dict, "an object", optional=False)
    _typed(prov, "protocol_versions", "provenance.", list, "a list", optional=False)
    commits = _typed(prov, "commits", "provenance.", list, "a list", optional=False)
    if not all(isinstance(c, str) for c in commits):
        raise Damaged("provenance.commits holds a value that is not a string")
    for i, g in enumerate(_list_of_objects(prov, "groups", "provenance.")):
        _typed(g, "seeds", f"provenance.groups[{i}].", str, "a string", optional=False)
    tests = _typed(summary, "tests", "", dict, "an object", optional=False)
    for key in ("figures", "shrinks", "counts"):
        for i, row in enumerate(_list_of_objects(tests, key, "tests.")):
            for name in ("robot", "condition") if key != "counts" else ("claim",):
                _typed(row, name, f"tests.{key}[{i}].", str, "a string", optional=False)
    return summary


def check_bench(rows, robots=()):
    """A multiverse folder's bench.json: for each robot (given, and any it holds), ebrl
    bench's measure, an object whose fused_loop is a number."""
    if not isinstance(rows, dict):
        raise Damaged(f"it holds {_name(rows)}, not an object of robots")
    for robot in robots:
        if robot not in rows:
            raise Damaged(f"{robot} is missing")
    for robot, row in rows.items():
        if not isinstance(row, dict):
            raise Damaged(f"{robot} is {_name(row)}, not an object")
        v = _typed(row, "fused_loop", f"{robot}.", (int, float), "a number", optional=False)
        if not (math.isnan(v) or 0 < v < math.inf):
            raise Damaged(f"{robot}.fused_loop is {v}, not a positive number")
    return rows


def read_json(path, check):
    """The JSON file at path, checked by check (one of the check_* above); Damaged naming
    the file (its path) and what is wrong."""
    path = pathlib.Path(path)
    try:
        value = _json(path)
    except Damaged as e:
        raise Damaged(f"{path}{str(e)[len(path.name):]}") from None  # "<path> is not JSON"
    try:
        return check(value)
    except Damaged as e:
        raise Damaged(f"{path}: {e}") from None


def move_aside(path):
    """Moves a damaged bookkeeping file to PATH.damaged-<UTC time> beside it (never
    deleting it); returns the new path."""
    path = pathlib.Path(path)
    stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y%m%dT%H%M%SZ")
    aside, n = path.with_name(f"{path.name}.{DAMAGED_PREFIX}{stamp}"), 1
    while aside.exists():
        n += 1
        aside = path.with_name(f"{path.name}.{DAMAGED_PREFIX}{stamp}-{n}")
    os.replace(path, aside)
    return aside


def check_validation(row_keys):
    """A study's validation file (ebrl fit --validate: validation.json, row_keys value,
    groups and claims; --stage first-trial: validation_first_trial_<drive>.json, distance
    and figures): its seeds, its settings and a best and a defaults row of those keys."""
    def check(v):
        if not isinstance(v, dict):
            raise Damaged(f"it holds {_name(v)}, not a validation")
        seeds = _typed(v, "seeds", "", list, "a list", optional=False)
        if not seeds or not all(isinstance(s, int) and not isinstance(s, bool) for s in seeds):
            raise Damaged("seeds is not a list of seeds")
        _typed(v, "params", "", dict, "an object", optional=False)
        rows = _typed(v, "rows", "", dict, "an object", optional=False)
        for name in ("best", "defaults"):
            row = _typed(rows, name, "rows.", dict, "an object", optional=False)
            for key in row_keys:
                if key not in row:
                    raise Damaged(f"rows.{name}.{key} is missing")
        return v
    return check
