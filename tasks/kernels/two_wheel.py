"""The two-wheel action family's step (Section 3.3), once, for every body that walks it.

Action a in [-1, 1]: turn |a| rad (a < 0 left, counter-clockwise), then move 2 (1 - |a|)
units along the new heading, each part scaled by the action noise's factor. "If the agent
cannot move any more because of collision with an object, the rest portion of move is
transferred into the angle of turn": the move ends where the body first touches a wall or
an obstacle (`room_ahead`, `touching`: every realisation's move phase stops there), and
its rest becomes turn (at 1 rad per 2 units) in the commanded turn's direction, or away
from the nearer side (leftover_turn "away"). Then the body halts. (blocked_move
"refuse", protocol 7's compensation for a body that slid along walls, is no reading of
Section 3.3: it undoes the move and turns all of it; kept only to remake protocol 7's
runs.)

`act` is that logic. How a body turns by an angle or moves a distance is its
realisation's: `act` runs the phases (turn, move, halt, and the save and restore of a
refused move) of the realisation whose record it is given, its kernels' PHASES, picked
by the record's type when numba compiles it (tasks.realisations.of_record).

Not cached on disk itself (an overload): it compiles in its realisation's phases, so it is
cached inside the entry points of tasks.kernels.env_step, whose module reaches every
realisation (compiled.cache).
"""
import math

import numpy as np
from numba import njit
from numba.extending import overload

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from tasks.kernels import bindings, sensing
from tasks.kernels.body import base_pose, factors
from tasks.readings import codes
from tasks.realisations import of_record

#: The family's fields of a record, after tasks.kernels.body.BODY_FIELDS: the substeps of the turn
#: and the move phases, the largest turn (rad) and move (units) per step, the tolerance
#: (units) past which a move was blocked, the blocked-move and leftover-turn readings
#: (BLOCKED_*, LEFTOVER_*), the state a refused move returns to (qpos, qvel, act); the
#: pairs (robot geom, room geom) that can touch (`room_ahead`), scratch for their segment.
FAMILY_FIELDS = ("n_turn", "n_move", "max_turn", "max_move", "tolerance", "blocked_move",
                 "leftover_turn", "qpos0", "qvel0", "act0", "pairs", "fromto")

#: The blocked-move readings' codes (tasks/readings.py): a blocked move stops at contact
#: and its rest is turned (STOP), or is refused whole, undone, and all of it turned
#: (REFUSE); the rest turns the commanded turn's way (COMMANDED) or away from the side
#: whose beams read nearer (AWAY).
BLOCKED_STOP, BLOCKED_REFUSE = codes("blocked_move", "stop", "refuse")
LEFTOVER_COMMANDED, LEFTOVER_AWAY = codes("leftover_turn", "commanded", "away")
#: turn_phase's `leftover`: the step's own turn, or a blocked move's leftover turn.
OWN_TURN, LEFTOVER = False, True
#: A body this close to the room along its heading (units) touches it: its move ends.
TOUCH = 1e-3
#: How far past a move's end (units) the room must be for the move to go unwatched
#: (clear_ahead): a 3D body drifts a little off its heading.
CLEARANCE = 0.5
#: A pair's gap (m) within which its geoms touch at a point (mj_geomDistance's segment
#: has no direction there).
CONTACT = 1e-9


# -- where the move ends ---------------------------------------------------------------------

@njit(cache=True)
def room_ahead(s, heading, reach):
    """How far (units) the body can still move along `heading` (rad) before one of its
    geoms touches the room (a wall or an obstacle; never the floor), looking `reach` units
    ahead: over the pairs (robot geom, room geom) that can touch, each pair's gap (MuJoCo's
    mj_geomDistance: negative when sunk in) over the rate at which a move along the heading
    closes it (the horizontal part, along the heading, of the unit normal from the robot's
    geom to the room's); pairs the move does not close are skipped. 0 when touching, inf
    when nothing is within reach. Exact for a flat wall; short of the touch at a corner (the
    gap is convex along the move), so going this far again and again reaches it from
    outside. Reads the geoms' poses: the kinematics of the last substep (bindings.run ends
    with mj_step1)."""
    c, sn = math.cos(heading), math.sin(heading)
    units, fromto, pairs = s.metres_to_units, s.fromto, s.pairs
    reach_m = reach / units
    ahead = np.inf
    for k in range(pairs.shape[0]):
        gap = bindings.mj_geomDistance(s.m, s.d, pairs[k, 0], pairs[k, 1], reach_m,
                                       fromto.ctypes.data)
        if gap >= reach_m:
            continue
        if abs(gap) > CONTACT:
            # fromto runs from the robot's geom to the room's: gap times the unit normal
            closing = ((fromto[3] - fromto[0]) * c + (fromto[4] - fromto[1]) * sn) / gap
        else:
            # touching (fromto is a point): the normal from the robot's centre to it
            closing = (fromto[0] - s.xpos[0]) * c + (fromto[1] - s.xpos[1]) * sn
        if closing <= 0.0:
            continue
        ahead = min(ahead, max(gap * units / closing, 0.0))
    return ahead


