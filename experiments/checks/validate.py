"""Checks of the command line's values, made before any work and before any heavy
import (numpy at most): a bad value is one line on stderr, exit status 2, nothing
written. Each check returns the value or raises ValueError with that line.

The limits below are documented in the README and in `ebrl run --help`.
"""
import dataclasses
import importlib
import math
import os
import pathlib
import tempfile
import types

import tasks
from experiments.running import execution, learners
from tasks.config import TaskConfig

#: Seeds run from 0 to MAX_SEED, and one command takes at most MAX_SEEDS of them.
MAX_SEED = 999_999
MAX_SEEDS = 10_000
#: Agent steps of one run (the paper's budgets are 30,000 and 100,000).
MAX_STEPS = 10_000_000
MAX_WORKERS = 1024
#: `ebrl bench`: timed steps per block, and blocks.
MAX_BENCH_STEPS = 1_000_000
MAX_BENCH_BLOCKS = 1_000
#: The agent's memory_size through --set (Table 1: 1024 and 4096); the agent allocates
#: its whole memory up front, so a huge value would exhaust RAM in every worker.
MAX_MEMORY_SIZE = 1_000_000
#: `ebrl fit` and `ebrl evolve`: trials (or generations) a study holds; CMA-ES's population.
MAX_TRIALS = 100_000
MAX_POPULATION = 1_000


def once(values, what):
    """values (a sequence), each given once; else ValueError naming the first given again
    ("size 3x3 is given more than once"): a repeated value would make the same runs twice."""
    seen = set()
    for value in values:
        if value in seen:
            raise ValueError(f"{what} {value} is given more than once")
        seen.add(value)
    return values


def seeds(text):
    """'0-49', '7' or '1,3,5' -> sorted list of seeds; refuses before expanding a range
    past MAX_SEED, more than MAX_SEEDS seeds, and a seed given twice ('0-9,5')."""
    chosen = set()
    for part in text.split(","):
        lo, sep, hi = part.strip().partition("-")
        try:
            lo = int(lo)
            hi = int(hi) if sep else lo
        except ValueError:
            raise ValueError(f"bad seed range {text!r} (use e.g. 0-49, 3 or 1,4,9)") from None
        if lo < 0:
            raise ValueError("seeds must be non-negative")
        if hi < lo:
            raise ValueError(f"reversed seed range {part.strip()!r}")
        if hi > MAX_SEED:
            raise ValueError(f"seeds go up to {MAX_SEED:,}, got {hi:,}")
        if hi - lo + 1 > MAX_SEEDS:
            raise ValueError(f"at most {MAX_SEEDS:,} seeds in one command, got {hi - lo + 1:,}")
        again = min((s for s in chosen if lo <= s <= hi), default=None)
        if again is not None:
            raise ValueError(f"seed {again} is given more than once in {text!r}")
        chosen.update(range(lo, hi + 1))  # at most MAX_SEED + 1 numbers
        if len(chosen) > MAX_SEEDS:
            raise ValueError(f"at most {MAX_SEEDS:,} seeds in one command, got more in {text!r}")
    return sorted(chosen)


def integer(text, lo, hi):
    """An integer from lo to hi (inclusive)."""
    try:
        value = int(text)
    except ValueError:
        raise ValueError(f"not an integer: {text!r}") from None
    if value < lo:
        raise ValueError(f"must be positive, got {value}" if lo == 1
                         else f"must be at least {lo:,}, got {value}")
    if value > hi:
        raise ValueError(f"must be at most {hi:,}, got {value:,}")
    return value


def fraction(text, option):
    """A number in (0, 1]."""
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{option} must be a number, got {text!r}") from None
    if not (0.0 < value <= 1.0):
        raise ValueError(f"{option} must be in (0, 1], got {text!r}")
    return value


