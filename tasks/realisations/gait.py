"""The gait realisation: the two-wheel action family (Section 3.3) executed by a legged
robot.

Action a in [-1, 1], as tasks.two_wheel's: turn |a| rad (a < 0 left), then move 2 (1 - |a|)
units along the new heading; a move that a wall stops is finished as a turn in the same
direction (or away from the nearer side, with leftover_turn="away"), at 1 rad per 2 units;
each part scaled by the action noise. A legged body has
no velocity servo to command: a hand-built central pattern generator (CPG) walks it, with
heading feedback. No learned policy.

The CPG is a trot: diagonal legs in phase, the two pairs half a cycle apart. The legs are
listed by the mount (Leg: a swing joint, one or more lift joints, optional held joints).
Leg i at phase phi (one cycle per 1 / frequency s) holds its swing joint at

    swing_i = swing_rest_i + amplitude * (forward * f_i + turn * r_i) * -cos(phi)

and lifts its foot, lift_j = lift_rest_j + lift * lift_sign_j * max(0, -sin(phi)) for each
of its lift joints j, in the half cycle its swing goes back (phi in [pi, 2 pi)); a held
joint stays at rest. f_i and r_i are each swing's share of a stance sweep that pushes the
body forward or turns it counter-clockwise (from the leg's kinematics at rest: the foot's
motion per radian against the -x direction and against the clockwise tangent),
lift_sign_j the sign that raises the foot; all are read from the model, so the gait needs
no leg names beyond the joints. What moves the joints is read from the model too: a
torque motor on each gets a PD loop (ctrl = kp (target - q) - kd dq, clipped to the
motor's range, the Ant's); position servos (on the joints or on tendons over them) get
their lengths at the targets (each servo's length per radian of each listed joint,
measured at load; clipped to its range, the suite quadruped's).

Heading feedback: in a turn, turn = clip(heading_gain * (target - heading)), forward = 0,
until the heading is within turn_tolerance or max_turn_seconds pass. In a move, forward = 1
(less over the last slow_down units), turn = the same feedback on the heading the move
started with, until the base has moved the commanded distance along it or max_move_seconds
pass; a move short by more than two_wheel.BLOCKED_TOLERANCE at its timeout was blocked.

A fall is a PhysicsError (tasks.navigation: the base tilted past max_tilt degrees) at the
end of a phase (a turn or a move, the legs back at rest), as the car's motors judge it; a
tilt within a phase that the robot recovers from is none (docs/interpretation.md, "The
suite quadruped": seed 8's one tick at 31 degrees). A run that raises one is a failed run.

The walking itself is compiled (tasks.kernels.gait: the CPG, the PD loops and the
feedback, the phases of the two-wheel family's step, tasks.kernels.two_wheel.act); this
module reads the legs' shares from the model and gives the episode's settings.
"""
import math

import numpy as np

from tasks import navigation
from tasks.actuators import OTHER_ADVICE, control_ranges, length_gains, model_kind, \
    model_why_other
from tasks.kernels.gait import GaitRecord
from tasks.kernels.gait import HELD, LIFT, SWING
from tasks.mount.frame import rest_data
from tasks.realisations.gait_parameters import PARAMETERS
from tasks.simulator import mujoco
from tasks.two_wheel import TwoWheel

#: A leg as a mount lists it: its swing joint (moves the foot fore and aft), its lift
#: joints (raise it), its held joints (an optional yaw, kept at rest); the file's names.
Leg = tuple[str, tuple[str, ...], tuple[str, ...]]


