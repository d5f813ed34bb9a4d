"""The optimal path as a yardstick for learned trials: how far a learned path is from the best.

Geometry: the shortest collision-free path of the robot's centre from the nominal
start to the goal square, in the room inflated by the robot's radius (rounded
corners, approximated by points on the arc), by Dijkstra over a visibility graph.

Steps under each robot's action limits, noise-free:
- two_wheel: a step turns t <= 1 rad and moves 2 (1 - t) units, so moving L units while
  turning Theta radians in all takes at least L / 2 + Theta steps: ceil(L / 2 + Theta)
  along the shortest path (Theta includes turning from the start heading).
- floating: each axis accelerates by at most 0.2 units/step per step, so along a unit
  direction u up to 0.2 / max(|ux|, |uy|). The fewest steps lie between two bounds:
  from below, accelerating at the diagonal's 0.2 sqrt(2) all the way (no braking: the
  trial ends on entering the goal) covers a n (n + 1) / 2 units in n steps; from above,
  stopping at every corner, a leg of L units takes 2 ceil(sqrt(L / a)) steps
  (accelerate then brake), a feasible plan. Ramming walls to stop lies in between.
"""
import functools
import heapq
import math

import numpy as np
import tasks
from models import rooms

ARC_POINTS = 6  # per rounded corner


def segment_box_distance(p, q, box):
    """Distance between segment pq and the axis-aligned box (x0, x1, y0, y1)."""
    x0, x1, y0, y1 = box
    # Intersection: Liang-Barsky clip.
    d = q - p
    t0, t1 = 0.0, 1.0
    for pk, qk in ((-d[0], p[0] - x0), (d[0], x1 - p[0]), (-d[1], p[1] - y0), (d[1], y1 - p[1])):
        if abs(pk) < 1e-12:
            if qk < 0:
                break
        else:
            t = qk / pk
            if pk < 0:
                t0 = max(t0, t)
            else:
                t1 = min(t1, t)
    else:
        if t0 <= t1:
            return 0.0

    def point_box(pt):
        dx = max(x0 - pt[0], 0.0, pt[0] - x1)
        dy = max(y0 - pt[1], 0.0, pt[1] - y1)
        return math.hypot(dx, dy)

    def point_segment(c):
        L2 = float(d @ d)
        t = 0.0 if L2 == 0 else min(max(float((c - p) @ d) / L2, 0.0), 1.0)
        return float(np.linalg.norm(p + t * d - c))

    corners = [np.array(c) for c in ((x0, y0), (x0, y1), (x1, y0), (x1, y1))]
    return min([point_box(p), point_box(q)] + [point_segment(c) for c in corners])


def segment_box_distances(p, qs, boxes):
    """segment_box_distance of the segments p -> each of qs (m, 2) and each box (k, 4):
    an (m, k) array, for many segments at once (the paths of a maze's many walls)."""
    p = np.asarray(p, dtype=float)
    qs = np.asarray(qs, dtype=float).reshape(-1, 2)[:, None, :]   # (m, 1, 2)
    b = np.asarray(boxes, dtype=float).reshape(-1, 4)[None]        # (1, k, 4)
    x0, x1, y0, y1 = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    d = qs - p                                                     # (m, 1, 2)
    dx, dy = d[..., 0], d[..., 1]
    t0 = np.zeros(np.broadcast_shapes(dx.shape, x0.shape))
    t1 = np.ones_like(t0)
    outside = np.zeros(t0.shape, bool)
    with np.errstate(divide="ignore", invalid="ignore"):
        for pk, qk in ((-dx, p[0] - x0), (dx, x1 - p[0]), (-dy, p[1] - y0), (dy, y1 - p[1])):
            pk, qk = np.broadcast_to(pk, t0.shape), np.broadcast_to(qk, t0.shape)
            flat = np.abs(pk) < 1e-12
            outside |= flat & (qk < 0)
            t = qk / pk
            t0 = np.where(~flat & (pk < 0), np.maximum(t0, t), t0)
            t1 = np.where(~flat & (pk > 0), np.minimum(t1, t), t1)
    crossing = ~outside & (t0 <= t1)

    def point_box(x, y):
        return np.hypot(np.maximum(np.maximum(x0 - x, 0.0), x - x1),
                        np.maximum(np.maximum(y0 - y, 0.0), y - y1))

    best = np.minimum(point_box(p[0], p[1]), point_box(qs[..., 0], qs[..., 1]))
    length2 = dx * dx + dy * dy
    for cx, cy in ((x0, y0), (x0, y1), (x1, y0), (x1, y1)):
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(length2 == 0, 0.0, ((cx - p[0]) * dx + (cy - p[1]) * dy) / length2)
        t = np.clip(t, 0.0, 1.0)
        best = np.minimum(best, np.hypot(p[0] + t * dx - cx, p[1] + t * dy - cy))
    return np.where(crossing, 0.0, best)


