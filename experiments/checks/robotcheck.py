"""`ebrl check`: does a robot do what its drive promises? For a newcomer's own robot
file as much as for the registered ones.

- `accuracy`: in free space, the achieved turn and move (two_wheel drive) or velocity
  change (floating drive) against the noise-free command, over random actions.
- `fuzz`: random actions that keep ramming walls, in episodes like the protocol's: the
  robot never ends inside an obstacle (by more than it may sink), stays upright (tilt
  under navigation.MAX_TILT_DEGREES), never gives NaN or a MuJoCo warning.
- the beams (tasks.beams): at the start, each between the floor and the walls' top
  (models.rooms.WALL_HEIGHT: a beam over the walls sees nothing of the room); after each
  free-space action of the accuracy check, none reads nearer than the nearest wall is to
  its origin (a nearer reading is the robot itself, or the floor: a robot that reads
  contact in open space is blind).
"""
import dataclasses
import math
import time

import numpy as np
import models
import tasks
from models import rooms

#: A robot may sink into a wall by this share of its radius at a fast contact, no more:
#: its centre stays out of every obstacle with half its body to spare. The floating
#: puck's soft 0.2 s contact (docs/interpretation.md, floating bump) lets it sink 0.53
#: units of its 1.5 at the speeds the fuzz builds up.
SINK_SHARE = 0.5
#: Section 3.3's 5% noise, as a share of the largest command, is the accuracy asked.
ACCURACY = 0.05
#: `ebrl check`'s default counts: random actions of the fuzz, free-space actions of the
#: accuracy check.
ACTIONS = 100_000
ACCURACY_ACTIONS = 1000


def clearance(layout, x, y):
    """Distance (units) from (x, y) to the nearest wall or obstacle surface of the room
    layout (models.room_layout); negative inside an obstacle."""
    field, obstacles, _, _ = layout
    x0, x1, y0, y1 = field
    dists = [x - x0, x1 - x, y - y0, y1 - y]
    for bx0, bx1, by0, by1 in obstacles:
        if bx0 < x < bx1 and by0 < y < by1:
            dists.append(-min(x - bx0, bx1 - x, y - by0, by1 - y))
        else:
            dists.append(math.hypot(max(bx0 - x, 0.0, x - bx1), max(by0 - y, 0.0, y - by1)))
    return min(dists)


def open_spot(layout):
    """The point of the room farthest from every wall and obstacle (a 1-unit grid)."""
    field = layout[0]
    points = [(x, y) for x in np.arange(field[0], field[1] + 1e-9, 1.0)
              for y in np.arange(field[2], field[3] + 1e-9, 1.0)]
    return max(points, key=lambda p: clearance(layout, *p))


def _quiet(robot, drive, room=None):
    env = tasks.load(robot, drive=drive, seed=0, sensor_noise=0.0, action_noise=0.0,
                     start_jitter=False, room=room)
    env.reset()
    return env


def accuracy(robot, actions=1000, seed=0, drive=None, room=None):
    """Errors of random noise-free actions in free space: for the two_wheel drive,
    |achieved - commanded| turn (rad) and move (units); for the floating drive, the
    velocity change (units/step) on each axis. Returns the error arrays and limits."""
    errors, limits, _, _ = free_space(robot, actions, seed, drive, room)
    return errors, limits


#: How much nearer (units) than the nearest wall a beam may read in free space: rounding.
BEAM_TOLERANCE = 1e-6


