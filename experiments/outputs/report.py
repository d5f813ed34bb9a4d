"""`ebrl report DIR`: summary.json, REPORT.md and the figures, from the run folders."""
import os
import pathlib
import re


from experiments import paper
from experiments.outputs import optimal, page, plots, verdict_tables, verdicts
from experiments.running import aggregate, lock, provenance, results

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
        ref = paper.reported(g)
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
    folder = root / "figures"
    folder.mkdir(exist_ok=True)
    robots = sorted({k[0] for k in runs}, key=lambda r: (aggregate.robot_order(r), r))
    for robot in robots:
        plots.cumulative_reward_figure(root, runs, robot,
                                         folder / f"cumulative_reward_{robot}.png")
        plots.traces_figure(root, runs, robot, folder / f"traces_{robot}.png")
    plots.first_vs_learned_figure(summary, folder / "first_vs_learned.png")
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
