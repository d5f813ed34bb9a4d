"""`ebrl fit`: a search over the readings the paper leaves open, against its Section 3.6 table.

The space (SPACE) is readings of the registry (tasks.readings: their values and
descriptions), switches and the continuous readings the paper leaves open, the latter
within bounds chosen here; Table 1, the room, the rangefinders (range 14, noise sd
12.75, 7 and 8 of them) and the actions' maxima stay fixed. A reading
of the agent (ebrl.Config) is shared by both robots; a reading of the floating drive
applies to the floating robot only, so the two-wheel runs of two trials that differ only
there are the same runs (made once; experiments.studies.study).

The objective (objective()) is the distance of a trial's Section 3.6 figures to the
paper's, one term per figure, plus a penalty per failing claim (report.claims):

    mean over figures of (log(ours / paper) / scale)^2  +  CLAIM_PENALTY x failing claims

with scale = log(1 + sd / mean) of the paper's own figure (the spread of one seed's
figure, as the paper reports it) for first-trial steps and steps per trial, and
SHRINK_SCALE for the shrinks (the paper gives no spread). A figure the trial cannot
compute (no run reached the goal) costs MISSING_TERM.

That is the "table" stage (STAGES). The "first-trial" stage (stage 1 of the fit:
`ebrl fit --stage first-trial --robot DRIVE`) fits one drive's physics and fallback
readings to the paper's first-trial distributions on first-trial runs, on the same
study runner: experiments/studies/first_trials.py.
"""
import dataclasses
import math
import pathlib

from experiments import paper
from experiments.outputs import plots, report
from experiments.running import aggregate, results, schema
from experiments.running import runner, settings
from experiments.studies import study
from tasks import readings as registry
from tasks.robots import resolve

STUDY_NAME = "fit"
#: The robots of a trial: the floating robot searched, the two-wheel robot its constraint.
ROBOTS = ("two_wheel", "floating")
SHRINK_SCALE = 0.3
MISSING_TERM = 25.0
CLAIM_PENALTY = 1.0
FIGURES = ("first_trial_steps", "steps_per_trial", "shrink")
#: `ebrl fit --stage`: this module's objective, or stage 1's (experiments.studies.first_trials).
STAGES = ("table", "first-trial")


@dataclasses.dataclass(frozen=True)
class Param:
    name: str       # a reading of the registry (tasks.readings)
    kind: str       # "choice" or "float"
    values: tuple   # the choices, or (low, high)
    scope: str      # "both" (an agent reading of every robot) or "floating" (the floating robot's)
    what: str

    def distribution(self):
        import optuna
        if self.kind == "choice":
            return optuna.distributions.CategoricalDistribution(self.values)
        return optuna.distributions.FloatDistribution(*self.values)


def param(name, bounds=None, scope=None):
    """A reading of the registry as a dimension of a space: a switch's every value, or a
    number searched within bounds (low, high), the study's own choice. The scope, unless
    given: "both" for an agent reading that acts on every robot; the floating robot's
    alone for the rest (the task's readings, and eq9_dead_zone's eq 9-10 fallback): the
    floating robot is searched, the two-wheel robot is the constraint."""
    reading = registry.READING_BY_NAME[name]
    if scope is None:
        scope = "both" if reading.scope == "agent" and not (reading.drives or reading.behaviours) \
            else "floating"
    if reading.switch:
        return Param(name, "choice", reading.values, scope, reading.what)
    return Param(name, "float", bounds, scope, reading.what)


