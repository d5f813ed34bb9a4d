"""Floating robot (Unemi 2000, Section 3.3): a frictionless puck with x/y thrusters.

Action (ah, av) in [-1, 1]^2: at the start of the step the velocity changes by
0.2 (ah, av) units/step (each axis scaled by noise), then the puck coasts with its
own velocity until it bumps into something. It starts at rest.
"""
from models import UNIT
from tasks import navigation

MAX_ACCELERATION = 0.2  # units per step, per step

# The thrust acts during the first substep, then the puck coasts for the rest.
SUBSTEPS = 10


class Physics(navigation.Physics):
    """Adds the thrusters, as force motors on the slide joints."""

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        self._thrust_x = self.model.name2id("robot/thrust_x", "actuator")
        self._thrust_y = self.model.name2id("robot/thrust_y", "actuator")
        self._mass = float(self.model.body_subtreemass[self.model.name2id("robot/base", "body")])

    def thrust(self, dvx, dvy):
        """Sets the thrust that changes the velocity by (dvx, dvy) units/step in one substep."""
        scale = UNIT / self.step_seconds * self._mass / self.timestep
        ctrl = self._ctrl
        ctrl[self._thrust_x] = dvx * scale
        ctrl[self._thrust_y] = dvy * scale


class Floating(navigation.Navigation):
    action_dim = 2

    def initialize_episode(self, physics):
        physics.step_seconds = SUBSTEPS * physics.timestep
        super().initialize_episode(physics)

    def get_observation(self, physics):
        obs = super().get_observation(physics)
        obs["velocity"] = physics.robot_velocity()
        return obs

    def before_step(self, action, physics):
        ah, av = self.checked_action(action)
        nh, nv = self.noise_factors()
        physics.thrust(MAX_ACCELERATION * ah * nh, MAX_ACCELERATION * av * nv)
        physics.step(1)
        physics.thrust(0.0, 0.0)
        # The environment then coasts for SUBSTEPS - 1 substeps.