def number(kind, name, text):
    """text as kind (int, float, bool or str) for the setting name; floats must be
    finite, booleans are true or false."""
    if kind is bool:
        if text.lower() not in ("true", "false"):
            raise ValueError(f"bad value for {name}: {text!r} (true or false)")
        return text.lower() == "true"
    if kind is str:
        return text
    try:
        value = kind(text)
    except ValueError:
        what = "an integer" if kind is int else "a number"
        raise ValueError(f"bad value for {name}: {text!r} (not {what})") from None
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"bad value for {name}: {text!r} (not a finite number)")
    return value


def available_memory():
    """Bytes of memory this machine has available now (/proc/meminfo's MemAvailable, else
    the free pages), None where neither can be read."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return None


def _bytes(n):
    for unit, size in (("PB", 2**50), ("TB", 2**40), ("GB", 2**30), ("MB", 2**20)):
        if n >= size:
            return f"{n / size:,.1f} {unit}"
    return f"{n / 2**10:,.1f} kB"


#: The learners whose memory grows with sizes a user sets (--set): (module, function of
#: (config, obs_dim, action_dim, steps) giving bytes, the sizes, each with its least).
_SIZED = {"qtable": ("ebrl.baselines.qtable", {"action_levels": 2}),
          "mfec": ("ebrl.baselines.mfec", {"memory_size": 1, "neighbours": 1,
                                           "action_levels": 2})}


def _largest(estimate, config, name, low, given, available):
    """The largest value of the size `name` from low to given whose estimate fits in
    available bytes (None when not even low does), the other fields as config's."""
    fields = dataclasses.asdict(config)

    def fits(v):
        return estimate(types.SimpleNamespace(**{**fields, name: v})) <= available
    if not fits(low):
        return None
    lo, hi = low, given
    while lo < hi:
        mid = (lo + hi + 1) // 2
        lo, hi = (mid, hi) if fits(mid) else (lo, mid - 1)
    return lo


