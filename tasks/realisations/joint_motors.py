"""The joint_motors realisation of the two-wheel family: a mount's forward and turn joints
(the file's names) under the file's own actuators on them, all torque motors, position
servos or velocity servos (tasks.actuators.ACTUATOR_KINDS): the target plan on the joints'
targets, its controller by their kind (its kernels: tasks.kernels.joint_motors,
tasks.kernels.plan)."""
import numpy as np

from tasks import navigation
from tasks.actuators import ACTUATOR_KINDS, length_gains, model_kind
from tasks.kernels.joint_motors import JointMotorsRecord
from tasks.mount.frame import rest_data
from tasks.realisations.wheels import Planned
from tasks.simulator import mujoco


class JointMotorsPhysics(Planned):
    """A mount's forward and turn joints under the file's own actuators on them. A mount's
    joints and gains are set on a subclass (tasks.realisations.Realisation.physics_class)."""

    Record = JointMotorsRecord
    #: The file's forward and turn joints.
    joints = ("", "")

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        mjm = self.model.ptr
        ids = [mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_JOINT, navigation.PREFIX + name)
               for name in self.joints]
        if min(ids) < 0:
            raise navigation.ContractError(f"joint motors need the joints {list(self.joints)}",
                                           field="action")
        gain, _ = length_gains(mjm, mjm.jnt_qposadr[ids].astype(np.int64), self.rest_qpos)
        motors = np.flatnonzero(np.any(gain != 0.0, axis=1)).astype(np.int64)
        kinds = {model_kind(mjm, a) for a in motors}
        if len(kinds) != 1 or None in kinds:
            raise navigation.ContractError(
                f"joint motors need the joints {list(self.joints)} moved by actuators of one "
                f"kind: {', '.join(ACTUATOR_KINDS)}", field="action.kind")
        forward = ids[0]
        if int(mjm.jnt_type[forward]) == int(mujoco.mjtJoint.mjJNT_HINGE):
            # a wheel: its body's first geom's radius
            body = int(mjm.jnt_bodyid[forward])
            geom = int(np.flatnonzero(mjm.geom_bodyid == body)[0])
            per_unit = self.unit / float(mjm.geom_size[geom, 0])
        else:
            per_unit = self.unit
        forward_sign, turn_sign = self._senses(mjm, ids)
        self.parts.update(joint_per_unit=per_unit * forward_sign, per_rad=1.0 * turn_sign,
                          **self.plan_parts(ids, motors, kinds.pop(), "action"))

    def _senses(self, mjm, ids):
        """(forward, turn): the senses of the two joints at rest, 1 or -1: the way the
        forward joint moves the robot along its forward axis (a wheel's hinge rolling on
        the floor, a slide), the way the turn hinge turns it (about z, or -z). ContractError
        naming the mount's field for a turn joint not about the vertical, or a forward
        joint that moves the robot across its forward axis."""
        d = rest_data(mjm, self.rest_qpos)
        _, rotation = self.frame_at(d)
        ahead = np.array([rotation[0], rotation[3], 0.0])   # the frame's x in the plane
        forward, turn = (d.xaxis[j] for j in ids)
        if abs(turn[2]) < 1.0 - 1e-6:
            raise navigation.ContractError(
                f"joint {self.joints[1]!r} turns about ({turn[0]:.2f}, "
                f"{turn[1]:.2f}, {turn[2]:.2f}) at rest, not the vertical: name a hinge "
                "about z or -z", field="action.turn")
        rolls = int(mjm.jnt_type[ids[0]]) == int(mujoco.mjtJoint.mjJNT_HINGE)
        along = np.array([forward[1], -forward[0], 0.0]) if rolls else forward
        along = along / max(1e-12, float(np.linalg.norm(along)))
        if abs(float(along @ ahead)) < 0.5:
            raise navigation.ContractError(
                f"joint {self.joints[0]!r} moves the robot along ({along[0]:.2f}, "
                f"{along[1]:.2f}, {along[2]:.2f}), across its forward axis ({ahead[0]:.2f}, "
                f"{ahead[1]:.2f}): {self._fitting_forward(d, along)}", field="forward")
        return (1.0 if along @ ahead > 0 else -1.0), (1.0 if turn[2] > 0 else -1.0)

    def _fitting_forward(self, d, along):
        """The forward values that fit: the base's axis (at rest, d) that the forward joint
        moves the robot along, either way (which way it faces is the file's to say)."""
        axes = d.xmat[self._base].reshape(3, 3)   # its columns: the base's axes in the world
        dots = axes.T @ along
        i = int(np.argmax(np.abs(dots)))
        if abs(float(dots[i])) < 0.99:
            return "name the base's axis it moves along"
        name = "xyz"[i]
        return f"forward = \"{name}\" or \"-{name}\", the base's axis it moves along"
