"""Two-wheel robot (Unemi 2000, Section 3.3): turn, then move, in one agent step.

Action a in [-1, 1]: turn |a| rad (a < 0 left, counter-clockwise; a > 0 right),
then move 2 (1 - |a|) units forward. When a collision stops the move, the rest
of it becomes turn in the same direction as the commanded turn (right when a = 0),
at the action's own rate of 1 rad per 2 units. Each part is scaled by noise.
"""
import math

from models import UNIT
from tasks import navigation

MAX_TURN = 1.0  # rad per step
MAX_MOVE = 2.0  # units per step

# Substeps of the room's 0.05 s timestep in each phase of an agent step.
TURN_SUBSTEPS = 4
MOVE_SUBSTEPS = 8
# A move that falls short of its command by more than this (units) was stopped.
BLOCKED_TOLERANCE = 0.1


class Physics(navigation.Physics):
    """Adds the drive: speed along the heading and yaw rate, each a velocity servo."""

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        self._forward = m.name2id("robot/forward", "actuator")
        self._turn = m.name2id("robot/turn", "actuator")
        # Deadbeat servos: kv = driven inertia / timestep reaches the target speed in one
        # semi-implicit Euler step. The base's mass drives forward and grip, its yaw
        # inertia the turn.
        mass = 1.0 / m.dof_invweight0[self._dx]
        yaw_inertia = 1.0 / m.dof_invweight0[m.jnt_dofadr[m.name2id("robot/yaw", "joint")]]
        for name, inertia in (("forward", mass), ("grip", mass), ("turn", yaw_inertia)):
            i = m.name2id(f"robot/{name}", "actuator")
            kv = inertia / m.opt.timestep
            m.actuator_gainprm[i, 0] = kv
            m.actuator_biasprm[i, 2] = -kv

    def drive(self, speed, yaw_rate):
        """Servo targets: speed in units/s along the heading, yaw rate in rad/s."""
        ctrl = self._ctrl
        ctrl[self._forward] = speed * UNIT
        ctrl[self._turn] = yaw_rate


class TwoWheel(navigation.Navigation):
    action_dim = 1

    def initialize_episode(self, physics):
        physics.step_seconds = (TURN_SUBSTEPS + MOVE_SUBSTEPS) * physics.timestep
        super().initialize_episode(physics)

    def before_step(self, action, physics):
        (a,) = self.checked_action(action)
        noise_turn, noise_move = self.noise_factors()
        turn = -a * MAX_TURN * noise_turn  # counter-clockwise positive
        self._move = MAX_MOVE * (1.0 - abs(a)) * noise_move
        self._turn_sign = 1.0 if turn > 0 else -1.0
        dt = physics.timestep
        physics.drive(0.0, turn / (TURN_SUBSTEPS * dt))
        physics.step(TURN_SUBSTEPS)
        x, y, heading = physics.robot_pose()
        self._from = (x, y, math.cos(heading), math.sin(heading))
        # The environment then runs the move phase: MOVE_SUBSTEPS substeps.
        physics.drive(self._move / (MOVE_SUBSTEPS * dt), 0.0)

    def after_step(self, physics):
        x, y, _ = physics.robot_pose()
        x0, y0, c, s = self._from
        rest = self._move - ((x - x0) * c + (y - y0) * s)
        if rest > BLOCKED_TOLERANCE:
            dt = physics.timestep
            leftover = self._turn_sign * rest * MAX_TURN / MAX_MOVE
            physics.drive(0.0, leftover / (TURN_SUBSTEPS * dt))
            physics.step(TURN_SUBSTEPS)
        physics.drive(0.0, 0.0)
        super().after_step(physics)