def shortest_path(start, field, obstacles, goal, radius):
    """(length, points) of the shortest path of a disc of `radius` from start into goal.
    Kept per process for each room and radius (`_shortest`): every report on a robot in a
    room asks for the same path, and a process that builds many reports (a study, the
    test suite) searched it again at each (0.1-0.3 s a robot)."""
    length, points = _shortest(tuple(map(float, start)), tuple(map(float, field)),
                               tuple(tuple(map(float, box)) for box in obstacles),
                               tuple(map(float, goal)), float(radius))
    return length, points.copy()


@functools.lru_cache(maxsize=64)
def _shortest(start, field, obstacles, goal, radius):
    """shortest_path's search, on hashable arguments (tuples of floats)."""
    fx0, fx1, fy0, fy1 = field[0] + radius, field[1] - radius, field[2] + radius, field[3] - radius
    eps = 1e-6
    start = np.asarray(start, dtype=float)
    boxes = np.asarray(obstacles, dtype=float).reshape(-1, 4)

    def free_many(p, qs):
        """free(p, q) for each q of qs."""
        qs = np.asarray(qs, dtype=float).reshape(-1, 2)
        ok = ((np.minimum(p[0], qs[:, 0]) >= fx0 - eps) & (np.maximum(p[0], qs[:, 0]) <= fx1 + eps)
              & (np.minimum(p[1], qs[:, 1]) >= fy0 - eps) & (np.maximum(p[1], qs[:, 1]) <= fy1 + eps))
        if len(boxes) and ok.any():
            ok[ok] = (segment_box_distances(p, qs[ok], boxes) >= radius - 1e-4).all(axis=1)
        return ok

    def free(p, q):
        return bool(free_many(p, [q])[0])

    nodes = [start]
    for x0, x1, y0, y1 in obstacles:
        for (cx, cy, a0) in ((x0, y0, math.pi), (x1, y0, 1.5 * math.pi), (x1, y1, 0.0),
                             (x0, y1, 0.5 * math.pi)):
            r = radius / math.cos(math.pi / 4 / ARC_POINTS) + 1e-3  # polygon outside the arc
            for k in range(ARC_POINTS + 1):
                a = a0 + (math.pi / 2) * k / ARC_POINTS
                pt = np.array([cx + r * math.cos(a), cy + r * math.sin(a)])
                if fx0 <= pt[0] <= fx1 and fy0 <= pt[1] <= fy1:
                    nodes.append(pt)
    # Points no path can touch (inside another wall's inflated box) are left out.
    nodes = [nodes[0]] + [pt for pt in nodes[1:] if free(pt, pt)]
    points = np.array(nodes)
    gx0, gx1, gy0, gy1 = goal[0], min(goal[1], fx1), goal[2], min(goal[3], fy1)

    def to_goal(p):
        q = np.array([min(max(p[0], gx0), gx1), min(max(p[1], gy0), gy1)])
        return q if free(p, q) else None

    dist = {0: 0.0}
    prev = {}
    heap = [(0.0, 0)]
    best, best_end = math.inf, None
    done = set()
    while heap:
        d, i = heapq.heappop(heap)
        if i in done or d >= best:
            continue
        done.add(i)
        q = to_goal(nodes[i])
        if q is not None and d + np.linalg.norm(q - nodes[i]) < best:
            best, best_end = d + float(np.linalg.norm(q - nodes[i])), (i, q)
        nd = d + np.linalg.norm(points - nodes[i], axis=1)
        known = np.array([dist.get(j, math.inf) for j in range(len(nodes))])
        candidates = [j for j in np.flatnonzero(nd < known) if j not in done and j != i]
        if not candidates:
            continue
        for j in np.asarray(candidates)[free_many(nodes[i], points[candidates])]:
            dist[int(j)], prev[int(j)] = float(nd[j]), i
            heapq.heappush(heap, (float(nd[j]), int(j)))
    i, q = best_end
    path = [q]
    while True:
        path.append(nodes[i])
        if i == 0:
            break
        i = prev[i]
    return best, np.array(path[::-1])


def _segments(path):
    """The path's non-empty segments, as (n, 2) displacement vectors."""
    seg = np.diff(path, axis=0)
    return seg[np.linalg.norm(seg, axis=1) > 1e-9]


def two_wheel_steps(path, heading=0.0):
    """ceil(L / 2 + total turning) along the path, from the start heading."""
    seg = _segments(path)
    angles = np.arctan2(seg[:, 1], seg[:, 0])
    turns = np.abs(np.angle(np.exp(1j * np.diff(np.concatenate([[heading], angles])))))
    return int(math.ceil(np.linalg.norm(seg, axis=1).sum() / 2.0 + turns.sum() - 1e-9))


CORNER = math.radians(45)  # the floating plan stops where the path bends more than this