def free_space(robot, actions=1000, seed=0, drive=None, room=None):
    """`accuracy`'s errors and limits; the beams in free space: {beam: (readings nearer
    than the nearest wall is to the beam's origin, the largest shortfall in units)} after
    each action, for every beam; and the errors signed by their commands (> 0: the turn,
    move or velocity change went past the command; < 0: it fell short), which tell a
    drive too weak or too slow from one too strong (its gains, its time_scale)."""
    from tasks import beams, floating, two_wheel
    entry = tasks.resolve(robot, drive)
    env = _quiet(entry, None, room)
    physics = env.physics
    layout = models.room_layout(physics.model)
    x, y = open_spot(layout)
    names = beams.beam_names(physics.model.ptr)
    short = np.zeros(len(names), dtype=int)
    worst = np.zeros(len(names))
    rng = np.random.default_rng(seed)
    errors, signs = {}, {}
    try:
        for _ in range(actions):
            if entry.drive == "two_wheel":
                physics.set_robot_pose(x, y, rng.uniform(-math.pi, math.pi))
                a = rng.uniform(-1.0, 1.0)
                x0, y0, h0 = physics.robot_pose()
                env.step([a])
                x1, y1, h1 = physics.robot_pose()
                errors.setdefault("turn", []).append(
                    math.remainder(h1 - h0, 2 * math.pi) + a * two_wheel.MAX_TURN)
                errors.setdefault("move", []).append(
                    math.hypot(x1 - x0, y1 - y0) - two_wheel.MAX_MOVE * (1.0 - abs(a)))
                signs.setdefault("turn", []).append(-np.sign(a))   # the command: -a rad
                signs.setdefault("move", []).append(1.0)
            else:
                physics.set_robot_pose(x, y, 0.0)
                a = rng.uniform(-1.0, 1.0, 2)
                env.step(a)
                dv = physics.robot_velocity() - floating.MAX_ACCELERATION * a
                errors.setdefault("velocity_x", []).append(dv[0])
                errors.setdefault("velocity_y", []).append(dv[1])
                signs.setdefault("velocity_x", []).append(np.sign(a[0]))
                signs.setdefault("velocity_y", []).append(np.sign(a[1]))
            # a reading (from the beam's origin) nearer than the nearest wall is to it
            walls = [clearance(layout, ox, oy) for ox, oy, _ in beams.origins(physics)]
            shortfall = np.asarray(walls) - (physics.ranges() + physics.robot_radius)
            short += shortfall > BEAM_TOLERANCE
            worst = np.maximum(worst, shortfall)
    finally:
        env.close()
    limits = ({"turn": ACCURACY * two_wheel.MAX_TURN, "move": ACCURACY * two_wheel.MAX_MOVE}
              if entry.drive == "two_wheel" else
              {k: ACCURACY * floating.MAX_ACCELERATION for k in ("velocity_x", "velocity_y")})
    limits.update((k, v) for k, v in entry.accuracy_limits if k in limits)  # a body's own
    seen = {name: (int(n), float(w)) for name, n, w in zip(names, short, worst)}
    signed = {k: np.asarray(v) * np.asarray(signs[k]) for k, v in errors.items()}
    return {k: np.abs(v) for k, v in errors.items()}, limits, seen, signed


def way(signed):
    """How the errors signed by their commands (free_space's) fall: 'N% short of the
    command, M% past it'."""
    short, past = (100.0 * float(np.mean(signed < 0.0)), 100.0 * float(np.mean(signed > 0.0)))
    return f"{short:.0f}% short of the command, {past:.0f}% past it"


def beam_heights(robot, drive=None, room=None):
    """Each beam's tasks.beams.Height at the start (units above the floor, where it leaves
    the robot and at the end of its range), and the walls' height (units)."""
    from tasks import beams
    entry = tasks.resolve(robot, drive)
    env = _quiet(entry, None, room)
    try:
        return beams.heights(env.physics, env.task.config.sensor_range), rooms.WALL_HEIGHT
    finally:
        env.close()


