"""Rooms as maps (models.rooms): the paper's room is the map `sutton`, the parser reads
hand-made maps and refuses bad ones in one line, random mazes are reachable, and robots
run, render and report in other rooms. (That a run in `sutton` is today's run bit for
bit: tests/test_robots.py's planar traces and tests/test_step_digests.py.)"""
import json

import numpy as np
import pytest

import models
import tasks
from experiments.outputs import optimal, rendering
from experiments.running import aggregate, execution, results, runner
from helpers import ebrl_here
from models import UNIT, rooms


def test_sutton_is_the_papers_room():
    """Section 3.1's room, written out here: 9 x 6 cells of 10 units, obstacles x 20-30 by
    y 20-50, x 50-60 by y 10-20, x 70-80 by y 30-60; the goal the top-right cell; the
    start 5 units from the left, 25 below the top, heading east."""
    field, obstacles, goal, start = models.room_layout(models.room_model("sutton"))
    assert field == (0.0, 90.0, 0.0, 60.0)
    assert sorted(obstacles) == [(20.0, 30.0, 20.0, 50.0), (50.0, 60.0, 10.0, 20.0),
                                 (70.0, 80.0, 30.0, 60.0)]
    assert goal == (80.0, 90.0, 50.0, 60.0)
    assert start == (5.0, 35.0, 0.0)
    assert models.room_model().ngeom == models.room_model("sutton").ngeom == 8


HAND_MADE = """# a hand-made map
# cell 20
*******
*P    *
* *** *
*   *G*
*******
"""


def test_a_hand_made_map():
    m = rooms.parse(HAND_MADE, "hand.txt")
    assert (m.width, m.height, m.cell) == (5, 3, 20.0)
    assert m.start == (0, 2) and m.goal == (4, 0)
    assert m.shortest_cells() == 6  # east along the top, then down the east column
    assert rooms.merged_walls(m) == [(1, 4, 1, 2), (3, 4, 0, 1)]  # one bar, one stub
    field, obstacles, goal, start = models.room_layout(models.room_model(m))
    assert field == (0.0, 100.0, 0.0, 60.0)
    assert sorted(obstacles) == [(20.0, 80.0, 20.0, 40.0), (60.0, 80.0, 0.0, 20.0)]
    assert goal == (80.0, 100.0, 0.0, 20.0)
    assert start == (10.0, 50.0, 0.0)


@pytest.mark.parametrize("text, words", [
    ("*****\n*P  *\n*****\n", "no 'G' cells"),
    ("*****\n* G *\n*****\n", "no 'P' cells"),
    ("******\n*PGG *\n******\n", "2 'G' cells"),
    ("*****\n*P*G*\n*****\n", "the goal cannot be reached"),
    ("*****\n*P x*\n*G  *\n*****\n", "line 2: unknown character 'x'"),
    ("*****\n*P G*\n****\n", "not a rectangle: line 3 has 4 cells"),
    ("*****\n P G*\n*****\n", "line 2: the border must be all walls"),
    ("# cell -3\n*****\n*P G*\n*****\n", "line 1: '# cell' needs a positive number"),
    ("# cell 11\n" + "*" * 32 + "\n*P" + " " * 28 + "G*\n" + "*" * 32 + "\n", "wider than"),
])
def test_a_bad_map_is_one_line_naming_its_file(text, words):
    with pytest.raises(rooms.MapError) as e:
        rooms.parse(text, "maps/bad.txt")
    assert str(e.value).startswith("maps/bad.txt: ") and words in str(e.value)
    assert "\n" not in str(e.value)


@pytest.mark.slow
def test_bad_maps_on_the_command_line(tmp_path):
    """Exit 2 and one line naming the file, before any work: a bad character (at
    parsing), and a corridor narrower than the robot (composing the robot in)."""
    for robot, text, words in (("two_wheel", "*****\n*P?G*\n*****\n", "unknown character '?'"),
                               ("floating", "# cell 2.5\n*****\n*P G*\n*****\n",
                                "narrower than the robot")):
        bad = tmp_path / f"{robot}.txt"
        bad.write_text(text)
        proc = ebrl_here("run", "--robot", robot, "--room", bad, "--out", tmp_path / "out")
        assert proc.returncode == 2 and not (tmp_path / "out").exists()
        assert len(proc.stderr.strip().splitlines()) == 1
        assert str(bad) in proc.stderr and words in proc.stderr


