"""`ebrl fit --stage first-trial`: stage 1 of the fit, the physics and the fallback's
readings of one drive against the paper's two first-trial distributions of that drive.

A run's first trial is the physics and the fallback alone (experiments.paper.FIRST_TRIALS:
memory never acts before the first reward), so no learning reading can move it, and a
first-trial run (execution.RunSpec.first_trial) costs a fraction of a full run: a trial
of this stage runs 64 or more seeds of each condition, to the first goal or the drive's
budget, through the one study runner (experiments.studies.study) that `ebrl fit` and
`ebrl evolve` share.

The space (SPACES) is per drive: the readings that can change a first trial: the random
walk's demand and the leftover turn (random_demand, leftover_turn; blocked_move is
stated, so not searched), the body's (radius; the floating bump, restitution, wall
friction), the floating drive's action
noise (the paper gives the two-wheel robot's 5% only) and the fallback's switches.
Table 1, the room, the sensors and the actions' maxima stay fixed. The objective is
`distance`; `validate` reruns a trial's settings and the defaults on held-out seeds.
"""
import dataclasses
import math
import pathlib

import numpy as np

from experiments import paper
from experiments.checks.validate import once
from experiments.running import results, runner, schema
from experiments.studies import study
from experiments.studies.fit import param

STAGE = "first-trial"
#: The kurtosis the sd's standard error assumes: an exponential's (9), which the paper's
#: first trials suggest (their sd is close to their mean, as an exponential's is).
KURTOSIS = 9.0
#: A term that cannot be computed (fewer than 2 runs reached the goal).
MISSING_TERM = 100.0
#: Per drive: the paper's robot whose first trials are fitted.
ROBOTS = {"two_wheel": "two_wheel", "floating": "floating"}
#: The least seeds a trial runs per condition.
MIN_SEEDS = 64


def _param(name, bounds=None):
    """A reading of the registry in a drive's space (fit.param; its scope: the drive's
    alone), a number within bounds (low, high), this stage's choice."""
    return param(name, bounds, scope="drive")


_FALLBACK = (_param("random_demand"), _param("random_in_avoidance"))
#: The search space of each drive (the radius from a body that still carries its sensors
#: to the ablation's largest, as `ebrl fit`'s).
SPACES = {
    "two_wheel": _FALLBACK + (
        # (not blocked_move: Section 3.3 states it, a move stopped at the touch, since
        # protocol 8 on the body itself)
        _param("leftover_turn"),
        _param("radius", (1.0, 2.5)),
    ),
    "floating": _FALLBACK + (
        _param("eq9_dead_zone"),
        _param("bump"),
        _param("restitution", (0.0, 1.0)),
        _param("wall_friction", (0.0, 1.5)),
        _param("action_noise", (0.0, 0.5)),
        _param("radius", (1.0, 2.5)),
    ),
}


def space(drive, text="all"):
    """The names of a drive's space that --space names ("all", or comma-separated);
    ValueError naming an unknown one."""
    if drive not in SPACES:
        raise ValueError(f"--stage {STAGE} fits one drive: --robot {' or '.join(SPACES)}, "
                         f"got {drive!r}")
    mine = {p.name: p for p in SPACES[drive]}
    names = tuple(mine) if text == "all" else tuple(n.strip() for n in text.split(",")
                                                    if n.strip())
    unknown = [n for n in names if n not in mine]
    if unknown or not names:
        raise ValueError(f"unknown reading {unknown[0] if unknown else text!r} in --space "
                         f"for --stage {STAGE} --robot {drive}; valid: {', '.join(mine)}")
    return once(names, "--space")


def default(name, robot):
    """The robot's current value of a reading (its readings, else the config's field;
    the file's radius 1.5 and friction 1 where that is None)."""
    from experiments.studies import fit
    return fit.default(name, robot)


def overrides(params, robot):
    """A trial's settings as sorted (name, value) pairs, the robot's defaults left out (so
    a setting equal to the defaults shares their runs)."""
    return tuple(sorted((k, v) for k, v in params.items() if v != default(k, robot)))


