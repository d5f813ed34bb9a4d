"""`ebrl report DIR`: summary.json, REPORT.md and the figures, from the run folders."""
import functools
import os
import pathlib
import re

import numpy as np

from experiments import paper
from experiments.outputs import page, verdict_tables, verdicts
from experiments.outputs import optimal
from experiments.running import aggregate, lock, provenance, results
from models import rooms
from tasks.robots import DRIVES

@functools.cache
def _room_layout(room=None):
    """The room's layout from its map (models.rooms.layout), once per room."""
    return rooms.layout(room)


def paper_figures(group, condition=None):
    """Section 3.6's figures for a summary group's drive and condition; None in a room
    other than the paper's (the paper ran its own room only)."""
    if group.get("room"):
        return None
    return paper.RESULTS.get((group.get("drive"), condition or group["condition"]))


def room_of(runs, robot):
    """The room (run parameters' "room"; None: the paper's) of a robot label's runs."""
    return next(run["parameters"].get("room") for (r, _, _), run in runs.items() if r == robot)


def draw_room(ax, room=None):
    """The room's map (models.rooms) in paper units: the field, the walls, the goal."""
    from matplotlib.patches import Rectangle
    field, obstacles, goal, _ = _room_layout(room)
    ax.add_patch(Rectangle((field[0], field[2]), field[1] - field[0], field[3] - field[2],
                           fill=False, lw=2, ec="0.2"))
    for x0, x1, y0, y1 in obstacles:
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, color="0.55"))
    ax.add_patch(Rectangle((goal[0], goal[2]), goal[1] - goal[0], goal[3] - goal[2],
                           color="tab:green", alpha=0.4))
    ax.set_xlim(field[0] - 1, field[1] + 1)
    ax.set_ylim(field[2] - 1, field[3] + 1)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


def legend_below(ax, **kwargs):
    """The legend of a room's axes (draw_room) under them, outside the room: it covers no
    part of it, the start and the goal above all, in any room."""
    return ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), borderaxespad=0.3,
                     frameon=False, **kwargs)


def fmt(v, digits=0):
    if v is None:
        return "-"
    return f"{v:,.{digits}f}"


def interval(ci, digits=0):
    return "-" if ci is None else f"[{fmt(ci[0], digits)}, {fmt(ci[1], digits)}]"


def comparison_rows(summary):
    """One row per (group, figure): paper, ours, 95% CI, ratio, and the verdict of the
    figure's tests against the paper (summary["tests"], experiments.outputs.verdicts)."""
    tests = summary["tests"]
    judged = {(r["robot"], r["condition"], r["figure"]): r["verdict"] for r in tests["figures"]}
    judged.update({(r["robot"], r["condition"], "shrink (per trial / first)"): r["verdict"]
                   for r in tests["shrinks"]})
    rows = []
    for g in summary["groups"]:
        ref = paper_figures(g)
        for key, label, digits in (("first_trial_steps", "first-trial steps", 0),
                                   ("steps_per_trial", "steps per trial", 0),
                                   ("shrink", "shrink (per trial / first)", 2)):
            ours = g[key]["mean"] if isinstance(g[key], dict) else g[key]
            ci = g[key]["ci95"] if isinstance(g[key], dict) else g["shrink_ci95"]
            sd = g[key]["sd"] if isinstance(g[key], dict) else None
            theirs = None if ref is None else (ref[key]["mean"] if isinstance(ref[key], dict)
                                               else ref[key])
            rows.append({
                "robot": g["robot"], "condition": g["condition"], "figure": label,
                "paper": theirs,
                "paper_sd": ref[key].get("sd") if ref and isinstance(ref[key], dict) else None,
                "ours": ours, "sd": sd, "ci95": ci, "digits": digits,
                "ratio": (ours / theirs) if ours is not None and theirs else None,
                "verdict": judged.get((g["robot"], g["condition"], label))
                if ref is not None else None,
            })
    return rows


def comparison_table(summary):
    lines = ["| robot | condition | figure | paper | ours (sd) | ours 95% CI | ours / paper "
             "| the tests' verdict |", "|---|---|---|---:|---:|---|---:|---|"]
    for r in comparison_rows(summary):
        d = r["digits"]
        paper_txt = fmt(r["paper"], d) + (f" ({fmt(r['paper_sd'])})" if r["paper_sd"] else "")
        ours_txt = fmt(r["ours"], d) + (f" ({fmt(r['sd'])})" if r["sd"] is not None else "")
        lines.append(f"| {r['robot']} | {r['condition']} | {r['figure']} | {paper_txt} | {ours_txt} "
                     f"| {interval(r['ci95'], d)} | {fmt(r['ratio'], 2)} | {r['verdict'] or '-'} |")
    return "\n".join(lines)


