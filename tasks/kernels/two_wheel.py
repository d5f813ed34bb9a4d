"""The two-wheel action family's step (Section 3.3), once, for every body that walks it.

Action a in [-1, 1]: turn |a| rad (a < 0 left, counter-clockwise), then move 2 (1 - |a|)
units along the new heading, each part scaled by the action noise's factor. When a
collision stops the move, its rest becomes turn (at 1 rad per 2 units) in the commanded
turn's direction, or away from the nearer side (leftover_turn "away"); with
blocked_move "refuse" the move is undone first and all of it turned. Then the body
halts.

`act` is that logic. How a body turns by an angle or moves a distance is its own: each
realisation's record (tasks.two_wheel.planar, .wheels, .motors, tasks.gait) provides
`turn_phase`, `move_phase`, `halt`, `save` and `restore` for its type (numba overloads
of the stubs below), and `act` calls them. tasks.steps dispatches a drive's record here.

Not cached on disk themselves (plain ``@njit``): `act` compiles in its realisation's
phases, which live in other modules, so it is cached only inside the entry points of
tasks.steps, whose module reaches every realisation (ebrl.compiled).
"""
import math

import numpy as np
from numba import njit
from numba.extending import overload

from ebrl import compiled  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from tasks.kernels import bindings, sensing
from tasks.kernels.body import base_pose, factors

#: The family's fields of a record, after tasks.body.BODY_FIELDS: the substeps of the turn
#: and the move phases, the largest turn (rad) and move (units) per step, the tolerance
#: (units) past which a move was blocked, the blocked-move and leftover-turn readings
#: (BLOCKED_*, LEFTOVER_*), the state a refused move returns to (qpos, qvel, act).
FAMILY_FIELDS = ("n_turn", "n_move", "max_turn", "max_move", "tolerance", "blocked_move",
                 "leftover_turn", "qpos0", "qvel0", "act0")

#: The blocked-move readings (tasks.config.BLOCKED_MOVES, in order): a blocked move stops
#: at contact and its rest is turned (STOP), or is refused whole, undone, and all of it
#: turned (REFUSE); the rest turns the commanded turn's way (COMMANDED) or away from the
#: side whose beams read nearer (AWAY: tasks.config.LEFTOVER_TURNS, in order).
BLOCKED_STOP, BLOCKED_REFUSE = range(2)
LEFTOVER_COMMANDED, LEFTOVER_AWAY = range(2)
#: turn_phase's `leftover`: the step's own turn, or a blocked move's leftover turn.
OWN_TURN, LEFTOVER = False, True


# -- what each realisation provides (numba overloads by record type) --------------------

def turn_phase(s, angle, leftover):
    """Turns the body by `angle` rad counter-clockwise; returns (status, substeps)."""
    raise NotImplementedError("overloaded for each realisation's record type")


def move_phase(s, distance):
    """Moves the body `distance` units forward; returns (status, substeps)."""
    raise NotImplementedError("overloaded for each realisation's record type")


def halt(s):
    """Ends the step: the body's drive at rest (stalled parts give up the rest); returns
    (status, substeps)."""
    raise NotImplementedError("overloaded for each realisation's record type")


def save(s):
    """Keeps the state a refused move returns to."""
    raise NotImplementedError("overloaded for each realisation's record type")


def restore(s):
    """Back to the state `save` kept (the caller then runs mj_forward)."""
    raise NotImplementedError("overloaded for each realisation's record type")


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


@njit
def act(s, a, u):
    """One step of the family for the clipped action a and the action noise's uniform
    draws u: the turn, the move, a blocked move's leftover turn, the halt. Returns
    (status, substeps run)."""
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
            sign = away_sign(sensing.ranges(s.m, s.d, s.flags, s.sensordata, s.beam0, s.beam1,
                                            s.metres_to_units, s.radius), sign)
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


# -- a realisation's registration -------------------------------------------------------

def realisation(record, turn, move, stop, keep=save_state, back=restore_state):
    """Registers a realisation's kernels for its record type (an ebrl.records.Record
    class): turn(s, angle, leftover) and move(s, distance) -> (status, substeps),
    stop(s) -> (status, substeps) (its halt), keep(s) and back(s) (its save and
    restore; default: MuJoCo's qpos, qvel and act)."""
    typ = record.numba_type

    @overload(turn_phase)
    def _turn(s, angle, leftover):
        if isinstance(s, typ):
            return lambda s, angle, leftover: turn(s, angle, leftover)

    @overload(move_phase)
    def _move(s, distance):
        if isinstance(s, typ):
            return lambda s, distance: move(s, distance)

    @overload(halt)
    def _halt(s):
        if isinstance(s, typ):
            return lambda s: stop(s)

    @overload(save)
    def _save(s):
        if isinstance(s, typ):
            return lambda s: keep(s)

    @overload(restore)
    def _restore(s):
        if isinstance(s, typ):
            return lambda s: back(s)
