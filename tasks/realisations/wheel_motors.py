"""The wheel_motors realisation of the two-wheel family: a mount's wheel hinges (contract
names ``left``, ``right``) turned through the file's own torque motors (``motor_0``,
``motor_1``, ...): the target plan on the wheels' angles, its PD loop solved for the
motors' controls (the MuJoCo car, models/mounts/car.toml; its kernels:
tasks.kernels.wheel_motors, tasks.kernels.plan)."""

from tasks import navigation
from tasks.kernels.wheel_motors import WheelMotorsRecord
from tasks.mount.joint_kinds import MOTOR_ROLE, WHEEL_JOINTS
from tasks.realisations.wheels import Planned, wheel_geometry
from tasks.simulator import mujoco


class WheelMotorsPhysics(Planned):
    """Two wheel hinges (``left``, ``right``) turned through the file's own motors. A
    mount's motor count and PD gains (kp N m/rad, kv N m s/rad) are set on a subclass
    (tasks.realisations.Realisation.physics_class)."""

    Record = WheelMotorsRecord
    motor_count = 2

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        mjm = self.model.ptr
        joints = [navigation.named_id(mjm, mujoco.mjtObj.mjOBJ_JOINT, role) for role in WHEEL_JOINTS]
        motors = [navigation.named_id(mjm, mujoco.mjtObj.mjOBJ_ACTUATOR, MOTOR_ROLE.format(k))
                  for k in range(self.motor_count)]
        if min(joints) < 0 or min(motors) < 0:
            raise navigation.ContractError(
                "wheel motors need hinges 'left' and 'right' and the motors "
                + ", ".join(repr(MOTOR_ROLE.format(k)) for k in range(self.motor_count)),
                field="action")
        #: Wheel radius (m) and half the track, the wheels' distance apart / 2 (m).
        self.wheel_radius, self.half_track = wheel_geometry(mjm, joints)
        self.parts.update(wheel_radius=self.wheel_radius, half_track=self.half_track,
                          **self.plan_parts(joints, motors, "torque motors", "action.motors"))
        #: forces[k, j]: motor k's generalised force on wheel dof j per unit control.
        self.motor_forces = self.parts["forces"]
