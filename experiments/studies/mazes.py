"""`ebrl maze-study`: the paper's closing claim tested on random mazes.

Unemi (2000) ends: "the proposed method could provide more effective profit for more
complicated task". Here both paper robots, both conditions, run in labmaze's random
mazes (models.rooms.random_map) of several sizes, several mazes per size and several
seeds per maze. The budget rule: STEPS_PER_CELL agent steps per cell of the maze's
shortest path (the fewest cell moves from start to goal), so a maze twice as long gets
twice the steps. Per robot and size, over (maze, seed) units:

- the avoidance behaviour's gain: random / avoidance first-trial steps (a run with no
  goal counts its budget, a lower bound, so the gain is then understated), random /
  avoidance steps per trial, and avoidance - random goals per 10,000 steps;
- learning's shrink: steps per trial / first-trial steps, for each condition.

95% intervals are percentile bootstraps resampling the (maze, seed) units of a size.
Runs are ordinary runs (`ebrl run --room random:WxH:MAZE` makes the same bytes) under
OUT/<robot>@random-WxH-MAZE/<condition>/seed_NNN.
"""
import pathlib

import numpy as np

from experiments.running import execution, results, runner
from models import rooms

ROBOTS = ("two_wheel", "floating")
CONDITIONS = ("random", "avoidance")
#: The default sizes (W x H cells): the paper's 9 x 6 first.
SIZES = ((9, 6), (15, 15), (21, 21))
#: Agent steps per cell of a maze's shortest path (the budget rule).
STEPS_PER_CELL = 1000
BOOTSTRAP_SAMPLES = 10_000
BOOTSTRAP_SEED = 20000
BEGIN, END = "<!-- maze-study:begin -->", "<!-- maze-study:end -->"


def room(size, maze):
    return f"random:{size[0]}x{size[1]}:{maze}"


def budget(size, maze, per_cell=STEPS_PER_CELL):
    return per_cell * rooms.load(room(size, maze)).shortest_cells()


def plan(sizes=SIZES, mazes=3, seeds=2, per_cell=STEPS_PER_CELL, robots=ROBOTS):
    """The study's specs: every robot, condition, size, maze (0..mazes-1) and seed; in
    the order to run them: seed by seed, maze by maze, every size, so that a study cut
    short holds whole (maze, seed) units of every size."""
    return [execution.RunSpec(robot, condition, seed, budget(size, maze, per_cell),
                             room=room(size, maze))
            for seed in range(seeds) for maze in range(mazes) for size in sizes
            for robot in robots for condition in CONDITIONS]


def run(out, specs, workers=1, progress=True):
    return runner.run(specs, pathlib.Path(out), workers=workers, progress=progress)


def _units(out, specs):
    """{(robot, size): {(maze, seed): {condition: metrics with 'steps'}}} of complete runs."""
    table = {}
    for spec in specs:
        if results.existing(out, spec) != "done":
            continue
        run = results.read_run_json(results.run_dir(out, spec) / "run.json")
        m = rooms.RANDOM.match(spec.room)
        size, maze = (int(m.group(1)), int(m.group(2))), int(m.group(3))
        metrics = dict(run["metrics"], steps=spec.steps,
                       shortest=rooms.load(spec.room).shortest_cells())
        table.setdefault((spec.robot, size), {}).setdefault((maze, spec.seed), {})[
            spec.condition] = metrics
    return table


def _first(m):
    """First-trial steps, or the budget when the run reached no goal (a lower bound)."""
    return m["first_trial_steps"] if m["first_trial_steps"] is not None else m["steps"]


def _per_trial(m):
    return m["steps_per_trial"] if m["steps_per_trial"] is not None else m["steps"]


