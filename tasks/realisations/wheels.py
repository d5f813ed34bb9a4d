"""The wheels realisation of the two-wheel family: two wheel hinges, ``left_wheel`` and
``right_wheel``, rolling on the floor, each under an integrated-velocity servo (the
``diff_drive`` robot, and a mount's `wheels` kind; its kernels: tasks.kernels.wheels).
`Ramped`, `Planned` and `wheel_geometry` serve the realisations whose phases ramp their
targets (wheels; wheel_motors and joint_motors, the target plan's: tasks.kernels.plan)."""
import numpy as np

from tasks import navigation
from tasks.actuators import ACTUATOR_KINDS, control_ranges, length_gains, motor_forces, \
    require_independent
from tasks.kernels.plan import TORQUE, gram, hold_here
from tasks.kernels.wheels import WheelsRecord, ramp_substeps
from tasks.realisations.servos import MISSING_ACTUATORS
from tasks.simulator import mujoco


def wheel_geometry(model, joints):
    """(wheel radius, half the track) in metres, from the two wheel hinges (joint ids):
    each wheel body's first geom, the bodies' y positions."""
    bodies = [int(model.jnt_bodyid[j]) for j in joints]
    geoms = [int(np.flatnonzero(model.geom_bodyid == b)[0]) for b in bodies]
    radius = float(model.geom_size[geoms[0], 0])
    half_track = float(abs(model.body_pos[bodies[0], 1] - model.body_pos[bodies[1], 1]) / 2)
    return radius, half_track


class Ramped(navigation.Physics):
    """A realisation whose phases move their targets over a ramp (a share of the phase)."""

    def phase_settings(self, n_turn, n_move):
        """The ramps of the episode's phases."""
        return dict(ramp_turn=ramp_substeps(n_turn), ramp_move=ramp_substeps(n_move))


class Planned(Ramped):
    """The target plan on two joints (tasks.kernels.plan): its parts of the record, and
    its targets held where the joints are when the robot is placed."""

    #: The plan's gains (torque motors: kp N m/rad, kv N m s/rad; velocity servos: kp 1/s):
    #: one for both joints, or a pair (the first joint's, the second's).
    kp = 0.0
    kv = 0.0

    def plan_parts(self, joints, motors, kind, field):
        """The plan's fields for the two joints (ids) moved by the actuators `motors` (ids)
        of one kind (tasks.actuators.ACTUATOR_KINDS); `field`: the mount's field the refusal of
        motors that cannot move the joints apart names."""
        mjm = self.model.ptr
        q = mjm.jnt_qposadr[joints].astype(np.int64)
        dof = mjm.jnt_dofadr[joints].astype(np.int64)
        motors = np.asarray(motors, dtype=np.int64)
        mode = ACTUATOR_KINDS.index(kind)
        gain, lengths = length_gains(mjm, q, self.rest_qpos)
        forces = (motor_forces(mjm, motors, dof, self.rest_qpos) if mode == TORQUE
                  else np.zeros((len(motors), 2)))
        mtm = gram(forces)
        if mode == TORQUE:
            require_independent(forces, mtm, field)
        ctrl_lo, ctrl_hi = control_ranges(mjm, motors)
        #: The plan's joints' qpos addresses, its state: the targets and the ramp's
        #: substeps left.
        self._joint_q = q
        self._target, self._ramp_left = np.zeros(2), np.zeros(1, dtype=np.int64)
        return dict(
            joint_q=q, joint_dof=dof, rest=self.rest_qpos[q].copy(), motors=motors, mode=mode,
            forces=forces, gram=mtm, gain=gain[motors].copy(), length0=lengths[motors].copy(),
            ctrl_lo=ctrl_lo, ctrl_hi=ctrl_hi, kp=_pair(self.kp), kv=_pair(self.kv),
            target=self._target, delta=np.zeros(2), ramp_left=self._ramp_left, tau=np.zeros(2),
            controls=np.zeros(len(motors)), target0=np.zeros(2),
            ramp_left0=np.zeros(1, dtype=np.int64))

    def set_robot_pose(self, x, y, heading=0.0):
        super().set_robot_pose(x, y, heading)
        hold_here(self._target, self._ramp_left, self._qpos, self._joint_q)


def _pair(gain):
    """A gain for each of the plan's two joints: a number for both, or a pair as given."""
    return np.broadcast_to(np.asarray(gain, dtype=float), (2,)).copy()


class WheelsPhysics(Ramped):
    """Two wheel hinges, ``left_wheel`` and ``right_wheel``, each under an
    integrated-velocity servo (tasks.kernels.wheels: the phases and the halt)."""

    Record = WheelsRecord

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        ids = [navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
               for name in ("left_wheel", "right_wheel")]
        if min(ids) < 0:
            raise navigation.ContractError(MISSING_ACTUATORS, field="action")
        joints = [int(m.actuator_trnid[i, 0]) for i in ids]
        #: Wheel radius (m) and half the track, the wheels' distance apart / 2 (m).
        self.wheel_radius, self.half_track = wheel_geometry(m, joints)
        acts = [int(m.actuator_actadr[i]) for i in ids]
        qpos = [int(m.jnt_qposadr[j]) for j in joints]
        self.parts.update(wheel_radius=self.wheel_radius, half_track=self.half_track,
                          left_actuator=ids[0], right_actuator=ids[1], left_act=acts[0],
                          right_act=acts[1], left_q=qpos[0], right_q=qpos[1])
