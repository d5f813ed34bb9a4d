"""Pictures in any room: a video frame's legend, caption and label, and the traces figure's
legends, never cover the start or the goal, in rooms whose goal sits where a legend used to
go (maps written here, `--room FILE`)."""
import numpy as np
import pytest

import helpers
import models
import tasks
from ebrl.agent import DECIDERS
from experiments.outputs import overlays as geometry
from experiments.outputs import plots, rendering
from experiments.running import results

#: The slow tier (pyproject.toml's markers): frames rendered and runs made.
pytestmark = pytest.mark.slow

H, W = rendering.HEIGHT, rendering.WIDTH

#: Two corridors in a 9 x 13 room, the start at the top left, the goal at the bottom right,
#: where the legend of a video frame sat.
CORRIDORS = """\
***********
*P        *
*         *
******    *
*         *
*         *
*    ******
*         *
*         *
******    *
*         *
*        G*
*         *
*         *
***********
"""
#: A small room whose runs reach the goal often: the goal at the bottom right, where the
#: traces figure's legends sat.
SMALL = """\
*******
*P    *
*     *
* **  *
*    G*
*******
"""


def flips(text):
    """The map and its mirror images: the start and the goal in each corner."""
    rows = text.splitlines()
    return {"as drawn": rows, "left-right": [r[::-1] for r in rows],
            "upside down": rows[::-1], "both": [r[::-1] for r in rows[::-1]]}


def changed(a, b):
    return np.abs(a.astype(int) - b.astype(int)).sum(axis=2) > 0


def site_pixels(physics, name, camera):
    """The pixels of a site as the camera shows it: a frame with the site recoloured
    against one without."""
    model = physics.model.ptr
    i = physics.model.name2id(name, "site")
    bare = rendering.frame(physics, camera=camera)
    rgba = model.site_rgba[i].copy()
    model.site_rgba[i] = (1.0, 0.0, 1.0, 1.0)
    try:
        shown = rendering.frame(physics, camera=camera)
    finally:
        model.site_rgba[i] = rgba
    return changed(shown, bare)


@pytest.mark.parametrize("flip", list(flips(CORRIDORS)))
def test_video_overlays_cover_neither_start_nor_goal(flip, tmp_path):
    path = tmp_path / "corridors.txt"
    path.write_text("\n".join(flips(CORRIDORS)[flip]) + "\n")
    env = tasks.load("two_wheel", seed=0, room=str(path))
    env.reset()
    physics = env.physics
    legend = [(f"{n} 25%", rendering.DECIDER_RGB[n]) for n in DECIDERS]
    overlays = dict(caption="step 12,345   trial 6   goals 5   chose: intrinsic",
                    label="avoidance", legend=legend)
    try:
        for camera in ("top", "perspective"):
            bare = rendering.frame(physics, camera=camera)
            covered = changed(rendering.frame(physics, camera=camera, **overlays), bare)
            goal, start = (site_pixels(physics, n, camera) for n in ("goal", "start"))
            assert goal.sum() > 200 and start.sum() > 50  # both in view
            assert covered.sum() > 5000  # three overlays drawn
            assert not (covered & goal).any(), f"{camera}: an overlay covers the goal"
            assert not (covered & start).any(), f"{camera}: an overlay covers the start"
            if flip == "as drawn" and camera == "top":
                # The room tells: the legend's usual corner (bottom right) holds the goal.
                left, bottom, right, top = geometry.box_at(
                    "legend", "bottom right", geometry.legend_size(len(legend)), H, W)
                assert goal[H - top:H - bottom, left:right].any()
    finally:
        env.close()


def test_placement_keeps_the_preferred_corners_where_they_are_free():
    sizes = {"legend": geometry.legend_size(4), "caption": (400, 33), "label": (100, 33)}
    assert geometry.place(sizes, [], H, W) == {
        "legend": "bottom right", "caption": "top left", "label": "bottom left"}
    # A goal in the bottom right: the legend to the bottom left, the label (whose corner
    # the legend took, and the goal the next) to the first free corner, the top right.
    got = geometry.place(sizes, [(W - 60, 20, W - 20, 60)], H, W)
    assert got == {"legend": "bottom left", "caption": "top left", "label": "top right"}
    # A goal clear of the label's box in the bottom right: the label goes there.
    got = geometry.place(sizes, [(W - 200, 45, W - 150, 90)], H, W)
    assert got == {"legend": "bottom left", "caption": "top left", "label": "bottom right"}
    # The start at the top left too: the caption to the top right.
    got = geometry.place(sizes, [(W - 60, 20, W - 20, 60), (20, H - 60, 60, H - 20)], H, W)
    assert got["caption"] == "top right" and got["legend"] == "bottom left"


def test_the_traces_figure_legends_cover_neither_start_nor_goal(tmp_path):
    room = tmp_path / "small.txt"
    room.write_text(SMALL)
    out = tmp_path / "results"
    helpers.ebrl_here("run", "--robot", "two_wheel", "--condition", "all", "--seeds", "0",
                      "--steps", "3000", "--room", room, "--workers", "1", "--no-progress",
                      "--out", out, check=True)
    runs = results.load_runs(out)
    label = "two_wheel@small"
    assert {c: r["metrics"]["goals"] >= 2 for (_, c, _), r in runs.items()} == {
        "random": True, "avoidance": True}  # each axes has its traces and legend
    fig = plots.traces_plot(out, runs, label)
    try:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        _, _, goal, start = models.room_layout(models.room_model(str(room)))
        half = (goal[1] - goal[0]) / 2, (goal[3] - goal[2]) / 2
        cells = {"goal": ((goal[0], goal[2]), (goal[1], goal[3])),
                 "start": ((start[0] - half[0], start[1] - half[1]),
                           (start[0] + half[0], start[1] + half[1]))}
        for ax in fig.axes:
            legend = ax.get_legend()
            assert legend is not None and len(legend.get_texts()) == 2
            box = legend.get_window_extent(renderer)
            for name, corners in cells.items():
                (x0, y0), (x1, y1) = ax.transData.transform(corners)
                assert box.x1 <= x0 or box.x0 >= x1 or box.y1 <= y0 or box.y0 >= y1, \
                    f"{ax.get_title()}: the legend covers the {name}"
            # The room tells: a legend at the lower right, as before, covered the goal.
            old = ax.legend(loc="lower right", fontsize=7).get_window_extent(renderer)
            (x0, y0), (x1, y1) = ax.transData.transform(cells["goal"])
            assert not (old.x1 <= x0 or old.x0 >= x1 or old.y1 <= y0 or old.y0 >= y1)
    finally:
        plots.pyplot().close(fig)
