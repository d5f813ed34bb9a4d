"""One agent step of any realisation, compiled: the entry points Python and the compiled
loop call, and the one table that says which kernels each realisation runs.

An agent step (`step`), read top to bottom: the action checked and clipped
(body.clip_finite); the realisation's action (`action`: DISPATCH below); the robot
still in the room (body.in_room: else the status OUTSIDE, a failed run); the goal test
(body.goal_reached); the observation (`observe`: Section 3.2's range codes and, for a
drive that senses it, the velocity). Everything that runs it runs this one function: the
dm_env hooks (tasks.navigation.Navigation, a step's work in before_step, its results read
back by after_step and get_observation), tasks.Environment's compiled step and the
protocol's compiled loop (experiments.running.fused). `observe` alone is an episode's
first observation.

DISPATCH is the dispatch table: each realisation's record type, its action and its
velocity reading, by name (the names of tasks.realisations and of the mounts' action
kinds). A two-wheel realisation's action is the family's step
(tasks.kernels.two_wheel.act) on the realisation's own phases, passed to it as
arguments; the thrusters' is the floating drive's step. `action` and `velocity` are
resolved from the table by the record's type when numba compiles an entry point for it:
the one place a record's type picks its code. This module imports every realisation's
kernels, so numba's cache of these entry points follows an edit of any of them
(compiled.cache).
"""
from numba import njit
from numba.extending import overload

from compiled import cache  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from tasks.kernels import bindings, body, gait, joint_motors, plan, sensing, servos, thrusters, \
    two_wheel, wheel_motors, wheels


# -- each realisation's action -------------------------------------------------------------

@njit(cache=True)
def servos_action(s, action, u):
    return two_wheel.act(s, action[0], u, servos.turn, servos.move, servos.halt,
                         two_wheel.save_state, two_wheel.restore_state)


@njit(cache=True)
def wheels_action(s, action, u):
    return two_wheel.act(s, action[0], u, wheels.turn, wheels.move, wheels.halt,
                         two_wheel.save_state, two_wheel.restore_state)


@njit(cache=True)
def wheel_motors_action(s, action, u):
    return two_wheel.act(s, action[0], u, wheel_motors.turn, wheel_motors.move, plan.halt,
                         plan.keep, plan.back)


@njit(cache=True)
def joint_motors_action(s, action, u):
    return two_wheel.act(s, action[0], u, joint_motors.turn, joint_motors.move, plan.halt,
                         plan.keep, plan.back)


@njit(cache=True)
def gait_action(s, action, u):
    return two_wheel.act(s, action[0], u, gait.turn, gait.move, gait.halt,
                         two_wheel.save_state, two_wheel.restore_state)


@njit(cache=True)
def thrusters_action(s, action, u):
    return thrusters.act(s, action, u)


@njit(cache=True)
def no_velocity(s, vel, noise):
    """A drive that senses no velocity: nothing."""


@njit(cache=True)
def thrusters_velocity(s, vel, noise):
    """The floating robot's velocity reading into vel (thrusters.velocity_reading)."""
    v = sensing.velocity(s.m, s.d, s.base, s.velocity, s.velocity6)
    vel[:] = thrusters.velocity_reading(s, v, noise)


#: The dispatch, by realisation: name -> (record, action(s, action, u) -> (status, substeps),
#: velocity(s, vel, noise)).
DISPATCH = {
    "servos": (servos.ServosRecord, servos_action, no_velocity),
    "wheels": (wheels.WheelsRecord, wheels_action, no_velocity),
    "wheel_motors": (wheel_motors.WheelMotorsRecord, wheel_motors_action, no_velocity),
    "joint_motors": (joint_motors.JointMotorsRecord, joint_motors_action, no_velocity),
    "gait": (gait.GaitRecord, gait_action, no_velocity),
    "thrusters": (thrusters.ThrustersRecord, thrusters_action, thrusters_velocity),
}


def _row(s):
    """DISPATCH' row of the record type s (numba's type, at compile time)."""
    for record, act, velocity in DISPATCH.values():
        if isinstance(s, record.numba_type):
            return act, velocity
    return None


def action(s, a, u):
    """The realisation's action for the clipped action a and the noise's draws u: its
    DISPATCH row's; returns (status, substeps). Compiled code only."""
    raise TypeError("tasks.kernels.env_step.action runs in compiled code (step)")


@overload(action)
def _action(s, a, u):
    row = _row(s)
    if row is not None:
        act = row[0]
        return lambda s, a, u: act(s, a, u)


def velocity(s, vel, noise):
    """The realisation's velocity reading into vel: its DISPATCH row's. Compiled code
    only."""
    raise TypeError("tasks.kernels.env_step.velocity runs in compiled code (observe, step)")


@overload(velocity)
def _velocity(s, vel, noise):
    row = _row(s)
    if row is not None:
        read = row[1]
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
