"""`ebrl multiverse`'s numbers: each universe's twelve figures and ten claims with their
intervals (its table, multiverse.csv), and across the universes each claim's share and
each factor's effects on it.

The claims are Section 3.6's ten, as `ebrl report` judges them (each by the test of
experiments.outputs.verdicts' claim_tests, at its raw p: the same verdicts,
tests/test_multiverse.py), each with a statistic and a 95% interval, numbered as RESULTS.md
numbers them:

- C1, C2, C7, C8 (avoidance cuts first-trial steps, steps per trial): the random walk's
  mean over the avoidance mean; holds when the one-sided Welch test of the random walk's
  mean above the avoidance mean rejects (verdicts.cut_p). The interval resamples seeds,
  the same seeds for both conditions (a seed gives both conditions the same streams).
- C3, C4, C9, C10 (learning shrinks trials): the shrink and its interval
  (aggregate.summarize); holds when the one-sided z test of its log below 0 rejects
  (verdicts.shrinks_p).
- C5 (most two-wheel random walks reach fewer than 30 goals in 30,000 steps): the share
  of runs below 30 goals, Wilson's interval; holds when the one-sided binomial test
  against a half rejects (verdicts.most_p).
- C6 (every two-wheel avoidance run reaches at least 49 goals): the fewest goals, a
  percentile bootstrap of the minimum; holds unless the rank test shows more of our runs
  below 49 than one distribution gives (verdicts.rank_below). C5 and C6 are judged at
  the paper's budget only.

Each universe is summarised from its runs' records (experiments.studies.
multiverse_records) under both definitions of steps per trial (DEFINITIONS: an analysis
choice beside the readings, computed from the same runs), and each claim of steps per
trial (by_definition) is judged under both: a specification each, the definition a ±1
column beside the factors' (crossed with the design, which keeps its resolution).

A factor's main effect on a claim is estimated by least squares on the design's ±1
columns (main effects and, where the universes run allow it, every two-factor
interaction: at resolution V none is aliased with another), over the universes of the
design that are complete; for a ratio or a shrink on the log scale (shown as the
statistic's ratio, alternative over plain), else on the statistic's own scale.
"""
import csv
import dataclasses
import io
import math
import warnings

import numpy as np

from experiments import paper
from experiments.outputs import report, verdicts
from experiments.running import aggregate
from experiments.running import execution
from experiments.studies import design
from tasks.robots import DRIVES
from tasks.robots import PAPER_ROBOTS, ROBOTS

BOOTSTRAP = 2000
SEED = 20240551


@dataclasses.dataclass(frozen=True)
class Claim:
    """A claim of Section 3.6: its number, robot, what, the paper's value, its bar, and
    its kind ("ratio", "shrink", "share", "min")."""
    key: str
    robot: str
    what: str
    paper: float
    bar: float
    kind: str

    @property
    def log(self):
        return self.kind in ("ratio", "shrink")

    def label(self):
        return f"{self.key}: {self.robot}: {self.what}"


def _claims():
    out, number = [], 1
    for robot in ("two_wheel", "floating"):
        ref = {c: paper.RESULTS[(robot, c)] for c in paper.CONDITIONS}
        for key, what in (("first_trial_steps", "avoidance cuts first-trial steps"),
                          ("steps_per_trial", "avoidance cuts steps per trial")):
            out.append(Claim(f"C{number}", robot, what, ref["random"][key]["mean"]
                             / ref["avoidance"][key]["mean"], 1.0, "ratio"))
            number += 1
        for c in paper.CONDITIONS:
            out.append(Claim(f"C{number}", robot, f"{c}: learning shrinks trials",
                             ref[c]["shrink"], 1.0, "shrink"))
            number += 1
        if robot == "two_wheel":
            goals = paper.TWO_WHEEL_GOALS
            out.append(Claim(f"C{number}", robot, "random: most runs reach fewer than 30 goals",
                             goals["random_below_30"] / paper.SEEDS, 0.5, "share"))
            out.append(Claim(f"C{number + 1}", robot, "avoidance: every run reaches at least "
                             f"{goals['avoidance_min']} goals", goals["avoidance_min"],
                             goals["avoidance_min"], "min"))
            number += 2
    return tuple(out)


#: The ten claims, C1-C10.
CLAIMS = _claims()

