"""The two-wheel drive (Unemi 2000, Section 3.3): turn, then move, in one agent step.

Action a in [-1, 1]: turn |a| rad (a < 0 left, counter-clockwise; a > 0 right),
then move 2 (1 - |a|) units forward. When a collision stops the move, the rest
of it becomes turn in the same direction as the commanded turn (right when a = 0),
at the action's own rate of 1 rad per 2 units. Each part is scaled by noise. The
readings `blocked_move` ("refuse": the blocked move is undone and all of it turned)
and `leftover_turn` ("away": the rest turns away from the nearer side) change that
(tasks.config; tasks.kernels.two_wheel_finish, which these hooks match).

Two ways to realise it, picked by the robot file's actuators (docs/adding_a_robot.md):
- `Physics`: a planar base whose velocity servos ``forward``, ``turn`` (and ``grip``)
  drive the speed along the heading and the yaw rate directly (`two_wheel`).
- `WheelPhysics`: two wheel hinges ``left_wheel`` and ``right_wheel`` rolling on the
  floor, under position servos whose targets follow the turn or the move (`diff_drive`).
A mount (tasks.mount) may instead name a file's wheel hinges and its own motors
(action kind "wheel_motors"):
- `MotorWheelPhysics`: the same wheel-angle plan (`WheelPlan`), its targets followed by
  a PD loop solved for the file's motors' controls at every substep, on the hooks only
  (the MuJoCo car, models/mounts/car.toml).
"""
import math

import mujoco
import numpy as np

from tasks import kernels, navigation, wheel_kernels
from tasks.config import BLOCKED_MOVES, LEFTOVER_TURNS

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


class Physics(navigation.Physics):
    """A planar base driven by velocity servos on its speed along the heading and its
    yaw rate (the wheels' mean and difference)."""

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        ids = {name: navigation.named_id(m, navigation.mujoco.mjtObj.mjOBJ_ACTUATOR, name)
               for name in ("forward", "turn", "grip")}
        if ids["forward"] < 0 or ids["turn"] < 0:
            raise navigation.ContractError(MISSING_ACTUATORS)
        self._forward, self._turn = ids["forward"], ids["turn"]
        self._settings.update(act0=self._forward, act1=self._turn)
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

    def ramp_substeps(self, n):
        """The servos' speeds hold for the whole of an n-substep phase."""
        return n

    def drive(self, speed, yaw_rate):
        """Servo targets: speed in units/s along the heading, yaw rate in rad/s."""
        ctrl = self._ctrl
        ctrl[self._forward] = speed * self.unit
        ctrl[self._turn] = yaw_rate

    def begin_turn(self, angle, n):
        """Sets the drive to turn by `angle` rad (counter-clockwise) over n substeps."""
        self.drive(0.0, angle / (n * self.timestep))

    def begin_move(self, distance, n):
        """Sets the drive to move `distance` units forward over n substeps."""
        self.drive(distance / (n * self.timestep), 0.0)

    def halt(self):
        self.drive(0.0, 0.0)


class TwoWheel(navigation.Navigation):
    action_dim = 1
    kind = kernels.TWO_WHEEL

    def initialize_episode(self, physics):
        dt = physics.timestep
        self._n_turn = navigation.substeps(TURN_SECONDS * self.time_scale, dt)
        self._n_move = navigation.substeps(MOVE_SECONDS * self.time_scale, dt)
        physics.step_seconds = (self._n_turn + self._n_move) * dt
        self.start_drive(physics, **self.kernel_settings(self._n_turn, self._n_move,
                                                         (MAX_TURN, MAX_MOVE)),
                         tolerance=BLOCKED_TOLERANCE,
                         ramp_first=physics.ramp_substeps(self._n_turn),
                         ramp_rest=physics.ramp_substeps(self._n_move),
                         blocked_move=BLOCKED_MOVES.index(self.config.blocked_move),
                         leftover_turn=LEFTOVER_TURNS.index(self.config.leftover_turn))
        super().initialize_episode(physics)

    def before_step(self, action, physics):
        (a,) = self.checked_action(action)
        noise_turn, noise_move = self.noise_factors()
        turn = -a * MAX_TURN * noise_turn  # counter-clockwise positive
        self._move = MAX_MOVE * (1.0 - abs(a)) * noise_move
        self._turn_sign = 1.0 if turn > 0 else -1.0
        physics.begin_turn(turn, self._n_turn)
        physics.step(self._n_turn)
        if self.config.blocked_move == "refuse":  # the state a refused move returns to
            self._saved = physics.saved_state()
        x, y, heading = physics.robot_pose()
        self._from = (x, y, math.cos(heading), math.sin(heading))
        # The environment then runs the move phase (move_substeps).
        physics.begin_move(self._move, self._n_move)

    def after_step(self, physics):
        x, y, _ = physics.robot_pose()
        x0, y0, c, s = self._from
        rest = self._move - ((x - x0) * c + (y - y0) * s)
        if rest > BLOCKED_TOLERANCE:
            sign = leftover_sign(self.config, physics, self._turn_sign)
            if self.config.blocked_move == "refuse":
                data = physics.data.ptr
                physics.restore_state(self._saved)
                before = data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
                mujoco.mj_forward(physics.model.ptr, data)
                if data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number != before:
                    physics.raise_for(kernels.UNSTABLE)
                rest = self._move
            leftover = sign * rest * MAX_TURN / MAX_MOVE
            physics.begin_turn(leftover, self._n_turn)
            physics.step(self._n_turn)
        physics.halt()
        super().after_step(physics)


