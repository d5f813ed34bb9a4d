"""`ebrl check --tune`: a mount's open drive values found by `ebrl check`'s own measures.

The open values are the mount's `time_scale` and the gains its action kind takes
(tasks.mount.parsed.Action.gains: joint_motors' kp and kv, one per joint; wheel_motors'
and wheels' kp and kv). Each trial writes them into the mount's text (nothing else of it
changes), parses that text as the tuned file beside the input will be, and runs the
check on it (experiments.checks.robotcheck.check: the accuracy over --accuracy-actions
free-space actions and the fuzz over --actions, each as `ebrl check` runs them, seed 0).

The objective, minimised by Optuna's TPE sampler (seeded: the same seed, trials and
counts give the same file), is `score`: the check's worst measure as a share of its limit
(the turn and move errors' largest, the fuzz's deepest sink, largest tilt and falls; a
failure the check does not size, robotcheck.UNMEASURED), under 1 where the check passes,
asked down to MARGIN (a trial's counts are shorter than the check's own, whose largest
errors are larger); within the margin, the shorter time_scale (the faster drive: every
run's cost, and the paper's robot's pace) scores less. The values kept are the passing
ones of least score (if none passed, the least score): by default every trial runs;
--first-pass stops after the first batch with a passing trial.

Trials run in batches of BATCH, one process each (two cores), told to the sampler in
their order: the file does not depend on how many cores ran them. Trial 0 is the mount
as it is. A sampled value is rounded to SIGNIFICANT digits, so the file reads as a person
would write it and holds exactly the values measured.

The tuned mount is written beside the input, `NAME.tuned.toml`, never over a file (one
that exists is refused before any work); the input is only read.
"""
import math
import os
import pathlib
import re
import tempfile
import time
import tomllib
from concurrent.futures import ProcessPoolExecutor

from experiments.checks import robotcheck, validate
from experiments.running import pool as run_pool
from experiments.running import worker
from tasks import mount as mounts
from tasks.robots import MOUNTS, ROBOTS, mount_entry

#: Trials asked of the sampler, and run at once, per batch.
BATCH = 2
#: Significant digits of a sampled value.
SIGNIFICANT = 3
#: The search's range about the mount's own value, on a log scale: time_scale from half
#: to four times it (a drive slower than the paper's ideal one, rarely faster); a gain
#: from a tenth to ten times it. A kv of 0: from 0 to the joint's kp, on a linear scale.
TIME_SCALE_RANGE = (0.5, 4.0)
GAIN_RANGE = (0.1, 10.0)
#: The counts of a trial's check, unless --actions and --accuracy-actions are given.
ACTIONS = 300
ACCURACY_ACTIONS = 100
#: The default number of trials (--trials).
TRIALS = 40
#: The share of each limit a trial's measures are asked to stay under; and the weight
#: of time_scale (0 at the search's shortest, 1 at its longest) within it.
MARGIN = 0.5
PACE = 0.01


def output_path(mount):
    """The tuned mount's path: NAME.tuned.toml beside the input."""
    mount = pathlib.Path(mount)
    return mount.with_name(f"{mount.stem}.tuned.toml")


def open_values(mount):
    """The mount's open drive values, {name: its value}, in the search's order:
    time_scale, then each gain, one per joint role where the kind takes one per joint
    (kp_forward, kp_turn, ...)."""
    values = {"time_scale": mount.time_scale}
    roles = mount.action.gain_joints
    for gain, v in mount.action.gains().items():
        if roles:
            per = v if isinstance(v, tuple) else (v,) * len(roles)
            values.update((f"{gain}_{role}", float(x)) for role, x in zip(roles, per))
        else:
            values[gain] = float(v)
    return values


def fields_of(mount, values):
    """The mount fields for `values` (open_values' names): {field: number or list},
    time_scale first."""
    out = {"time_scale": values["time_scale"]}
    roles = mount.action.gain_joints
    for gain in mount.action.gains():
        out[gain] = [values[f"{gain}_{role}"] for role in roles] if roles else values[gain]
    return out


