"""The thrusters realisation, the floating drive's: the robot file's actuators
``thrust_x`` and ``thrust_y``, force motors along the world's x and y (on slide joints,
or on a site with a world-fixed reference site); the paper's ``floating`` robot and a
mount's `thrusters` kind (its kernels: tasks.kernels.thrusters)."""
import numpy as np

from tasks import navigation
from tasks.kernels import bindings, thrusters as kernels
from tasks.kernels.thrusters import ThrustersRecord
from tasks.readings import READING_BY_NAME
from tasks.simulator import mujoco

#: The bump reading (tasks/readings.py), whose code the coast reads.
BUMPS = READING_BY_NAME["bump"]


class ThrustersPhysics(navigation.Physics):
    """Adds the thrusters, as force motors along the world's x and y; and, for the bump
    readings "stop" and "bounce", the velocity change at a contact, applied after each
    substep (tasks.kernels.thrusters.bump_phase)."""

    Record = ThrustersRecord

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        thrust_x = navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "thrust_x")
        thrust_y = navigation.named_id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "thrust_y")
        if thrust_x < 0 or thrust_y < 0:
            raise navigation.ContractError("the floating drive needs actuators 'thrust_x' "
                                           "and 'thrust_y'", field="action")
        if self.n_beams != 8:
            raise navigation.ContractError(
                "the floating drive needs 8 rangefinders (E, NE, N, NW, W, SW, S, SE; eq 10)",
                field="beams")
        self._mass = float(m.body_subtreemass[self._base])
        if self._free is not None:  # a free joint's dofs start with x, y
            dof_x, dof_y = self.free_dof, self.free_dof + 1
        else:
            if (self._joints.x_sign, self._joints.y_sign) != (1.0, 1.0):
                raise navigation.ContractError(
                    "the floating drive pushes slides along x and y; the base's run along -x "
                    "or -y (a mount's joints = \"planar\" adds slides along x and y)",
                    field="joints")
            dof_x = m.jnt_dofadr[self.base_joints["x"]]
            dof_y = m.jnt_dofadr[self.base_joints["y"]]
        #: The bumper geom's id (the bump readings' coast watches its contacts).
        self.hull = navigation.named_id(m, mujoco.mjtObj.mjOBJ_GEOM, "hull")
        d = data.ptr
        contact_f, contact_i, layout = bindings.contact_views(d)
        self.parts.update(
            thrust_x=thrust_x, thrust_y=thrust_y, hull=self.hull, dof_x=int(dof_x),
            dof_y=int(dof_y), ncon=bindings.contact_count(d), contact_f=contact_f,
            contact_i=contact_i, layout=layout, qpos0=np.empty(m.nq), qvel0=np.empty(m.nv),
            normal=np.empty(2), velocity6=self._body_velocity, bump=BUMPS.code("grip"),
            restitution=1.0)

    def set_bump(self, bump, restitution=1.0):
        """The bump reading applied after each substep: "stop" or "bounce" (with the
        share of the speed into the wall that it reflects); anything else leaves a wall
        to the contact's physics ("grip", "slide")."""
        self.parts.update(bump=BUMPS.code(bump), restitution=float(restitution))

    def step(self, nstep=1):
        """Substeps with the bump reading (tasks.kernels.thrusters.bump_phase): with "stop"
        or "bounce", a substep that brings the bumper into a wall while moving towards it
        is undone and the velocity becomes 0 ("stop") or its mirror image off the wall
        ("bounce"); with the others, the substeps as navigation.Physics.step runs them."""
        if nstep <= 0 or self.record is None:
            return super().step(nstep)
        status = kernels.bump_phase(self.record, nstep)
        self.substeps += nstep
        if status != bindings.OK:
            self.raise_for(status)

    def set_robot_pose(self, x, y, heading=0.0):
        """Places the robot at (x, y), at rest, heading 0 whatever is asked: a floating
        robot's beams point along the world's axes (E, NE, N, ...)."""
        super().set_robot_pose(x, y, 0.0)

    def thrust_scale(self):
        """The force per unit/step of velocity change in one substep."""
        return self.unit / self.step_seconds * self._mass / self.timestep