def leftover_sign(config, physics, commanded):
    """The way a blocked move's rest turns (counter-clockwise +1): the commanded turn's,
    or with leftover_turn "away" away from the nearer side at the blocked pose
    (kernels.away_sign). The hooks' reading, for every two-wheel action family's task."""
    if config.leftover_turn == "away":
        return kernels.away_sign(physics.ranges(), commanded)
    return commanded


def move_substeps(timestep, time_scale=1.0):
    """Substeps the environment runs per agent step: the move phase."""
    return navigation.substeps(MOVE_SECONDS * time_scale, timestep)


class WheelPlan(navigation.Physics):
    """The wheel-angle plan of two wheel hinges rolling on the floor: a phase of n
    substeps turns the wheels by the phase's angles (a turn: opposite, a move: alike)
    in its first RAMP share of the substeps, then lets them settle on their targets;
    `halt` gives up the rest where the wheels are. WheelPhysics executes it through
    servos added on the wheels, MotorWheelPhysics through the file's own motors."""

    #: Share of a phase over which the wheel targets move; the rest is for settling.
    RAMP = 0.5

    def _wheel_geometry(self, joints):
        """The wheel radius and half the track, from the two wheel hinges (joint ids):
        each wheel body's first geom, the bodies' y positions."""
        m = self.model
        bodies = [int(m.jnt_bodyid[j]) for j in joints]
        geoms = [int(np.flatnonzero(m.geom_bodyid == b)[0]) for b in bodies]
        #: Wheel radius (m) and half the track, the wheels' distance apart / 2 (m).
        self.wheel_radius = float(m.geom_size[geoms[0], 0])
        self.half_track = float(abs(m.body_pos[bodies[0], 1] - m.body_pos[bodies[1], 1]) / 2)

    def ramp_substeps(self, n):
        """The substeps of an n-substep phase over which the wheels' targets move."""
        return max(1, round(self.RAMP * n))

    def _wheel_speeds(self, left, right, n):
        """Turns the wheels by (left, right) rad over the ramp of an n-substep phase."""
        raise NotImplementedError

    def begin_turn(self, angle, n):
        """Turns by `angle` rad (counter-clockwise) over an n-substep phase."""
        w = angle * self.half_track / self.wheel_radius
        self._wheel_speeds(-w, w, n)

    def begin_move(self, distance, n):
        """Moves `distance` units forward over an n-substep phase."""
        w = distance * self.unit / self.wheel_radius
        self._wheel_speeds(w, w, n)


class WheelPhysics(WheelPlan):
    """Two wheel hinges, ``left_wheel`` and ``right_wheel``, each under an
    integrated-velocity servo: the control is the wheel's speed, the servo's target
    angle integrates it and a PD loop on the wheel's angle follows. A phase of n
    substeps sets the speeds that turn the wheels by the phase's angle in its first
    RAMP share of the substeps; the rest lets the wheels settle on their targets. No
    Python runs between phase boundaries."""

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        ids = [navigation.named_id(m, navigation.mujoco.mjtObj.mjOBJ_ACTUATOR, name)
               for name in ("left_wheel", "right_wheel")]
        if min(ids) < 0:
            raise navigation.ContractError(MISSING_ACTUATORS)
        joints = [int(m.actuator_trnid[i, 0]) for i in ids]
        self._wheel_geometry(joints)
        self._wheel_ctrl = ids
        self._wheel_act = [int(m.actuator_actadr[i]) for i in ids]
        self._wheel_qpos = [int(m.jnt_qposadr[j]) for j in joints]
        self._ramp_left = 0  # substeps left of the current phase's ramp
        self._settings.update(
            wheels=1, act0=ids[0], act1=ids[1], act_adr0=self._wheel_act[0],
            act_adr1=self._wheel_act[1], wheel_q0=self._wheel_qpos[0],
            wheel_q1=self._wheel_qpos[1], half_track=self.half_track,
            wheel_radius=self.wheel_radius)

    def _wheel_speeds(self, left, right, n):
        """Turns the wheels by (left, right) rad over the ramp of an n-substep phase."""
        ramp = self.ramp_substeps(n)
        self._ramp_left = ramp
        ctrl = self._ctrl
        ctrl[self._wheel_ctrl[0]] = left / (ramp * self.timestep)
        ctrl[self._wheel_ctrl[1]] = right / (ramp * self.timestep)

    def step(self, nstep=1):
        """Steps through the phase: the ramp, then the wheels settle at rest targets."""
        ramp = min(self._ramp_left, nstep)
        if ramp:
            super().step(ramp)
            self._ramp_left -= ramp
            if not self._ramp_left:
                self._ctrl[self._wheel_ctrl[0]] = self._ctrl[self._wheel_ctrl[1]] = 0.0
            nstep -= ramp
        if nstep:
            super().step(nstep)

    def halt(self):
        """Stops the targets where the wheels are: a stalled wheel gives up the rest."""
        ctrl, act, q = self._ctrl, self._act, self._qpos
        for c, a, j in zip(self._wheel_ctrl, self._wheel_act, self._wheel_qpos):
            ctrl[c] = 0.0
            act[a] = q[j]
        self._ramp_left = 0


