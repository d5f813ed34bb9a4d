"""`ebrl evolve-report`: EVOLVE.md, the paper's hand-coded intrinsic behaviours against
the evolved ones (Section 4's proposal), from the folders that the README's evolution
commands write:

    EVOLVE/                  the studies of `ebrl evolve --out EVOLVE`: evolve-<robot>
                             (for the learner) and evolve-<robot>-controller (alone)
    HAND/                    the protocol's runs (results/): the paper's rules, EBRL learning
    EVOLVED/learner          EBRL learning with evolve-<robot>_best.json
    EVOLVED/controller       EBRL learning with evolve-<robot>-controller_best.json
    EVOLVED/alone_<which>    the paper's rule (paper), or either genome, driving alone
                             (exploration_rate=1: the memory never acts)
    EVOLVED/transfer         the planar robots' genomes on the 3D robots, unchanged

Every table is the avoidance condition at the robot's budget, means over the held-out
seeds with 95% percentile bootstrap intervals (aggregate.summarize). A folder that is
missing leaves its rows out, with a line saying so.
"""
import functools
import pathlib

from ebrl import behaviour as genomes
from experiments.outputs import plots, report
from experiments.running import aggregate, results
from experiments.studies import study
from experiments.studies import evolve
from tasks.robots import ROBOTS

#: The paper's robots whose behaviours are evolved, and the 3D robot each transfers to.
PLANAR = ("two_wheel", "floating")
TRANSFER = {"diff_drive": "two_wheel", "hovercraft": "floating"}
#: Issue 18's target: steps per trial of the hand-coded learner over the evolved one.
TARGET = {"two_wheel": 1.2, "floating": 1.5}
CONDITION = "avoidance"
LEARNING = (("hand-coded (the paper's rule)", None),
            ("evolved for the learner", "learner"),
            ("evolved as a controller", "controller"))
ALONE = (("hand-coded (the paper's rule)", "alone_paper"),
         ("evolved for the learner", "alone_learner"),
         ("evolved as a controller", "alone_controller"))
BEGIN, END = "<!-- ebrl evolve-report: generated, do not edit -->", "<!-- ebrl evolve-report: end -->"


@functools.cache
def _folder(folder):
    """(runs, {robot label: the avoidance group of their summary}) of a run folder, each
    folder loaded and bootstrapped once per report (write clears the cache); ({}, {}) if
    there is no folder or no run in it."""
    folder = pathlib.Path(folder)
    if not folder.is_dir():
        return {}, {}
    try:
        runs = results.load_runs(folder)
    except results.ResultsError:
        return {}, {}
    summary = aggregate.summarize(runs)
    return runs, {g["robot"]: g for g in summary["groups"] if g["condition"] == CONDITION}


def _groups(folder):
    return _folder(folder)[1]


def _cell(stats, digits=0):
    if stats is None or stats.get("mean") is None:
        return "-"
    return f"{report.fmt(stats['mean'], digits)} {report.interval(stats['ci95'])}"


def _goals(folder, robot):
    import numpy as np
    values = [run["metrics"]["goals"] for (r, c, _), run in sorted(_folder(folder)[0].items())
              if (r, c) == (robot, CONDITION)]
    rng = np.random.default_rng(aggregate.BOOTSTRAP_SEED)
    return {"mean": float(np.mean(values)), "ci95": aggregate.bootstrap_ci(values, rng)}


def _apart(hand, evolved):
    """Whether the evolved steps-per-trial interval lies wholly below the hand-coded one."""
    a, b = hand["steps_per_trial"]["ci95"], evolved["steps_per_trial"]["ci95"]
    return bool(a and b and b[1] < a[0])