#: The search space. The ranges: policy_threshold up to 0.5 (0.3-0.4 moved the floating
#: learners most in a first trial, DEVELOPERS.md); a radius from the two-wheel body's
#: smallest credible size to the ablation's largest; action noise up to 50% (the paper
#: gives the floating robot none); velocity noise up to 0.2 units/step (one full thrust).
SPACE = (
    param("episode"),
    param("recall_at_trial_end"),
    param("eq7_scope"),
    param("forgetting"),
    param("random_in_avoidance"),
    param("eq9_dead_zone"),
    param("policy_threshold", (0.0, 0.5)),
    param("initial_reliability", (0.0, 1.0)),
    param("bump"),
    param("thrust"),
    param("action_noise", (0.0, 0.5)),
    param("velocity_noise", (0.0, 0.2)),
    param("velocity_code"),
    param("wall_friction", (0.0, 1.5)),
    param("restitution", (0.0, 1.0)),
    param("radius", (1.0, 2.5)),
)
PARAMETER_BY_NAME = {p.name: p for p in SPACE}


def default(name, robot="floating"):
    """A robot's current value of a reading (its readings: tasks.robots.Robot,
    else the config's field; the file's radius 1.5 and friction 1 where that is None).
    The search's subject is the floating robot: its defaults are trial 0 and the text
    of a trial's readings; a setting shared by both robots is run as given on each."""
    value = settings.default(name, [resolve(robot)])
    return {"radius": 1.5, "wall_friction": 1.0}.get(name, value) if value is None else value


def overrides(params, robot):
    """A trial's settings for one robot, as sorted (name, value) pairs, defaults left out
    (so a setting equal to the defaults shares their runs)."""
    floating = resolve(robot).drive == "floating"
    chosen = {k: v for k, v in params.items()
              if (PARAMETER_BY_NAME[k].scope == "both" or floating) and v != default(k, robot)}
    return tuple(sorted(chosen.items()))


@dataclasses.dataclass
class Problem:
    """`ebrl fit` for experiments.studies.study: the space, a trial's runs, its score."""
    names: tuple = tuple(PARAMETER_BY_NAME)
    rungs: tuple = ((0, 1), tuple(range(6)))
    steps: int = None  # None: each robot's budget
    room: str = None  # models.rooms' room; None: the paper's

    def distributions(self):
        return {n: PARAMETER_BY_NAME[n].distribution() for n in self.names}

    def specs(self, params, seeds):
        out = []
        for robot in ROBOTS:
            out += runner.plan((robot,), paper.CONDITIONS, seeds, self.steps,
                               overrides(params, robot), room=self.room)
        return out

    def score(self, params, runs):
        summary = aggregate.summarize(runs)
        value, terms, claims = objective(summary)
        return value, {"figures": figures(summary), "terms": terms,
                       "claims": [[c, o, bool(h)] for c, o, h in claims]}


def figures(summary):
    """{'robot/condition/figure': our mean} of a summary's groups."""
    out = {}
    for g in summary["groups"]:
        for f in FIGURES:
            value = g[f] if f == "shrink" else g[f]["mean"]
            out[f"{g['robot']}/{g['condition']}/{f}"] = value
    return out


def scale(drive, condition, figure):
    """The scale of a figure's log ratio (module docstring)."""
    ref = paper.RESULTS[(drive, condition)][figure]
    if figure == "shrink":
        return SHRINK_SCALE
    return math.log1p(ref["sd"] / ref["mean"])


def paper_value(drive, condition, figure):
    ref = paper.RESULTS[(drive, condition)][figure]
    return ref if figure == "shrink" else ref["mean"]


def objective(summary):
    """(value, {figure: term}, claims) of a summary (module docstring); eq-free, so
    tests compute it by hand on made-up figures."""
    terms = {}
    for g in summary["groups"]:
        for f in FIGURES:
            ours = g[f] if f == "shrink" else g[f]["mean"]
            key = f"{g['robot']}/{g['condition']}/{f}"
            if not ours:
                terms[key] = MISSING_TERM
                continue
            ratio = math.log(ours / paper_value(g["drive"], g["condition"], f))
            terms[key] = (ratio / scale(g["drive"], g["condition"], f)) ** 2
    claims = report.claims(summary)
    failing = sum(not held for _, _, held in claims)
    value = sum(terms.values()) / max(len(terms), 1) + CLAIM_PENALTY * failing
    return value, terms, claims