def summarize(out, specs):
    """Rows per robot and size: the gains and shrinks, with 95% bootstrap intervals."""
    rows = []
    for (robot, size), units in sorted(_units(out, specs).items()):
        units = [u for _, u in sorted(units.items()) if set(u) == set(CONDITIONS)]
        if not units:
            continue
        a = {c: np.array([[_first(u[c]), _per_trial(u[c]), 1e4 * u[c]["goals"] / u[c]["steps"],
                           u[c]["first_trial_steps"] is not None] for u in units], float)
             for c in CONDITIONS}
        per_pt = {c: np.array([[u[c]["first_trial_steps"] or np.nan,
                                u[c]["steps_per_trial"] or np.nan] for u in units])
                  for c in CONDITIONS}

        def stats(idx):
            r, v = a["random"][idx], a["avoidance"][idx]
            out = {"first_gain": r[:, 0].mean() / v[:, 0].mean(),
                   "trial_gain": r[:, 1].mean() / v[:, 1].mean(),
                   "goal_gain": v[:, 2].mean() - r[:, 2].mean()}
            for c in CONDITIONS:
                pairs = per_pt[c][idx]
                pairs = pairs[~np.isnan(pairs).any(axis=1)]
                out[f"shrink_{c}"] = (pairs[:, 1].mean() / pairs[:, 0].mean()
                                      if len(pairs) else np.nan)
            return out

        n = len(units)
        point = stats(np.arange(n))
        rng = np.random.default_rng(BOOTSTRAP_SEED)
        draws = [stats(rng.integers(0, n, n)) for _ in range(BOOTSTRAP_SAMPLES if n > 1 else 0)]
        row = {"robot": robot, "size": f"{size[0]}x{size[1]}", "units": n,
               "shortest": float(np.mean([u["random"]["shortest"] for u in units])),
               "steps": float(np.mean([u["random"]["steps"] for u in units])),
               "reached": {c: int(a[c][:, 3].sum()) for c in CONDITIONS},
               "first": {c: float(a[c][:, 0].mean()) for c in CONDITIONS},
               "per_trial": {c: float(a[c][:, 1].mean()) for c in CONDITIONS},
               "goals": {c: float(a[c][:, 2].mean()) for c in CONDITIONS}}
        for key, value in point.items():
            values = np.array([d[key] for d in draws], float)
            values = values[np.isfinite(values)]
            ci = (None if len(values) < 2 else
                  [float(x) for x in np.percentile(values, [2.5, 97.5])])
            row[key] = {"mean": None if not np.isfinite(value) else float(value), "ci95": ci}
        rows.append(row)
    return rows


def _ci(s, digits=1, pct=False):
    def f(v):
        return f"{v:.0%}" if pct else f"{v:,.{digits}f}"
    if s["mean"] is None:
        return "-"
    return f(s["mean"]) + (f" [{f(s['ci95'][0])}, {f(s['ci95'][1])}]" if s["ci95"] else "")


def table(rows):
    lines = ["| robot | maze (cells) | mazes x seeds | shortest path (cells) | budget (steps) | "
             "first trials reached (random / avoidance) | first-trial gain (random / avoidance) | "
             "steps-per-trial gain | goals per 10k steps gained | shrink, random | "
             "shrink, avoidance |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(
            f"| {r['robot']} | {r['size']} | {r['units']} | {r['shortest']:.0f} | {r['steps']:,.0f} "
            f"| {r['reached']['random']}/{r['units']} / {r['reached']['avoidance']}/{r['units']} "
            f"| {_ci(r['first_gain'])}x | {_ci(r['trial_gain'])}x | {_ci(r['goal_gain'])} "
            f"| {_ci(r['shrink_random'], pct=True)} | {_ci(r['shrink_avoidance'], pct=True)} |")
    return "\n".join(lines)