def beam_lines(robot, actions, seen, heights, wall):
    """The check's lines on the beams, each ending ok or FAIL, and how many failed: the
    beams over the walls' top (or under the floor) at the start, and those that read
    nearer than any wall in free space (seen: free_space's)."""
    lines, failed = [], 0
    out = [h for h in heights if not (0.0 < h.origin < wall and 0.0 < h.end < wall)]
    low = min(min(h.origin, h.end) for h in heights)
    high = max(max(h.origin, h.end) for h in heights)
    if out:
        failed += 1
        listed = ", ".join(f"{h.beam} ({h.origin:.2f} to {h.end:.2f})" for h in out)
        lines.append(f"{robot}: beams outside the walls' height (0 to {wall:g} units) at the "
                     f"start: {listed} units above the floor, so they see nothing of the "
                     "room: set the beams lower FAIL")
    else:
        lines.append(f"{robot}: beams at the start {low:.2f} to {high:.2f} units above the "
                     f"floor, under the walls' top ({wall:g} units) ok")
    blind = {name: v for name, v in seen.items() if v[0]}
    actions = f"{actions} free-space actions"
    if blind:
        failed += 1
        listed = ", ".join(f"{name} ({n} times, up to {w:.2f} units short)"
                           for name, (n, w) in blind.items())
        lines.append(f"{robot}: beams that read nearer than any wall after {actions}: "
                     f"{listed}: they see the robot itself (or the floor), not the room "
                     "FAIL")
    else:
        lines.append(f"{robot}: beams after {actions}: no reading nearer than the nearest "
                     "wall ok")
    return lines, failed


def fuzz(robot, actions=100_000, seed=0, drive=None, room=None):
    """Random actions biased to keep ramming walls, resetting at the goal; returns the
    worst clearance (units), the largest tilt (degrees), NaN and warning counts, and the
    seconds it took; the falls (a PhysicsError: unstable, tipped over), each followed by a
    new episode, for a robot whose [check] allows any (a gait's), else the error
    propagates."""
    from dm_control.rl import control
    entry = tasks.resolve(robot, drive)
    env = tasks.load(entry, seed=seed, room=room)
    physics = env.physics
    layout = models.room_layout(physics.model)
    data = physics.data.ptr
    warnings_before = sum(w.number for w in data.warning)
    rng = np.random.default_rng(seed)
    dim = env.action_spec().shape[0]
    bias = np.zeros(dim)
    worst, tilt, nans, radius = math.inf, 0.0, 0, physics.robot_radius
    falls, counted = 0, "falls" in dict(entry.accuracy_limits)
    started = time.perf_counter()
    env.reset()
    try:
        for i in range(actions):
            if i % 300 == 0:  # a new direction to ram, now and then
                bias = rng.uniform(-0.6, 0.6, dim)
            action = np.clip(rng.normal(0.0, 0.5, dim) + bias, -1.0, 1.0)
            try:
                if env.step(action).last():
                    env.reset()
            except control.PhysicsError:
                if not counted:
                    raise
                falls += 1
                env.reset()
            x, y, _ = physics.robot_pose()
            worst = min(worst, clearance(layout, x, y) - radius)
            tilt = max(tilt, physics.tilt())
            nans += int(not np.isfinite(data.qpos).all())
    finally:
        warnings = sum(w.number for w in data.warning) - warnings_before
        env.close()
    return {"robot": entry.name, "actions": actions, "worst_clearance": worst,
            "sink_limit": SINK_SHARE * radius,
            "max_tilt_degrees": math.degrees(tilt), "nan_steps": nans, "warnings": warnings,
            "falls": falls, "fall_limit": dict(entry.accuracy_limits).get("falls", 0),
            "seconds": time.perf_counter() - started}


#: A failure whose size the check does not measure (a NaN, a MuJoCo warning, beams that
#: see nothing of the room, an unstable or tipped robot) as a share of its limit: worse
#: than any measured failure, so a search (experiments.checks.tune) leaves it first.
UNMEASURED = 1000.0


@dataclasses.dataclass(frozen=True)
class Checked:
    """One robot's check (`check`): its lines, each ending ok or FAIL; how many failed;
    and each measure as a share of its limit (the accuracy's largest errors, the fuzz's
    deepest sink, largest tilt and falls; UNMEASURED for a failure with no size), where
    under 1 passes (an accuracy's exactly 1 too): what `ebrl check --tune` scores."""
    lines: tuple[str, ...]
    failed: int
    shares: dict

    @property
    def passed(self) -> bool:
        return self.failed == 0

    def worst(self) -> tuple[str, float]:
        """(the measure, its share) nearest its limit, or furthest past it."""
        name = max(self.shares, key=self.shares.get)
        return name, self.shares[name]


