"""`ebrl ablate`: how much each reading of the paper moves each claim.

Every reading with a credible alternative (docs/interpretation.md) is a field of the
agent's config (ebrl.Config) or the task's (tasks.TaskConfig), with its entry in the
readings' registry (tasks.readings: values, scope, description). The matrix changes one
reading at a time from the defaults (and, with --combo, several together), runs the
protocol for each cell in its own folder (resumable like `ebrl run`), and writes
ABLATION.md and ablation.json: the Section 3.6 figures of every cell with 95% intervals,
and which of the paper's ten claims hold. The defaults' cell is taken from a baseline
run folder (`--baseline results`) for the same seeds, or run here.
"""
import dataclasses
import json
import pathlib

from experiments import paper
from experiments.outputs import report
from experiments.running import aggregate, results, runner
from experiments.running import settings
from tasks import readings as registry
from tasks.robots import PAPER_ROBOTS, ROBOTS, resolve


@dataclasses.dataclass(frozen=True)
class Ablated:
    """A reading of the registry (tasks.readings) and the values the ablation tries."""
    reading: object        # tasks.readings' record: its scope and description
    values: tuple          # the config field's default first (a robot's may be another)

    @property
    def name(self):
        return self.reading.name

    @property
    def what(self):
        return self.reading.what


def _ablated(name, values=None):
    """A switch tries every value of its registry entry; a number the values given here."""
    reading = registry.READING_BY_NAME[name]
    return Ablated(reading, reading.values if reading.switch else values)


#: The readings ablated, in the matrix's order. The numbers tried for the numeric ones
#: are the ablation's own; everything else comes from the registry.
READINGS = (
    _ablated("bump"),
    _ablated("eq9_dead_zone"),
    _ablated("random_in_avoidance"),
    _ablated("random_demand"),
    _ablated("blocked_move"),
    _ablated("leftover_turn"),
    _ablated("episode"),
    _ablated("recall_at_trial_end"),
    _ablated("initial_reliability", (1.0, 0.5, 0.0)),
    _ablated("eq7_scope"),
    _ablated("forgetting"),
    _ablated("radius", (None, 1.0, 2.5)),
    _ablated("policy_threshold", (0.0, 0.05, 0.2)),
    # the untried Section 2 readings (docs/interpretation.md, "The agent")
    _ablated("eq7_signal"),
    _ablated("eq7_walk"),
    _ablated("utility_cutoff", (1e-4, 0.0)),
    _ablated("forgetting_link"),
    _ablated("recall_candidates"),
    _ablated("exploration"),
)
ABLATED_BY_NAME = {r.name: r for r in READINGS}
DEFAULT = "default"


def cell_name(changes):
    """'bump=slide+episode=continuing' for [(name, value), ...]; 'default' for none."""
    return "+".join(f"{k}={v}" for k, v in changes) or DEFAULT


def cells(readings, combos):
    """[(name, changes)] of the matrix: each value of each reading alone (a robot whose
    default it is skips it: plan), then each combination."""
    out = [(cell_name([(r.name, v)]), ((r.name, v),)) for r in readings for v in r.values]
    return out + [(cell_name(c), tuple(c)) for c in combos]


def _is_default(changes, robot):
    """Whether every change is already the robot's default (its readings, else the
    config's field): such a cell is the default's cell for that robot."""
    entry = resolve(robot)
    return all(settings.default(name, [entry]) == value for name, value in changes)


def _concerns(changes, robot, condition):
    """Whether every ablated reading a cell changes acts on this robot (its drive, its
    fallback behaviour) and this condition (the registry's scope, tasks.readings.applies)."""
    entry = resolve(robot)
    return all(registry.applies(ABLATED_BY_NAME[name].reading, entry, condition)
               for name, _ in changes if name in ABLATED_BY_NAME)


def plan(robots, seeds, steps, readings, combos, room=None):
    """{folder name: specs} for every cell, each cell only where its readings apply; in
    room (execution.RunSpec.room)."""
    out = {}
    for name, changes in cells(readings, combos):
        specs = [s for s in runner.plan(robots, paper.CONDITIONS, seeds, steps, changes, room=room)
                 if _concerns(changes, s.robot, s.condition) and not _is_default(changes, s.robot)]
        if specs:
            out[name] = specs
    return out


def run(out, robots, seeds, steps, readings, combos, baseline=None, workers=None,
        progress=True, room=None):
    """Runs the matrix under out (the defaults' cell from baseline when given); returns
    {cell: runs} of the complete runs and the failed (name, error) pairs."""
    out = pathlib.Path(out)
    plans = plan(robots, seeds, steps, readings, combos, room)
    default_specs = runner.plan(robots, paper.CONDITIONS, seeds, steps, room=room)
    if baseline is not None:
        if runner.pending(baseline, default_specs):
            raise results.ResultsError(f"{baseline} lacks some of the default runs for these "
                                       "robots, seeds and budgets; run them there first")
    else:
        plans = {DEFAULT: default_specs, **plans}
    for name, specs in plans.items():  # refuse damaged or mismatched folders first
        runner.pending(out / name, specs)
    # Every cell's runs on one worker pool, cell after cell: a pool's start costs about
    # as much as a short cell's runs. A spec that two cells share (their readings alike
    # for a robot) waits for a second pool, so each run is written to its own cell.
    batches = []
    for name, specs in plans.items():
        for spec in specs:
            batch = next((b for b in batches if spec not in b), None)
            if batch is None:
                batches.append(batch := {})
            batch[spec] = name
    failed = []
    for batch in batches:
        ran = runner.run(list(batch), lambda spec, cell=batch: out / cell[spec],
                         workers=workers, progress=progress)
        failed += [(f"{batch[s]}/{s.name}", e) for s, e in ran.failed]
    cell_runs = {DEFAULT: results.load_runs(baseline if baseline is not None else out / DEFAULT,
                                            default_specs)}
    for name, specs in plans.items():
        if name != DEFAULT:
            done = [s for s in specs if results.existing(out / name, s) == "done"]
            if done:
                cell_runs[name] = results.load_runs(out / name, done)
    return cell_runs, failed


