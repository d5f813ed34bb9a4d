"""Issue 48, item 6: why our two-wheel random walk reaches the goal sooner than the paper's.

    .venv/bin/python -m experiments.studies.walk --seeds 7000-7099 --out walk

Four measurements of the two-wheel random walk under Section 3.4's Gaussian demand (mean 0,
sd 0.5, clipped to Section 3.3's (-1, 1)), each printed as a markdown table and written to
OUT/walk.json:

1. **What Section 3.3 implies per step** (`implied`): the commanded turn |a| rad and move
   2 (1 - |a|) units, each discounted by up to 5% (uniform), for the clipped Gaussian a.
2. **What the body does per step** (`body`): the planar robot in MuJoCo (tasks.load, the
   compiled step), driven by Gaussian demands from its first step until the goal (or
   `--steps`): the distance it actually moves, the turn it actually takes, the share of
   steps blocked at a wall (a move short of its command by more than the drive's 0.1-unit
   tolerance), and the share of the room's free cells (2 x 2 units) its centre has visited
   at 500, 1,000, 2,000 and 4,000 steps (a walk that reached the goal keeps its coverage).
3. **The same walk as ideal kinematics** (`kinematic`): a disc in the same room that turns,
   moves straight until it touches a wall, turns the rest of the move (1 rad per 2 units,
   the commanded way) and halts: Section 3.3 with no physics at all; and the same with the
   goal removed, for coverage over time.
4. **The first trial** (the protocol's own runs, `ebrl run --first-trial` as
   `experiments.studies.grid` makes them): every open body value of the two-wheel robot
   (radius, blocked_move, leftover_turn) on the seeds, against the paper's 6,087 +- 5,789
   over 49 of 50 runs (Welch's test), beside the kinematic walk's.

The body's numbers (2) and the first trials (4) are the real simulator's; (3) is the
yardstick that tells the physics from the text.
"""
import argparse
import json
import math
import pathlib
import sys

import numpy as np
from numba import njit

import tasks
from ebrl import compiled  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from experiments import paper
from experiments.commands.arguments import seeds as parse_seeds
from experiments.outputs import verdicts
from experiments.running.execution import seeds_for
from experiments.studies import grid
from tasks.robots import ROBOTS

BUDGET = 30_000
SD = 0.5          # Section 3.4
NOISE = 0.05      # Section 3.3: "maximum 5% discount"
MAX_TURN, MAX_MOVE, TOLERANCE = 1.0, 2.0, 0.1
FIELD = (90.0, 60.0)
BLOCKS = np.array([[20, 30, 20, 50], [50, 60, 10, 20], [70, 80, 30, 60]], dtype=np.float64)
GOAL = (80.0, 90.0, 50.0, 60.0)
START, JITTER_XY, JITTER_HEADING = (5.0, 35.0), 3.0, math.radians(15)
CELL = 2.0
COVERAGE_AT = (500, 1000, 2000, 4000)
#: The body values of the first-trial grid (4): the radius from a robot with its seven
#: beams to one that half fills a 10-unit corridor; both readings of the blocked move.
RADII = (1.0, 1.367, 1.5, 2.0, 2.5, 3.0, 3.5)
GAUSSIAN = (("random_demand", "gaussian"),)


def clipped_gaussian(sd=SD, n=200_001):
    """E|a| and P(|a| = 1) of a = clip(N(0, sd), -1, 1), by quadrature."""
    z = np.linspace(-8 * sd, 8 * sd, n)
    w = np.exp(-0.5 * (z / sd) ** 2)
    w /= w.sum()
    a = np.minimum(np.abs(z), 1.0)
    return float((a * w).sum()), float(w[np.abs(z) >= 1.0].sum())


def implied(sd=SD):
    """Section 3.3's expected turn and move per step of the clipped Gaussian walk."""
    mean_abs, saturated = clipped_gaussian(sd)
    discount = 1.0 - NOISE / 2
    return {"turn": mean_abs * MAX_TURN * discount,
            "move": 2.0 * (1.0 - mean_abs) * discount,
            "saturated": saturated}


