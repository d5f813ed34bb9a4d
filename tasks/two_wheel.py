"""The two-wheel drive (Unemi 2000, Section 3.3): turn, then move, in one agent step.

Action a in [-1, 1]: turn |a| rad (a < 0 left, counter-clockwise; a > 0 right),
then move 2 (1 - |a|) units forward. When a collision stops the move (the body touches
a wall or an obstacle: the move ends there), the rest of it becomes turn in the same
direction as the commanded turn (right when a = 0), at the action's own rate of 1 rad
per 2 units. Each part is scaled by noise. The reading `leftover_turn` ("away": the rest
turns away from the nearer side) changes the turn's way; `blocked_move` "refuse" (the
move undone, all of it turned: protocol 7's, no reading of Section 3.3) remakes protocol
7's runs (tasks/readings.py). The step itself is tasks.kernels.two_wheel.act, written
once; a realisation says how a body turns and moves (tasks.realisations: servos, wheels,
wheel_motors, joint_motors, gait). This module is the family's task: its constants, the
geom pairs a move watches (`touch_pairs`) and each episode's settings.
"""
import numpy as np

from tasks import navigation
from tasks.readings import READING_BY_NAME
from tasks.simulator import mujoco

MAX_TURN = 1.0  # rad per step
MAX_MOVE = 2.0  # units per step

# Seconds of each phase of an agent step: a turn, then a move, then (when blocked) a
# leftover turn. At the planar robots' 0.05 s timestep: 4 + 8 (+ 4) substeps.
TURN_SECONDS = 0.2
MOVE_SECONDS = 0.4
# A move that falls short of its command by more than this (units) was stopped.
BLOCKED_TOLERANCE = 0.1


def touch_pairs(model, base):
    """The pairs (robot geom, room geom) that can touch, as an (n, 2) int32 array: every
    geom of the robot (the tree under its base body) with every geom of the room that
    MuJoCo's contype/conaffinity let it collide with, the floor excepted (model: an
    MjModel)."""
    root = model.body_rootid[base]
    mine = model.body_rootid[model.geom_bodyid] == root
    floor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    kind, affinity = model.geom_contype, model.geom_conaffinity
    pairs = [(g, w) for g in np.flatnonzero(mine) for w in np.flatnonzero(~mine)
             if w != floor and (kind[g] & affinity[w] or kind[w] & affinity[g])]
    return np.array(pairs, dtype=np.int32).reshape(-1, 2)


class TwoWheel(navigation.Navigation):
    """The two-wheel action family on a wheeled body: a turn phase and a move phase of
    fixed seconds, whose substeps the episode fixes (the gait's task,
    tasks.realisations.gait.GaitTask, walks them instead)."""

    action_dim = 1

    def family_settings(self, physics):
        """The family's part of a record (tasks.kernels.two_wheel.FAMILY_FIELDS) but its
        phases' substeps: its constants, the task config's readings (as their codes),
        room for the state a refused move returns to, and the geom pairs that tell where a
        move touches the room."""
        m = physics.model
        config = self.config
        return dict(max_turn=MAX_TURN, max_move=MAX_MOVE, tolerance=BLOCKED_TOLERANCE,
                    blocked_move=READING_BY_NAME["blocked_move"].code(config.blocked_move),
                    leftover_turn=READING_BY_NAME["leftover_turn"].code(config.leftover_turn),
                    qpos0=np.empty(m.nq), qvel0=np.empty(m.nv), act0=np.empty(m.na),
                    pairs=touch_pairs(m.ptr, physics.body["base"]), fromto=np.empty(6))

    def drive_settings(self, physics):
        dt = physics.timestep
        n_turn = navigation.substeps(TURN_SECONDS * self.time_scale, dt)
        n_move = navigation.substeps(MOVE_SECONDS * self.time_scale, dt)
        physics.step_seconds = (n_turn + n_move) * dt
        return dict(n_turn=n_turn, n_move=n_move, **self.family_settings(physics),
                    **physics.phase_settings(n_turn, n_move))