def setting_text(params):
    """A trial's readings that differ from the defaults, as 'name=value' text."""
    changed = [(k, v) for k, v in sorted(params.items()) if v != default(k)]
    return ", ".join(f"{k}={_short(v)}" for k, v in changed) or "the defaults"


def _short(v):
    return f"{v:.3g}" if isinstance(v, float) else str(v)


# -- validation ------------------------------------------------------------------
def validate_best(problem, trial_params, out, seeds, workers=None, backend="local",
                  progress=True):
    """Runs a trial's settings and the defaults on seeds (full budgets, never used by
    the search); writes and returns validation.json's content."""
    where = lambda spec: study.run_folder(out, spec)  # noqa: E731
    rows = {}
    plans = {"best": problem.specs(trial_params, seeds), "defaults": problem.specs({}, seeds)}
    # Seed by seed (the longest runs of a seed first), so that an interrupted validation
    # holds whole seeds of both settings.
    all_specs = sorted({s for v in plans.values() for s in v},
                       key=lambda s: (s.seed, -s.steps, s.robot, s.condition, s.overrides))
    ran = runner.run(all_specs, where, workers=workers, backend=backend, progress=progress)
    if ran.failed:
        return None, ran.failed
    for name, specs in plans.items():
        runs = {}
        for s in specs:
            runs.update(results.load_runs(where(s), [s]))
        summary = aggregate.summarize(runs)
        value, terms, claims = objective(summary)
        rows[name] = {"value": value, "groups": summary["groups"],
                      "claims": [[c, o, bool(h)] for c, o, h in claims]}
    data = {"seeds": list(seeds), "params": trial_params, "steps": problem.steps, "rows": rows}
    results.atomic_write(pathlib.Path(out) / "validation.json", results.dumps(data))
    return data, []


# -- the report -------------------------------------------------------------------
def importances(s, names):
    """{target: {reading: importance}} over the complete trials, for the objective and
    for each figure's term (its squared scaled log ratio to the paper's): PED-ANOVA
    (Optuna's PedAnovaImportanceEvaluator: how much each reading's distribution in the
    best tenth of the trials differs from its distribution in all of them; deterministic,
    no other package). {} with fewer than 10 complete trials."""
    import optuna
    done = s.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
    if len(done) < 10:
        return {}
    evaluator = optuna.importance.PedAnovaImportanceEvaluator
    out = {"objective": optuna.importance.get_param_importances(
        s, evaluator=evaluator(), params=list(names), normalize=True)}
    for key in done[0].user_attrs["rungs"][0]["terms"]:
        out[key] = optuna.importance.get_param_importances(
            s, evaluator=evaluator(), params=list(names), normalize=True,
            target=lambda t, key=key: t.user_attrs["rungs"][0]["terms"][key])
    return out


def objective_figure(s, path):
    """The objective of every complete trial over trial numbers, and the best so far."""
    import optuna
    plt = plots.pyplot()
    done = s.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
    xs = [t.number for t in done]
    ys = [t.value for t in done]
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.scatter(xs, ys, s=10, alpha=0.6, label="trial (first rung's seeds)")
    best, line = math.inf, []
    for y in ys:
        best = min(best, y)
        line.append(best)
    ax.step(xs, line, where="post", color="C3", label="best so far")
    plots.log_y(ax)
    ax.set_xlabel("trial")
    ax.set_ylabel("objective (lower is closer to the paper)")
    ax.legend(loc="upper right", fontsize=8)
    return plots.save(fig, path, dpi=110)