def shown(fields):
    """'time_scale 4.0, kp [83.4, 152.0], kv 30.0'."""
    return ", ".join(f"{k} {_toml(v)}" for k, v in fields.items())


def _toml(v):
    """A number, or a list of them, as TOML (the float's shortest exact text)."""
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    return repr(float(v))


def _rounded(x):
    return float(f"{x:.{SIGNIFICANT}g}")


def _ranges(start):
    """{name: (low, high, log)} of the search, about the start's values (open_values')."""
    ranges = {}
    for name, v in start.items():
        if name == "time_scale":
            lo, hi = (v * f for f in TIME_SCALE_RANGE)
            ranges[name] = (lo, min(hi, 1000.0), True)   # tasks.mount.parsing.TIME_SCALE's
        elif v > 0:
            ranges[name] = (v * GAIN_RANGE[0], v * GAIN_RANGE[1], True)
        else:   # a kv of 0: up to its joint's kp
            ranges[name] = (0.0, start.get(name.replace("kv", "kp", 1), 1.0) or 1.0, False)
    return ranges


# -- the mount's text, rewritten ---------------------------------------------------------

class RewriteError(ValueError):
    """A mount whose text cannot be rewritten field by field (a dotted key, an inline
    [action] table, a value over several lines): one line naming the field."""


_HEADER = re.compile(r"^\s*\[")
_ACTION = re.compile(r"^\s*\[\s*action\s*\]\s*(#.*)?$")


def _key(name):
    return re.compile(rf"^(\s*{re.escape(name)}\s*=\s*)([^#]*?)(\s*(#.*)?)$")


def rewrite(text, path, fields, header=None):
    """The mount's text with `fields` (fields_of's: time_scale in the top table, the gains
    in [action]) set, each on its own line (a line that gives it is rewritten, its comment
    kept; one that does not is added); every other byte as it was (but a newline ending
    the last line), and `header` (a comment) first. RewriteError when the text, read
    back, does not give exactly these values and the input's others."""
    lines = text.splitlines(keepends=True)
    if lines and not lines[-1].endswith("\n"):
        lines[-1] += "\n"
    first = next((i for i, line in enumerate(lines) if _HEADER.match(line)), len(lines))
    action = next((i for i, line in enumerate(lines) if _ACTION.match(line)), None)
    for name, value in fields.items():
        if name == "time_scale":
            start, end = 0, first
        elif action is None:
            raise _not_one_to_a_line(path, name)
        else:
            start = action + 1
            end = next((i for i in range(start, len(lines)) if _HEADER.match(lines[i])),
                       len(lines))
        pattern = _key(name)
        at = next((i for i in range(start, end) if pattern.match(lines[i])), None)
        if at is None:   # after the table's last key
            at = max((i for i in range(start, end)
                      if lines[i].strip() and not lines[i].lstrip().startswith("#")),
                     default=start - 1) + 1
            lines.insert(at, f"{name} = {_toml(value)}\n")
            if at <= first:
                first += 1
            if action is not None and at <= action:
                action += 1
        else:
            m = pattern.match(lines[at].rstrip("\n"))
            if m.group(2).count("[") != m.group(2).count("]"):   # a list over several lines
                raise _not_one_to_a_line(path, name)
            lines[at] = f"{m.group(1)}{_toml(value)}{m.group(3)}\n"
    out = "".join(([header + "\n"] if header else []) + lines)
    _check_rewrite(text, out, path, fields)
    return out


def _check_rewrite(text, out, path, fields):
    """RewriteError unless `out` reads as `text` with `fields` set."""
    try:
        before, after = tomllib.loads(text), tomllib.loads(out)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, ValueError) as e:
        raise RewriteError(f"{path}: --tune cannot rewrite it: {e}") from None
    expected = dict(before)
    expected["action"] = dict(before.get("action", {}))
    for name, value in fields.items():
        (expected if name == "time_scale" else expected["action"])[name] = value
    if after != expected:
        wrong = next((n for n, v in fields.items()
                      if (after if n == "time_scale" else after.get("action", {})).get(n) != v),
                     None)
        raise _not_one_to_a_line(path, wrong)


