"""The servos realisation of the two-wheel family: a planar base (slide x, slide y, hinge
yaw) driven by velocity servos on its speed along the heading (``forward``), its yaw
rate (``turn``) and, optionally, a sideways ``grip`` held at zero: the paper's
``two_wheel`` robot, and a mount's `servos` kind (its kernels: tasks.kernels.servos)."""
import numpy as np

from tasks import navigation
from tasks.kernels.servos import ServosRecord
from tasks.simulator import mujoco

MISSING_ACTUATORS = ("the two_wheel drive needs actuators 'forward' and 'turn' (a planar "
                     "base) or 'left_wheel' and 'right_wheel' (wheels)")


class ServosPhysics(navigation.Physics):
    """A planar base driven by velocity servos on its speed along the heading and its
    yaw rate (the wheels' mean and difference)."""

    Record = ServosRecord

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        ids = {name: navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
               for name in ("forward", "turn", "grip")}
        if ids["forward"] < 0 or ids["turn"] < 0:
            raise navigation.ContractError(MISSING_ACTUATORS, field="action")
        # the turn servo's sense: a servo on the yaw hinge turns the base by its gear's
        # sign times the hinge's (1 about z, -1 about -z)
        turn_sign = 1.0
        if (int(m.actuator_trntype[ids["turn"]]) == int(mujoco.mjtTrn.mjTRN_JOINT)
                and int(m.actuator_trnid[ids["turn"], 0]) == self.base_joints.get("yaw")):
            turn_sign = float(np.sign(m.actuator_gear[ids["turn"], 0])) * self.yaw_sign
        self.parts.update(forward_actuator=ids["forward"], turn_actuator=ids["turn"],
                          turn_sign=turn_sign)
        # Deadbeat servos: kv = driven inertia / timestep reaches the target speed in one
        # semi-implicit Euler step. The base's mass drives forward and grip, its yaw
        # inertia the turn.
        if "yaw" not in self.base_joints:
            raise navigation.ContractError("a planar two_wheel base needs a hinge about z (a "
                                           "mount's joints = \"planar\" adds one)",
                                           field="joints")
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
