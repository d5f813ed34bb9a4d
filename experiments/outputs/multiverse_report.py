"""`ebrl multiverse`'s report: MULTIVERSE.md (the draft of RESULTS.md's section "How much
the conclusions depend on the open details") and a specification curve per claim.

A specification curve (Simonsohn, Simmons and Nelson 2020) is one claim's statistic in
every universe, sorted, with its interval, the paper's value and the claim's bar, the
literal and the current protocols marked, and below it the grid of which factor is at
its alternative level in each universe.
"""
import dataclasses
import os
import pathlib
import re
import warnings

import numpy as np

from experiments import paper
from experiments.outputs import multiverse as mv
from experiments.outputs import plots, report
from experiments.running import results
from experiments.studies import multiverse as study
from tasks.protocols import PROTOCOL_VERSION
from tasks.robots import PAPER_ROBOTS

#: Machines of this many cores for the Ray estimate.
RAY_CORES = 16
#: The markers of the multiverse's block on a page (`ebrl multiverse --results`).
BLOCK = ("<!-- ebrl multiverse: generated, do not edit -->", "<!-- ebrl multiverse: end -->")


def _value(records, point, claim):
    u, d = point
    return records[(u.name, d)]["claims"][claim.key]


def spec_curve(claim, factor_list, chosen, universes, records, path):
    """The claim's specification curve as a PNG at path: every complete universe's
    statistic, under each definition of steps per trial for a claim of steps per trial
    (mv.by_definition); None when no universe has its statistic."""
    definitions = mv.DEFINITIONS if mv.by_definition(claim) else mv.DEFINITIONS[:1]
    pts = [(u, d) for u in universes for d in definitions if records.get((u.name, d))
           and _value(records, (u, d), claim)["value"] is not None
           and (_value(records, (u, d), claim)["value"] > 0 or not claim.log)]
    if not pts:
        return None
    pts.sort(key=lambda p: _value(records, p, claim)["value"])
    rows = [i for i, f in enumerate(factor_list)
            if f in chosen or any(u.codes[claim.robot][i] > 0 for u, _ in pts)]
    labels = [factor_list[i].key + (" (inert)" if study.levels(
        factor_list[i], claim.robot).source == "inert" else "") for i in rows]
    cells = [[u.codes[claim.robot][i] > 0 for u, _ in pts] for i in rows]
    if len(definitions) > 1:
        labels.append(f"{mv.CHOICE}: {mv.DEFINITIONS[1]}")
        cells.append([d == mv.DEFINITIONS[1] for _, d in pts])
    plt = plots.pyplot()
    n = len(pts)
    fig, (ax, grid) = plt.subplots(
        2, 1, sharex=True, figsize=(min(max(6.0, 0.06 * n + 3.5), 18.0), 3.2 + 0.22 * len(cells)),
        gridspec_kw={"height_ratios": [3.0, 0.22 * len(cells) + 0.3], "hspace": 0.05})
    x = np.arange(n)
    vals = np.array([_value(records, p, claim)["value"] for p in pts], dtype=np.float64)
    cis = [_value(records, p, claim)["ci"] or [v, v] for p, v in zip(pts, vals)]
    held = [bool(_value(records, p, claim)["holds"]) for p in pts]
    colours = ["tab:green" if h else "tab:red" for h in held]
    lo = np.array([c[0] for c in cis])
    if claim.log:
        lo = np.where(lo > 0, lo, vals)
    ax.vlines(x, lo, [c[1] for c in cis], colors=colours, alpha=0.45, lw=1.2)
    ax.scatter(x, vals, c=colours, s=10, zorder=3)
    for mark, style in (("literal", dict(marker="*", s=160, label="literal protocol")),
                        ("current", dict(marker="D", s=60, label="current protocol"))):
        at = [i for i, (u, d) in enumerate(pts) if mark in u.marks and d == mv.DEFINITIONS[0]]
        if at:
            ax.scatter(at, vals[at], facecolors="none", edgecolors="k", zorder=4, lw=1.2, **style)
            for i in at:
                grid.axvline(i, color="k", lw=0.8, alpha=0.6)
    ax.axhline(claim.paper, ls="--", color="0.35", lw=1, label=f"paper ({claim.paper:.3g})")
    ax.axhline(claim.bar, ls=":", color="tab:red", lw=1, label=f"the claim's bar ({claim.bar:g})")
    if claim.log:
        from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
        ax.set_yscale("log")
        ax.yaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.yaxis.set_minor_formatter(NullFormatter())
    ax.set_title(f"{claim.label()}: holds in {sum(held)} of {n} specifications shown",
                 fontsize=9, pad=20)
    ax.set_ylabel({"ratio": "random / avoidance", "shrink": "shrink", "share": "share < 30 goals",
                   "min": "fewest goals"}[claim.kind], fontsize=8)
    ax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(0.0, 1.0), ncol=4, frameon=False,
              borderaxespad=0.1)
    grid.pcolormesh(np.arange(n + 1) - 0.5, np.arange(len(cells) + 1) - 0.5, np.array(cells),
                    cmap="Greys", vmin=0, vmax=1.6, edgecolors="w", linewidth=0.3 if n < 80 else 0)
    grid.set_ylim(len(cells) - 0.5, -0.5)
    grid.set_yticks(range(len(cells)))
    grid.set_yticklabels(labels, fontsize=7)
    grid.set_xticks([])
    grid.set_xlabel("specifications (universe and definition), by the statistic (grid: dark = "
                    "the alternative level)", fontsize=8)
    with warnings.catch_warnings():  # tight_layout and the grid's axes: harmless
        warnings.simplefilter("ignore", UserWarning)
        return plots.save(fig, path)