def _not_one_to_a_line(path, name):
    field = "file" if name is None else name if name == "time_scale" else f"action.{name}"
    return RewriteError(f"{path}: {field}: --tune writes each value on a line of its own "
                        "(time_scale in the top table, the gains under an [action] header); "
                        "write the mount so")


# -- the search ---------------------------------------------------------------------------

def evaluate(out, text, actions, accuracy_actions, room):
    """One trial: the check of the mount `text` as the file `out` (robotcheck.check)."""
    entry = mount_entry(mounts.parse(out, text))
    return robotcheck.check(entry, actions, accuracy_actions, room=room, name=str(out))


def _pool(workers):
    """The trials' processes: the run pool's start method (experiments.running.pool)."""
    return ProcessPoolExecutor(max_workers=workers, mp_context=run_pool.context())


def search(mount_path, trials, seed, actions, accuracy_actions, room=None, first_pass=False,
           progress=True, report=print):
    """Runs the search (the module's docstring); returns (the tuned text, its fields, its
    Checked, the trial's number, the trials run, the start's fields and Checked)."""
    import optuna   # here, not at the top: the command line imports this module, and stays light

    mount_path = pathlib.Path(mount_path)
    out = output_path(mount_path)
    text = mount_path.read_text()
    m = mounts.parse(mount_path)
    start = open_values(m)
    ranges = _ranges(start)
    header = (f"# {', '.join(fields_of(m, start))} by `ebrl check --tune` from "
              f"{mount_path.name} ({trials} trials, sampler seed {seed})")
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    study = optuna.create_study(direction="minimize",
                                sampler=optuna.samplers.TPESampler(seed=seed))
    study.enqueue_trial(start)   # trial 0: the mount as it is
    results = []   # (number, fields, text, Checked, score)
    bar = None
    if progress:
        from tqdm import tqdm   # as optuna
        bar = tqdm(total=trials, unit="trial", dynamic_ncols=True, desc=f"tune {mount_path.name}")
    workers = max(1, min(BATCH, os.cpu_count() or 1))
    try:
        # the workers' numpy and numba: one thread each
        with worker.single_threaded(), _pool(workers) as pool:
            while len(results) < trials:
                asked = [study.ask() for _ in range(min(BATCH, trials - len(results)))]
                batch = []
                for trial in asked:
                    values = {name: trial.suggest_float(name, lo, hi, log=log)
                              for name, (lo, hi, log) in ranges.items()}
                    if trial.number:   # trial 0 keeps the mount's own
                        values = {name: _rounded(v) for name, v in values.items()}
                    fields = fields_of(m, values)
                    batch.append((trial, fields, rewrite(text, out, fields, header)))
                futures = [pool.submit(evaluate, out, t, actions, accuracy_actions, room)
                           for _, _, t in batch]
                for (trial, fields, t), future in zip(batch, futures):
                    checked = future.result()
                    value = score(checked, fields["time_scale"], ranges)
                    study.tell(trial, value)
                    results.append((trial.number, fields, t, checked, value))
                if bar is not None:
                    best = min(results, key=rank)[3]
                    bar.update(len(batch))
                    bar.set_postfix_str(f"best: {_worst(best)}"
                                        + (" (passes)" if best.passed else ""))
                if first_pass and any(r[3].passed for r in results):
                    break
    finally:
        if bar is not None:
            bar.close()
    number, fields, tuned, checked, _ = min(results, key=rank)
    return tuned, fields, checked, number, len(results), fields_of(m, start), results[0][3]