def _figure_rows(groups_by_name):
    """Markdown rows: each figure of the paper beside each named summary's groups."""
    names = list(groups_by_name)
    lines = ["| robot | condition | figure | paper | " + " | ".join(names) + " |",
             "|---|---|---|---:|" + "---:|" * len(names)]
    first = groups_by_name[names[0]]
    for g in first:
        for f in FIGURES:
            cells = []
            for n in names:
                h = next((x for x in groups_by_name[n]
                          if (x["robot"], x["condition"]) == (g["robot"], g["condition"])), None)
                if h is None:
                    cells.append("-")
                elif f == "shrink":
                    cells.append(report.fmt(h["shrink"], 2))
                else:
                    cells.append(f"{report.fmt(h[f]['mean'])} {report.interval(h[f]['ci95'])}")
            pv = paper_value(g["drive"], g["condition"], f)
            lines.append(f"| {g['robot']} | {g['condition']} | {f.replace('_', ' ')} | "
                         f"{report.fmt(pv, 2 if f == 'shrink' else 0)} | " + " | ".join(cells) + " |")
    return lines


def tables(s, out, names):
    """The markdown of FIT.md's body (also RESULTS.md's Search block)."""
    import optuna
    trials = s.get_trials(deepcopy=False)
    done = [t for t in trials if t.state == optuna.trial.TrialState.COMPLETE]
    failed = [t for t in trials if t.state == optuna.trial.TrialState.FAIL]
    lines = [f"{len(done)} complete trials ({len(failed)} failed or interrupted) in study "
             f"`{s.study_name}`. Each ran on seeds "
             + ", ".join(f"{r[0]}-{r[-1]}" for r in _rungs(done)) + " (the later rungs only "
             "for promoted trials); the best are ranked on their largest rung.", "",
             "| trial | objective | seeds | claims held | readings (changed from the defaults) |",
             "|---:|---:|---:|---:|---|"]
    for t in study.best_trials(s, 8):
        d = study.deepest(t)
        held = sum(c[2] for c in d["claims"])
        lines.append(f"| {t.number} | {d['value']:.3g} | {len(d['seeds'])} | "
                     f"{held}/{len(d['claims'])} | {setting_text(t.params)} |")
    imp = importances(s, names)
    if imp:
        targets = list(imp)
        lines += ["", "Importance of each reading (PED-ANOVA over the complete trials, "
                  "normalised per column; the objective, then each figure's term, the "
                  "distance of that figure to the paper's):", "",
                  "| reading | " + " | ".join(t.replace("/", " ").replace("_", " ") for t in targets) + " |",
                  "|---|" + "---:|" * len(targets)]
        from tasks.robots import resolve

        def cell(target, n):  # a floating reading cannot move a two-wheel figure
            if target != "objective" and PARAMETER_BY_NAME[n].scope == "floating" and \
                    resolve(target.split("/")[0]).drive != "floating":
                return "-"
            return f"{imp[target].get(n, 0):.2f}"
        for n in names:
            lines.append(f"| {n} | " + " | ".join(cell(t, n) for t in targets) + " |")
        lines += ["", "A figure that no reading moves (the two-wheel random walk's first trial: "
                  "no learner acts before its first reward) shows equal importances; a "
                  "reading's importance for a figure it cannot move is shown as '-'."]
    vpath = pathlib.Path(out) / "validation.json"
    v = results.read_bookkeeping(vpath, schema.check_validation(("value", "groups", "claims")))
    if v is not None:  # a damaged one is set aside, named, and made by the next --validate
        rows = v["rows"]
        seeds = v["seeds"]
        budget = "the paper's budgets" if v.get("steps") is None else f"{v['steps']:,} steps a run"
        lines += ["", f"Held-out validation on seeds {seeds[0]}-{seeds[-1]} ({len(seeds)} seeds "
                  f"the search never used), {budget}: the best trial's readings ("
                  f"{setting_text(v['params'])}) beside the defaults. 95% intervals are "
                  "percentile bootstraps over seeds.", ""]
        lines += _figure_rows({"best": rows["best"]["groups"], "defaults": rows["defaults"]["groups"]})
        lines += ["", "| claim | best | defaults |", "|---|---|---|"]
        def verdicts(row):
            return {c: f"{o} ({'holds' if h else 'fails'})" for c, o, h in row["claims"]}
        best_v, default_v = verdicts(rows["best"]), verdicts(rows["defaults"])
        for c in dict.fromkeys(list(best_v) + list(default_v)):
            lines.append(f"| {c} | {best_v.get(c, '-')} | {default_v.get(c, '-')} |")
        lines.append("")
        lines.append(f"Objective: best {rows['best']['value']:.3g}, defaults "
                     f"{rows['defaults']['value']:.3g}; claims held: best "
                     f"{sum(c[2] for c in rows['best']['claims'])}/{len(rows['best']['claims'])}, "
                     f"defaults {sum(c[2] for c in rows['defaults']['claims'])}/"
                     f"{len(rows['defaults']['claims'])}.")
    return "\n".join(lines)