@njit(cache=True)
def clear_ahead(s, heading, distance):
    """True when nothing of the room lies within a move of `distance` units along `heading`
    and CLEARANCE beyond (room_ahead): the move cannot touch, so its phase need not watch
    each substep (one call per move instead of one per substep)."""
    reach = distance + CLEARANCE
    return room_ahead(s, heading, reach) >= reach


@njit(cache=True)
def touching(s, heading):
    """True when the body touches the room along `heading`: its move there is blocked
    (room_ahead within TOUCH)."""
    return room_ahead(s, heading, 2 * TOUCH) <= TOUCH


# -- the family's step -------------------------------------------------------------------

@njit(cache=True)
def away_sign(distances, commanded):
    """The leftover turn's sign (counter-clockwise +1) under LEFTOVER_AWAY, from the
    beams' surface distances, leftmost first: away from the half whose nearest beam
    reads nearer (the left half nearer: -1, a right turn; the right: +1), the middle
    beam of an odd count in neither; `commanded` on a tie (nothing seen on either side
    included)."""
    n = distances.shape[0]
    half = n // 2
    left, right = np.inf, np.inf
    for i in range(half):
        left = min(left, distances[i])
        right = min(right, distances[n - 1 - i])
    if left < right:
        return -1.0
    if right < left:
        return 1.0
    return commanded


@njit(cache=True)
def save_state(s):
    """The MuJoCo state a refused move returns to: qpos, qvel, act."""
    s.qpos0[:] = s.qpos
    s.qvel0[:] = s.qvel
    s.act0[:] = s.act


@njit(cache=True)
def restore_state(s):
    """Back to save_state's qpos, qvel, act."""
    s.qpos[:] = s.qpos0
    s.qvel[:] = s.qvel0
    s.act[:] = s.act0


def act(s, a, u):
    """One step of the family for the clipped action a and the action noise's uniform
    draws u, on the phases of the realisation whose record s is (its kernels' PHASES, by
    its row of tasks.realisations.REALISATIONS): turn_phase(s, angle, leftover) and
    move_phase(s, distance) -> (status, substeps), halt(s) -> (status, substeps) (the
    body's drive at rest, stalled parts giving up the rest), save(s) and restore(s) (the
    state a refused move returns to; the caller of restore runs mj_forward). The turn,
    the move, a blocked move's leftover turn, the halt. Returns (status, substeps run).
    Compiled code only."""
    raise TypeError("tasks.kernels.two_wheel.act runs in compiled code (env_step.step)")


@overload(act)
def _act(s, a, u):
    realisation = of_record(s)
    if realisation is None or realisation.drive != "two_wheel":
        return None
    turn_phase, move_phase, halt, save, restore = realisation.kernels().PHASES

    def impl(s, a, u):
        noise_turn, noise_move = factors(s, u)
        turn = -a * s.max_turn * noise_turn  # counter-clockwise positive
        move = s.max_move * (1.0 - abs(a)) * noise_move
        sign = 1.0 if turn > 0 else -1.0
        status, n = turn_phase(s, turn, OWN_TURN)
        if status != bindings.OK:
            return status, n
        if s.blocked_move == BLOCKED_REFUSE:
            save(s)
        x0, y0, heading = base_pose(s)
        c, sn = math.cos(heading), math.sin(heading)
        status, k = move_phase(s, move)
        n += k
        if status != bindings.OK:
            return status, n
        x, y, _ = base_pose(s)
        rest = move - ((x - x0) * c + (y - y0) * sn)
        if rest > s.tolerance:
            if s.leftover_turn == LEFTOVER_AWAY:
                sign = away_sign(sensing.ranges(s.m, s.d, s.flags, s.sensordata, s.beam0,
                                                s.beam1, s.metres_to_units, s.radius), sign)
            if s.blocked_move == BLOCKED_REFUSE:
                restore(s)
                before = s.bad_qacc[0]
                bindings.mj_forward(s.m, s.d)
                if s.bad_qacc[0] != before:
                    return bindings.UNSTABLE, n
                rest = move
            leftover = sign * rest * s.max_turn / s.max_move
            status, k = turn_phase(s, leftover, LEFTOVER)
            n += k
            if status != bindings.OK:
                return status, n
        status, k = halt(s)
        return status, n + k

    return impl