# -- the distance -------------------------------------------------------------------
def sample(first_trials, runs):
    """Our figures of a condition from its runs' first-trial steps (None for a run that
    did not reach the goal): {mean, sd (ddof 1), reached, runs, tail (the share not
    reached)}; mean and sd None with fewer than 2 reached."""
    reached = np.array([v for v in first_trials if v is not None], dtype=np.float64)
    n, r = int(runs), len(reached)
    return {"mean": float(reached.mean()) if r >= 2 else None,
            "sd": float(reached.std(ddof=1)) if r >= 2 else None,
            "reached": r, "runs": n, "tail": (n - r) / n if n else None}


def terms(ours, ref):
    """The three squared z-scores of one condition (`distance`): {"mean", "sd", "tail"}."""
    r_p, n_p, m_p, s_p = ref["reached"], ref["runs"], ref["mean"], ref["sd"]
    r, n = ours["reached"], ours["runs"]
    out = {}
    if ours["mean"] is None:
        out["mean"] = out["sd"] = MISSING_TERM
    else:
        both = 1.0 / r_p + 1.0 / r
        out["mean"] = ((ours["mean"] - m_p) / (s_p * math.sqrt(both))) ** 2
        out["sd"] = ((ours["sd"] - s_p) / (s_p * math.sqrt((KURTOSIS - 1.0) / 4.0 * both))) ** 2
    q_p, q = (n_p - r_p) / n_p, (n - r) / n
    pooled = (n_p - r_p + n - r) / (n_p + n)
    if pooled == 0.0:  # neither the paper nor we have a run without the goal
        out["tail"] = 0.0
    else:
        out["tail"] = (q - q_p) ** 2 / (pooled * (1.0 - pooled) * (1.0 / n_p + 1.0 / n))
    return out


def distance(samples, drive):
    """Stage 1's objective: how far our first trials of a drive lie from the paper's, in
    units of the sampling error of the figures compared.

    For each condition c (random, avoidance), the paper's n_p = 50 runs of which r_p
    reached the goal within the budget, their mean m_p and sd s_p (over the r_p), and
    ours on n seeds, r reached, mean m and sd s (ddof 1, over the r), q = (n - r) / n
    and q_p = (n_p - r_p) / n_p the shares not reached:

        z_mean = (m - m_p) / (s_p sqrt(1/r_p + 1/r))
        z_sd   = (s - s_p) / (s_p sqrt((K - 1)/4 (1/r_p + 1/r))),  K = KURTOSIS = 9
        z_tail = (q - q_p) / sqrt(qb (1 - qb) (1/n_p + 1/n)),  qb = (n_p - r_p + n - r) / (n_p + n)

        distance = sum over c of z_mean^2 + z_sd^2 + z_tail^2

    z_mean compares two sample means of one distribution of sd s_p (the paper's, so a
    trial cannot buy a small distance with a wide spread); z_sd uses the standard error
    of a sample sd, s sqrt((K - 1) / (4 r)), with the kurtosis of an exponential (the
    paper's sd is about its mean); z_tail is the pooled two-proportion z-test (0 where
    neither has a run without the goal). Each is the difference of two samples, so the
    paper's own 50 runs count as well as ours. If ours are drawn as the paper's, the
    distance is about chi-square with 6 degrees of freedom: 6 on average, below 12.6 19
    times in 20. A condition with fewer than 2 runs at the goal costs MISSING_TERM for
    its mean and its sd.

    samples: {condition: `sample`(...)}. Returns (distance, {"condition/figure": term})."""
    out = {}
    for condition in paper.CONDITIONS:
        for k, v in terms(samples[condition], paper.FIRST_TRIALS[(drive, condition)]).items():
            out[f"{condition}/{k}"] = v
    return sum(out.values()), out