@pytest.mark.parametrize("size", [(9, 6), (21, 21), (4, 7)])
def test_random_mazes_are_reachable_and_drawn_by_their_seed(size):
    for seed in range(3):
        name = f"random:{size[0]}x{size[1]}:{seed}"
        m = rooms.load(name)
        assert (m.width, m.height) == size
        again = rooms.parse(m.text(), name)  # its text is a valid map: one P, one G, reachable
        assert again.rows == m.rows == rooms.random_map(*size, seed).rows
        free = {(c, r) for c in range(m.width) for r in range(m.height) if not m.wall(c, r)}
        assert set(rooms.reachable(m)) == free  # every free cell reachable
        assert m.shortest_cells() == max(rooms.reachable(m).values())  # the farthest cell
    assert rooms.load("random:21x21:0").rows != rooms.load("random:21x21:1").rows


@pytest.mark.slow
def test_a_room_is_part_of_a_runs_record_and_folder(tmp_path):
    spec = execution.RunSpec("two_wheel", "avoidance", 0, 60, room="u_maze")
    paper = execution.RunSpec("two_wheel", "avoidance", 0, 60, room="sutton")
    assert paper.room is None and paper == execution.RunSpec("two_wheel", "avoidance", 0, 60)
    assert spec.label == "two_wheel@u_maze" and paper.label == "two_wheel"
    assert spec.parameters()["room"] == "u_maze" and "room" not in paper.parameters()
    assert spec.parameters()["model_sha256"] != paper.parameters()["model_sha256"]
    assert execution.RunSpec("two_wheel", "avoidance", 0, 1, room="random:9x6:3").label \
        == "two_wheel@random-9x6-3"
    ran = runner.run([spec, paper], tmp_path, workers=1, progress=False)
    assert ran.made == 2 and not ran.failed
    runs = results.load_runs(tmp_path)
    assert {k[0] for k in runs} == {"two_wheel", "two_wheel@u_maze"}
    assert set(results.load_runs(tmp_path, room="u_maze")) == {("two_wheel@u_maze", "avoidance", 0)}
    assert set(results.load_runs(tmp_path, room=None)) == {("two_wheel", "avoidance", 0)}
    groups = aggregate.summarize(runs)["groups"]
    assert {g["robot"]: g.get("room") for g in groups} == {"two_wheel": None,
                                                           "two_wheel@u_maze": "u_maze"}
    # A trace stays inside its own room's field.
    trace = np.load(tmp_path / "two_wheel@u_maze" / "avoidance" / "seed_000" / "trace.npz")
    xy = trace["trace"] / trace["scale"]
    assert xy[:, 0].max() < 30 and xy[:, 1].max() < 30
    assert json.loads((tmp_path / "two_wheel@u_maze" / "avoidance" / "seed_000" / "config.json")
                      .read_text())["room"] == "u_maze"


@pytest.mark.parametrize("robot, room", [("two_wheel", "medium"), ("floating", "random:9x6:1"),
                                         ("diff_drive", "random:9x6:1")])
def test_robots_run_and_render_in_other_rooms(robot, room):
    """A short run in a Gymnasium-Robotics map and a random maze; the start, the goal and
    the top camera follow the map."""
    m = rooms.load(room)
    env = tasks.load(robot, seed=0, room=room)
    try:
        physics = env.physics
        sc, sr = m.start
        assert physics.start[:2] == ((sc + 0.5) * m.cell, (sr + 0.5) * m.cell)
        (x0, y0), (x1, y1) = physics.goal_box
        gc, gr = m.goal
        assert (x0, y0, x1, y1) == (gc * m.cell, gr * m.cell, (gc + 1) * m.cell, (gr + 1) * m.cell)
        env.reset()
        for _ in range(40):
            env.step(np.zeros(env.action_spec().shape))
        x, y, _ = physics.robot_pose()
        assert 0 < x < m.width * m.cell and 0 < y < m.height * m.cell
        frame = rendering.frame(physics)
        assert frame.shape == (rendering.HEIGHT, rendering.WIDTH, 3) and frame.std() > 5
        # The top camera frames the whole field.
        mj, d = physics.model.ptr, physics.data.ptr
        cam = mj.camera("top").id
        axes = d.cam_xmat[cam].reshape(3, 3)
        f = (rendering.HEIGHT / 2) / np.tan(np.radians(mj.cam_fovy[cam]) / 2)
        for corner in ((0, 0), (m.width * m.cell, m.height * m.cell)):
            cx, cy, cz = axes.T @ (np.array([*corner, 0.0]) * UNIT - d.cam_xpos[cam])
            assert abs(f * cy / cz) < rendering.HEIGHT / 2 and abs(f * cx / cz) < rendering.WIDTH / 2
    finally:
        env.close()
    result = execution.execute(execution.RunSpec(robot, "avoidance", 0, 150, room=room))
    assert len(result["trace"]) == 151