def goals_table(summary):
    lines = ["| robot | condition | budget | reached first goal | goals min / median / max "
             "| runs below 30 goals |",
             "|---|---|---:|---:|---|---:|"]
    for g in summary["groups"]:
        f = g["first_trial_steps"]
        lines.append(f"| {g['robot']} | {g['condition']} | {fmt(g['steps'])} | {f['reached']}/{g['seeds']} "
                     f"| {g['goals']['min']} / {fmt(g['goals']['median'], 1)} / {g['goals']['max']} "
                     f"| {g['goals']['below_30']}/{g['seeds']} |")
    return "\n".join(lines)


def claims(summary):
    """Section 3.6's qualitative claims for each robot, each judged by a test on our runs
    (verdicts.claim_tests), as (claim, ours with the test's p, holds)."""
    return [(c["claim"], f"{c['ours']}, {c['test']} p {verdict_tables.p_text(c['p'])}",
             c["holds"]) for c in verdicts.claim_tests(summary)]


def claims_table(summary):
    """The claims' table from the summary's tests (verdicts.tested)."""
    return verdict_tables.claims_table(summary["tests"]["claims"])


# -- figures ----------------------------------------------------------------------
def save(fig, path, dpi=90):
    """Lays out, writes and closes a figure; returns path. The image is the figure's tight
    box, so a legend under a room (legend_below) is never cut off."""
    fig.tight_layout()
    try:
        with results.atomic_file(path) as tmp:
            fig.savefig(tmp, dpi=dpi, format=pathlib.Path(path).suffix[1:] or "png",
                        bbox_inches="tight", pad_inches=0.05)
    finally:
        pyplot().close(fig)
    return path


def log_y(ax):
    """A log scale on ax's y axis, its ticks labelled as plain numbers (300, 1000, 6000).
    matplotlib's own labels are mathtext (10^3), whose parser is a large part of a report's
    figures' cost (docs/speed.md, "The test suite's time")."""
    from matplotlib import ticker
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(ticker.LogFormatter())
    ax.yaxis.set_minor_formatter(ticker.LogFormatter(labelOnlyBase=False))


def pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def cumulative_reward_figure(root, runs, robot, path):
    """Figures 3 and 5: cumulative reward against steps, every seed and the mean."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6), sharey=True)
    colours = {"random": "tab:orange", "avoidance": "tab:blue"}
    for k, condition in enumerate(paper.CONDITIONS):
        seeds = sorted(s for r, c, s in runs if (r, c) == (robot, condition))
        if not seeds:
            continue
        steps = runs[(robot, condition, seeds[0])]["parameters"]["steps"]
        grid = np.linspace(0, steps, 400)
        curves = []
        for s in seeds:
            _, _, ends = results.load_trace(root, robot, condition, s)
            axes[k].step(np.concatenate([[0], ends, [steps]]),
                         np.concatenate([[0], np.arange(1, len(ends) + 1), [len(ends)]]),
                         where="post", lw=0.6, alpha=0.5, color=colours[condition])
            curves.append(np.searchsorted(ends, grid, side="right"))
        mean = np.mean(curves, axis=0)
        axes[k].plot(grid, mean, color="k", lw=1.5, label="mean")
        axes[k].set_title(f"{'without' if condition == 'random' else 'with'} avoidance ({len(seeds)} seeds)")
        axes[k].set_xlabel("steps")
        axes[2].plot(grid, mean, color=colours[condition], lw=2,
                     label=f"{'without' if condition == 'random' else 'with'} avoidance")
    axes[0].set_ylabel("cumulative reward (goals)")
    drive = next((run["parameters"].get("drive") for (r, _, _), run in runs.items() if r == robot),
                 None)
    budget = DRIVES[drive].budget if drive in DRIVES else None
    if drive == "two_wheel" and all(run["parameters"]["steps"] == budget
                                    for (r, _, _), run in runs.items() if r == robot):
        # Section 3.6's marks at 30,000 steps: 43 of 50 random walks below 30 goals, and 49
        # goals the worst avoidance run
        goals = paper.TWO_WHEEL_GOALS
        axes[0].axhline(30, color="tab:red", ls="--", lw=1,
                        label=f"30 goals (paper: {goals['random_below_30']} of 50 runs below)")
        axes[1].axhline(goals["avoidance_min"], color="tab:red", ls="--", lw=1,
                        label=f"{goals['avoidance_min']} goals (paper: the worst run)")
        for ax in axes[:2]:
            ax.legend(loc="upper left", fontsize=8)
    axes[2].set_title("comparison of means")
    axes[2].set_xlabel("steps")
    axes[2].legend()
    figure = {"two_wheel": "the paper's Figure 3: ", "floating": "the paper's Figure 5: "}
    fig.suptitle(f"{figure.get(drive, '')}{robot}: learning performance (cumulative reward)")
    save(fig, path)


def typical_seed(runs, robot, condition):
    """The seed with the median steps per trial among those with at least two goals."""
    cands = sorted((run["metrics"]["steps_per_trial"], s) for (r, c, s), run in runs.items()
                   if (r, c) == (robot, condition) and run["metrics"]["goals"] >= 2)
    return cands[len(cands) // 2][1] if cands else None


def traces_figure(root, runs, robot, path):
    """Figures 2 and 4: typical successful traces: the median seed's first trial and a
    typical learned one."""
    save(traces_plot(root, runs, robot), path)


def traces_plot(root, runs, robot):
    """traces_figure's figure, not yet saved: one axes a condition, each its room with its
    legend below it."""
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.9))
    for ax, condition in zip(axes, paper.CONDITIONS):
        draw_room(ax, room_of(runs, robot))
        seed = typical_seed(runs, robot, condition)
        if seed is None:
            ax.set_title(f"{condition}: no seed with two goals")
            continue
        paths = results.trial_paths(*results.load_trace(root, robot, condition, seed))
        # A typical learned trial: the median-length trial of the seed's second half.
        later = sorted(range(len(paths) // 2, len(paths)), key=lambda i: len(paths[i]))
        k = later[len(later) // 2]
        first, last = paths[0], paths[k]
        ax.plot(first[:, 0], first[:, 1], lw=0.4, color="0.6", alpha=0.7,
                label=f"first trial ({len(first) - 1} steps)")
        ax.plot(last[:, 0], last[:, 1], lw=1.2, color="tab:red",
                label=f"typical learned trial, #{k + 1} ({len(last) - 1} steps)")
        ax.plot(*last[0], "o", color="tab:blue")
        ax.set_title(f"{'without' if condition == 'random' else 'with'} avoidance, seed {seed}")
        legend_below(ax, fontsize=7)
    drive = next((run["parameters"].get("drive") for (r, _, _), run in runs.items() if r == robot),
                 None)
    figure = {"two_wheel": "the paper's Figure 2: ", "floating": "the paper's Figure 4: "}
    fig.suptitle(f"{figure.get(drive, '')}{robot}: typical traces of successful trials")
    return fig


def first_vs_learned_figure(summary, path):
    """First-trial steps against learned steps per trial, ours (95% CI) and the paper's."""
    plt = pyplot()
    groups = summary["groups"]
    fig, ax = plt.subplots(figsize=(8, 3.8))
    x = np.arange(len(groups))
    for off, key, colour, label in ((-0.18, "first_trial_steps", "tab:gray", "first trial"),
                                    (0.18, "steps_per_trial", "tab:purple", "steps per trial")):
        means = [g[key]["mean"] or 0 for g in groups]
        err = np.array([[m - (g[key]["ci95"] or [m, m])[0], (g[key]["ci95"] or [m, m])[1] - m]
                        for m, g in zip(means, groups)]).T
        ax.bar(x + off, means, 0.34, color=colour, label=f"ours: {label}", yerr=err, capsize=3)
        ref = [(paper_figures(g) or {}).get(key, {}).get("mean") for g in groups]
        ax.plot(x + off, [np.nan if v is None else v for v in ref], "k_", ms=18, mew=2,
                label=f"paper: {label}" if off < 0 else None)
    ax.plot([], [], "k_", ms=18, mew=2, label="paper: steps per trial")
    log_y(ax)
    ax.set_xticks(x, [f"{g['robot']}\n{g['condition']}" for g in groups])
    ax.set_ylabel("steps")
    ax.legend(fontsize=7, ncol=2)
    save(fig, path)


BEGIN, END = "<!-- ebrl report: generated, do not edit -->", "<!-- ebrl report: end -->"


def markers(section=None):
    """(begin, end) of a page's generated block: the main one (BEGIN, END), or a section's,
    named by it."""
    if section is None:
        return BEGIN, END
    return (f"<!-- ebrl report: {section}: generated, do not edit -->",
            f"<!-- ebrl report: {section}: end -->")


def section_slug(section):
    """A section's name as a file name's part: summary-<slug>.json."""
    return re.sub(r"[^a-z0-9]+", "-", section.lower()).strip("-")