def floating_steps(path, max_acceleration=0.2):
    """Stop-at-every-corner bang-bang plan: sum of 2 ceil(sqrt(L / a)) over the legs
    between bends of more than CORNER (the arc points around a corner are one bend)."""
    seg = _segments(path)
    legs, current, heading = [], np.zeros(2), None
    for d in seg:
        angle = math.atan2(d[1], d[0])
        if heading is not None and abs(math.remainder(angle - heading, 2 * math.pi)) > CORNER:
            legs.append(current)
            current, heading = np.zeros(2), angle
        current = current + d
        heading = math.atan2(current[1], current[0]) if heading is None else heading
    legs.append(current)
    steps = 0
    for d in legs:
        length = float(np.linalg.norm(d))
        a = max_acceleration / max(abs(d[0]), abs(d[1])) * length
        steps += 2 * math.ceil(math.sqrt(length / a) - 1e-9)
    return steps


def floating_lower_bound(length, max_acceleration=0.2):
    """Fewest n with a n (n + 1) / 2 >= length at a = max_acceleration sqrt(2)."""
    a = max_acceleration * math.sqrt(2.0)
    return int(math.ceil((-1 + math.sqrt(1 + 8 * length / a)) / 2 - 1e-9))


def optimal(robot, drive=None, room=None):
    """{'length', 'steps', 'steps_lower', 'path'} for robot (a registered name, or a file
    with its drive) from the room's nominal start, in paper units; steps is the feasible
    plan, steps_lower a bound no trial can beat. room: models.rooms' (None: the paper's)."""
    from tasks import navigation
    entry = tasks.resolve(robot, drive)
    field, obstacles, goal, start = rooms.layout(room)
    # the robot's radius under its readings, from its model in the room as tasks.load
    # compiles it (no environment, so a report loads none of the drive's compiled kernels;
    # the model the command compiled for its runs' parameters, once per process)
    radius = navigation.robot_radius(tasks.compiled_model(entry, entry.task_config(), room)[0])
    length, path = shortest_path(start[:2], field, obstacles, goal, radius)
    if entry.drive == "two_wheel":
        steps = lower = two_wheel_steps(path, start[2])
    else:
        steps, lower = floating_steps(path), floating_lower_bound(length)
    return {"length": length, "steps": steps, "steps_lower": lower, "path": path}


def yardstick(runs, root=None):
    """Per group: optimal steps beside the best, median-last and mean learned trials."""
    out = []
    cache = {}
    for robot, condition in sorted({(r, c) for r, c, _ in runs}):
        p = next(run["parameters"] for (r, _, _), run in runs.items() if r == robot)
        file = p.get("robot_file")
        # a mount file's name need not be a shipped one: its path finds it
        key = (p.get("mount_file") or file or p.get("robot_name", robot),
               p["drive"] if file else None, p.get("room"))
        if key not in cache:  # one per robot, whichever learners ran it
            cache[key] = optimal(*key)
        best = cache[key]
        ms = [run["metrics"] for (r, c, _), run in runs.items() if (r, c) == (robot, condition)]
        mins = [m["min_trial_steps"] for m in ms if m["min_trial_steps"] is not None]
        lasts = [m["last_trial_steps"] for m in ms if m["last_trial_steps"] is not None]
        per = [m["steps_per_trial"] for m in ms if m["steps_per_trial"] is not None]
        out.append({
            "robot": robot, "condition": condition,
            "optimal_length": round(best["length"], 2), "optimal_steps": best["steps"],
            "optimal_steps_lower": best["steps_lower"],
            "best_trial_steps": min(mins) if mins else None,
            "median_last_trial_steps": float(np.median(lasts)) if lasts else None,
            "mean_steps_per_trial": float(np.mean(per)) if per else None,
            "seeds_with_optimal_trial": int(sum(m <= best["steps"] for m in mins)),
            "seeds": len(ms),
        })
    return out


def table(rows):
    lines = ["| robot | condition | shortest path (units) | optimal steps | best trial | median last trial | "
             "mean steps per trial / optimal | seeds with a trial at or below the optimal plan |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        ratio = (r["mean_steps_per_trial"] / r["optimal_steps"]) if r["mean_steps_per_trial"] else None
        steps = (str(r["optimal_steps"]) if r["optimal_steps_lower"] == r["optimal_steps"]
                 else f"{r['optimal_steps_lower']}-{r['optimal_steps']}")
        lines.append(f"| {r['robot']} | {r['condition']} | {r['optimal_length']:.1f} | {steps} "
                     f"| {r['best_trial_steps'] if r['best_trial_steps'] is not None else '-'} "
                     f"| {r['median_last_trial_steps'] if r['median_last_trial_steps'] is not None else '-'} "
                     f"| {'-' if ratio is None else f'{ratio:.1f}x'} "
                     f"| {r['seeds_with_optimal_trial']}/{r['seeds']} |")
    return "\n".join(lines)
