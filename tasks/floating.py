"""The floating drive (Unemi 2000, Section 3.3): thrust, then coast.

Action (ah, av) in [-1, 1]^2: at the start of the step the velocity changes by
0.2 (ah, av) units/step (each axis scaled by noise), then the robot coasts with its
own velocity until it bumps into something. It starts at rest. The robot file's
actuators ``thrust_x`` and ``thrust_y`` push along the world's x and y axes
(motors on slide joints, or on a site with a world-fixed reference site). The step
itself is tasks.kernels.floating.act (with the bump readings' coast, its bump_phase).
"""
import mujoco
import numpy as np

import models
from tasks import navigation
from tasks.kernels import bindings
from tasks.config import THRUSTS
from tasks.kernels import floating as kernels
from tasks.kernels.floating import FloatingDrive

MAX_ACCELERATION = 0.2  # units per step, per step
#: The velocity code's full scale (TaskConfig.velocity_code "code"), in units/step: the
#: two-wheel robot's longest move per step, a speed the puck rarely exceeds.
VELOCITY_FULL_SCALE = 2.0

# Seconds per agent step; the thrust acts during its first substep, then the robot
# coasts for the rest. At the planar robots' 0.05 s timestep: 10 substeps.
STEP_SECONDS = 0.5


def edit_model(spec, config):
    """The radius (navigation.edit_model) and the walls of the bump reading: "slide" and
    "bounce" make the bumper frictionless (condim 1); "grip" and "stop" keep its file's,
    with wall_friction, when given, as its sliding friction."""
    navigation.edit_model(spec, config)
    hull = spec.geom(models.PREFIX + "hull")
    if hull is None:
        return
    if config.bump in ("slide", "bounce"):
        hull.condim = 1
    elif config.wall_friction is not None:
        hull.friction[0] = config.wall_friction


class Physics(navigation.Physics):
    """Adds the thrusters, as force motors along the world's x and y; and, for the bump
    readings "stop" and "bounce", the velocity change at a contact, applied after each
    substep (tasks.kernels.floating.bump_phase)."""

    Record = FloatingDrive

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        thrust_x = navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "thrust_x")
        thrust_y = navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "thrust_y")
        if thrust_x < 0 or thrust_y < 0:
            raise navigation.ContractError("the floating drive needs actuators 'thrust_x' "
                                           "and 'thrust_y'")
        if self.n_beams != 8:
            raise navigation.ContractError(
                "the floating drive needs 8 rangefinders (E, NE, N, NW, W, SW, S, SE; eq 10)")
        self._mass = float(m.body_subtreemass[self._base])
        if self._free is not None:  # a free joint's dofs start with x, y
            dof_x, dof_y = self.free_dof, self.free_dof + 1
        else:
            dof_x = m.jnt_dofadr[self.base_joints["x"]]
            dof_y = m.jnt_dofadr[self.base_joints["y"]]
        #: The bumper geom's id (the bump readings' coast watches its contacts).
        self.hull = navigation.named_id(m, mujoco.mjtObj.mjOBJ_GEOM, "hull")
        d = data.ptr
        contact_f, contact_i, layout = bindings.contact_views(d)
        self.parts.update(
            thrust_x=thrust_x, thrust_y=thrust_y, hull=self.hull, dof_x=int(dof_x),
            dof_y=int(dof_y), ncon=bindings.contact_count(d), contact_f=contact_f,
            contact_i=contact_i, layout=layout, qpos0=np.empty(m.nq), qvel0=np.empty(m.nv),
            normal=np.empty(2), velocity6=self._body_velocity, bump=kernels.BUMP_PHYSICS,
            restitution=1.0)

    def set_bump(self, bump, restitution=1.0):
        """The bump reading applied after each substep: "stop" or "bounce" (with the
        share of the speed into the wall that it reflects); anything else leaves a wall
        to the contact's physics ("grip", "slide")."""
        self.parts.update(bump={"stop": kernels.BUMP_STOP,
                                "bounce": kernels.BUMP_BOUNCE}.get(bump, kernels.BUMP_PHYSICS),
                          restitution=float(restitution))

    def step(self, nstep=1):
        """Substeps with the bump reading (kernels.bump_phase): with "stop" or "bounce", a
        substep that brings the bumper into a wall while moving towards it is undone and
        the velocity becomes 0 ("stop") or its mirror image off the wall ("bounce"); with
        the others, the substeps as navigation.Physics.step runs them."""
        if nstep <= 0 or self.record is None:
            return super().step(nstep)
        status = kernels.bump_phase(self.record, nstep)
        self.substeps += nstep
        if status != bindings.OK:
            self.raise_for(status)

    def set_robot_pose(self, x, y, heading=0.0):
        """Places the robot at (x, y), at rest, heading 0 whatever is asked: a floating
        robot's beams point along the world's axes (E, NE, N, ...)."""
        super().set_robot_pose(x, y, 0.0)

    def thrust_scale(self):
        """The force per unit/step of velocity change in one substep."""
        return self.unit / self.step_seconds * self._mass / self.timestep


class Floating(navigation.Navigation):
    action_dim = 2
    observation_keys = ("range", "velocity")

    def __init__(self, config=navigation.TaskConfig(), **kw):
        super().__init__(config, **kw)
        self.velocity_noise = float(config.velocity_noise)

    def drive_settings(self, physics):
        n = substeps(physics.timestep, self.time_scale)
        physics.step_seconds = n * physics.timestep
        physics.set_bump(self.config.bump, self.config.restitution)
        return dict(n_thrust=1, n_coast=n - 1, max_acceleration=MAX_ACCELERATION,
                    thrust=THRUSTS.index(self.config.thrust),
                    velocity=physics.step_seconds / physics.unit,
                    thrust_force=physics.thrust_scale(),
                    velocity_code=int(self.config.velocity_code == "code"),
                    velocity_full=VELOCITY_FULL_SCALE)

    def sense_velocity(self, physics):
        """The velocity reading (units/step): with velocity_noise, plus Gaussian noise of
        that sd; with velocity_code "code", through the 0-255 code over
        +-VELOCITY_FULL_SCALE and back (tasks.kernels.floating.velocity_reading)."""
        noise = (self.random.normal(0.0, self.velocity_noise, size=2)
                 if self.velocity_noise > 0 else np.zeros(0))
        return kernels.velocity_reading(physics.record, physics.robot_velocity(), noise)


def substeps(timestep, time_scale=1.0):
    """Substeps per agent step."""
    return max(2, navigation.substeps(STEP_SECONDS * time_scale, timestep))