# -- the problem for experiments.studies.study ---------------------------------------
@dataclasses.dataclass
class Problem:
    """Stage 1 for one drive: its space, a trial's first-trial runs, their distance."""
    drive: str
    names: tuple = None
    rungs: tuple = (tuple(range(MIN_SEEDS)),)
    steps: int = None  # None: the drive's budget (the paper's tail is "within 30,000")
    room: str = None  # models.rooms' room; None: the paper's

    def __post_init__(self):
        if self.names is None:
            self.names = space(self.drive)
        self.robot = ROBOTS[self.drive]

    def distributions(self):
        by = {p.name: p for p in SPACES[self.drive]}
        return {n: by[n].distribution() for n in self.names}

    def defaults(self):
        """The robot's current readings, trial 0."""
        return {n: default(n, self.robot) for n in self.names}

    def specs(self, params, seeds):
        return runner.plan((self.robot,), paper.CONDITIONS, seeds, self.steps,
                           overrides(params, self.robot), first_trial=True, room=self.room)

    def samples(self, runs):
        """{condition: sample} of runs (robot, condition, seed) -> run.json."""
        out = {}
        for condition in paper.CONDITIONS:
            firsts = [r["metrics"]["first_trial_steps"] for (_, c, _), r in runs.items()
                      if c == condition]
            out[condition] = sample(firsts, len(firsts))
        return out

    def score(self, params, runs):
        samples = self.samples(runs)
        value, parts = distance(samples, self.drive)
        return value, {"figures": samples, "terms": parts}


def validate(problem, params, out, seeds, workers=None, backend="local", progress=True):
    """Reruns a trial's settings and the defaults on held-out seeds; writes and returns
    validation_first_trial_<drive>.json: per setting its figures beside the paper's and
    its distance. ([], None) on failed runs: (data, failed)."""
    where = lambda spec: study.run_folder(out, spec)  # noqa: E731
    plans = {"best": problem.specs(params, seeds), "defaults": problem.specs({}, seeds)}
    todo = sorted({s for v in plans.values() for s in v},
                  key=lambda s: (s.seed, s.condition, s.overrides))
    ran = runner.run(todo, where, workers=workers, backend=backend, progress=progress)
    if ran.failed:
        return None, ran.failed
    rows = {}
    for name, specs in plans.items():
        runs = {}
        for s in specs:
            runs.update(results.load_runs(where(s), [s]))
        samples = problem.samples(runs)
        value, parts = distance(samples, problem.drive)
        rows[name] = {"distance": value, "terms": parts, "figures": samples}
    data = {"drive": problem.drive, "seeds": list(seeds), "params": params,
            "steps": problem.steps,
            "paper": {c: paper.FIRST_TRIALS[(problem.drive, c)] for c in paper.CONDITIONS},
            "rows": rows}
    results.atomic_write(pathlib.Path(out) / f"validation_first_trial_{problem.drive}.json",
                         results.dumps(data))
    return data, []


# -- the report -----------------------------------------------------------------------
def _fmt(v, digits=0):
    return "-" if v is None else f"{v:,.{digits}f}"


def figure_rows(figures_by_name, drive):
    """Markdown rows: the paper's first trials beside each named setting's."""
    names = list(figures_by_name)
    lines = ["| condition | figure | paper | " + " | ".join(names) + " |",
             "|---|---|---:|" + "---:|" * len(names)]
    for c in paper.CONDITIONS:
        ref = paper.FIRST_TRIALS[(drive, c)]
        ref_tail = (ref["runs"] - ref["reached"]) / ref["runs"]
        for f, pv, digits in (("mean", ref["mean"], 0), ("sd", ref["sd"], 0),
                              ("tail", ref_tail, 3)):
            cells = [_fmt(figures_by_name[n][c][f], digits) for n in names]
            lines.append(f"| {c} | {f} | {_fmt(pv, digits)} | " + " | ".join(cells) + " |")
    return lines


def text(params, robot):
    changed = [(k, v) for k, v in sorted(params.items()) if v != default(k, robot)]
    return ", ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}"
                     for k, v in changed) or "the defaults"