# -- the ideal kinematic walk --------------------------------------------------------------

@njit(cache=True)
def _clearance(x, y, r):
    """Smallest distance from the disc's surface to a wall (negative inside one)."""
    d = min(x, FIELD[0] - x, y, FIELD[1] - y) - r
    for k in range(BLOCKS.shape[0]):
        x0, x1, y0, y1 = BLOCKS[k]
        dx = max(x0 - x, 0.0, x - x1)
        dy = max(y0 - y, 0.0, y - y1)
        d = min(d, math.sqrt(dx * dx + dy * dy) - r)
    return d


@njit(cache=True)
def _advance(x, y, c, s, length, r):
    """How far along (c, s) the disc moves before it touches a wall, at most length."""
    step = 0.05
    t = 0.0
    while t < length:
        nxt = min(t + step, length)
        if _clearance(x + nxt * c, y + nxt * s, r) < 0.0:
            lo, hi = t, nxt
            for _ in range(30):
                mid = 0.5 * (lo + hi)
                if _clearance(x + mid * c, y + mid * s, r) < 0.0:
                    hi = mid
                else:
                    lo = mid
            return lo
        t = nxt
    return length


@njit(cache=True)
def _walk(seed, r, steps, sd, refuse, goal, trace, per):
    """One kinematic walk; returns the steps to the goal (or -1). trace[k]: the position
    after step k; per[k - 1]: step k's (moved, commanded, turned, blocked)."""
    np.random.seed(seed)
    x = START[0] + np.random.uniform(-JITTER_XY, JITTER_XY)
    y = START[1] + np.random.uniform(-JITTER_XY, JITTER_XY)
    h = np.random.uniform(-JITTER_HEADING, JITTER_HEADING)
    trace[0, 0], trace[0, 1] = x, y
    for k in range(1, steps + 1):
        a = min(1.0, max(-1.0, np.random.normal(0.0, sd)))
        turn = -a * MAX_TURN * np.random.uniform(1.0 - NOISE, 1.0)
        move = MAX_MOVE * (1.0 - abs(a)) * np.random.uniform(1.0 - NOISE, 1.0)
        sign = 1.0 if turn > 0 else -1.0
        h += turn
        c, s = math.cos(h), math.sin(h)
        made = _advance(x, y, c, s, move, r)
        blocked = move - made > TOLERANCE
        turned = abs(turn)
        if blocked:
            if refuse:
                made = 0.0
            h += sign * (move - made) * MAX_TURN / MAX_MOVE
            turned += (move - made) * MAX_TURN / MAX_MOVE
        x += made * c
        y += made * s
        trace[k, 0], trace[k, 1] = x, y
        per[k - 1, 0], per[k - 1, 1], per[k - 1, 2] = made, MAX_MOVE * (1.0 - abs(a)), turned
        per[k - 1, 3] = 1.0 if blocked else 0.0
        if goal and GOAL[0] <= x <= GOAL[1] and GOAL[2] <= y <= GOAL[3]:
            return k
    return -1


def kinematic(seeds, radius, steps=BUDGET, sd=SD, refuse=False, goal=True):
    """[(steps to the goal or None, trace, per-step (moved, commanded, turned, blocked))]
    of the kinematic walk, one per seed."""
    out = []
    for seed in seeds:
        trace, per = np.empty((steps + 1, 2)), np.empty((steps, 4))
        k = _walk(seed, radius, steps, sd, refuse, goal, trace, per)
        n = steps if k < 0 else k
        out.append((None if k < 0 else int(k), trace[: n + 1], per[:n]))
    return out


# -- coverage ------------------------------------------------------------------------------

def free_cells(radius):
    """Boolean grid of the CELL x CELL cells whose centre the robot's centre can occupy."""
    nx, ny = int(FIELD[0] / CELL), int(FIELD[1] / CELL)
    ok = np.zeros((nx, ny), dtype=bool)
    for i in range(nx):
        for j in range(ny):
            ok[i, j] = _clearance((i + 0.5) * CELL, (j + 0.5) * CELL, radius) >= 0.0
    return ok


