"""One agent step of any drive, compiled: the entry points Python and the compiled loop call.

`step` is a whole agent step of the dm_env hooks' work (the action clipped, the drive's
action, the goal test, the range codes and, floating, the velocity), as
tasks.navigation.Navigation.compiled_step and the protocol's compiled loop
(experiments.running.fused) run it; `act` is the drive's action alone, as the hooks'
before_step runs it. Both dispatch on the record's type: the floating drive's
(tasks.kernels.floating.act) or the two-wheel family's (tasks.kernels.two_wheel.act) on
one of its realisations (planar, wheels, motors, gait, joints). This module imports every
drive's kernels, so numba's cache of these entry points follows an edit of any of them
(ebrl.compiled).
"""
from numba import njit
from numba.extending import overload

from ebrl import compiled  # noqa: F401  numba's cache keyed on every file a kernel compiles in
from tasks.kernels import bindings, body, floating, gait, joints, motors, planar, sensing, \
    two_wheel, wheels

#: The two-wheel family's realisations' record types.
TWO_WHEEL_RECORDS = tuple(r.numba_type for r in (planar.PlanarDrive, wheels.WheelDrive,
                                                 motors.MotorWheelDrive, gait.GaitDrive,
                                                 joints.JointDrive))


def drive_act(s, action, u):
    """The drive's action for the clipped action and the noise's draws u; returns
    (status, substeps)."""
    raise NotImplementedError("overloaded for each drive's record type")


@overload(drive_act)
def _drive_act(s, action, u):
    if isinstance(s, floating.FloatingDrive.numba_type):
        return lambda s, action, u: floating.act(s, action, u)
    if isinstance(s, TWO_WHEEL_RECORDS):
        return lambda s, action, u: two_wheel.act(s, action[0], u)


def read_velocity(s, vel, noise):
    """The floating robot's velocity reading into vel (tasks.kernels.floating); nothing
    for the others."""
    raise NotImplementedError("overloaded for each drive's record type")


@overload(read_velocity)
def _read_velocity(s, vel, noise):
    if isinstance(s, floating.FloatingDrive.numba_type):
        def impl(s, vel, noise):
            v = sensing.velocity(s.m, s.d, s.base, s.velocity, s.velocity6)
            vel[:] = floating.velocity_reading(s, v, noise)
        return impl
    if isinstance(s, TWO_WHEEL_RECORDS):
        return lambda s, vel, noise: None


@njit(cache=True)
def act(s, action, u):
    """The drive's action (the hooks' before_step) on a clipped action; returns (status,
    substeps run)."""
    return drive_act(s, action, u)


@njit(cache=True)
def step(s, action, u, noise, velocity_noise, codes, vel):
    """One agent step of the record's drive on a finite action (clipped in place): the
    range codes into codes and, floating, the velocity into vel. Returns (status,
    substeps run, in the goal)."""
    if not body.clip_unit(action):
        return bindings.NOT_FINITE, 0, False
    status, n = drive_act(s, action, u)
    if status != bindings.OK:
        return status, n, False
    goal = body.goal_reached(s)
    codes[:] = body.sense(s, noise)
    read_velocity(s, vel, velocity_noise)
    return bindings.OK, n, goal
