"""One agent step of any realisation, compiled: the entry points Python and the compiled
loop call.

An agent step (`step`), read top to bottom: the action checked and clipped
(body.clip_finite); the realisation's action (`action`); the robot still in the room
(body.in_room: else the status OUTSIDE, a failed run); the goal test
(body.goal_reached); the observation (`observe`: Section 3.2's range codes and, for a
drive that senses it, the velocity). Everything that runs it runs this one function: the
dm_env hooks (tasks.navigation.Navigation, a step's work in before_step, its results read
back by after_step and get_observation), tasks.Environment's compiled step and Section
3.6's compiled loop (experiments.running.fused). `observe` alone is an episode's first
observation.

Which kernels a realisation runs is its row of tasks.realisations.REALISATIONS, the one
table: its record type and its kernels' module. A two-wheel realisation's action is the
family's step (tasks.kernels.two_wheel.act), which runs the module's PHASES; a floating
one's is the module's `act`, and its velocity reading the module's `velocity`. They are
picked by the record's type (tasks.realisations.of_record) when numba compiles an entry
point for it.
"""
from numba import njit
from numba.extending import overload

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
# Every realisation's kernels, imported here so that numba's cache of the entry points
# follows an edit of any of them (compiled.cache); tasks.realisations.REALISATIONS names them.
from tasks.kernels import bindings, body, gait, joint_motors, servos, thrusters, two_wheel, \
    wheel_motors, wheels  # noqa: F401
from tasks.realisations import of_record


# -- each realisation's action and velocity reading ---------------------------------------

def action(s, a, u):
    """The realisation's action for the clipped action a and the noise's draws u; returns
    (status, substeps). A two-wheel realisation's is the family's step on its PHASES, a
    floating one's its kernels' `act`. Compiled code only."""
    raise TypeError("tasks.kernels.env_step.action runs in compiled code (step)")


@overload(action)
def _action(s, a, u):
    realisation = of_record(s)
    if realisation is None:
        return None
    if realisation.drive == "two_wheel":
        return lambda s, a, u: two_wheel.act(s, a[0], u)
    act = realisation.kernels().act
    return lambda s, a, u: act(s, a, u)


def velocity(s, vel, noise):
    """The realisation's velocity reading into vel: its kernels' `velocity` where its drive
    senses one (the floating drive's), else nothing. Compiled code only."""
    raise TypeError("tasks.kernels.env_step.velocity runs in compiled code (observe, step)")


@overload(velocity)
def _velocity(s, vel, noise):
    realisation = of_record(s)
    if realisation is None:
        return None
    read = getattr(realisation.kernels(), "velocity", None)
    if read is None:
        return lambda s, vel, noise: None
    return lambda s, vel, noise: read(s, vel, noise)


# -- the entry points ----------------------------------------------------------------------

@njit(cache=True)
def observe(s, noise, velocity_noise, codes, vel):
    """The observation: the range codes plus noise into codes (Section 3.2) and the
    realisation's velocity reading into vel."""
    codes[:] = body.sense(s, noise)
    velocity(s, vel, velocity_noise)


@njit(cache=True)
def step(s, a, u, noise, velocity_noise, codes, vel):
    """One agent step of the record's realisation on a finite action (clipped in place):
    the range codes into codes and, floating, the velocity into vel. Returns (status,
    substeps run, in the goal)."""
    if not body.clip_finite(a):
        return bindings.NOT_FINITE, 0, False
    status, n = action(s, a, u)
    if status != bindings.OK:
        return status, n, False
    if not body.in_room(s):
        return bindings.OUTSIDE, n, False
    goal = body.goal_reached(s)
    observe(s, noise, velocity_noise, codes, vel)
    return bindings.OK, n, goal