def coverage(trace, free, at=COVERAGE_AT):
    """Share of the free cells the path has crossed by each step in `at` (the path's last
    coverage after it ends), the path sampled every 0.25 units between positions."""
    trace = np.asarray(trace, dtype=np.float64)
    seen = np.zeros_like(free)
    out, k = [], 0
    total = free.sum()
    for end in at:
        while k < min(end, len(trace) - 1):
            p, q = trace[k], trace[k + 1]
            n = max(1, int(math.ceil(np.hypot(*(q - p)) / 0.25)))
            pts = p + np.outer(np.linspace(0, 1, n + 1), q - p)
            i = np.clip((pts[:, 0] // CELL).astype(int), 0, free.shape[0] - 1)
            j = np.clip((pts[:, 1] // CELL).astype(int), 0, free.shape[1] - 1)
            seen[i, j] = True
            k += 1
        out.append(float((seen & free).sum() / total))
    return out


# -- the body in MuJoCo --------------------------------------------------------------------

def body(seeds, task_overrides=(), steps=BUDGET, sd=SD):
    """Per-step records of the planar two-wheel robot (its registry entry with
    task_overrides) driven by clipped Gaussian demands until the goal or `steps`:
    {"moved", "commanded", "turned", "blocked", "first", "coverage"} over every step of
    every seed (first: steps to the goal or None per seed)."""
    entry = ROBOTS["two_wheel"]
    config = entry.task_config(**dict(task_overrides))
    radius = config.radius or 1.5
    free = free_cells(radius)
    moved, commanded, turned, blocked, first, cover = [], [], [], [], [], []
    for seed in seeds:
        env = tasks.load(entry, seed=seeds_for(seed)[0], config=config)
        rng = np.random.default_rng(seed)
        env.reset()
        x, y, h = env.physics.robot_pose()
        trace, reached = [(x, y)], None
        for k in range(1, steps + 1):
            a = float(np.clip(rng.normal(0.0, sd), -1.0, 1.0))
            ts = env.step(np.array([a]))
            x1, y1, h1 = env.physics.robot_pose()
            cmd = MAX_MOVE * (1.0 - abs(a))
            made = math.hypot(x1 - x, y1 - y)
            moved.append(made)
            commanded.append(cmd)
            turned.append(abs(math.remainder(h1 - h, 2 * math.pi)))
            blocked.append(cmd * (1.0 - NOISE) - made > TOLERANCE)
            trace.append((x1, y1))
            x, y, h = x1, y1, h1
            if ts.last():
                reached = k
                break
        env.close()
        first.append(reached)
        cover.append(coverage(trace, free))
    return {"moved": np.array(moved), "commanded": np.array(commanded),
            "turned": np.array(turned), "blocked": np.array(blocked), "first": first,
            "coverage": np.array(cover)}


def per_step(record):
    """A body's or kinematic walk's per-step means: moved, commanded, turned, blocked."""
    return {"moved": float(record["moved"].mean()),
            "commanded": float(record["commanded"].mean() * (1 - NOISE / 2)),
            "turned": float(record["turned"].mean()),
            "blocked": float(record["blocked"].mean())}


def kinematic_record(seeds, radius, steps=BUDGET, sd=SD, refuse=False, goal=True):
    """The kinematic walk's record, as `body` gives the MuJoCo one."""
    free = free_cells(radius)
    per, first, cover = [], [], []
    for k, trace, steps_of in kinematic(seeds, radius, steps, sd, refuse, goal):
        per.append(steps_of)
        first.append(k)
        cover.append(coverage(trace, free))
    per = np.concatenate(per)
    return {"moved": per[:, 0], "commanded": per[:, 1], "turned": per[:, 2],
            "blocked": per[:, 3] > 0, "first": first, "coverage": np.array(cover)}


def wall_ideal(deg, gap=0.1):
    """Section 3.3's kinematics for wall_test's move: (along the wall, towards it, turn):
    gap / tan(angle) along, gap towards, and the rest of the 2 units, 2 - gap / sin(angle),
    turned at 1 rad per 2 units."""
    a = math.radians(deg)
    return gap / math.tan(a), gap, (MAX_MOVE - gap / math.sin(a)) * MAX_TURN / MAX_MOVE


def wall_test(angles=(90, 60, 45, 30, 15, 5), gap=0.1, task_overrides=(), protocol="adopted",
              robot="two_wheel"):
    """What one full move (a = 0, no noise) does to a two-wheel robot (a name or file
    tasks.load takes) whose hull is started `gap` units from the bottom wall, heading into
    it at each angle (degrees), under a protocol's readings and the overrides: {angle:
    (distance made along the wall, distance made towards it, turn taken)}; Section 3.3's
    kinematics: wall_ideal."""
    import mujoco

    entry = tasks.resolve(robot).under(protocol)
    config = entry.task_config(**(dict(task_overrides) | {"action_noise": 0.0,
                                                          "sensor_noise": 0.0}))
    env = tasks.load(entry, seed=0, config=config)
    env.reset()
    r = env.physics.robot_radius
    out = {}
    for deg in angles:
        h = -math.radians(deg)
        env.physics.set_robot_pose(40.0, r + gap, h)
        mujoco.mj_forward(env.physics.model.ptr, env.physics.data.ptr)
        x0, y0, h0 = env.physics.robot_pose()
        env.step(np.array([0.0]))
        x1, y1, h1 = env.physics.robot_pose()
        out[deg] = (x1 - x0, y0 - y1, abs(math.remainder(h1 - h0, 2 * math.pi)))
    env.close()
    return out


# -- the first trials ---------------------------------------------------------------------

def against_paper(first, budget=BUDGET):
    """Our first trials (None: not reached) against the paper's two-wheel random walk:
    mean, sd, reached of n, and Welch's two-sided p (verdicts.welch)."""
    s = grid.summary(first, budget)
    ref = paper.FIRST_TRIALS[("two_wheel", "random")]
    p = (verdicts.welch(s["mean"], s["sd"], s["reached"], ref["mean"], ref["sd"],
                        ref["reached"])["p"] if s["sd"] else None)
    return dict(s, ratio=s["mean"] / ref["mean"] if s["mean"] else None, welch_p=p)


def first_trial_grid(out, seeds, workers=1):
    """The protocol's first-trial runs of the random walk at every body value (RADII x
    blocked_move x leftover_turn), Gaussian demand: {setting name: against_paper}."""
    settings = [GAUSSIAN + s for s in grid.product(
        radius=RADII, blocked_move=("stop", "refuse"), leftover_turn=("commanded", "away"))]
    runs = grid.run(out, "two_wheel", settings, ("random",), seeds, workers=workers)
    return {grid.name(s[1:]): against_paper(grid.first_trials(r, "random"))
            for s, r in runs.items()}


def table(rows, columns):
    """A markdown table of {name: {column: value}} rows."""
    lines = ["| setting | " + " | ".join(columns) + " |",
             "|---|" + "---:|" * len(columns)]
    for name, row in rows.items():
        cells = []
        for c in columns:
            v = row.get(c)
            cells.append("-" if v is None else (f"{v:,.3f}" if isinstance(v, float) and abs(v) < 10
                                                else f"{v:,.0f}" if isinstance(v, float) else str(v)))
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


#: The bodies measured per step: the literal one (the file's radius 1.5, the move stopped
#: at contact, the rest turned the commanded way), the same with the blocked move refused,
#: and protocol 6's (radius 1.367, the rest turned away from the nearer side).
#: Every body value is given, so that the registry's own (whatever protocol) never enters.
BODIES = {"literal (1.5, stop, commanded)": (("radius", 1.5), ("blocked_move", "stop"),
                                             ("leftover_turn", "commanded")),
          "refuse (1.5, refuse, commanded)": (("radius", 1.5), ("blocked_move", "refuse"),
                                              ("leftover_turn", "commanded")),
          "protocol 6 (1.367, stop, away)": (("radius", 1.366638388002404),
                                             ("blocked_move", "stop"), ("leftover_turn", "away"))}
PER_STEP = ["moved", "commanded", "turned", "blocked", "cover@1000", "cover@4000", "mean",
            "sd", "reached", "ratio", "welch_p"]


def _row(record):
    cover = {f"cover@{k}": float(v) for k, v in zip(COVERAGE_AT, record["coverage"].mean(axis=0))}
    return dict(per_step(record), **cover, **against_paper(record["first"]))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=parse_seeds, default=list(range(7000, 7100)))
    p.add_argument("--out", type=pathlib.Path, default=pathlib.Path("walk"))
    p.add_argument("--workers", type=int, default=1)
    p.add_argument("--body-seeds", type=int, default=30,
                   help="seeds of the per-step MuJoCo measurement: the first N of --seeds")
    args = p.parse_args(argv)
    seeds = args.seeds
    report = {"implied": implied(), "seeds": [min(seeds), max(seeds), len(seeds)]}
    print("## 1. Section 3.3 per step, the clipped Gaussian demand (sd 0.5)\n")
    print(", ".join(f"{k} {v:.3f}" for k, v in report["implied"].items()))
    report["wall"] = {name: {str(k): v for k, v in wall_test(task_overrides=over).items()}
                      for name, over in (("stop", BODIES["literal (1.5, stop, commanded)"]),
                                         ("refuse", BODIES["refuse (1.5, refuse, commanded)"]))}
    print("\n## One full move (a = 0) from 0.1 units off a wall: (along it, towards it, turn)\n")
    for name, rows in report["wall"].items():
        print(f"- MuJoCo, {name}: " + "; ".join(f"{k} deg: {a:.2f}, {b:.2f}, {c:.2f}"
                                                for k, (a, b, c) in rows.items()))
    ideal = {k: (0.1 / math.tan(math.radians(k)), 0.1, (2 - 0.1 / math.sin(math.radians(k))) / 2)
             for k in (90, 60, 45, 30, 15, 5)}
    print("- Section 3.3 (kinematic): " + "; ".join(f"{k} deg: {a:.2f}, {b:.2f}, {c:.2f}"
                                                    for k, (a, b, c) in ideal.items()))
    rows = {f"MuJoCo, {name}": _row(body(seeds[: args.body_seeds], over))
            for name, over in BODIES.items()}
    for refuse in (False, True):
        rows[f"kinematic, 1.5, {'refuse' if refuse else 'stop'}"] = _row(
            kinematic_record(seeds, 1.5, refuse=refuse))
    rec = kinematic_record(seeds[: args.body_seeds], 1.5, steps=max(COVERAGE_AT), goal=False)
    rows["kinematic, 1.5, stop, no goal"] = dict(
        per_step(rec), **{f"cover@{k}": float(v) for k, v in zip(COVERAGE_AT, rec["coverage"].mean(axis=0))})
    report["per_step"] = rows
    print(f"\n## 2-3. Per step and the first trial (MuJoCo on {args.body_seeds} seeds, "
          f"kinematic on {len(seeds)})\n")
    print(table(rows, PER_STEP))
    report["kinematic_radius"] = {f"kinematic, {r}, {'refuse' if f else 'stop'}": against_paper(
        [k for k, _, _ in kinematic(seeds, r, refuse=f)]) for r in RADII for f in (False, True)}
    report["grid"] = first_trial_grid(args.out / "runs", seeds, args.workers)
    print("\n## 4. The protocol's first trials at every body value (Gaussian walk), and the "
          "kinematic walk's\n")
    print(table(report["grid"] | report["kinematic_radius"],
                ["mean", "sd", "median", "reached", "ratio", "welch_p"]))
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "walk.json").write_text(json.dumps(report, indent=2, sort_keys=True) + "\n")
    print(f"\nwritten: {args.out / 'walk.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
