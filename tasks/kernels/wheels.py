"""The wheels realisation of the two-wheel family: two wheel hinges rolling on the floor, ``left_wheel`` and
``right_wheel``, each under an integrated-velocity servo (the ``diff_drive`` robot): the
control is the wheel's speed, the servo's target angle integrates it and a PD loop on
the wheel's angle follows. A phase of n substeps sets the speeds that turn the wheels by
the phase's angles (a turn: opposite, a move: alike) over its first RAMP share of the
substeps, then zero speeds for the rest, the servos settling on their targets; the halt
puts the targets where the wheels are, so a stalled wheel gives up the rest."""
from numba import njit

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from compiled import records
from tasks.kernels import bindings, two_wheel as family
from tasks.kernels.body import BODY_FIELDS, base_pose


#: Share of a phase over which the wheels' targets move; the rest is for settling.
RAMP = 0.5
#: The ramps' fields: the substeps of the turn's and the move's ramps (ramp_substeps).
RAMP_FIELDS = ("ramp_turn", "ramp_move")
#: The wheels' geometry: half the track (m) and the wheels' radius (m).
WHEEL_FIELDS = ("half_track", "wheel_radius")


def ramp_substeps(n):
    """The substeps of an n-substep phase over which the wheels' targets move."""
    return max(1, round(RAMP * n))


@records.record(*BODY_FIELDS, *family.FAMILY_FIELDS, *RAMP_FIELDS, *WHEEL_FIELDS,
                "left_actuator", "right_actuator", "left_act", "right_act", "left_q", "right_q")
class WheelsRecord(records.Record):
    """The wheels' record: the body, the family's fields, the ramps, the wheels' geometry,
    the servos' ids, their activations' (act) and the wheel hinges' qpos addresses."""


WheelsRecord.constructor = njit(cache=True)(lambda *values: WheelsRecord(*values))


@njit(cache=True)
def phase(s, left, right, n, ramp, heading, watch):
    """A phase of n substeps turning the wheels by (left, right) rad over the first
    `ramp` substeps, then zero speeds for the rest. With `watch` (a move), the phase ends
    where the body touches the room along `heading` (family.touching, checked before each
    substep), the wheels held there (`halt`). The tilt is checked at the ramp's end and the
    phase's.
    Returns (status, substeps)."""
    dt = s.timestep
    s.ctrl[s.left_actuator] = left / (ramp * dt)
    s.ctrl[s.right_actuator] = right / (ramp * dt)
    for k in range(n):
        if k == ramp:
            if s.free != 0 and bindings.tilted(s.xmat, s.min_cos_tilt):
                return bindings.TIPPED, n
            s.ctrl[s.left_actuator] = 0.0
            s.ctrl[s.right_actuator] = 0.0
        if watch and family.touching(s, heading):
            halt(s)
            return bindings.OK, k
        status = bindings.run(s.m, s.d, 1, s.bad_qacc, s.xmat, False, s.min_cos_tilt)
        if status != bindings.OK:
            return status, n
    s.ctrl[s.left_actuator] = 0.0
    s.ctrl[s.right_actuator] = 0.0
    if s.free != 0 and bindings.tilted(s.xmat, s.min_cos_tilt):
        return bindings.TIPPED, n
    return bindings.OK, n


@njit(cache=True)
def turn_angles(s, angle):
    """The wheels' angles (left, right) that turn the body by `angle` rad counter-clockwise:
    -+angle * half track / radius."""
    w = angle * s.half_track / s.wheel_radius
    return -w, w


@njit(cache=True)
def move_angles(s, distance):
    """The wheels' angles (left, right) that move the body `distance` units forward: both
    distance / radius."""
    w = distance * s.unit / s.wheel_radius
    return w, w


@njit(cache=True)
def turn(s, angle, leftover):
    """Turns by `angle` rad counter-clockwise over the turn phase."""
    left, right = turn_angles(s, angle)
    return phase(s, left, right, s.n_turn, s.ramp_turn, 0.0, False)


@njit(cache=True)
def move(s, distance):
    """Moves `distance` units forward over the move phase, ending where the body touches
    the room."""
    left, right = move_angles(s, distance)
    _, _, heading = base_pose(s)
    return phase(s, left, right, s.n_move, s.ramp_move, heading,
                 not family.clear_ahead(s, heading, distance))


@njit(cache=True)
def halt(s):
    """The wheels' speeds 0 and their targets where the wheels are."""
    s.ctrl[s.left_actuator] = 0.0
    s.act[s.left_act] = s.qpos[s.left_q]
    s.ctrl[s.right_actuator] = 0.0
    s.act[s.right_act] = s.qpos[s.right_q]
    return bindings.OK, 0


#: The two-wheel family's step on this body (tasks.kernels.two_wheel.act, through
#: tasks.kernels.env_step.action): the turn, move and halt phases, then how a refused
#: move's state is kept and given back.
PHASES = (turn, move, halt, family.save_state, family.restore_state)