def comparison_table(rows, robots):
    """rows: (label, folder or None); the avoidance learners' figures per robot."""
    lines = ["| robot | behaviour | seeds | first trial | steps per trial | goals | "
             "hand-coded / this (steps per trial) | intervals apart |",
             "|---|---|---:|---|---|---|---:|:-:|"]
    missing = []
    for robot in robots:
        hand = None
        for label, folder in rows:
            g = _groups(folder).get(robot) if folder is not None else None
            if g is None:
                missing.append(f"{robot}, {label} ({folder})")
                continue
            if hand is None:
                hand = (g, folder)
            ratio = hand[0]["steps_per_trial"]["mean"] / g["steps_per_trial"]["mean"] \
                if g["steps_per_trial"]["mean"] else None
            same = g is hand[0]
            lines.append(
                f"| {robot} | {label} | {g['seeds']} | {_cell(g['first_trial_steps'])} "
                f"| {_cell(g['steps_per_trial'])} | {_cell(_goals(folder, robot), 1)} "
                f"| {'-' if same or ratio is None else f'{ratio:.2f}x'} "
                f"| {'' if same else ('yes' if _apart(hand[0], g) else 'no')} |")
    return "\n".join(lines), missing


def genome_table(evolve_dir, robot):
    """The paper's genome beside the two evolved ones, field by field."""
    cols = [("the paper's rule", evolve.paper_genome(ROBOTS[robot]))]
    for label, name in (("for the learner", evolve.study_name(robot)),
                        ("as a controller", evolve.study_name(robot, learning=False))):
        path = pathlib.Path(evolve_dir) / f"{name}_best.json"
        if path.is_file():
            cols.append((label, genomes.load(path)))
    dicts = [genomes.to_dict(g) for _, g in cols]
    lines = ["| field | " + " | ".join(c for c, _ in cols) + " |",
             "|---|" + "---|" * len(cols)]
    for k in dicts[0]:
        if k == "behaviour":
            continue
        lines.append(f"| {k} | " + " | ".join(_show(d.get(k)) for d in dicts) + " |")
    return "\n".join(lines)


def _show(v):
    if isinstance(v, list):
        return "[" + ", ".join(f"{x:.2f}" for x in v) + "]"
    if v is None:
        return "null (eq 10's symmetry)"
    return f"{v:.3g}" if isinstance(v, float) else str(v)