# -- MULTIVERSE.md ---------------------------------------------------------------------
def _v(x, log):
    if x is None:
        return "-"
    return f"{x:.2f}" if log or abs(x) < 10 else f"{x:,.0f}"


def _claim_cell(claim, x):
    if x is None or x["value"] is None:
        return "-"
    ci = x["ci"]
    digits = claim.log or claim.kind == "share"
    text = _v(x["value"], digits) + (f" [{_v(ci[0], digits)}, {_v(ci[1], digits)}]" if ci else "")
    return f"{text} ({'holds' if x['holds'] else 'fails'})"


def _level_text(values):
    return ", ".join(f"{k}={v}" for k, v in values.items()) or "-"


def factor_table(factor_list, chosen):
    lines = ["| factor | in the design | " + " | ".join(f"{r}: plain -> alternative"
                                                      for r in PAPER_ROBOTS)
             + " | the paper's words |", "|---|:-:|" + "---|" * len(PAPER_ROBOTS) + "---|"]
    for f in factor_list:
        cells = []
        for r in PAPER_ROBOTS:
            lv = study.levels(f, r)
            changed = {k: v for k, v in lv.alternative.items() if lv.plain[k] != v}
            cells.append("inert" if lv.source == "inert" else
                         f"{_level_text({k: lv.plain[k] for k in changed})} -> "
                         f"{_level_text(changed)} ({lv.source})")
        lines.append(f"| `{f.key}`: {f.label} | {'yes' if f in chosen else 'plain'} | "
                     + " | ".join(cells) + f" | {f.sentence} |")
    return "\n".join(lines)


def _verdict(a):
    if not a["judged"]:
        return "not judged"
    if a["holds"] == a["judged"]:
        return "holds in every universe"
    if a["holds"] == 0:
        return "fails in every universe"
    return "holds in part"


def deciding(a, factor_list, chosen):
    """(key, share plain, share alternative) of the chosen factor whose level moves the
    share of universes holding the claim most; None for a claim that holds or fails in
    every universe judged."""
    if not a["judged"] or a["holds"] in (0, a["judged"]):
        return None
    keys = mv.keys(factor_list, chosen)
    gaps = [abs(p - q) if p is not None and q is not None else -1 for p, q in a["holds_by_level"]]
    i = int(np.argmax(gaps))
    return (keys[i], *a["holds_by_level"][i])