#: A section's name (--section): it stands in the page's markers (HTML comments) and its
#: file's name, so letters, digits, spaces and a little punctuation, never "--".
SECTION_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9 _.,()+&'/-]{0,59}")
#: Files beside the page that are not a section's: the headline's literal summary.
_NOT_SECTIONS = {"literal"}
_SECTION_BEGIN = re.compile(r"<!-- ebrl report: (.+?): generated, do not edit -->")


def check_section(section):
    """--section NAME as a block's name: ValueError (one line) for a name that cannot
    stand in a marker or a file name, or whose file is another's."""
    if not section.strip():
        raise ValueError("--section: give the block a name")
    if not SECTION_NAME.fullmatch(section) or "--" in section or section != section.strip():
        raise ValueError(f"--section {section!r}: not a block's name (it goes in the page's "
                         "HTML comments and summary-NAME.json): at most 60 letters, digits, "
                         "spaces and - _ . , ( ) + & ' /, a letter or digit first, no '--'")
    slug = section_slug(section)
    if slug in _NOT_SECTIONS:
        raise ValueError(f"--section {section!r}: its file summary-{slug}.json is the "
                         "headline's (ebrl report --literal); give another name")
    return slug


def check_section_clash(results_md, section):
    """ValueError when the page holds a section of another name whose file name is this
    one's ("Run A" and "run a" both write summary-run-a.json)."""
    text = page.read(results_md) or ""
    slug = section_slug(section)
    other = next((name for name in dict.fromkeys(_SECTION_BEGIN.findall(text))
                  if name != section and section_slug(name) == slug), None)
    if other is not None:
        raise ValueError(f"--section {section!r}: {results_md} has the section {other!r}, "
                         f"whose file summary-{slug}.json this name's would overwrite; give "
                         f"that name exactly, or a name that differs in its letters or digits")


def publish(root, results_md, figures_dir, section=None):
    """Regenerates the tables of results_md (between its markers, keeping the rest),
    copies the figures into figures_dir and summary.json beside results_md; with a
    section, that section's block (the tests, the claims and the learning curves: the
    rest is in its REPORT.md) and summary-<section>.json, the main block untouched."""
    root, results_md, figures_dir = map(pathlib.Path, (root, results_md, figures_dir))
    summary = results.read_summary(root / "summary.json")
    figures_dir.mkdir(parents=True, exist_ok=True)
    rel = os.path.relpath(figures_dir, results_md.parent)
    begin, end = markers(section)
    block = [begin, "", *provenance.lines(summary["provenance"]),
             *failed_section(summary, "###")]
    pngs = sorted((root / "figures").glob("*.png"))
    if section is None:
        block += ["### Section 3.6, the paper against ours", "", comparison_table(summary), "",
                  *verdict_tables.section(summary["tests"], "###"),
                  "### Goals within the budget", "", goals_table(summary), "",
                  "### Qualitative claims", "", claims_table(summary), ""]
        if "optimal" in summary:
            block += ["### Against the optimal path", "", optimal_table(summary["optimal"]), ""]
    else:  # a section beside the main block: the tests, the claims, the learning curves
        block += [*verdict_tables.section(summary["tests"], "###"),
                  "### Qualitative claims", "", claims_table(summary), ""]
        pngs = [p for p in pngs if p.name.startswith("cumulative_reward")]
    for png in pngs:  # only the figures the block shows: a section's never replace others
        copy(png, figures_dir / png.name)
        block += [f"![{png.stem}]({rel}/{png.name})", ""]
    block.append(end)
    replace_block(results_md, begin, end, block)
    name = "summary.json" if section is None else f"summary-{section_slug(section)}.json"
    results.atomic_write(results_md.parent / name, results.dumps(summary))
    return results_md


def copy(src, dst):
    """Copies a file through the one atomic write (results.atomic_write)."""
    results.atomic_write(dst, pathlib.Path(src).read_bytes())
    return dst


def replace_block(path, begin, end, block):
    """Writes the lines `block` (which start with begin and end with end) over the block
    between the markers in path, keeping the rest byte for byte; appends them to a page
    without the block (experiments.outputs.page: a broken block is PageError, one line,
    nothing written)."""
    return page.replace(path, begin, end, block)


def optimal_table(rows):
    return optimal.table(rows)