def fitness_lines(evolve_dir, robot, figures):
    """The studies' settings, first and best fitness, and their figures (under figures)."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    storage = study.storage_url(None, evolve_dir)
    lines = []
    for learning in (True, False):
        name = evolve.study_name(robot, learning)
        try:
            s = optuna.load_study(study_name=name, storage=storage)
        except Exception:  # no such study (or no storage): its line says so
            lines.append(f"- `{name}`: not run.")
            continue
        rows = evolve.fitness_rows(s)
        if not rows:
            lines.append(f"- `{name}`: no complete trial.")
            continue
        settings = s.user_attrs.get("settings", {})
        fig = pathlib.Path(figures) / f"{name}_fitness.png"
        evolve.fitness_figure(s, fig)
        lines.append(
            f"- `{name}` ({'EBRL learning' if learning else 'the behaviour alone'}; population "
            f"{settings.get('population')}, seeds {_seeds(settings.get('seeds'))}, "
            f"{settings.get('steps') or 'the budget'} steps a run): "
            f"{len(evolve.complete(s))} trials over {rows[-1][0]} generations; mean goals "
            f"{rows[0][2]:.1f} for the paper's rule (generation 0), best {rows[-1][4]:.1f}.")
        lines += ["", f"  ![{name}]({fig.as_posix()})", ""]
    return lines


def _seeds(seeds):
    if not seeds:
        return "?"
    return f"{seeds[0]}-{seeds[-1]}" if seeds == list(range(seeds[0], seeds[-1] + 1)) else \
        ", ".join(map(str, seeds))


def traces_figure(hand, learner, robot, path):
    """One held-out seed (the hand-coded learner's median), its first trial and a late one,
    hand-coded beside evolved."""
    plt = plots.pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.9))
    runs = _folder(hand)[0]
    seed = plots.typical_seed(runs, robot, CONDITION)
    for ax, (label, folder) in zip(axes, (("hand-coded", hand), ("evolved for the learner", learner))):
        plots.draw_room(ax)
        try:
            paths = results.trial_paths(*results.load_trace(folder, robot, CONDITION, seed))
        except (FileNotFoundError, TypeError):
            ax.set_title(f"{label}: no run of seed {seed}")
            continue
        if not paths:
            ax.set_title(f"{label}, seed {seed}: no goal")
            continue
        later = sorted(range(len(paths) // 2, len(paths)), key=lambda i: len(paths[i]))
        k = later[len(later) // 2]
        ax.plot(*paths[0].T, lw=0.4, color="0.6", alpha=0.7,
                label=f"first trial ({len(paths[0]) - 1} steps)")
        ax.plot(*paths[k].T, lw=1.2, color="tab:red",
                label=f"typical late trial, #{k + 1} ({len(paths[k]) - 1} steps)")
        ax.set_title(f"{label}, seed {seed}: {len(paths)} goals")
        plots.legend_below(ax, fontsize=7)
    fig.suptitle(f"{robot}, EBRL with avoidance")
    return plots.save(fig, path)


def build(evolve_dir, hand, evolved, figures):
    """EVOLVE.md's body (markdown) and the trace figures under figures."""
    evolve_dir, hand, evolved = map(pathlib.Path, (evolve_dir, hand, evolved))
    learning_rows = [(label, hand if which is None else evolved / which) for label, which in LEARNING]
    alone_rows = [(label, evolved / which) for label, which in ALONE]
    out = []
    table, missing = comparison_table(learning_rows, PLANAR)
    out += ["### EBRL learning with each behaviour (held-out seeds, the paper's budgets)", "",
            table, ""]
    for robot in PLANAR:
        hand_g, evo_g = _groups(hand).get(robot), _groups(evolved / "learner").get(robot)
        if hand_g and evo_g:
            ratio = hand_g["steps_per_trial"]["mean"] / evo_g["steps_per_trial"]["mean"]
            met = ratio >= TARGET[robot] and _apart(hand_g, evo_g)
            out.append(f"- {robot}: the target, {TARGET[robot]}x fewer steps per trial with "
                       f"intervals apart, is {'met' if met else 'not met'} ({ratio:.2f}x).")
    out += ["", "### Each behaviour alone (exploration_rate=1: the memory never acts)", ""]
    table, missing_alone = comparison_table(alone_rows, PLANAR)
    out += [table, ""]
    out += ["### Transfer: the planar robots' genomes on the 3D robots, unchanged", ""]
    rows = [("hand-coded (the paper's rule)", hand), ("evolved for the learner", evolved / "transfer")]
    table, missing_transfer = comparison_table(rows, tuple(TRANSFER))
    out += [table, ""]
    for robot in PLANAR:
        out += [f"### {robot}: the genomes", "", genome_table(evolve_dir, robot), "",
                "Fitness over generations:", ""] + fitness_lines(evolve_dir, robot, figures) + [""]
        if _groups(hand).get(robot) and _groups(evolved / "learner").get(robot):
            fig = pathlib.Path(figures) / f"evolved_traces_{robot}.png"
            traces_figure(hand, evolved / "learner", robot, fig)
            out += [f"![{robot} traces]({fig.as_posix()})", ""]
    gone = missing + missing_alone + missing_transfer
    if gone:
        out += ["Not run (no runs in the folder): " + "; ".join(gone) + ".", ""]
    return "\n".join(out)


def write(evolve_dir, hand, evolved, out, figures, results_md=None):
    """EVOLVE.md at out (and the block in RESULTS.md when given); returns out."""
    _folder.cache_clear()  # runs may have been added since an earlier report
    pathlib.Path(figures).mkdir(exist_ok=True)  # its parent exists (validate.output_folder)
    body = build(evolve_dir, hand, evolved, figures)
    text = "\n".join(["# Evolved intrinsic behaviours (Section 4's proposal)", "",
                      "Made by `ebrl evolve-report` (experiments/studies/evolved.py) from "
                      f"`{evolve_dir}`, `{hand}` and `{evolved}`.", "", body, ""])
    results.atomic_write(pathlib.Path(out), text)
    if results_md is not None:
        report.replace_block(results_md, BEGIN, END, [BEGIN, "", body, END])
    return pathlib.Path(out)