def _deciding(a, factor_list, chosen):
    d = deciding(a, factor_list, chosen)
    return "-" if d is None else f"`{d[0]}`: holds in {d[1]:.0%} plain, {d[2]:.0%} alternative"


def claims_table(analysis, factor_list, chosen, universes, records):
    marked = {m: next((u for u in universes if m in u.marks), None) for m in ("literal", "current")}
    lines = ["| claim | paper | literal protocol | current protocol | holds in (95% CI) | "
             "across the readings | the reading that decides it most |",
             "|---|---:|---|---|---|---|---|"]
    for c in mv.CLAIMS:
        a = analysis[c.key]
        cells = [_claim_cell(c, (records.get((u.name, mv.DEFINITIONS[0])) or {})
                             .get("claims", {}).get(c.key)
                             if u else None) for u in marked.values()]
        share = "-" if a["share"] is None else \
            f"{a['holds']}/{a['judged']} ({a['share_ci'][0]:.0%}-{a['share_ci'][1]:.0%})"
        lines.append(f"| {c.label()} | {_v(c.paper, c.log or c.kind == 'share')} | "
                     + " | ".join(cells) + f" | {share} | {_verdict(a)} | "
                     f"{_deciding(a, factor_list, chosen)} |")
    return "\n".join(lines)


def plain_words(analysis, factor_list, chosen):
    """The claims in words: which hold in every universe judged, which in none, which in
    part (and the reading that decides each most), which are not judged."""
    every, none, part, unjudged = [], [], [], []
    for c in mv.CLAIMS:
        a = analysis[c.key]
        if not a["judged"]:
            unjudged.append(c.key)
        elif a["holds"] == a["judged"]:
            every.append(c.key)
        elif a["holds"] == 0:
            none.append(c.key)
        else:
            d = deciding(a, factor_list, chosen)
            part.append(f"{c.key} in {a['holds']} of {a['judged']} (most decided by `{d[0]}`: "
                        f"{d[1]:.0%} of universes with it plain, {d[2]:.0%} with its "
                        "alternative)")
    lines = []
    for head, items in (("Hold in every universe", every), ("Hold in none", none),
                        ("Hold in part", part), ("Not judged", unjudged)):
        if items:
            lines.append(f"- {head}: {'; '.join(items)}.")
    return "\n".join(lines)


def figures_table(universes, records):
    """The twelve figures: the paper's, the literal and the current protocol's, and their
    spread over the design's complete universes; steps per trial and the shrink under
    each definition of steps per trial."""
    marked = [next((u for u in universes if m in u.marks), None) for m in ("literal", "current")]
    lines = ["| robot | condition | figure | steps per trial | paper | literal | current | "
             "universes: median (5%-95%) | within 1.5x of the paper |",
             "|---|---|---|---|---:|---:|---:|---|---:|"]
    for key in mv.FIGURES:
        robot, condition, figure = key
        ref = paper.RESULTS[(robot, condition)][figure]
        ref = ref["mean"] if isinstance(ref, dict) else ref
        log = figure == "shrink"
        definitions = mv.DEFINITIONS if figure != "first_trial_steps" else mv.DEFINITIONS[:1]
        for d in definitions:
            rows = [records[(u.name, d)] for u in universes
                    if u.row is not None and records.get((u.name, d))]
            cells = [_v((records.get((u.name, d)) or {}).get("figures", {}).get(key, (None,))[0],
                        log) if u else "-" for u in marked]
            values = np.array([r["figures"][key][0] for r in rows
                               if r["figures"].get(key, (None,))[0] is not None])
            if len(values):
                q = np.percentile(values, [5, 50, 95])
                spread = f"{_v(q[1], log)} ({_v(q[0], log)}-{_v(q[2], log)})"
                within = (f"{int(np.sum((values >= ref / 1.5) & (values <= ref * 1.5)))}/"
                          f"{len(values)}")
            else:
                spread, within = "-", "-"
            lines.append(f"| {robot} | {condition} | {figure.replace('_', ' ')} | "
                         f"{d if len(definitions) > 1 else '-'} | {_v(ref, log)} | "
                         + " | ".join(cells) + f" | {spread} | {within} |")
    return "\n".join(lines)