def figure(rows, path):
    """Gains against the mean shortest path, one line per robot, with 95% intervals."""
    from experiments.outputs.plots import pyplot, save
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(11, 3.4))
    for ax, key, title in zip(axes, ("first_gain", "trial_gain", "goal_gain"),
                              ("first-trial steps, random / avoidance",
                               "steps per trial, random / avoidance",
                               "goals per 10k steps, avoidance - random")):
        for robot, colour in zip(ROBOTS, ("tab:blue", "tab:orange")):
            mine = [r for r in rows if r["robot"] == robot and r[key]["mean"] is not None]
            if not mine:
                continue
            x = [r["shortest"] for r in mine]
            y = [r[key]["mean"] for r in mine]
            err = np.array([[m - (r[key]["ci95"] or [m, m])[0], (r[key]["ci95"] or [m, m])[1] - m]
                            for m, r in zip(y, mine)]).T
            ax.errorbar(x, y, yerr=err, marker="o", capsize=3, color=colour, label=robot)
            for xi, yi, r in zip(x, y, mine):
                ax.annotate(r["size"], (xi, yi), fontsize=7, xytext=(3, 3),
                            textcoords="offset points")
        ax.axhline(0.0 if key == "goal_gain" else 1.0, color="0.6", lw=0.8)
        ax.set_title(title, fontsize=9)
        ax.set_xlabel("shortest path (cells)")
    axes[0].legend(fontsize=8)
    fig.suptitle("the avoidance behaviour's gain against the maze's size (95% intervals)")
    save(fig, path)


#: What mazes.json keeps of each complete run (its metrics in run.json): the data behind
#: the table and the figure, a few dozen bytes a run, so a study's record can be committed.
RUN_FIELDS = ("first_trial_steps", "steps_per_trial", "goals", "steps", "shortest")


def runs(out, specs):
    """Each complete run's RUN_FIELDS, one row a run: robot, size, maze, seed, condition."""
    return [{"robot": robot, "size": f"{size[0]}x{size[1]}", "maze": maze, "seed": seed,
             "condition": condition, **{k: metrics[k] for k in RUN_FIELDS}}
            for (robot, size), units in sorted(_units(out, specs).items())
            for (maze, seed), by_condition in sorted(units.items())
            for condition, metrics in sorted(by_condition.items())]


def write(out, specs, sizes, mazes, seeds, per_cell):
    """MAZES.md, mazes.json (the rows of the table and each run's record, `runs`) and
    figures/mazes.png under out; returns MAZES.md's path."""
    out = pathlib.Path(out)
    rows = summarize(out, specs)
    (out / "figures").mkdir(exist_ok=True)
    figure(rows, out / "figures" / "mazes.png")
    results.atomic_write(out / "mazes.json", results.dumps(
        {"sizes": [f"{w}x{h}" for w, h in sizes], "mazes": mazes, "seeds": seeds,
         "steps_per_cell": per_cell, "rows": rows, "runs": runs(out, specs)}))
    text = "\n".join([
        f"# The maze study: {out}", "",
        f"Sizes {', '.join(f'{w}x{h}' for w, h in sizes)}; {mazes} mazes per size, {seeds} "
        f"seeds per maze; budget {per_cell:,} steps per cell of the shortest path. Gains "
        "are ratios of means over (maze, seed) units; 95% percentile bootstrap intervals "
        "resampling them. A run that reached no goal counts its budget as its first trial "
        "(and steps per trial): a lower bound.", "", table(rows), "",
        "![gains against the maze's size](figures/mazes.png)", ""])
    results.atomic_write(out / "MAZES.md", text)
    return out / "MAZES.md"


def publish(out, results_md, figures_dir):
    """RESULTS.md's maze-study block (between BEGIN and END): the table, the figure."""
    from experiments.outputs import report
    out = pathlib.Path(out)
    report.copy(out / "figures" / "mazes.png", pathlib.Path(figures_dir) / "mazes.png")
    text = (out / "MAZES.md").read_text().split("\n", 2)[2]
    block = text.replace("](figures/", f"]({pathlib.Path(figures_dir).as_posix()}/")
    report.replace_block(results_md, BEGIN, END, [BEGIN, block.strip(), END])
    return results_md
