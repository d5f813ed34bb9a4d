"""The floating drive (Unemi 2000, Section 3.3): thrust, then coast.

Action (ah, av) in [-1, 1]^2: at the start of the step the velocity changes by
0.2 (ah, av) units/step (each axis scaled by noise), then the robot coasts with its
own velocity until it bumps into something. It starts at rest. The robot file's
actuators ``thrust_x`` and ``thrust_y`` push along the world's x and y axes
(motors on slide joints, or on a site with a world-fixed reference site).
"""

import mujoco
import numpy as np

import models
from tasks import kernels, navigation
from tasks.config import THRUSTS

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
    substep (tasks.kernels.bump_phase)."""

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        self._thrust_x = navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "thrust_x")
        self._thrust_y = navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "thrust_y")
        if self._thrust_x < 0 or self._thrust_y < 0:
            raise navigation.ContractError("the floating drive needs actuators 'thrust_x' "
                                           "and 'thrust_y'")
        if self._beams.stop - self._beams.start != 8:
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
        self._settings.update(act0=self._thrust_x, act1=self._thrust_y, hull=self.hull,
                              dof_x=dof_x, dof_y=dof_y)

    def set_bump(self, bump, restitution=1.0):
        """The bump reading applied after each substep: "stop" or "bounce" (with the
        share of the speed into the wall that it reflects); anything else leaves a wall
        to the contact's physics ("grip", "slide")."""
        self.set_drive(bump={"stop": kernels.BUMP_STOP,
                             "bounce": kernels.BUMP_BOUNCE}.get(bump, kernels.BUMP_PHYSICS),
                       restitution=restitution)

    def step(self, nstep=1):
        """Substeps; with "stop" or "bounce", a substep that brings the bumper into a wall
        while moving towards it is undone (no contact forces act, nothing sinks in), and
        the velocity becomes 0 ("stop") or its mirror image off the wall ("bounce", the
        part into the wall scaled by the restitution); with the others, the substeps as
        navigation.Physics.step runs them."""
        status = kernels.bump_phase(self.drive_record(), nstep)
        self.substeps += nstep
        if status != kernels.OK:
            self.raise_for(status)

    def set_robot_pose(self, x, y, heading=0.0):
        """Places the robot at (x, y), at rest, heading 0 whatever is asked: a floating
        robot's beams point along the world's axes (E, NE, N, ...)."""
        super().set_robot_pose(x, y, 0.0)

    def thrust_scale(self):
        """The force per unit/step of velocity change in one substep."""
        return self.unit / self.step_seconds * self._mass / self.timestep

    def thrust(self, dvx, dvy):
        """Sets the thrust that changes the velocity by (dvx, dvy) units/step in one substep."""
        scale = self.thrust_scale()
        ctrl = self._ctrl
        ctrl[self._thrust_x] = dvx * scale
        ctrl[self._thrust_y] = dvy * scale


class Floating(navigation.Navigation):
    action_dim = 2
    kind = kernels.FLOATING
    observation_keys = ("range", "velocity")

    def __init__(self, config=navigation.TaskConfig(), **kw):
        super().__init__(config, **kw)
        self.velocity_noise = float(config.velocity_noise)

    def initialize_episode(self, physics):
        physics.step_seconds = substeps(physics.timestep, self.time_scale) * physics.timestep
        physics.set_bump(self.config.bump, self.config.restitution)
        n = substeps(physics.timestep, self.time_scale)
        self.start_drive(physics, **self.kernel_settings(1, n - 1, (MAX_ACCELERATION, 0.0)),
                         thrust=THRUSTS.index(self.config.thrust),
                         velocity=physics.step_seconds / physics.unit,
                         thrust_force=physics.thrust_scale(),
                         velocity_code=self.config.velocity_code == "code",
                         velocity_full=VELOCITY_FULL_SCALE)
        super().initialize_episode(physics)

    def get_observation(self, physics):
        obs = super().get_observation(physics)
        obs["velocity"] = self.sense_velocity(physics)
        return obs

    def sense_velocity(self, physics):
        """The velocity reading (units/step): with velocity_noise, plus Gaussian noise of
        that sd; with velocity_code "code", through the 0-255 code over
        +-VELOCITY_FULL_SCALE and back (Section 3.2's encoding applied to a velocity)."""
        v = physics.robot_velocity()
        config = self.config
        if config.velocity_noise > 0:
            v = v + self.random.normal(0.0, config.velocity_noise, size=2)
        if config.velocity_code == "code":
            half = navigation.SENSOR_LEVELS / 2
            code = np.rint(np.clip(v / VELOCITY_FULL_SCALE, -1.0, 1.0) * half + half)
            v = (code - half) / half * VELOCITY_FULL_SCALE
        return v

    def demand(self, a):
        """The velocity change (units/step) for a demand a in [-1, 1], by the thrust
        reading: "scaled" 0.2 a, "demand" a, "clipped" a clipped to [-0.2, 0.2]."""
        thrust = self.config.thrust
        if thrust == "scaled":
            return MAX_ACCELERATION * a
        if thrust == "demand":
            return a
        return min(max(a, -MAX_ACCELERATION), MAX_ACCELERATION)

    def before_step(self, action, physics):
        ah, av = self.checked_action(action)
        nh, nv = self.noise_factors()
        physics.thrust(self.demand(ah) * nh, self.demand(av) * nv)
        physics.step(1)
        physics.thrust(0.0, 0.0)
        # The environment then coasts for the other substeps.


def substeps(timestep, time_scale=1.0):
    """Substeps per agent step."""
    return max(2, navigation.substeps(STEP_SECONDS * time_scale, timestep))


def move_substeps(timestep, time_scale=1.0):
    """Substeps the environment runs per agent step: the coast after the thrust."""
    return substeps(timestep, time_scale) - 1