def effects_tables(analysis, factor_list, chosen, top=3):
    keys = mv.keys(factor_list, chosen)
    lines = ["Main effects (a ratio or a shrink: the statistic at the alternative level over "
             "the plain one; the share: its difference; the fewest goals: goals; "
             f"`{mv.CHOICE}`: the definition, budget over goals against the mean of the "
             "completed trials, '-' where it does not act):", "",
             "| factor | " + " | ".join(c.key for c in mv.CLAIMS) + " |",
             "|---|" + "---:|" * len(mv.CLAIMS)]
    for i, k in enumerate(keys):
        row = []
        for c in mv.CLAIMS:
            e = analysis[c.key]["effects"]
            row.append(mv.effect_text(c, e["mains"][i]) if e else "-")
        lines.append(f"| `{k}` | " + " | ".join(row) + " |")
    lines += ["", f"The {top} largest two-factor interactions on each claim's statistic "
              "(as its main effects read):", ""]
    for c in mv.CLAIMS:
        e = analysis[c.key]["effects"]
        if not e or not e["pairs"]:
            lines.append(f"- {c.key}: not estimated (the universes run do not identify them)")
            continue
        biggest = sorted(e["pairs"].items(), key=lambda kv: -abs(kv[1]))[:top]
        lines.append(f"- {c.key}: " + "; ".join(f"`{keys[i]}` x `{keys[j]}` {mv.effect_text(c, v)}"
                                                 for (i, j), v in biggest))
    return "\n".join(lines)


def _hours(seconds):
    if seconds < 60:
        return f"{seconds:.0f} s"
    return f"{seconds / 3600:.1f} h" if seconds >= 3600 else f"{seconds / 60:.1f} min"


def cost_text(n_runs, seconds, timing, bench, steps_by_robot):
    """The cost section's lines: the wall time these calls took, the runs' own compute
    (seconds: each distinct complete run's, as its run.json records it) and the floor it
    sets on the workers used, `ebrl bench`'s per-step cost times the runs' steps where
    measured (bench), and a Ray cluster's time."""
    made = [s for s in timing if s.get("runs_made") or s.get("interrupted")]
    wall = sum(s["seconds"] for s in made)
    workers = max((s["workers"] for s in made), default=1)
    compute = float(sum(seconds))
    stopped = sum(1 for s in made if s.get("interrupted"))
    lines = [f"- Runs: {n_runs:,} distinct (a run that universes share is made once), "
             f"{len(seconds):,} complete; made by {len(made)} call(s) of `ebrl multiverse`"
             + (f" ({stopped} stopped and resumed)" if stopped else "")
             + f" in **{_hours(wall)}** of wall time on {workers} worker(s)."]
    if seconds:
        lines.append(f"- Their compute, as each run records it: {_hours(compute)} of one core "
                     f"({compute / len(seconds):.1f} s a run on average, the longest "
                     f"{max(seconds):.0f} s); the floor on {workers} worker(s): "
                     f"{_hours(compute / workers)}.")
    if bench:
        total = sum(steps_by_robot[r] * bench[r]["fused_loop"] * 1e-6 for r in steps_by_robot)
        per = ", ".join(f"{r} {b['fused_loop']:.0f} us a step" for r, b in bench.items())
        line = (f"- `ebrl bench`'s cost of a step (its fused loop, the runs' own: {per}) "
                f"times the {n_runs:,} runs' steps: {_hours(total)} of one core; the floor on "
                f"{workers} worker(s): {_hours(total / workers)}.")
        parts = ("raw_physics", "reference_pass")
        if all(isinstance(bench[r].get(k), (int, float)) for r in steps_by_robot for k in parts):
            floor = sum(steps_by_robot[r] * sum(bench[r][k] for k in parts) * 1e-6
                        for r in steps_by_robot)
            line += (" Raw physics (`mj_step` alone) and the reference pass over the memory "
                     f"(ebrl.benchmark) a step: {_hours(floor)} of one core, "
                     f"{_hours(floor / workers)} on {workers} worker(s).")
        lines.append(line)
        compute = compute or total
    if compute:
        longest = max(seconds, default=0.0)
        cells = [f"{n} x {RAY_CORES} cores: {_hours(max(compute / (n * RAY_CORES), longest))}"
                 for n in (1, 4, 16, 64)]
        lines.append(f"- On a Ray cluster (`--backend ray`, docs/cluster.md: a run is a task "
                     f"of one CPU) of N machines of {RAY_CORES} cores: about the compute over "
                     f"N x {RAY_CORES}, never under the longest run, plus each node's first "
                     "compile of the kernels: " + "; ".join(cells) + ".")
    return lines


