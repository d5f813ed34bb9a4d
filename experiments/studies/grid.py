"""Settings of a robot's readings, each run on the same seeds, each in its own folder: the
first-trial grids of issue 48 (the walk study, `experiments/studies/walk.py` at commit
f9a3f0f, and protocol 7's body fits), protocol 8's body fit (body_fit) and any other set of
`--set` settings run side by side.

A setting is a tuple of (reading, value) pairs, given to every run as its overrides
(`ebrl run --set`); its runs go to OUT/<robot>/<setting's name>/, as `ebrl run --out` would
write them, so the same call resumes (finished runs are skipped) and `ebrl report` reads
any one folder.
"""
import itertools
import pathlib

import numpy as np

from experiments import paper
from experiments.running import results, runner


def name(setting):
    """A setting's folder name: "radius=2,blocked_move=stop" ("default" when empty)."""
    return ",".join(f"{k}={v}" for k, v in setting) or "default"


def product(**values):
    """Every combination of the readings' values, as settings (the names in keyword order)."""
    keys = list(values)
    return [tuple(zip(keys, combo)) for combo in itertools.product(*(values[k] for k in keys))]


def folder(out, robot, setting):
    return pathlib.Path(out) / robot / name(setting)


def run(out, robot, settings, conditions, seeds, *, first_trial=True, steps=None, workers=1,
        progress=False):
    """Runs every setting's runs not yet on disk (all settings on one worker pool) and
    returns {setting: {(condition, seed): run.json}}."""
    specs, where = [], {}
    for setting in settings:
        for spec in runner.plan((robot,), conditions, seeds, steps, setting,
                                first_trial=first_trial):
            specs.append(spec)
            where[spec] = folder(out, robot, setting)
    runner.run(specs, lambda spec: where[spec], workers=workers, progress=progress)
    out_runs = {}
    for setting in settings:
        runs = results.load_runs(folder(out, robot, setting))
        out_runs[setting] = {(c, s): r for (_, c, s), r in runs.items()
                             if c in conditions and s in set(seeds)}
    return out_runs


def first_trials(runs, condition):
    """The first-trial steps of a condition's runs, None for a run without a goal, in seed
    order."""
    keys = sorted(k for k in runs if k[0] == condition)
    return [runs[k]["metrics"]["first_trial_steps"] for k in keys]


def summary(values, budget):
    """{mean, sd, reached, runs, median, late (share past budget / 5 among reached)} of
    first-trial steps (None: not reached within the budget)."""
    reached = np.array([v for v in values if v is not None], dtype=np.float64)
    return {"mean": float(reached.mean()) if len(reached) else None,
            "sd": float(reached.std(ddof=1)) if len(reached) > 1 else None,
            "median": float(np.median(reached)) if len(reached) else None,
            "reached": int(len(reached)), "runs": len(values)}


def paper_first_trial(drive, condition):
    """The paper's first-trial figures of a drive and condition (experiments.paper)."""
    return paper.FIRST_TRIALS[(drive, condition)]


def table(rows, columns):
    """A markdown table of {setting name: {column: value}} rows."""
    lines = ["| setting | " + " | ".join(columns) + " |",
             "|---|" + "---:|" * len(columns)]
    for setting, row in rows.items():
        cells = []
        for c in columns:
            v = row.get(c)
            cells.append("-" if v is None else (f"{v:,.3f}" if isinstance(v, float) and abs(v) < 10
                                                else f"{v:,.0f}" if isinstance(v, float) else str(v)))
        lines.append(f"| {setting} | " + " | ".join(cells) + " |")
    return "\n".join(lines)