def build(root, room=False):
    """Rebuilds summary.json, REPORT.md and the figures under root; returns REPORT.md's
    path. room: only that room's runs (None: the paper's; False: every room's, each
    robot label's runs in its own room, models.rooms)."""
    root = pathlib.Path(root)
    damaged = {}  # run folders that cannot be read: skipped, one line each, counted below
    runs = results.load_runs(root, room=room, damaged=damaged)
    prov = provenance.of(runs, root)  # refuses to pool different protocols or parameters
    failed = results.failed_runs(root)  # named below, never averaged
    summary = aggregate.summarize(runs)
    summary["provenance"] = prov
    summary["tests"] = verdicts.tested(summary)
    summary["locks"] = lock.of_runs(root, runs)  # the environments the runs were made in
    if failed:
        summary["failed"] = [{"run": name, "error": error} for name, error in failed.items()]
    if damaged:
        summary["damaged"] = [{"run": name, "reason": e.reason} for name, e in damaged.items()]
    figures = root / "figures"
    figures.mkdir(exist_ok=True)
    robots = sorted({k[0] for k in runs}, key=lambda r: (aggregate.robot_order(r), r))
    for robot in robots:
        cumulative_reward_figure(root, runs, robot, figures / f"cumulative_reward_{robot}.png")
        traces_figure(root, runs, robot, figures / f"traces_{robot}.png")
    first_vs_learned_figure(summary, figures / "first_vs_learned.png")
    extra = []
    try:
        from experiments.outputs import optimal
        summary["optimal"] = optimal.yardstick(runs, root)
        extra = ["", "## Against the optimal path", "", optimal.table(summary["optimal"])]
    except ImportError:
        pass
    results.atomic_write(root / "summary.json", results.dumps(summary))
    lines = [
        f"# Report: {root}", "",
        f"{len(runs)} runs. Section 3.6 of Unemi (2000) beside ours; 95% intervals are "
        "percentile bootstraps over seeds.", "",
        *provenance.lines(prov),
        "Environment: requirements.lock " + ", ".join(summary["locks"]) + " (config.json's "
        "versions.lock: the first 12 hex digits of its sha256).", "",
        *failed_section(summary), *damaged_section(summary),
        "## Section 3.6 figures", "", comparison_table(summary), "",
        *verdict_tables.section(summary["tests"]),
        "## Goals within the budget", "", goals_table(summary), "",
        "## Qualitative claims", "", claims_table(summary), *extra, "",
        "## Figures", "",
    ]
    for robot in robots:
        lines += [f"![{robot} cumulative reward](figures/cumulative_reward_{robot}.png)", "",
                  f"![{robot} traces](figures/traces_{robot}.png)", ""]
    lines += ["![first trial against learned](figures/first_vs_learned.png)", ""]
    results.atomic_write(root / "REPORT.md", "\n".join(lines))
    return root / "REPORT.md"


def failed_section(summary, heading="##"):
    """REPORT.md's (and RESULTS.md's) list of the failed runs, which no figure averages."""
    failed = summary.get("failed")
    if not failed:
        return []
    return ([f"{heading} Failed runs: {len(failed)}, not averaged", "",
             "Each one's run.json holds its error and traceback; what to do: "
             + results.advice((f["error"] for f in failed), "run the command that made them "
                              "again") + ".",
             ""] + [f"- `{f['run']}`: {f['error']}" for f in failed] + [""])


def damaged_section(summary):
    """REPORT.md's list of the run folders skipped because their files cannot be read."""
    damaged = summary.get("damaged")
    if not damaged:
        return []
    return ([f"## Damaged runs: {len(damaged)}, skipped", "",
             "Their files cannot be read; `ebrl run` moves them into the run folder's "
             "damaged-<time>/ and makes the run again (docs/failures.md).", ""]
            + [f"- `{d['run']}`: {d['reason']}" for d in damaged] + [""])


def sweep_table(out, param, rows, failed=()):
    """SWEEP.md under out: each group's figures at every value of param; rows are
    (value, runs as results.load_runs gives them); failed, (run folder, error) pairs of
    the failed runs, which the rows leave out."""
    lines = [f"# Sweep over {param}", "",
             "| " + param + " | robot | condition | seeds | first-trial steps | steps per trial (95% CI) "
             "| shrink | goals min / median |", "|---:|---|---|---:|---:|---|---:|---|"]
    for value, runs in rows:
        s = aggregate.summarize(runs)
        for g in s["groups"]:
            p = g["steps_per_trial"]
            lines.append(f"| {value} | {g['robot']} | {g['condition']} | {g['seeds']} "
                         f"| {fmt(g['first_trial_steps']['mean'])} | {fmt(p['mean'])} {interval(p['ci95'])} "
                         f"| {fmt(g['shrink'], 2)} | {g['goals']['min']} / {fmt(g['goals']['median'], 1)} |")
    if failed:
        lines += [""] + failed_section({"failed": [{"run": r, "error": e} for r, e in failed]})[:-1]
    path = pathlib.Path(out) / "SWEEP.md"
    results.atomic_write(path, "\n".join(lines) + "\n")
    return path
