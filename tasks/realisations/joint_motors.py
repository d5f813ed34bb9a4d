"""The joint_motors realisation of the two-wheel family: a mount's forward and turn joints
(the file's names) under the file's own actuators on them, all torque motors, position
servos or velocity servos (tasks.actuators.KINDS): the target plan on the joints'
targets, its controller by their kind (its kernels: tasks.kernels.joint_motors,
tasks.kernels.plan)."""
import mujoco
import numpy as np

from tasks import navigation
from tasks.actuators import KINDS, length_gains, model_kind
from tasks.kernels.joint_motors import JointMotorsRecord
from tasks.realisations.wheels import Planned


class JointMotorsPhysics(Planned):
    """A mount's forward and turn joints under the file's own actuators on them. A mount's
    joints and gains are set on a subclass (tasks.realisations.Realisation.physics)."""

    Record = JointMotorsRecord
    #: The file's forward and turn joints.
    joints = ("", "")

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        mjm = self.model.ptr
        ids = [mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_JOINT, navigation.PREFIX + name)
               for name in self.joints]
        if min(ids) < 0:
            raise navigation.ContractError(f"joint motors need the joints {list(self.joints)}")
        gain, _ = length_gains(mjm, mjm.jnt_qposadr[ids].astype(np.int64))
        motors = np.flatnonzero(np.any(gain != 0.0, axis=1)).astype(np.int64)
        kinds = {model_kind(mjm, a) for a in motors}
        if len(kinds) != 1 or None in kinds:
            raise navigation.ContractError(
                f"joint motors need the joints {list(self.joints)} moved by actuators of one "
                f"kind: {', '.join(KINDS)}")
        forward = ids[0]
        if int(mjm.jnt_type[forward]) == int(mujoco.mjtJoint.mjJNT_HINGE):
            # a wheel: its body's first geom's radius
            body = int(mjm.jnt_bodyid[forward])
            geom = int(np.flatnonzero(mjm.geom_bodyid == body)[0])
            per_unit = self.unit / float(mjm.geom_size[geom, 0])
        else:
            per_unit = self.unit
        self.parts.update(joint_per_unit=per_unit, per_rad=1.0,
                          **self.plan_parts(ids, motors, kinds.pop(), "joint motors"))