#: The analysis choice beside the readings: a run's steps per trial (Section 3.6: "The
#: average number of steps per trial within 30,000 steps of learning"), computed from
#: the same runs both ways: the mean of its completed trials (execution.metrics, what
#: `ebrl report` prints: the plain one), or its budget over its goals. 6-25% apart at
#: 2-8 goals (the unfinished last trial counts in the second).
DEFINITIONS = ("mean", "budget")
#: The choice's key beside the factors' (tables, the effects, the curves).
CHOICE = "steps_per_trial"


def by_definition(claim):
    """Whether a claim's statistic is of steps per trial (the ratio of steps per trial
    and the shrinks), so that the definition can change it."""
    return claim.kind == "shrink" or (claim.kind == "ratio" and "per trial" in claim.what)


def run_of(record, definition):
    """A record (experiments.studies.multiverse_records) as the run the summary takes
    (aggregate.summarize: its metrics, its steps, its memory decisions), its steps per
    trial by the definition."""
    trials = record["trials"]
    metrics = execution.metrics(np.cumsum(np.asarray(trials, dtype=np.int64)))
    if definition == "budget":
        metrics["steps_per_trial"] = record["steps"] / len(trials) if trials else None
    return {"metrics": metrics, "memory_decisions": record["memory_decisions"],
            "seconds": record["seconds"],
            "parameters": {"steps": record["steps"], "drive": ROBOTS[record["robot"]].drive,
                           "learner": "ebrl"}}
#: The twelve figures: (robot, condition, figure).
FIGURES = tuple((r, c, f) for r in ("two_wheel", "floating") for c in paper.CONDITIONS
                for f in ("first_trial_steps", "steps_per_trial", "shrink"))


def wilson(k, n, z=1.959963984540054):
    """Wilson's 95% interval of a share k / n ([0, 1] for n = 0)."""
    if n == 0:
        return [0.0, 1.0]
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return [max(0.0, centre - half), min(1.0, centre + half)]


def _per_seed(runs, robot, condition, metric):
    seeds = sorted(s for r, c, s in runs if (r, c) == (robot, condition))
    return seeds, np.array([np.nan if (v := runs[(robot, condition, s)]["metrics"][metric])
                            is None else v for s in seeds], dtype=np.float64)