def test_the_optimal_path_follows_the_map():
    """In the U-maze the shortest path runs round the bar: longer than the straight line
    from start to goal, shorter than the cells' Manhattan walk."""
    best = optimal.optimal("two_wheel", room="u_maze")
    straight = 20.0 - 5.0  # from the start cell's centre to the goal cell's near edge
    assert straight < best["length"] < 6 * 10.0
    assert best["path"][:, 0].max() > 20.0  # it goes round the bar's east end


@pytest.mark.slow
def test_rooms_lists_the_shipped_maps():
    proc = ebrl_here("rooms", check=True)
    for name in rooms.MAPS:
        assert f"\n{name} " in proc.stdout
    assert "random:WxH:SEED" in proc.stdout


@pytest.mark.slow
def test_the_maze_study_runs_its_budget_rule_and_writes_its_table(tmp_path):
    """A tiny maze study: the budget is the rule's, every (maze, seed) unit of every size
    comes before the next seed's, and MAZES.md has a row per robot and size."""
    from experiments.studies import mazes
    sizes = ((5, 5), (7, 4))
    specs = mazes.plan(sizes, mazes=1, seeds=2, per_cell=15)
    assert len(specs) == 2 * 2 * 2 * 2
    assert [s.seed for s in specs] == [0] * 8 + [1] * 8
    for s in specs:
        assert s.steps == 15 * rooms.load(s.room).shortest_cells()
    ran = mazes.run(tmp_path, specs, workers=1, progress=False)
    assert ran.made == len(specs) and not ran.failed
    path = mazes.write(tmp_path, specs, sizes, 1, 2, 15)
    record = json.loads((tmp_path / "mazes.json").read_text())
    rows = record["rows"]
    assert {(r["robot"], r["size"]) for r in rows} == {
        (robot, size) for robot in mazes.ROBOTS for size in ("5x5", "7x4")}
    assert all(r["units"] == 2 for r in rows)
    # each run's record: what its run.json says, one row a run
    assert len(record["runs"]) == len(specs)
    for r in record["runs"]:
        spec = next(s for s in specs if (s.robot, s.condition, s.seed, s.room) == (
            r["robot"], r["condition"], r["seed"], f"random:{r['size']}:{r['maze']}"))
        made = results.read_run_json(results.run_dir(tmp_path, spec) / "run.json")["metrics"]
        assert r["goals"] == made["goals"] and r["steps"] == spec.steps
        assert r["first_trial_steps"] == made["first_trial_steps"]
    text = path.read_text()
    assert "| two_wheel | 7x4 | 2 |" in text and (tmp_path / "figures" / "mazes.png").stat().st_size > 0


@pytest.mark.slow
def test_a_command_compiles_each_robot_once_in_its_process(tmp_path, monkeypatch):
    """`ebrl run` in a room compiles each robot's model once in its own process (issue 60,
    item 6): the room's check, the runs' parameters (the model's digest) and the report's
    yardstick (the robot's radius) read one tasks.compiled_model; the workers compile
    their own."""
    import tasks.environment
    compiled = []
    real = tasks.environment.compile_robot

    def counted(entry, *args, **kwargs):
        compiled.append(entry.name)
        return real(entry, *args, **kwargs)

    monkeypatch.setattr(tasks.environment, "compile_robot", counted)
    tasks.compiled_model.cache_clear()
    proc = ebrl_here("run", "--robot", "paper", "--room", "u_maze", "--seeds", "0", "--steps",
                     "100", "--workers", "1", "--no-progress", "--out", tmp_path / "out")
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "out" / "REPORT.md").exists()
    assert sorted(compiled) == ["floating", "two_wheel"]
