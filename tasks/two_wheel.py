"""The two-wheel drive (Unemi 2000, Section 3.3): turn, then move, in one agent step.

Action a in [-1, 1]: turn |a| rad (a < 0 left, counter-clockwise; a > 0 right),
then move 2 (1 - |a|) units forward. When a collision stops the move, the rest
of it becomes turn in the same direction as the commanded turn (right when a = 0),
at the action's own rate of 1 rad per 2 units. Each part is scaled by noise. The
readings `blocked_move` ("refuse": the blocked move is undone and all of it turned)
and `leftover_turn` ("away": the rest turns away from the nearer side) change that
(tasks.config). The step itself is tasks.kernels.two_wheel.act, written once; the
realisations here say how a body turns and moves (their kernels: tasks.kernels.planar,
.wheels, .motors), picked by the robot file's actuators (docs/adding_a_robot.md):
- `Physics`: a planar base whose velocity servos ``forward``, ``turn`` (and
  ``grip``) drive the speed along the heading and the yaw rate directly (`two_wheel`).
- `WheelPhysics`: two wheel hinges ``left_wheel`` and ``right_wheel`` rolling on
  the floor, under position servos whose targets follow the turn or the move
  (`diff_drive`).
- `MotorWheelPhysics`: a mount's wheel hinges under the file's own motors
  (action kind "wheel_motors": the MuJoCo car, models/mounts/car.toml).
- `JointMotorPhysics`: a mount's forward and turn joints under the file's own torque
  motors, position servos or velocity servos (action kind "joint_motors";
  tasks.kernels.joints).
tasks.gait walks the same family with legs.
"""
import mujoco
import numpy as np

from tasks import navigation
from tasks.config import BLOCKED_MOVES, LEFTOVER_TURNS
from tasks.kernels.joints import MODES, POSITION, TORQUE, VELOCITY, JointDrive
from tasks.kernels.motors import MotorWheelDrive, gram, hold_here
from tasks.kernels.planar import PlanarDrive
from tasks.kernels.wheels import WheelDrive, ramp_substeps

MAX_TURN = 1.0  # rad per step
MAX_MOVE = 2.0  # units per step

# Seconds of each phase of an agent step: a turn, then a move, then (when blocked) a
# leftover turn. At the planar robots' 0.05 s timestep: 4 + 8 (+ 4) substeps.
TURN_SECONDS = 0.2
MOVE_SECONDS = 0.4
# A move that falls short of its command by more than this (units) was stopped.
BLOCKED_TOLERANCE = 0.1

MISSING_ACTUATORS = ("the two_wheel drive needs actuators 'forward' and 'turn' (a planar "
                     "base) or 'left_wheel' and 'right_wheel' (wheels)")

#: A wheel_motors mount's roles (tasks.mount): the file's wheel hinges, and its motors
#: by contract name motor_0, motor_1, ...
WHEEL_JOINTS = ("left", "right")
MOTOR_ROLE = "motor_{}"
#: The control each motor is probed with at load, to measure its generalised force per
#: unit control on the wheels (small, so no joint's actuatorfrcrange clips it).
PROBE = 1e-3


def family_settings(config, physics):
    """The family's part of a record (tasks.kernels.two_wheel.FAMILY_FIELDS) but its
    phases' substeps: its constants, the task config's readings, room for the state a
    refused move returns to."""
    m = physics.model
    return dict(max_turn=MAX_TURN, max_move=MAX_MOVE, tolerance=BLOCKED_TOLERANCE,
                blocked_move=BLOCKED_MOVES.index(config.blocked_move),
                leftover_turn=LEFTOVER_TURNS.index(config.leftover_turn),
                qpos0=np.empty(m.nq), qvel0=np.empty(m.nv), act0=np.empty(m.na))


class TwoWheel(navigation.Navigation):
    """The two-wheel action family on a wheeled body: a turn phase and a move phase of
    fixed seconds, whose substeps the episode fixes."""

    action_dim = 1

    def drive_settings(self, physics):
        dt = physics.timestep
        n_turn = navigation.substeps(TURN_SECONDS * self.time_scale, dt)
        n_move = navigation.substeps(MOVE_SECONDS * self.time_scale, dt)
        physics.step_seconds = (n_turn + n_move) * dt
        return dict(n_turn=n_turn, n_move=n_move, **family_settings(self.config, physics),
                    **physics.phase_settings(n_turn, n_move))