def check(robot, actions, accuracy_actions, drive=None, room=None, name=None):
    """Both checks of one robot (a name, a file or a tasks.Robot), as `ebrl check` prints
    them (name: the robot as the lines name it; default: robot): a Checked. A robot that
    falls over or turns unstable in free space, or in the fuzz where its [check] counts
    no falls, fails that check with the simulation's one-line reason."""
    from dm_control.rl import control
    from tasks import navigation
    name = robot if name is None else name
    lines, failed, shares = [], 0, {}
    try:
        errors, limits, seen, signed = free_space(robot, accuracy_actions, drive=drive,
                                                  room=room)
    except control.PhysicsError as e:
        failed += 1
        shares["free space"] = UNMEASURED
        lines.append(f"{name}: free-space actions: {e} FAIL")
        errors = None
    if errors is not None:
        beams, beams_failed = beam_lines(name, accuracy_actions, seen,
                                         *beam_heights(robot, drive, room))
        lines += beams
        failed += beams_failed
        if beams_failed:
            shares["beams"] = UNMEASURED
        for key, e in errors.items():
            ok = e.max() <= limits[key]
            failed += not ok
            shares[key] = float(e.max() / limits[key])
            lines.append(f"{name}: {key} error over {len(e)} free-space actions: median "
                         f"{np.median(e):.4f}, 95% {np.percentile(e, 95):.4f}, max {e.max():.4f} "
                         f"(limit {limits[key]:.3f}; {way(signed[key])}) {'ok' if ok else 'FAIL'}")
    counted = "falls" in dict(tasks.resolve(robot, drive).accuracy_limits)
    try:
        r = fuzz(robot, actions, drive=drive, room=room)
    except control.PhysicsError as e:
        failed += 1
        shares["fuzz"] = UNMEASURED
        lines.append(f"{name}: {actions:,} random actions: {e} FAIL")
        return Checked(tuple(lines), failed, shares)
    # a gait's falls are counted instead (tasks.realisations.gait's max_tilt)
    max_tilt = 90.0 if counted else navigation.MAX_TILT_DEGREES
    deepest = max(0.0, -r["worst_clearance"])
    ok = (r["worst_clearance"] > -r["sink_limit"] and r["nan_steps"] == 0
          and r["warnings"] == 0 and r["max_tilt_degrees"] < max_tilt
          and r["falls"] <= r["fall_limit"])
    failed += not ok
    shares.update(deepest=deepest / r["sink_limit"], tilt=r["max_tilt_degrees"] / max_tilt,
                  falls=r["falls"] / (r["fall_limit"] + 1))
    if r["nan_steps"] or r["warnings"]:
        shares["NaN or warnings"] = UNMEASURED
    lines.append(f"{name}: {actions:,} random actions in {r['seconds']:.0f} s: deepest into a "
                 f"wall {deepest:.3f} units (limit {r['sink_limit']:.2f}), largest tilt "
                 f"{r['max_tilt_degrees']:.2f} degrees, NaN steps {r['nan_steps']}, MuJoCo "
                 f"warnings {r['warnings']}, falls {r['falls']} (limit {r['fall_limit']:.0f}) "
                 f"{'ok' if ok else 'FAIL'}")
    return Checked(tuple(lines), failed, shares)


def main(robots, actions, accuracy_actions, drive=None, room=None):
    """Prints both checks for each robot; returns 0 if every robot passes, else 1."""
    failed = 0
    for robot in robots:
        checked = check(robot, actions, accuracy_actions, drive, room)
        for line in checked.lines:
            print(line)
        failed += checked.failed
    return 1 if failed else 0
