"""The report's plots (the paper's Figures 2-5 made from our runs, and its first-trial
and learned steps beside Section 3.6's) and what every plot of the tool shares: the room
drawn in paper units, a legend below it, log axes with plain labels, and one save that
lays a figure out and writes it atomically."""
import functools
import pathlib

import numpy as np

from experiments import paper
from experiments.running import results
from models import rooms
from tasks.robots import DRIVES


@functools.cache
def _room_layout(room=None):
    """The room's layout from its map (models.rooms.layout), once per room."""
    return rooms.layout(room)


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
        ref = [(paper.reported(g) or {}).get(key, {}).get("mean") for g in groups]
        ax.plot(x + off, [np.nan if v is None else v for v in ref], "k_", ms=18, mew=2,
                label=f"paper: {label}" if off < 0 else None)
    ax.plot([], [], "k_", ms=18, mew=2, label="paper: steps per trial")
    log_y(ax)
    ax.set_xticks(x, [f"{g['robot']}\n{g['condition']}" for g in groups])
    ax.set_ylabel("steps")
    ax.legend(fontsize=7, ncol=2)
    save(fig, path)