class Physics(navigation.Physics):
    """A planar base driven by velocity servos on its speed along the heading and its
    yaw rate (the wheels' mean and difference)."""

    Record = PlanarDrive

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        ids = {name: navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
               for name in ("forward", "turn", "grip")}
        if ids["forward"] < 0 or ids["turn"] < 0:
            raise navigation.ContractError(MISSING_ACTUATORS)
        self.parts.update(forward_actuator=ids["forward"], turn_actuator=ids["turn"])
        # Deadbeat servos: kv = driven inertia / timestep reaches the target speed in one
        # semi-implicit Euler step. The base's mass drives forward and grip, its yaw
        # inertia the turn.
        if "yaw" not in self.base_joints:
            raise navigation.ContractError("a planar two_wheel base needs a hinge about z")
        dof = {role: m.jnt_dofadr[j] for role, j in self.base_joints.items()}
        mass = 1.0 / m.dof_invweight0[dof["x"]]
        yaw_inertia = 1.0 / m.dof_invweight0[dof["yaw"]]
        for name, inertia in (("forward", mass), ("grip", mass), ("turn", yaw_inertia)):
            i = ids[name]
            if i < 0:
                continue
            kv = inertia / m.opt.timestep
            m.actuator_gainprm[i, 0] = kv
            m.actuator_biasprm[i, 2] = -kv

    def phase_settings(self, n_turn, n_move):
        """The realisation's settings for the episode's phases: none."""
        return {}


class WheelPlan(navigation.Physics):
    """Two wheel hinges rolling on the floor: their radius and track, and the ramps of
    the episode's phases. WheelPhysics drives them through servos added on the wheels,
    MotorWheelPhysics through the file's own motors."""

    def _wheel_geometry(self, joints):
        """The wheel radius and half the track, from the two wheel hinges (joint ids):
        each wheel body's first geom, the bodies' y positions."""
        m = self.model
        bodies = [int(m.jnt_bodyid[j]) for j in joints]
        geoms = [int(np.flatnonzero(m.geom_bodyid == b)[0]) for b in bodies]
        #: Wheel radius (m) and half the track, the wheels' distance apart / 2 (m).
        self.wheel_radius = float(m.geom_size[geoms[0], 0])
        self.half_track = float(abs(m.body_pos[bodies[0], 1] - m.body_pos[bodies[1], 1]) / 2)
        self.parts.update(wheel_radius=self.wheel_radius, half_track=self.half_track)

    def phase_settings(self, n_turn, n_move):
        """The ramps of the episode's phases."""
        return dict(ramp_turn=ramp_substeps(n_turn), ramp_move=ramp_substeps(n_move))


class WheelPhysics(WheelPlan):
    """Two wheel hinges, ``left_wheel`` and ``right_wheel``, each under an
    integrated-velocity servo (tasks.kernels.wheels: the phases and the halt)."""

    Record = WheelDrive

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        ids = [navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
               for name in ("left_wheel", "right_wheel")]
        if min(ids) < 0:
            raise navigation.ContractError(MISSING_ACTUATORS)
        joints = [int(m.actuator_trnid[i, 0]) for i in ids]
        self._wheel_geometry(joints)
        acts = [int(m.actuator_actadr[i]) for i in ids]
        qpos = [int(m.jnt_qposadr[j]) for j in joints]
        self.parts.update(left_actuator=ids[0], right_actuator=ids[1], left_act=acts[0],
                          right_act=acts[1], left_q=qpos[0], right_q=qpos[1])


class MotorWheelPhysics(WheelPlan):
    """Two wheel hinges (``left``, ``right``) turned through the file's own motors, a PD
    loop on the wheels' angles solved for the motors' controls (tasks.kernels.motors)."""

    Record = MotorWheelDrive
    #: Set by motor_wheel_physics from the mount: its motors' count and the PD gains
    #: (N m per rad, N m s per rad).
    motor_count = 2
    kp = 0.0
    kv = 0.0

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        mjm = m.ptr
        joints = [navigation.named_id(m, mujoco.mjtObj.mjOBJ_JOINT, role) for role in WHEEL_JOINTS]
        motors = [navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, MOTOR_ROLE.format(k))
                  for k in range(self.motor_count)]
        if min(joints) < 0 or min(motors) < 0:
            raise navigation.ContractError(
                "wheel motors need hinges 'left' and 'right' and the motors "
                + ", ".join(repr(MOTOR_ROLE.format(k)) for k in range(self.motor_count)))
        self._wheel_geometry(joints)
        self._wheel_q = mjm.jnt_qposadr[joints].astype(np.int64)
        motors = np.array(motors, dtype=np.int64)
        ctrl_lo = mjm.actuator_ctrlrange[motors, 0].copy()
        ctrl_hi = mjm.actuator_ctrlrange[motors, 1].copy()
        unlimited = ~mjm.actuator_ctrllimited[motors].astype(bool)
        ctrl_lo[unlimited], ctrl_hi[unlimited] = -np.inf, np.inf
        wheel_dof = mjm.jnt_dofadr[joints].astype(np.int64)
        #: forces[k, j]: motor k's generalised force on wheel dof j per unit control.
        self.motor_forces = motor_forces(mjm, motors, wheel_dof)
        mtm = gram(self.motor_forces)
        a, _, e, det = mtm
        if abs(det) <= 1e-12 * max(1e-300, a + e) ** 2:
            raise navigation.ContractError(
                "action.motors: the motors do not turn the two wheels independently "
                f"(force per unit control on the wheels: {self.motor_forces.tolist()})")
        #: The plan's state: the wheels' targets (rad) and the ramp's substeps left.
        self._target, self._ramp_left = np.zeros(2), np.zeros(1, dtype=np.int64)
        self.parts.update(
            wheel_q=self._wheel_q, wheel_dof=wheel_dof, motors=motors,
            forces=self.motor_forces, gram=mtm, ctrl_lo=ctrl_lo, ctrl_hi=ctrl_hi,
            kp=float(self.kp), kv=float(self.kv), target=self._target, delta=np.zeros(2),
            ramp_left=self._ramp_left, tau=np.zeros(2), controls=np.zeros(self.motor_count),
            target0=np.zeros(2), ramp_left0=np.zeros(1, dtype=np.int64))

    def set_robot_pose(self, x, y, heading=0.0):
        super().set_robot_pose(x, y, heading)
        hold_here(self._target, self._ramp_left, self._qpos, self._wheel_q)