def _rungs(done):
    seen = []
    for t in done:
        for r in t.user_attrs.get("rungs", []):
            if r["seeds"] not in seen:
                seen.append(r["seeds"])
    return sorted(seen, key=len) or [[0]]


def write(s, out, names):
    """FIT.md and fit_objective.png under out; returns FIT.md's path (a storage that
    fails meanwhile: study.StorageError)."""
    with study.storage_errors(s):
        return _write(s, out, names)


def _write(s, out, names):
    out = pathlib.Path(out)
    best = study.best_trials(s, 1)
    lines = ["# `ebrl fit`: the readings against Section 3.6", "",
             "Objective: the mean over the twelve Section 3.6 figures of (log(ours / paper) / "
             "scale)^2, scale = log(1 + sd / mean) of the paper's figure (the shrinks: "
             f"{SHRINK_SCALE}), plus {CLAIM_PENALTY:g} per failing claim "
             "(experiments/studies/fit.py). Lower is closer to the paper.", "",
             "The space: " + "; ".join(f"`{p.name}` ({p.what}; "
                                       + ("/".join(map(str, p.values)) if p.kind == "choice"
                                          else f"{p.values[0]}-{p.values[1]}")
                                       + ("" if p.scope == "both" else ", floating only") + ")"
                                       for p in SPACE if p.name in names) + ".", "",
             tables(s, out, names), ""]
    if best:
        d = study.deepest(best[0])
        lines += ["", f"Trial {best[0].number}'s figures on its {len(d['seeds'])} seeds:", "",
                  "| figure | paper | ours |", "|---|---:|---:|"]
        for key, v in d["figures"].items():
            robot, cond, f = key.split("/")
            from tasks.robots import resolve
            pv = paper_value(resolve(robot).drive, cond, f)
            lines.append(f"| {key} | {report.fmt(pv, 2 if f == 'shrink' else 0)} | "
                         f"{report.fmt(v, 2 if f == 'shrink' else 0)} |")
    if s.get_trials(deepcopy=False):
        objective_figure(s, out / "fit_objective.png")
        lines += ["", "![objective over trials](fit_objective.png)", ""]
    path = out / "FIT.md"
    results.atomic_write(path, "\n".join(lines))
    return path


FIT_BEGIN = "<!-- ebrl fit: generated, do not edit -->"
FIT_END = "<!-- ebrl fit: end -->"


def publish(s, out, names, results_md, figures_dir):
    """RESULTS.md's Search block, and the objective figure beside its other figures."""
    figures_dir = pathlib.Path(figures_dir)
    figures_dir.mkdir(parents=True, exist_ok=True)
    src = pathlib.Path(out) / "fit_objective.png"
    block = [FIT_BEGIN, "", tables(s, out, names), ""]
    if src.exists():
        report.copy(src, figures_dir / "fit_objective.png")
        rel = pathlib.Path(figures_dir).resolve().relative_to(pathlib.Path(results_md).resolve().parent)
        block += [f"![objective over trials]({rel / 'fit_objective.png'})", ""]
    report.replace_block(results_md, FIT_BEGIN, FIT_END, block + [FIT_END])
    return results_md