#: A wheel_motors mount's roles (tasks.mount): the file's wheel hinges, and its motors
#: by contract name motor_0, motor_1, ...
WHEEL_JOINTS = ("left", "right")
MOTOR_ROLE = "motor_{}"
#: The control each motor is probed with at load, to measure its generalised force per
#: unit control on the wheels (small, so no joint's actuatorfrcrange clips it).
PROBE = 1e-3


class MotorWheelPhysics(WheelPlan):
    """Two wheel hinges (contract names ``left``, ``right``) turned through the file's
    own motors (``motor_0``, ``motor_1``, ...: torque motors on the wheel joints or on
    tendons over them), none added. The wheel-angle plan is WheelPlan's, its targets
    held here: at every substep the desired wheel torques are
    tau = kp (target - q) - kv dq, and the motors' controls that give them
    (tasks.wheel_kernels.motor_controls, clipped to each motor's range); one compiled
    call (tasks.wheel_kernels.wheel_phase) per phase. The kernels' compiled step does
    not drive it (hooks_only): the Environment runs the hooks."""

    hooks_only = True
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
        self._wheel_dof = mjm.jnt_dofadr[joints].astype(np.int64)
        self._motors = np.array(motors, dtype=np.int64)
        self._ctrl_lo = mjm.actuator_ctrlrange[motors, 0].copy()
        self._ctrl_hi = mjm.actuator_ctrlrange[motors, 1].copy()
        unlimited = ~mjm.actuator_ctrllimited[motors].astype(bool)
        self._ctrl_lo[unlimited], self._ctrl_hi[unlimited] = -np.inf, np.inf
        self.motor_forces = motor_forces(mjm, self._motors, self._wheel_dof)
        #: M^T M's (a, b, e, det), which motor_controls inverts at every substep.
        self._mtm = wheel_kernels.gram(self.motor_forces)
        a, _, e, det = self._mtm
        if abs(det) <= 1e-12 * max(1e-300, a + e) ** 2:
            raise navigation.ContractError(
                "action.motors: the motors do not turn the two wheels independently "
                f"(force per unit control on the wheels: {self.motor_forces.tolist()})")
        #: The plan's state: the wheels' targets (rad), their step per substep of the
        #: ramp and the ramp's substeps left; the kernel's scratch (torques, controls).
        self._target = np.zeros(2)
        self._delta = np.zeros(2)
        self._ramp_left = np.zeros(1, dtype=np.int64)
        self._tau = np.zeros(2)
        self._c = np.zeros(self.motor_count)

    def set_drive(self, **settings):
        """Keeps the settings but builds no kernels' record: no compiled step drives
        these motors (hooks_only)."""
        self._settings.update(settings)
        self.record = None
        return None

    def _wheel_speeds(self, left, right, n):
        """The targets move by (left, right) rad over the ramp of an n-substep phase."""
        ramp = self.ramp_substeps(n)
        self._ramp_left[0] = ramp
        self._delta[0], self._delta[1] = left / ramp, right / ramp

    def step(self, nstep=1):
        """nstep substeps of the phase, the PD loop on the motors at each."""
        status = wheel_kernels.wheel_phase(
            self._m, self._d, nstep, self._bad_qacc, self._xmat, self._free is not None,
            self._min_cos_tilt, self._qpos, self._qvel, self._ctrl, self._wheel_q,
            self._wheel_dof, self._motors, self.motor_forces, self._mtm, self._ctrl_lo,
            self._ctrl_hi,
            self.kp, self.kv, self._target, self._delta, self._ramp_left, self._tau, self._c)
        self.substeps += nstep
        if status != kernels.OK:
            self.raise_for(status)

    def halt(self):
        """The targets where the wheels are: a stalled wheel gives up the rest."""
        self._target[:] = self._qpos[self._wheel_q]
        self._ramp_left[0] = 0

    def set_robot_pose(self, x, y, heading=0.0):
        super().set_robot_pose(x, y, heading)
        self.halt()

    def saved_state(self):
        return super().saved_state() + (self._target.copy(), self._ramp_left.copy())

    def restore_state(self, saved):
        super().restore_state(saved[:-2])
        self._target[:], self._ramp_left[:] = saved[-2:]


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


def motor_wheel_physics(mount):
    """MotorWheelPhysics with a wheel_motors mount's motor count and gains."""
    gains = dict(mount.gait)
    motors = [name for role, name in mount.action[1:] if role not in WHEEL_JOINTS]
    return type("MotorWheelPhysics", (MotorWheelPhysics,),
                {"motor_count": len(motors), "kp": gains["kp"], "kv": gains["kv"]})