def motor_forces(model, motors, dofs):
    """forces[k, j]: motor k's generalised force on dof j per unit of its control, measured
    on a scratch MjData at the model's rest pose (qfrc_actuator with motor k's control at
    PROBE and the others 0, less with all 0, over PROBE; control clamping off meanwhile)."""
    d = mujoco.MjData(model)
    flags = model.opt.disableflags
    model.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_CLAMPCTRL)
    try:
        mujoco.mj_forward(model, d)
        rest = d.qfrc_actuator[dofs].copy()
        forces = np.zeros((len(motors), len(dofs)))
        for k, a in enumerate(motors):
            d.ctrl[:] = 0.0
            d.ctrl[a] = PROBE
            mujoco.mj_forward(model, d)
            forces[k] = (d.qfrc_actuator[dofs] - rest) / PROBE
    finally:
        model.opt.disableflags = flags
    return forces


def is_torque_motor(model, a):
    """Whether actuator a is a torque motor (MuJoCo's <motor>: fixed gain, no bias, no
    activation dynamics)."""
    return (int(model.actuator_biastype[a]) == int(mujoco.mjtBias.mjBIAS_NONE)
            and int(model.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_FIXED)
            and int(model.actuator_dyntype[a]) == int(mujoco.mjtDyn.mjDYN_NONE))


def is_position_servo(model, a):
    """Whether actuator a is a position servo (MuJoCo's <position>, or a <general> of
    bias -kp * length, any damping): its control is the length it holds."""
    return (int(model.actuator_biastype[a]) == int(mujoco.mjtBias.mjBIAS_AFFINE)
            and int(model.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_FIXED)
            and model.actuator_biasprm[a, 0] == 0.0
            and model.actuator_biasprm[a, 1] == -model.actuator_gainprm[a, 0] != 0.0)


def is_velocity_servo(model, a):
    """Whether actuator a is a velocity servo (MuJoCo's <velocity>: bias -kv * speed, no
    position term, no activation dynamics): its control is the speed it holds."""
    return (int(model.actuator_biastype[a]) == int(mujoco.mjtBias.mjBIAS_AFFINE)
            and int(model.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_FIXED)
            and int(model.actuator_dyntype[a]) == int(mujoco.mjtDyn.mjDYN_NONE)
            and model.actuator_biasprm[a, 0] == 0.0 and model.actuator_biasprm[a, 1] == 0.0
            and model.actuator_biasprm[a, 2] == -model.actuator_gainprm[a, 0] != 0.0)


def length_gains(model, qadrs):
    """(gain, lengths): gain[a, j] every actuator's length per unit of the joint at qpos
    address qadrs[j] (central differences at the rest pose, entries under 1e-9 zeroed),
    and the actuators' lengths at rest. For a joint or a fixed tendon this is the
    transmission's gear times coefficient, whatever the actuator's kind."""
    d = mujoco.MjData(model)
    gain = np.zeros((model.nu, len(qadrs)))
    h = 1e-3
    for c, q in enumerate(qadrs):
        lengths = []
        for delta in (h, -h):
            d.qpos[:] = model.qpos0
            d.qpos[q] += delta
            mujoco.mj_fwdPosition(model, d)
            lengths.append(d.actuator_length.copy())
        gain[:, c] = (lengths[0] - lengths[1]) / (2 * h)
    gain[np.abs(gain) < 1e-9] = 0.0
    d.qpos[:] = model.qpos0
    mujoco.mj_fwdPosition(model, d)
    return gain, d.actuator_length.copy()


