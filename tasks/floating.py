"""The floating drive (Unemi 2000, Section 3.3): thrust, then coast.

Action (ah, av) in [-1, 1]^2: at the start of the step the velocity changes by
0.2 (ah, av) units/step (each axis scaled by noise), then the robot coasts with its
own velocity until it bumps into something. It starts at rest. The robot file's
actuators ``thrust_x`` and ``thrust_y`` push along the world's x and y axes
(motors on slide joints, or on a site with a world-fixed reference site).
"""
import mujoco

from models import UNIT
from tasks import navigation

MAX_ACCELERATION = 0.2  # units per step, per step

# Seconds per agent step; the thrust acts during its first substep, then the robot
# coasts for the rest. At the planar robots' 0.05 s timestep: 10 substeps.
STEP_SECONDS = 0.5


class Physics(navigation.Physics):
    """Adds the thrusters, as force motors along the world's x and y."""

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        self._thrust_x = navigation._id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "thrust_x")
        self._thrust_y = navigation._id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "thrust_y")
        if self._thrust_x < 0 or self._thrust_y < 0:
            raise navigation.ContractError("the floating drive needs actuators 'thrust_x' "
                                           "and 'thrust_y'")
        if self._beams.stop - self._beams.start != 8:
            raise navigation.ContractError(
                "the floating drive needs 8 rangefinders (E, NE, N, NW, W, SW, S, SE; eq 10)")
        self._mass = float(m.body_subtreemass[self._base])

    def set_robot_pose(self, x, y, heading=0.0):
        """Places the robot at (x, y), at rest, heading 0 whatever is asked: a floating
        robot's beams point along the world's axes (E, NE, N, ...)."""
        super().set_robot_pose(x, y, 0.0)

    def thrust(self, dvx, dvy):
        """Sets the thrust that changes the velocity by (dvx, dvy) units/step in one substep."""
        scale = UNIT / self.step_seconds * self._mass / self.timestep
        ctrl = self._ctrl
        ctrl[self._thrust_x] = dvx * scale
        ctrl[self._thrust_y] = dvy * scale


class Floating(navigation.Navigation):
    action_dim = 2

    def initialize_episode(self, physics):
        physics.step_seconds = substeps(physics.timestep, self.time_scale) * physics.timestep
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
        # The environment then coasts for the other substeps.


def substeps(timestep, time_scale=1.0):
    """Substeps per agent step."""
    return max(2, round(STEP_SECONDS * time_scale / timestep))


def move_substeps(timestep, time_scale=1.0):
    """Substeps the environment runs per agent step: the coast after the thrust."""
    return substeps(timestep, time_scale) - 1