@dataclasses.dataclass
class Context:
    """What MULTIVERSE.md says: the factors, the design, the universes and their records,
    the analysis, the seeds and steps, the runs' commits, the costs, the failed runs."""
    factor_list: tuple
    chosen: tuple
    design: object
    universes: list
    records: dict
    analysis: dict
    seeds: list
    steps: object
    n_runs: int
    seconds: list
    commits: list
    timing: list
    bench: dict
    steps_by_robot: dict
    figures: dict
    failed: list
    records_folder: str = ""
    unused: int = 0


def protocols_text(universes, factor_list):
    """Which universe each protocol is, from tasks.protocols as it stands: the literal
    one the design's all-plain row (u001), the adopted one the universe at each factor's
    adopted level (a row of the design, or `current` beside it), its levels named."""
    literal = next((u for u in universes if "literal" in u.marks), None)
    current = next(u for u in universes if "current" in u.marks)
    up = []
    for i, f in enumerate(factor_list):
        robots = [r for r in PAPER_ROBOTS if current.codes[r][i] > 0]
        if robots:
            up.append(f"`{f.key}`" + ("" if len(robots) == len(PAPER_ROBOTS)
                                      else f" (the {', '.join(robots)} robot's)"))
    where = (f"the design's row {current.row + 1} ({current.name})" if current.row is not None
             else f"`{current.name}`, run beside the design (no row of the design gives "
                  "its readings: its levels may differ between the robots, and a value it "
                  "gives as a number, as the two-wheel radius 1.5, the plain level leaves to "
                  "the robot file, which need not run the same bits)")
    return (("The literal protocol (`ebrl run --protocol literal`) is u001, every factor "
             "plain. " if literal is not None else "")
            + f"The current protocol (`ebrl run`, the adopted readings of protocol "
            f"{PROTOCOL_VERSION}) is {where}: at the alternative level "
            + (", ".join(up) if up else "no factor") + ", every other factor plain; its "
            "runs are the adopted protocol's, bit for bit (tests/test_multiverse.py).")