def control_ranges(model, actuators):
    """(lo, hi): the actuators' control ranges, infinite where unlimited."""
    lo = model.actuator_ctrlrange[actuators, 0].copy()
    hi = model.actuator_ctrlrange[actuators, 1].copy()
    unlimited = ~model.actuator_ctrllimited[actuators].astype(bool)
    lo[unlimited], hi[unlimited] = -np.inf, np.inf
    return lo, hi


class JointMotorPhysics(WheelPlan):
    """A mount's forward and turn joints (the file's names: `joints`) under the file's
    own actuators on them, all torque motors, position servos or velocity servos: the
    wheels' plan on the joints' targets and a controller per kind
    (tasks.kernels.joints)."""

    Record = JointDrive
    #: Set by joint_motor_physics from the mount: the file's forward and turn joints,
    #: the gains (torque motors: kp N m/rad and kv N m s/rad; velocity servos: kp 1/s).
    joints = ("", "")
    kp = 0.0
    kv = 0.0

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        mjm = self.model.ptr
        ids = [mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_JOINT, navigation.PREFIX + name)
               for name in self.joints]
        if min(ids) < 0:
            raise navigation.ContractError(f"joint motors need the joints {list(self.joints)}")
        q = mjm.jnt_qposadr[ids].astype(np.int64)
        dof = mjm.jnt_dofadr[ids].astype(np.int64)
        gain, lengths = length_gains(mjm, q)
        motors = np.flatnonzero(np.any(gain != 0.0, axis=1)).astype(np.int64)
        kinds = [k for k, test in zip((TORQUE, POSITION, VELOCITY),
                                      (is_torque_motor, is_position_servo, is_velocity_servo))
                 if len(motors) and all(test(mjm, a) for a in motors)]
        if not kinds:
            raise navigation.ContractError(
                f"joint motors need the joints {list(self.joints)} moved by actuators of one "
                f"kind: {', '.join(MODES)}")
        mode = kinds[0]
        forces = motor_forces(mjm, motors, dof) if mode == TORQUE else np.zeros((len(motors), 2))
        mtm = gram(forces)
        if mode == TORQUE and abs(mtm[3]) <= 1e-12 * max(1e-300, mtm[0] + mtm[2]) ** 2:
            raise navigation.ContractError(
                "joint motors: the motors do not move the two joints independently (force "
                f"per unit control on them: {forces.tolist()})")
        ctrl_lo, ctrl_hi = control_ranges(mjm, motors)
        forward, turn = ids
        if int(mjm.jnt_type[forward]) == int(mujoco.mjtJoint.mjJNT_HINGE):
            # a wheel: its body's first geom's radius
            body = int(mjm.jnt_bodyid[forward])
            geom = int(np.flatnonzero(mjm.geom_bodyid == body)[0])
            per_unit = self.unit / float(mjm.geom_size[geom, 0])
        else:
            per_unit = self.unit
        self._joint_q = q
        #: The plan's state: the joints' targets and the ramp's substeps left.
        self._target, self._ramp_left = np.zeros(2), np.zeros(1, dtype=np.int64)
        self.parts.update(
            joint_per_unit=per_unit, per_rad=1.0, joint_q=q, joint_dof=dof, rest=mjm.qpos0[q].copy(),
            motors=motors, mode=mode, forces=forces, gram=mtm, gain=gain[motors].copy(),
            length0=lengths[motors].copy(), ctrl_lo=ctrl_lo, ctrl_hi=ctrl_hi,
            kp=float(self.kp), kv=float(self.kv), target=self._target, delta=np.zeros(2),
            ramp_left=self._ramp_left, tau=np.zeros(2), controls=np.zeros(len(motors)),
            target0=np.zeros(2), ramp_left0=np.zeros(1, dtype=np.int64))

    def set_robot_pose(self, x, y, heading=0.0):
        super().set_robot_pose(x, y, heading)
        hold_here(self._target, self._ramp_left, self._qpos, self._joint_q)


def joint_motor_physics(joints, kp, kv):
    """JointMotorPhysics with a joint_motors mount's joints (forward, turn) and gains."""
    return type("JointMotorPhysics", (JointMotorPhysics,),
                {"joints": tuple(joints), "kp": kp, "kv": kv})


def motor_wheel_physics(motor_count, kp, kv):
    """MotorWheelPhysics with a wheel_motors mount's motor count and PD gains."""
    return type("MotorWheelPhysics", (MotorWheelPhysics,),
                {"motor_count": motor_count, "kp": kp, "kv": kv})


#: The realisations a robot file picks by an actuator's contract name (tasks.load); a
#: mount's wheel_motors picks motor_wheel_physics.
PHYSICS = {"left_wheel": WheelPhysics, "forward": Physics}