def summarize(cell_runs):
    """ablation.json's content: every cell's summary and its claims."""
    data = {"cells": {}}
    for name, runs in cell_runs.items():
        s = aggregate.summarize(runs)
        if name != DEFAULT:  # a cell runs only what its readings touch: fill in the rest
            have = {(g["robot"], g["condition"]) for g in s["groups"]}
            s["groups"] += [g for g in aggregate.summarize(cell_runs[DEFAULT])["groups"]
                            if (g["robot"], g["condition"]) not in have]
            s["groups"].sort(key=lambda g: (aggregate.robot_order(g["robot"]),
                                            paper.CONDITIONS.index(g["condition"])))
        claims = [{"claim": c, "ours": o, "holds": bool(h)} for c, o, h in report.claims(s)]
        data["cells"][name] = {"groups": s["groups"], "claims": claims,
                               "claims_held": sum(c["holds"] for c in claims)}
    return data


def _row(cell, g):
    f, p = g["first_trial_steps"], g["steps_per_trial"]
    return (f"| {cell} | {g['robot']} | {g['condition']} | {g['seeds']} "
            f"| {report.fmt(f['mean'])} {report.interval(f['ci95'])} "
            f"| {report.fmt(p['mean'])} {report.interval(p['ci95'])} | {report.fmt(g['shrink'], 2)} "
            f"| {g['goals']['min']} / {report.fmt(g['goals']['median'], 1)} |")


def _defaults(name):
    """A reading's default, per paper robot where they differ: 'keep (floating), zero'."""
    values = {r: settings.default(name, [ROBOTS[r]]) for r in PAPER_ROBOTS}
    if len(set(map(str, values.values()))) == 1:
        return next(iter(values.values()))
    return ", ".join(f"{v} ({r})" for r, v in values.items())


def tables(data):
    """The markdown of ABLATION.md's tables (also RESULTS.md's Ablation section)."""
    cells_ = data["cells"]
    default_groups = {(g["robot"], g["condition"]): g for g in cells_[DEFAULT]["groups"]}
    claim_names = list(dict.fromkeys(c["claim"] for cell in cells_.values()
                                     for c in cell["claims"]))
    lines = ["| cell | claims held | " + " | ".join(f"C{i + 1}" for i in range(len(claim_names))) + " |",
             "|---|---:|" + ":-:|" * len(claim_names)]
    for name, c in cells_.items():
        held = {x["claim"]: x["holds"] for x in c["claims"]}
        lines.append(f"| {name} | {c['claims_held']}/{len(c['claims'])} | "
                     + " | ".join({True: "yes", False: "no", None: "-"}[held.get(n)]
                                  for n in claim_names) + " |")
    lines += ["", "Claims: " + "; ".join(f"C{i + 1} {n}" for i, n in enumerate(claim_names)) + ".", "",
              "| cell | robot | condition | seeds | first-trial steps (95% CI) | steps per trial (95% CI) "
              "| shrink | goals min / median |", "|---|---|---|---:|---|---|---:|---|"]
    for name, c in cells_.items():
        for g in c["groups"]:
            same = name != DEFAULT and (g["robot"], g["condition"]) in default_groups and \
                g == default_groups[(g["robot"], g["condition"])]
            if not same:
                lines.append(_row(name, g))
    return "\n".join(lines)


ABLATION_BEGIN = "<!-- ebrl ablate: generated, do not edit -->"
ABLATION_END = "<!-- ebrl ablate: end -->"


def write(out, data, failed=()):
    """ablation.json and ABLATION.md under out; returns ABLATION.md's path."""
    out = pathlib.Path(out)
    results.atomic_write(out / "ablation.json", results.dumps(data))
    lines = ["# Ablation of the paper's unwritten details", "",
             "One reading changed at a time from each robot's defaults (its readings, "
             "docs/interpretation.md), then "
             "the combinations named by --combo. A cell runs only the robots and conditions "
             "its readings touch; its other rows are the default's. 95% intervals are "
             "percentile bootstraps over seeds.", "", "Readings:", ""]
    lines += [f"- `{r.name}`: {', '.join(map(str, r.values))} (default {_defaults(r.name)}): {r.what}"
              for r in READINGS]
    lines += ["", tables(data), ""]
    if failed:
        lines += ["## Failed runs (not averaged)", ""] + [f"- {n}: {e}" for n, e in failed] + [""]
    path = out / "ABLATION.md"
    results.atomic_write(path, "\n".join(lines))
    return path


def publish(out, results_md):
    """RESULTS.md's Ablation block, from out/ablation.json."""
    data = json.loads((pathlib.Path(out) / "ablation.json").read_text())
    report.replace_block(results_md, ABLATION_BEGIN, ABLATION_END,
                         [ABLATION_BEGIN, "", tables(data), "", ABLATION_END])
    return results_md