class GaitPhysics(navigation.Physics):
    """A legged base on a free joint, its legs' joints under the gait: PD loops onto
    their torque motors, or their targets onto position servos. A mount's parameters and
    legs are set on a subclass (tasks.realisations.Realisation.physics_class)."""

    Record = GaitRecord
    gait = dict(PARAMETERS)
    #: The legs (Leg), in the mount's order.
    legs: tuple[Leg, ...] = ()

    def _reload_from_data(self, data):
        self._min_cos_tilt = math.cos(math.radians(self.gait["max_tilt"]))
        super()._reload_from_data(data)
        m = self.model
        if self._free is None:
            raise navigation.ContractError("the gait drive needs a base on a free joint",
                                           field="joints")
        mjm = m.ptr
        self._listing(mjm)
        self._shares(mjm)
        g = self.gait
        k = int(g["control_substeps"])

        def ticks(seconds):
            return max(1, round(seconds / (k * self.timestep)))

        self.parts.update(
            leg=self._leg, role=self._role, lift_sign=self._lift_sign, q=self._q, dq=self._dq,
            rest=self._rest, acts=self._acts, ctrl_lo=self._ctrl_lo, ctrl_hi=self._ctrl_hi,
            motor_sign=self._motor_sign,
            forward_share=self._forward_share, turn_share=self._turn_share, offset=self._offset,
            servos=self._servos, servo_gain=self._servo_gain, servo_rest=self._servo_rest,
            servo_lo=self._servo_lo, servo_hi=self._servo_hi,
            kp=float(g["kp"]), kd=float(g["kd"]), tick=k * self.timestep, control_substeps=k,
            **{name: float(g[name]) for name in (
                "amplitude", "lift", "frequency", "heading_gain", "turn_tolerance",
                "slow_down", "coast", "max_turn_seconds", "max_move_seconds",
                "feedback_seconds")},
            n_feedback=ticks(g["feedback_seconds"]), n_settle=ticks(g["settle_seconds"]))

    def _listing(self, mjm):
        """The listed joints (each leg's swing, then lifts, then held joints) and what
        drives them: a torque motor on each (PD loops), or position servos (every servo
        that moves a listed joint; their controls' change per radian measured from
        their lengths at rest)."""
        if not self.legs:
            raise navigation.ContractError("the gait drive needs legs listed", field="action.legs")
        names, leg, role = [], [], []
        for i, (swing, lifts, held) in enumerate(self.legs):
            for r, group in ((SWING, (swing,)), (LIFT, lifts), (HELD, held)):
                names += group
                leg += [i] * len(group)
                role += [r] * len(group)
        joints = []
        for name in names:
            j = mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_JOINT, navigation.PREFIX + name)
            if j < 0 or int(mjm.jnt_type[j]) not in (int(mujoco.mjtJoint.mjJNT_HINGE),
                                                     int(mujoco.mjtJoint.mjJNT_SLIDE)):
                raise navigation.ContractError(f"the gait drive needs a hinge or slide {name!r}",
                                               field="action.legs")
            joints.append(j)
        self._joints = np.array(joints, dtype=np.int64)
        self._leg = np.array(leg, dtype=np.int64)
        self._role = np.array(role, dtype=np.int64)
        self._q = mjm.jnt_qposadr[self._joints].astype(np.int64)
        self._dq = mjm.jnt_dofadr[self._joints].astype(np.int64)
        self._rest = self.rest_qpos[self._q].copy()
        # what moves each listed joint: the actuators' lengths' change per radian of it
        gain, lengths = length_gains(mjm, self._q, self.rest_qpos)
        movers = np.flatnonzero(np.any(gain != 0.0, axis=1))
        other = next((a for a in movers if model_kind(mjm, a) is None), None)
        if other is not None:
            raise navigation.ContractError(
                f"the gait drive needs the listed joints moved by torque motors or position "
                f"servos; actuator {mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_ACTUATOR, other)!r} "
                f"is neither: {model_why_other(mjm, other)}: {OTHER_ADVICE}", field="action.legs")
        lo, hi = control_ranges(mjm, np.arange(mjm.nu))
        if all(model_kind(mjm, a) == "torque motors" and int(mjm.actuator_trntype[a]) == int(
                mujoco.mjtTrn.mjTRN_JOINT) for a in movers):
            acts = np.full(len(joints), -1, dtype=np.int64)
            for a in movers:
                acts[list(self._joints).index(mjm.actuator_trnid[a, 0])] = a
            missing = [names[c] for c in range(len(joints)) if acts[c] < 0 and role[c] != HELD]
            if missing:
                raise navigation.ContractError(
                    f"the gait drive needs a motor on joint {missing[0]!r}", field="action.legs")
            self._acts = acts
            self._servos = np.zeros(0, dtype=np.int64)
            # a motor's force per unit control on its joint: gear times gain
            force = mjm.actuator_gear[acts, 0] * mjm.actuator_gainprm[acts, 0]
            self._motor_sign = np.where((acts >= 0) & (force < 0), -1.0, 1.0)
        elif all(model_kind(mjm, a) == "position servos" for a in movers):
            self._acts = np.full(len(joints), -1, dtype=np.int64)
            self._servos = movers.astype(np.int64)
            self._motor_sign = np.ones(len(joints))
        else:
            raise navigation.ContractError(
                "the gait drive needs the listed joints moved by torque motors on them "
                "or by position servos, not a mix", field="action.legs")
        self._ctrl_lo = np.where(self._acts >= 0, lo[self._acts], 0.0)
        self._ctrl_hi = np.where(self._acts >= 0, hi[self._acts], 0.0)
        self._servo_gain = gain[self._servos].copy()
        self._servo_rest = lengths[self._servos].copy()
        self._servo_lo, self._servo_hi = lo[self._servos], hi[self._servos]

    def _shares(self, mjm):
        """Each leg's forward and turning shares (its swing joint's) and each lift
        joint's sign, from the kinematics at rest (the foot: the far end of the leg's
        outermost body, the first leaf below its last lift joint)."""
        d = rest_data(mjm, self.rest_qpos)
        origin, rot = self.frame_at(d)   # the robot's frame: forward x, up z
        rot = rot.reshape(3, 3)
        legs = len(self.legs)
        swing = [int(np.flatnonzero((self._leg == i) & (self._role == SWING))[0])
                 for i in range(legs)]
        lifts = [np.flatnonzero((self._leg == i) & (self._role == LIFT)) for i in range(legs)]

        def outermost(body):
            children = np.flatnonzero((mjm.body_parentid == body) & (np.arange(mjm.nbody) != body))
            return body if len(children) == 0 else outermost(int(children[0]))

        feet = [outermost(int(mjm.jnt_bodyid[self._joints[lifts[i][-1]]])) for i in range(legs)]

        def foot(leg):
            # the outermost body's frame plus its geoms' farthest point
            body = feet[leg]
            geoms = np.flatnonzero(mjm.geom_bodyid == body)
            points = d.geom_xpos[geoms] if len(geoms) else d.xpos[body][None]
            far = points[np.argmax(np.linalg.norm(points[:, :2] - origin[:2], axis=1))]
            return rot.T @ (far - origin)

        def moved(qadr, delta, leg):
            d.qpos[:] = self.rest_qpos
            d.qpos[qadr] += delta
            mujoco.mj_kinematics(mjm, d)
            return foot(leg)

        self._forward_share = np.zeros(legs)
        self._turn_share = np.zeros(legs)
        self._lift_sign = np.zeros(len(self._q))
        h = 1e-3
        for leg in range(legs):
            q = self._q[swing[leg]]
            p = moved(q, 0.0, leg)
            dp = (moved(q, h, leg) - moved(q, -h, leg)) / (2 * h)
            # stance pushes the body forward: the foot moves towards -x relative to it
            self._forward_share[leg] = -dp[0] / max(1e-9, np.linalg.norm(dp[:2]))
            # stance turns the body counter-clockwise: the foot moves clockwise about it
            cw = np.array([p[1], -p[0]]) / max(1e-9, math.hypot(p[0], p[1]))
            self._turn_share[leg] = float(dp[:2] @ cw) / max(1e-9, np.linalg.norm(dp[:2]))
            for c in lifts[leg]:
                up = moved(self._q[c], h, leg)[2] - moved(self._q[c], -h, leg)[2]
                self._lift_sign[c] = 1.0 if up > 0 else -1.0
        #: Trot: legs whose feet are diagonal share a phase. Leg i's phase offset, cycles.
        side = np.array([np.sign(foot_xy[1]) for foot_xy in
                         (moved(self._q[swing[leg]], 0.0, leg) for leg in range(legs))])
        front = np.array([np.sign(moved(self._q[swing[leg]], 0.0, leg)[0]) for leg in range(legs)])
        self._offset = np.where(side * front > 0, 0.0, 0.5)

    def episode_settings(self):
        """The CPG's state at an episode's start: phase 0, targets 0; scratch."""
        return dict(phase=np.zeros(1), target=np.zeros(len(self._q)),
                    share=np.zeros(len(self.legs)))


def check_config(config):
    """ValueError for a task reading the gait cannot run: a refused move (a walked step
    cannot be put back)."""
    if config.blocked_move != "stop":
        raise ValueError("the gait drive has blocked_move=stop only (a walked step cannot "
                         "be put back)")


class GaitTask(TwoWheel):
    """The two-wheel action family through the CPG (see the module's docstring)."""

    def drive_settings(self, physics):
        check_config(self.config)
        # an agent step's nominal seconds (the velocity read-out's unit): the longest
        # turn and move
        g = physics.gait
        physics.step_seconds = g["max_turn_seconds"] + g["max_move_seconds"]
        return dict(n_turn=0, n_move=0, **self.family_settings(physics),
                    **physics.episode_settings())