def memory_fits(agent, config, dims, steps, overrides, robot, available=None):
    """ValueError (one line naming the option and the largest value that fits) when a
    learner with the sizes set in overrides would hold more than the memory available
    (available_memory(), or given); dims is (obs_dim, action_dim) of the robot's task."""
    if agent not in _SIZED:
        return
    module, sizes = _SIZED[agent]
    given = {name: overrides[name] for name in sizes if name in overrides}
    if not given:
        return
    available = available_memory() if available is None else available
    if available is None:
        return
    bytes_of = importlib.import_module(module).memory_bytes

    def estimate(c):
        return bytes_of(c, *dims, steps)
    need = estimate(config)
    if need <= available:
        return
    options = [(name, _largest(estimate, config, name, sizes[name], value, available))
               for name, value in given.items()]
    name, largest = max(options, key=lambda o: -1 if o[1] is None else given[o[0]] // max(o[1], 1))
    said = (f"the largest {name} that fits is {largest:,}" if largest is not None else
            f"it does not fit even at {name}={sizes[name]}: lower "
            + ", ".join(n for n in given if n != name))
    value = given[name]
    shown = f"{value:,}" if value < 10**18 else f"{str(value)[:3]}... ({len(str(value))} digits)"
    held = "over 1,000 PB" if need >= 1000 * 2**50 else f"about {_bytes(need)}"
    raise ValueError(f"--set {name}={shown}: the {agent} agent of {robot} would hold "
                     f"{held}, more than the {_bytes(available)} of memory "
                     f"available; {said}")


def agent_configs(robots, overrides, drive=None, agent="ebrl", steps=None):
    """Builds each robot's agent config and task config with the overrides once, here,
    as a run would (execution.RunSpec), so that a name the chosen learner and the task do
    not have, or a value their configs refuse, stops the command before any run."""
    overrides = dict(overrides)
    size = overrides.get("memory_size")
    if size is not None and size > MAX_MEMORY_SIZE:
        raise ValueError(f"memory_size must be at most {MAX_MEMORY_SIZE:,}, got {size:,}")
    config_cls = learners.learner(agent).config
    known = {f.name for cls in (config_cls, TaskConfig) for f in dataclasses.fields(cls)}
    unknown = next((k for k in overrides if k not in known), None)
    if unknown is not None:
        raise ValueError(f"--set {unknown} is not a parameter of the {agent} agent or the task")
    task_fields = {f.name for f in dataclasses.fields(TaskConfig)}
    shown = " ".join(f"{k}={v}" for k, v in sorted(overrides.items()))
    for robot in robots:
        spec = execution.RunSpec(robot, "random", 0, 1, tuple(sorted(overrides.items())),
                                drive, agent)
        try:
            task = spec.task_config()
        except (TypeError, ValueError) as e:
            raise ValueError(f"task parameters {shown}: {e}") from None
        mount = spec.entry.mount
        if mount is not None:   # the readings its action kind cannot run (a gait's)
            try:
                mount.action.check_task_config(task)
            except ValueError as e:
                raise ValueError(f"task parameters {shown}: {robot}: {e}") from None
        try:
            config = spec.agent_config()
        except (TypeError, ValueError) as e:
            shown = " ".join(f"{k}={v}" for k, v in sorted(overrides.items())
                             if k not in task_fields)
            raise ValueError(f"agent parameters {shown} for {robot}: {e}") from None
        if agent in _SIZED and any(name in overrides for name in _SIZED[agent][1]):
            memory_fits(agent, config, _dims(spec), steps or spec.entry.budget, overrides,
                        robot)


def _dims(spec):
    """(obs_dim, action_dim) of a run's agent: its modalities' sizes, its drive's action
    (the robot's task, loaded once here)."""
    env = tasks.load(spec.entry, seed=0)
    try:
        obs = env.observation_spec()
        return (sum(obs[key].shape[0] for key, _ in spec.entry.modalities),
                env.action_spec().shape[0])
    finally:
        env.close()


def _can_create_in(folder):
    """Whether a file can be made in folder. Probed with an unnamed temporary file
    (O_TMPFILE where the system has it), so the probe leaves nothing behind; os.access
    alone says yes to root even on a read-only or virtual file system."""
    if not os.access(folder, os.W_OK | os.X_OK):
        return False
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError:
        return False
    return True


def _parent_folder(path, option):
    parent = path.parent
    if not parent.is_dir():
        what = "is not a folder" if parent.exists() else "does not exist"
        raise ValueError(f"{option} {path}: {parent} {what}")
    if not _can_create_in(parent):
        raise ValueError(f"{option} {path}: cannot write in {parent}")
    return parent


def output_folder(path, option):
    """A folder the command writes into: an existing, writable folder, or a new one
    whose parent folder exists and is writable (missing parents are never made)."""
    path = pathlib.Path(path)
    if path.exists() or path.is_symlink():
        if not path.is_dir():
            raise ValueError(f"{option} {path} exists and is not a folder")
        if not _can_create_in(path):
            raise ValueError(f"{option} {path}: cannot write in it")
    else:
        _parent_folder(path, option)
    return path


def output_file(path, option, suffix=None):
    """A file the command writes: not a folder, in an existing writable folder."""
    path = pathlib.Path(path)
    if suffix is not None and path.suffix.lower() != suffix:
        raise ValueError(f"{option} must end in {suffix}, got {path}")
    if path.is_dir():
        raise ValueError(f"{option} {path} is a folder")
    _parent_folder(path, option)
    return path


def results_folder(path, option="", writable=False):
    """An existing folder of results; writable when the command writes its report."""
    path = pathlib.Path(path)
    if not path.is_dir():
        prefix = f"{option}: " if option else ""
        raise ValueError(f"{prefix}no results folder at {path}"
                         + (" (it is a file)" if path.exists() else ""))
    if writable and not _can_create_in(path):
        raise ValueError(f"cannot write the report in {path}")
    return path
