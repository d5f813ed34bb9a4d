"""The floating drive (Unemi 2000, Section 3.3): thrust, then coast.

Action (ah, av) in [-1, 1]^2: at the start of the step the velocity changes by
0.2 (ah, av) units/step (each axis scaled by noise), then the robot coasts with its
own velocity until it bumps into something. It starts at rest. Its one realisation is
the thrusters (tasks.realisations.thrusters: the robot file's actuators ``thrust_x``
and ``thrust_y`` push along the world's x and y axes); the step itself is
tasks.kernels.thrusters.act (with the bump readings' coast, its bump_phase). This module
is the drive's task: its constants, each episode's settings, its edit of the model.
"""
import models
from tasks import navigation
from tasks.readings import READING_BY_NAME

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


class Floating(navigation.Navigation):
    """The floating drive's task: thrust, then coast; it senses its velocity too."""

    action_dim = 2
    observation_keys = ("range", "velocity")

    edit_model = staticmethod(edit_model)

    def drive_settings(self, physics):
        n = substeps(physics.timestep, self.time_scale)
        physics.step_seconds = n * physics.timestep
        physics.set_bump(self.config.bump, self.config.restitution)
        return dict(n_thrust=1, n_coast=n - 1, max_acceleration=MAX_ACCELERATION,
                    thrust=READING_BY_NAME["thrust"].code(self.config.thrust),
                    velocity=physics.step_seconds / physics.unit,
                    thrust_force=physics.thrust_scale(),
                    velocity_code=READING_BY_NAME["velocity_code"].code(self.config.velocity_code),
                    velocity_full=VELOCITY_FULL_SCALE)


def substeps(timestep, time_scale=1.0):
    """Substeps per agent step."""
    return max(2, navigation.substeps(STEP_SECONDS * time_scale, timestep))
