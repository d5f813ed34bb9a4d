"""The gait drive: the two-wheel action family (Section 3.3) executed by a legged robot.

Action a in [-1, 1], as tasks.two_wheel: turn |a| rad (a < 0 left), then move 2 (1 - |a|)
units along the new heading; a move that a wall stops is finished as a turn in the same
direction (or away from the nearer side, with leftover_turn="away"), at 1 rad per 2 units;
each part scaled by the action noise. A legged body has
no velocity servo to command: a hand-built central pattern generator (CPG) walks it, with
heading feedback. No learned policy.

The CPG is a trot: diagonal legs in phase, the two pairs half a cycle apart. Leg i at
phase phi (one cycle per 1 / frequency s) holds its hip at

    hip_i = hip_rest_i + amplitude * (forward * f_i + turn * r_i) * -cos(phi)

and lifts its foot, ankle_i = ankle_rest_i + lift * lift_i * max(0, -sin(phi)), in the
half cycle its hip swings back (phi in [pi, 2 pi)). f_i and r_i are each hip's share of a
stance sweep that pushes the body forward or turns it counter-clockwise (from the hip's
kinematics at rest: the foot's motion per radian against the -x direction and against the
clockwise tangent), lift_i the ankle's sign that raises the foot; all are read from the
model, so the gait needs no leg names beyond its actuators. A PD loop per joint turns the
targets into the file's motor controls (ctrl = kp (target - q) - kd dq, clipped to the
motor's range).

Heading feedback: in a turn, turn = clip(heading_gain * (target - heading)), forward = 0,
until the heading is within turn_tolerance or max_turn_seconds pass. In a move, forward = 1
(less over the last slow_down units), turn = the same feedback on the heading the move
started with, until the base has moved the commanded distance along it or max_move_seconds
pass; a move short by more than two_wheel.BLOCKED_TOLERANCE at its timeout was blocked.

A fall is a PhysicsError (tasks.navigation: the base tilted past max_tilt degrees), as for
any free-joint robot; a run that raises one is a failed run.

The walking itself is compiled (tasks.kernels.gait: the CPG, the PD loops and the
feedback, as the two-wheel family's realisation, tasks.kernels.two_wheel.act); this module
reads the legs' shares from the model and gives the episode's settings.
"""
import math

import mujoco
import numpy as np

from tasks import navigation

from tasks.kernels.gait import GaitDrive
from tasks.two_wheel import family_settings

#: The gait's parameters (a mount's [action.gait] may set any of them) and defaults.
PARAMETERS = {
    "frequency": 1.0,          # CPG cycles per second
    "amplitude": 0.45,         # hip sweep, rad (the ant's hips reach +-0.52)
    "lift": 0.35,              # ankle lift in the swing, rad (the ant's ankles reach +-0.35)
    "kp": 15.0,                # PD gain, control per rad
    "kd": 1.0,                 # PD damping, control per rad/s
    "heading_gain": 2.0,       # turn command per rad of heading error
    "turn_tolerance": 0.01,    # rad: a turn ends within this of its target
    "slow_down": 0.5,          # units: the move's forward command ramps down over these
    "coast": 0.06,             # units: a move stops this short of its target (the body
                               # coasts on as the legs return to rest)
    "max_turn_seconds": 4.0,
    "max_move_seconds": 6.0,
    "settle_seconds": 0.3,     # at the end of each phase the legs return to rest
    "control_substeps": 1,     # substeps per CPG and PD update
    "feedback_seconds": 0.05,  # seconds between heading and distance feedback updates
    "max_tilt": 30.0,          # degrees: a base tilted further has fallen
}

#: The gait's actuators by role, as a mount maps them: hip_0..3 and ankle_0..3.
LEGS = 4