def write(s, out, problem):
    """FIT_first_trial_<drive>.md under out: the best trials, their figures beside the
    paper's, and the held-out validation when there is one. Returns its path."""

    import optuna
    out = pathlib.Path(out)
    done = s.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
    lines = [f"# `ebrl fit --stage {STAGE} --robot {problem.robot}`", "",
             "Distance: the sum over both conditions of the squared z-scores of the mean, "
             "the sd and the share not at the goal, each against its sampling error "
             "(experiments/studies/first_trials.py, `distance`; about 6 when ours are "
             "drawn as the paper's).", "",
             f"{len(done)} complete trials in study `{s.study_name}`.", "",
             "| trial | distance | seeds | readings (changed from the defaults) |",
             "|---:|---:|---:|---|"]
    best = study.best_trials(s, 8)
    for t in best:
        d = study.deepest(t)
        lines.append(f"| {t.number} | {d['value']:.3g} | {len(d['seeds'])} | "
                     f"{text(t.params, problem.robot)} |")
    if best:
        d = study.deepest(best[0])
        lines += ["", f"Trial {best[0].number} on its {len(d['seeds'])} seeds:", ""]
        lines += figure_rows({"best": d["figures"]}, problem.drive)
    vpath = out / f"validation_first_trial_{problem.drive}.json"
    v = results.read_bookkeeping(vpath, schema.check_validation(("distance", "figures")))
    if v is not None:  # a damaged one is set aside, named, and made by the next --validate
        rows = v["rows"]
        lines += ["", f"Held-out validation on seeds {v['seeds'][0]}-{v['seeds'][-1]} "
                  f"({len(v['seeds'])} seeds no trial used): {text(v['params'], problem.robot)} "
                  f"(distance {rows['best']['distance']:.3g}) beside the defaults "
                  f"({rows['defaults']['distance']:.3g}).", ""]
        lines += figure_rows({"best": rows["best"]["figures"],
                              "defaults": rows["defaults"]["figures"]}, problem.drive)
    path = out / f"FIT_first_trial_{problem.drive}.md"
    results.atomic_write(path, "\n".join(lines) + "\n")
    return path


# -- the command ----------------------------------------------------------------------
def check_args(robot, space_text, seeds, promote_seeds, validate_seeds):
    """`ebrl fit --stage first-trial`'s own checks, before any work: (names, rungs);
    ValueError with the line to print."""
    names = space(robot, space_text)
    if len(seeds) < MIN_SEEDS:
        raise ValueError(f"--stage {STAGE} needs at least {MIN_SEEDS} seeds per trial "
                         f"(e.g. --seeds 0-{MIN_SEEDS - 1}), got {len(seeds)}")
    promote_seeds = seeds if promote_seeds is None else promote_seeds
    if not set(seeds) <= set(promote_seeds):
        raise ValueError("--promote-seeds must include every seed of --seeds")
    if validate_seeds is not None and set(validate_seeds) & set(promote_seeds):
        raise ValueError("--validate seeds must be seeds the search never uses (not in "
                         "--seeds or --promote-seeds)")
    rungs = (tuple(seeds),) if list(seeds) == list(promote_seeds) else \
        (tuple(seeds), tuple(promote_seeds))
    return names, rungs


def fit(problem, s, out, n_trials, *, batch=4, workers=None, backend="local", promote=0.1,
        progress=True, validate_seeds=None, trial=None):
    """Runs the stage's study to n_trials (the defaults first, as trial 0: study.load's
    `first`, problem.defaults()), then, with
    validate_seeds, the best trial (or trial number `trial`) and the defaults on them;
    writes the report. Returns (outcome, report path, failed (name, error) pairs); a
    ValueError for a trial that cannot be validated."""
    outcome = study.optimize(problem, s, out, n_trials, batch=batch, workers=workers,
                             backend=backend, promote=promote, progress=progress)
    failed = [(f"trial {n}", e) for n, e in outcome.failed]
    if validate_seeds is not None:
        best = study.best_trials(s, 1) if trial is None else \
            [t for t in s.trials if t.number == trial and "rungs" in t.user_attrs]
        if not best:
            raise ValueError(f"no complete trial {'to validate' if trial is None else trial}")
        params = {k: v for k, v in best[0].params.items() if k in problem.names}
        _, lost = validate(problem, params, out, validate_seeds, workers, backend, progress)
        failed += [(spec.name, e) for spec, e in lost]
    return outcome, write(s, out, problem), failed