def _paired_ratio(runs, robot, metric, rng):
    """(random mean / avoidance mean, its 95% interval resampling seeds) or (None, None)."""
    seeds, a = _per_seed(runs, robot, "random", metric)
    seeds_b, b = _per_seed(runs, robot, "avoidance", metric)
    if seeds != seeds_b or np.all(np.isnan(a)) or np.all(np.isnan(b)):
        return None, None
    value = float(np.nanmean(a) / np.nanmean(b))
    idx = rng.integers(0, len(a), size=(BOOTSTRAP, len(a)))
    with warnings.catch_warnings(), np.errstate(invalid="ignore", divide="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)  # a resample with no goal reached
        ratios = np.nanmean(a[idx], axis=1) / np.nanmean(b[idx], axis=1)
    ratios = ratios[np.isfinite(ratios)]
    ci = [float(x) for x in np.percentile(ratios, [2.5, 97.5])] if len(ratios) else None
    return value, ci


def claim_values(runs, summary):
    """{claim key: {"value", "ci", "holds"}} of one universe (value None where it cannot be
    computed or judged; C5 and C6 only at the paper's two-wheel budget)."""
    rng = np.random.default_rng(SEED)
    groups = {(g["robot"], g["condition"]): g for g in summary["groups"]}
    out = {}
    for c in CLAIMS:
        value, ci, holds = None, None, None
        if c.kind == "ratio":
            metric = "first_trial_steps" if "first" in c.what else "steps_per_trial"
            value, ci = _paired_ratio(runs, c.robot, metric, rng)
            p = verdicts.cut_p(groups[(c.robot, "random")], groups[(c.robot, "avoidance")],
                               metric)
            holds = None if value is None else _rejects(p)
        elif c.kind == "shrink":
            g = groups[(c.robot, c.what.split(":")[0])]
            value, ci = g["shrink"], g["shrink_ci95"]
            holds = None if value is None else _rejects(verdicts.shrinks_p(g))
        else:
            cond = "random" if c.kind == "share" else "avoidance"
            g = groups[(c.robot, cond)]
            if g["steps"] == DRIVES[c.robot].budget:
                _, goals = _per_seed(runs, c.robot, cond, "goals")
                if c.kind == "share":
                    k = int(np.sum(goals < 30))
                    value, ci = k / len(goals), wilson(k, len(goals))
                    holds = _rejects(verdicts.most_p(k, len(goals)))
                else:
                    idx = rng.integers(0, len(goals), size=(BOOTSTRAP, len(goals)))
                    value = float(goals.min())
                    ci = [float(x) for x in np.percentile(goals[idx].min(axis=1), [2.5, 97.5])]
                    holds = not _rejects(verdicts.rank_below(int(np.sum(goals < c.bar)),
                                                             len(goals)))
        out[c.key] = {"value": value, "ci": ci, "holds": holds}
    return out


def _rejects(p):
    """Whether a claim's test rejects at verdicts.ALPHA (a test that cannot be made does not)."""
    return p is not None and p < verdicts.ALPHA


def figure_values(summary):
    """{(robot, condition, figure): (value, ci)} of the twelve figures."""
    out = {}
    for g in summary["groups"]:
        for f in ("first_trial_steps", "steps_per_trial"):
            out[(g["robot"], g["condition"], f)] = (g[f]["mean"], g[f]["ci95"])
        out[(g["robot"], g["condition"], "shrink")] = (g["shrink"], g["shrink_ci95"])
    return out


def universe_record(runs, definition=None):
    """A complete universe's summary, figures and claims (None for an incomplete one);
    given a definition, runs are records (run_of)."""
    if runs is None:
        return None
    if definition is not None:
        runs = {k: run_of(r, definition) for k, r in runs.items()}
    summary = aggregate.summarize(runs)
    return {"summary": summary, "figures": figure_values(summary),
            "claims": claim_values(runs, summary),
            "seconds": float(sum(r.get("seconds", 0.0) for r in runs.values()))}


def agrees_with_report(record):
    """Whether a universe's verdicts are `ebrl report`'s (report.claims, in its order)."""
    theirs = [ok for _, _, ok in report.claims(record["summary"])]
    ours = [record["claims"][c.key]["holds"] for c in CLAIMS
            if record["claims"][c.key]["holds"] is not None]
    return [bool(x) for x in theirs] == [bool(x) for x in ours]


# -- the table ---------------------------------------------------------------------
def _fmt(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return f"{v:.10g}"
    return str(v)


def _code_text(universe, k):
    codes = {r: c[k] for r, c in universe.codes.items()}
    if len(set(codes.values())) == 1:
        return f"{next(iter(codes.values())):+d}"
    return ";".join(f"{r}:{c:+d}" for r, c in codes.items())


def table(factor_list, universes, records):
    """multiverse.csv's text: one row per universe and definition of steps per trial
    (records: {(universe name, definition): universe_record}): its name, design row,
    marks, the definition, each factor's code, each robot's readings, the twelve figures
    and the ten claims with their intervals ("" where not computed; complete 0 for a
    universe with runs missing)."""
    names = {r: sorted({n for u in universes for n in u.readings(r)}) for r in PAPER_ROBOTS}
    head = ["universe", "row", "marks", CHOICE, "complete"] + [f.key for f in factor_list]
    head += [f"{r}.{n}" for r in PAPER_ROBOTS for n in names[r]]
    for r, c, f in FIGURES:
        head += [f"{r}.{c}.{f}", f"{r}.{c}.{f}.lo", f"{r}.{c}.{f}.hi"]
    for c in CLAIMS:
        head += [c.key, f"{c.key}.lo", f"{c.key}.hi", f"{c.key}.holds"]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(head)
    for u in universes:
        for definition in DEFINITIONS:
            rec = records.get((u.name, definition))
            row = [u.name, "" if u.row is None else u.row + 1, " ".join(u.marks), definition,
                   int(rec is not None)]
            row += [_code_text(u, k) for k in range(len(factor_list))]
            for r in PAPER_ROBOTS:
                mine = u.readings(r)
                row += [_fmt(mine.get(n)) for n in names[r]]
            for key in FIGURES:
                value, ci = rec["figures"].get(key, (None, None)) if rec else (None, None)
                row += [_fmt(value), _fmt(ci[0] if ci else None), _fmt(ci[1] if ci else None)]
            for c in CLAIMS:
                x = rec["claims"][c.key] if rec else {"value": None, "ci": None, "holds": None}
                ci = x["ci"]
                row += [_fmt(x["value"]), _fmt(ci[0] if ci else None),
                        _fmt(ci[1] if ci else None), "" if x["holds"] is None else int(x["holds"])]
            w.writerow(row)
    return buf.getvalue()


# -- across the universes ------------------------------------------------------------
def transform(claim, values):
    v = np.asarray(values, dtype=np.float64)
    return np.log(v) if claim.log else v


def fit_effects(codes, y):
    """Least squares of y on the ±1 codes (rows x k): {"mains": [k effects], "pairs":
    {(i, j): effect}} (an effect is twice the coefficient: alternative less plain), pairs
    only where the universes identify every two-factor interaction, mains only where they
    identify the main effects; None where not even those."""
    codes, y = np.asarray(codes, dtype=np.float64), np.asarray(y, dtype=np.float64)
    if len(y) == 0:
        return None
    for interactions in (True, False):
        x, names = design.model_matrix(codes, interactions)
        if np.linalg.matrix_rank(x) == x.shape[1]:
            coef = np.linalg.lstsq(x, y, rcond=None)[0]
            effects = {n: 2 * c for n, c in zip(names, coef) if n}
            return {"mains": [effects[(i,)] for i in range(codes.shape[1])],
                    "pairs": {n: e for n, e in effects.items() if len(n) == 2}}
    return None


def analysis_json(analysis, names):
    """analyse's answer as JSON takes it: each claim's two-factor effects keyed "a x b" by
    the keys' names (names: keys()'s), not by their (i, j) indices."""
    out = {}
    for claim, entry in analysis.items():
        effects = entry.get("effects")
        if effects is not None:
            effects = dict(effects, pairs={f"{names[i]} x {names[j]}": e
                                           for (i, j), e in effects["pairs"].items()})
        out[claim] = dict(entry, effects=effects)
    return out


def keys(factor_list, chosen):
    """The keys the analysis reports on: the chosen factors', then the definition of steps
    per trial (CHOICE)."""
    return [f.key for f in factor_list if f in chosen] + [CHOICE]


def specifications(claim, universes, records):
    """The claim's specifications among the design's complete universes: (universe,
    definition) pairs, both definitions for a claim of steps per trial (by_definition),
    the plain one alone for the others (which the definition does not change)."""
    definitions = DEFINITIONS if by_definition(claim) else DEFINITIONS[:1]
    return [(u, d) for u in universes for d in definitions
            if u.row is not None and records.get((u.name, d))]


def analyse(factor_list, chosen, universes, records):
    """Per claim: the specifications judged, the share holding with its interval, the
    chosen factors' and the definition's effects on its statistic (the definition's None
    where it does not act), and the share holding at each one's two levels ({claim key:
    ...}; the effects and the shares in keys()' order)."""
    index = [i for i, f in enumerate(factor_list) if f in chosen]
    out = {}
    for c in CLAIMS:
        acts = by_definition(c)

        def code(u, d):
            return [u.codes[c.robot][i] for i in index] + ([1 if d == DEFINITIONS[1] else -1]
                                                           if acts else [])

        def verdict(u, d):
            return records[(u.name, d)]["claims"][c.key]

        judged = [(u, d) for u, d in specifications(c, universes, records)
                  if verdict(u, d)["holds"] is not None]
        k = sum(verdict(u, d)["holds"] for u, d in judged)
        valued = [(u, d) for u, d in judged if (verdict(u, d)["value"] or 0) > 0 or not c.log]
        effects = fit_effects([code(u, d) for u, d in valued],
                              transform(c, [verdict(u, d)["value"] for u, d in valued]))
        if effects is not None and not acts:
            effects["mains"].append(None)
        by_level = []  # each key: the share holding at its plain, its alternative level
        for j in range(len(index) + 1):
            shares = []
            for level in (-1, 1):
                at = [verdict(u, d)["holds"] for u, d in judged
                      if j < len(code(u, d)) and code(u, d)[j] == level]
                shares.append(sum(at) / len(at) if at else None)
            by_level.append(shares)
        out[c.key] = {
            "judged": len(judged), "holds": int(k), "share": k / len(judged) if judged else None,
            "share_ci": wilson(k, len(judged)) if judged else None,
            "effects": effects, "holds_by_level": by_level,
        }
    return out


def effect_text(claim, effect):
    """An effect as read: x1.23 (a log-scale statistic's ratio), else +0.12 (share) or +3.0
    goals; "-" for none."""
    if effect is None:
        return "-"
    if claim.log:
        return f"x{math.exp(effect):.2f}"
    return f"{effect:+.2f}" if claim.kind == "share" else f"{effect:+.1f}"