class Physics(navigation.Physics):
    """A legged base on a free joint, its hips and ankles under the gait's PD loops."""

    Record = GaitDrive
    gait = dict(PARAMETERS)

    def _reload_from_data(self, data):
        self._min_cos_tilt = math.cos(math.radians(self.gait["max_tilt"]))
        super()._reload_from_data(data)
        m = self.model
        if self._free is None:
            raise navigation.ContractError("the gait drive needs a base on a free joint")
        mjm = m.ptr
        act = {}
        for role in [f"hip_{i}" for i in range(LEGS)] + [f"ankle_{i}" for i in range(LEGS)]:
            i = navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, role)
            if i < 0:
                raise navigation.ContractError(f"the gait drive needs an actuator {role!r}")
            act[role] = i
        self._acts = np.array([act[f"hip_{i}"] for i in range(LEGS)]
                              + [act[f"ankle_{i}"] for i in range(LEGS)], dtype=np.int64)
        joints = mjm.actuator_trnid[self._acts, 0]
        self._q = mjm.jnt_qposadr[joints].astype(np.int64)
        self._dq = mjm.jnt_dofadr[joints].astype(np.int64)
        self._ctrl_lo = mjm.actuator_ctrlrange[self._acts, 0].copy()
        self._ctrl_hi = mjm.actuator_ctrlrange[self._acts, 1].copy()
        unlimited = ~mjm.actuator_ctrllimited[self._acts].astype(bool)
        self._ctrl_lo[unlimited], self._ctrl_hi[unlimited] = -np.inf, np.inf
        self._rest = mjm.qpos0[self._q].copy()
        self._shares(mjm, joints)
        g = self.gait
        k = int(g["control_substeps"])

        def ticks(seconds):
            return max(1, round(seconds / (k * self.timestep)))

        self.parts.update(
            acts=self._acts, q=self._q, dq=self._dq, rest=self._rest, ctrl_lo=self._ctrl_lo,
            ctrl_hi=self._ctrl_hi, forward_share=self._forward_share,
            turn_share=self._turn_share, lift_sign=self._lift_sign, offset=self._offset,
            kp=float(g["kp"]), kd=float(g["kd"]), tick=k * self.timestep, control_substeps=k,
            **{name: float(g[name]) for name in (
                "amplitude", "lift", "frequency", "heading_gain", "turn_tolerance",
                "slow_down", "coast", "max_turn_seconds", "max_move_seconds",
                "feedback_seconds")},
            n_feedback=ticks(g["feedback_seconds"]), n_settle=ticks(g["settle_seconds"]))

    def _shares(self, mjm, joints):
        """Each hip's forward and turning shares and each ankle's lift sign, from the
        kinematics at rest (the foot: the far end of the leg's outermost body)."""
        d = mujoco.MjData(mjm)
        mujoco.mj_kinematics(mjm, d)
        base = self._base
        rot = d.xmat[base].reshape(3, 3)

        def foot(leg):
            # the outermost body below the hip's: its frame plus its geoms' farthest point
            body = int(mjm.jnt_bodyid[joints[LEGS + leg]])
            geoms = np.flatnonzero(mjm.geom_bodyid == body)
            points = d.geom_xpos[geoms] if len(geoms) else d.xpos[body][None]
            far = points[np.argmax(np.linalg.norm(points[:, :2] - d.xpos[base][:2], axis=1))]
            return rot.T @ (far - d.xpos[base])

        def moved(qadr, delta, leg):
            d.qpos[:] = mjm.qpos0
            d.qpos[qadr] += delta
            mujoco.mj_kinematics(mjm, d)
            return foot(leg)

        self._forward_share = np.zeros(LEGS)
        self._turn_share = np.zeros(LEGS)
        self._lift_sign = np.zeros(LEGS)
        h = 1e-3
        for leg in range(LEGS):
            p = moved(self._q[leg], 0.0, leg)
            dp = (moved(self._q[leg], h, leg) - moved(self._q[leg], -h, leg)) / (2 * h)
            # stance pushes the body forward: the foot moves towards -x relative to it
            self._forward_share[leg] = -dp[0] / max(1e-9, np.linalg.norm(dp[:2]))
            # stance turns the body counter-clockwise: the foot moves clockwise about it
            cw = np.array([p[1], -p[0]]) / max(1e-9, math.hypot(p[0], p[1]))
            self._turn_share[leg] = float(dp[:2] @ cw) / max(1e-9, np.linalg.norm(dp[:2]))
            up = moved(self._q[LEGS + leg], h, leg)[2] - moved(self._q[LEGS + leg], -h, leg)[2]
            self._lift_sign[leg] = 1.0 if up > 0 else -1.0
        #: Trot: legs whose feet are diagonal share a phase. Leg i's phase offset, cycles.
        side = np.array([np.sign(foot_xy[1]) for foot_xy in
                         (moved(self._q[leg], 0.0, leg) for leg in range(LEGS))])
        front = np.array([np.sign(moved(self._q[leg], 0.0, leg)[0]) for leg in range(LEGS)])
        self._offset = np.where(side * front > 0, 0.0, 0.5)

    def episode_settings(self):
        """The CPG's state at an episode's start: phase 0, targets 0; scratch."""
        return dict(phase=np.zeros(1), target=np.zeros(2 * LEGS), share=np.zeros(LEGS))


def check_config(config):
    """ValueError for a task reading the gait cannot run: a refused move (a walked step
    cannot be put back)."""
    if config.blocked_move != "stop":
        raise ValueError("the gait drive has blocked_move=stop only (a walked step cannot "
                         "be put back)")


class Gait(navigation.Navigation):
    """The two-wheel action family through the CPG (see the module's docstring)."""

    action_dim = 1

    def drive_settings(self, physics):
        check_config(self.config)
        # an agent step's nominal seconds (the velocity read-out's unit): the longest
        # turn and move
        g = physics.gait
        physics.step_seconds = g["max_turn_seconds"] + g["max_move_seconds"]
        return dict(n_turn=0, n_move=0, **family_settings(self.config, physics),
                    **physics.episode_settings())


def physics_class(parameters):
    """gait.Physics with a mount's parameters (a dict of PARAMETERS' names)."""
    return type("GaitPhysics", (Physics,), {"gait": PARAMETERS | dict(parameters)})