def score(checked, time_scale, ranges):
    """A trial's score (the module's docstring): its worst share, or MARGIN where under it,
    plus PACE times its time_scale's place in the search's range (log scale)."""
    lo, hi, _ = ranges["time_scale"]
    pace = math.log(time_scale / lo) / math.log(hi / lo) if hi > lo else 0.0
    return max(checked.worst()[1], MARGIN) + PACE * min(max(pace, 0.0), 1.0)


def rank(result):
    """A search's result (number, fields, text, Checked, score): passing first, then the
    least score, then the earliest."""
    number, _, _, checked, value = result
    return (not checked.passed, value, number)


def _worst(checked):
    name, share = checked.worst()
    return f"{name} at {share:.3g} of its limit"


def write_new(path, text):
    """Writes text to path, a file that must not exist (FileExistsError, nothing written
    over): a temporary file beside it, linked to its name only if that is free."""
    path = pathlib.Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        try:
            os.link(tmp, path)
        except FileExistsError:
            raise
        except OSError:   # a file system without hard links: made only if it is free
            with open(path, "x") as f:
                f.write(text)
    finally:
        os.unlink(tmp)


def main(mount_path, trials, seed, actions, accuracy_actions, room=None, first_pass=False,
         progress=True):
    """`ebrl check --tune` (its arguments checked: experiments.commands.check): prints the
    start's measures, the values found and the check's lines at them, writes the tuned
    mount; 0 when they pass, 1 when no trial passed (the best is written all the same)."""
    out = output_path(mount_path)
    started = time.perf_counter()
    tuned, fields, checked, number, ran, start, at_start = search(
        mount_path, trials, seed, actions, accuracy_actions, room, first_pass, progress)
    seconds = time.perf_counter() - started
    print(f"{mount_path}: as it is ({shown(start)}): worst {_worst(at_start)} "
          f"{'ok' if at_start.passed else 'FAIL'}")
    print(f"{mount_path}: {ran} trials (sampler seed {seed}; each {accuracy_actions:,} "
          f"free-space and {actions:,} random actions) in {_duration(seconds)}: trial "
          f"{number}, {shown(fields)}, worst {_worst(checked)}")
    for line in checked.lines:
        print(line)
    write_new(out, tuned)
    if checked.passed:
        print(f"{mount_path}: wrote {out}; `ebrl check --robot {out}` checks it over the "
              "check's own counts")
        return 0
    print(f"{mount_path}: no trial passed; the nearest written to {out}: more --trials, or "
          "see docs/adding_a_robot.md (tuning with ebrl check --tune)")
    return 1


def _duration(seconds):
    return f"{seconds:.0f} s" if seconds < 120 else f"{seconds / 60:.1f} min"


def check_args(robot, out):
    """The checks --tune makes before any work, each a ValueError of one line: a mount
    file (not a registered robot, a shipped mount or a robot file), an output that does
    not exist in a writable folder, and a mount whose fields --tune can rewrite."""
    if robot in ROBOTS:
        raise ValueError(f"--tune: {robot!r} is a registered robot: its drive values are its "
                         "entry's in tasks/robots.py, not a mount's; --tune takes a mount "
                         "file (.toml)")
    if robot in MOUNTS:
        raise ValueError(f"--tune: {robot!r} is a shipped mount ({MOUNTS[robot]}): copy it "
                         "and give the copy, which --tune writes beside")
    path = pathlib.Path(robot)
    if path.suffix.lower() != ".toml":
        raise ValueError(f"--tune: {robot} is a robot file, not a mount: its gains are its "
                         "own; --tune takes a mount file (.toml)")
    if out.exists() or out.is_symlink():
        raise ValueError(f"--tune: {out} exists (an earlier tune's?): move or remove it; "
                         "--tune never writes over a file")
    validate.output_file(out, "--tune: the tuned mount")
    m = mounts.parse(path)
    start = open_values(m)
    if any(not math.isfinite(v) for v in start.values()):   # parse refuses these already
        raise ValueError(f"--tune: {path}: a drive value is not a finite number")
    rewrite(path.read_text(), path, fields_of(m, start))