def markdown(ctx):
    seeds = ctx.seeds
    seed_text = f"{seeds[0]}-{seeds[-1]}" if seeds == list(range(seeds[0], seeds[-1] + 1)) \
        else ",".join(map(str, seeds))
    design_rows = [u for u in ctx.universes if u.row is not None]
    complete = sum(1 for u in ctx.universes if ctx.records.get((u.name, mv.DEFINITIONS[0])))
    current = next(u for u in ctx.universes if "current" in u.marks)
    lines = ["# How much the conclusions depend on the open details", "",
             f"Protocol {PROTOCOL_VERSION}; runs made at commit(s) {', '.join(ctx.commits) or '-'}; "
             f"seeds {seed_text} ({len(seeds)} per universe, robot and condition); "
             + ("the paper's budgets" if ctx.steps is None else f"{ctx.steps:,} steps a run (a cap, "
                "not the paper's budgets: C5 and C6 are not judged)") + ".", "",
             f"**The design**: {ctx.design.name()} over the {len(ctx.chosen)} factors below "
             f"(generators {', '.join(ctx.design.generators) or 'none'}; {ctx.design.source}), "
             "so that no main effect or two-factor interaction is aliased with another; "
             f"{len(design_rows)} of its {ctx.design.runs} universes run"
             + ("" if current.row is not None else ", and the current protocol beside them")
             + f"; {complete} complete. Every universe runs both paper robots in both "
             f"conditions, and each claim of steps per trial is judged under both its "
             f"definitions (`{mv.CHOICE}`: an analysis choice, computed from the same runs).",
             "", protocols_text(ctx.universes, ctx.factor_list), "",
             f"**The data**: the runs' records in {ctx.records_folder or 'OUT/records'} "
             "(experiments/studies/multiverse_records.py: each run's parameters' digest, its "
             "trials and its goals), from which this page is made with no run (`ebrl "
             "multiverse --report-only`)"
             + (f"; {ctx.unused:,} records there belong to no run of this plan (another "
                "adopted protocol's levels, other seeds) and are left out" if ctx.unused else "")
             + ".", "",
             "## The factors", "",
             "Plain: the literal protocol's reading. Alternative: the adopted protocol's where "
             "it differs (adopted), else the other reading the text allows (alternative). "
             "docs/interpretation.md, \"The multiverse\", gives each one's reason.", "",
             factor_table(ctx.factor_list, ctx.chosen), "",
             "## The claims across the universes", "",
             "Each claim's statistic with its 95% interval in the literal and the current "
             "protocol, and the share of the design's complete universes in which it holds "
             "(Wilson's 95% interval); the reading that decides it most: the factor whose "
             "alternative level changes the share of universes holding it most (a main "
             "effect on the verdict).", "",
             claims_table(ctx.analysis, ctx.factor_list, ctx.chosen, ctx.universes, ctx.records),
             "", "In plain words:", "", plain_words(ctx.analysis, ctx.factor_list, ctx.chosen),
             "", "## The twelve figures across the universes", "",
             figures_table(ctx.universes, ctx.records), "",
             "## Effects on each claim's statistic", "",
             effects_tables(ctx.analysis, ctx.factor_list, ctx.chosen), "",
             "## Specification curves", "",
             "Each claim's statistic in every complete universe, sorted (green: holds; red: "
             "fails), with its interval, the paper's value (dashed) and the claim's bar "
             "(dotted); the literal protocol a star, the current a diamond (under the plain "
             "definition of steps per trial); below, the factors at their alternative level "
             "and the definition at budget over goals (dark).", ""]
    # one paragraph: the curves side by side where the page is wide enough
    lines += [f"![{key}]({path})" for key, path in ctx.figures.items()] + [""]
    lines += ["## Cost", ""] + cost_text(ctx.n_runs, ctx.seconds, ctx.timing, ctx.bench,
                                         ctx.steps_by_robot) + [""]
    if ctx.failed:
        lines += ["## Failed runs (their universes left out)", ""]
        lines += [f"- {n}: {e}" for n, e in ctx.failed] + [""]
    lines += ["The table: multiverse.csv (one row per universe and definition of steps per "
              "trial, in the order they run: its design row in standard order, its factors' "
              "codes, each robot's readings, the twelve figures and the ten claims with their "
              "95% intervals).", ""]
    return "\n".join(lines)


def write(out, ctx):
    path = pathlib.Path(out) / "MULTIVERSE.md"
    results.atomic_write(path, markdown(ctx))
    return path


def publish(out, text, page, figures_dir):
    """MULTIVERSE.md's text as the page's block (BLOCK; the rest of the page kept byte for
    byte), one heading level down (a section of RESULTS.md), its specification curves
    copied into figures_dir as multiverse_<name>.png and linked from there."""
    page, figures_dir = pathlib.Path(page), pathlib.Path(figures_dir)
    figures_dir.mkdir(parents=True, exist_ok=True)
    rel = pathlib.PurePosixPath(os.path.relpath(figures_dir, page.parent))
    lines = []
    for line in text.splitlines():
        if line.startswith("#"):
            line = "#" + line
        link = re.fullmatch(r"!\[(.*)\]\(figures/(.+\.png)\)", line)
        if link:
            name = f"multiverse_{link[2]}"
            report.copy(pathlib.Path(out) / "figures" / link[2], figures_dir / name)
            line = f"![{link[1]}]({rel / name})"
        lines.append(line)
    begin, end = BLOCK
    report.replace_block(page, begin, end, [begin, "", *lines, "", end])
    return page
