"""The navigation task shared by both robots (Unemi 2000, Sections 3.1-3.2).

`Physics` holds the named read-outs in paper units; `Navigation` owns the reward
at the goal, the start jitter, the rangefinder encoding and noise, termination
and the action noise. Each robot's module adds only its action mapping.
"""
import collections
import math

import mujoco
import numpy as np
from dm_control import mujoco as dm_mujoco
from dm_control.rl import control
from dm_control.suite import base
from dm_env import specs

from models import UNIT

# Section 3.1: start 5 units from the left edge and 25 below the top edge
# (y = 60 - 25), heading right (+x), jittered by +-3 units and +-15 degrees.
START = (5.0, 35.0, 0.0)
START_JITTER_XY = 3.0
START_JITTER_HEADING = np.deg2rad(15.0)

# Section 3.2: range 14 units, encoded 0 (nothing) .. 255 (touching), noise sd 5%.
SENSOR_RANGE = 14.0
SENSOR_LEVELS = 255
SENSOR_NOISE = 0.05 * SENSOR_LEVELS  # 12.75

# Section 3.3: each action component is scaled by a factor drawn from [1 - 0.05, 1].
ACTION_NOISE = 0.05


def encode_range(distance):
    """Section 3.2: surface distance in units (inf = no hit) -> code in 0..255.

    0 when nothing is within SENSOR_RANGE, else round(255 * (1 - d / 14)), so a
    touching beam (d <= 0) reads 255.
    """
    code = np.maximum(distance, 0.0)
    code *= -SENSOR_LEVELS / SENSOR_RANGE
    code += SENSOR_LEVELS
    np.rint(code, out=code)
    return np.maximum(code, 0.0, out=code)


class Physics(dm_mujoco.Physics):
    """Named read-outs of the room with one robot, in paper units and radians."""

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        jx, jy = m.name2id("robot/x", "joint"), m.name2id("robot/y", "joint")
        yaw = mujoco.mj_name2id(m.ptr, mujoco.mjtObj.mjOBJ_JOINT, "robot/yaw")
        self._qx, self._qy = int(m.jnt_qposadr[jx]), int(m.jnt_qposadr[jy])
        self._dx, self._dy = int(m.jnt_dofadr[jx]), int(m.jnt_dofadr[jy])
        self._qyaw = int(m.jnt_qposadr[yaw]) if yaw >= 0 else None
        self.robot_radius = m.geom_size[m.name2id("robot/hull", "geom"), 0] / UNIT
        beams = np.flatnonzero(m.sensor_type == mujoco.mjtSensor.mjSENS_RANGEFINDER)
        adr = m.sensor_adr[beams]
        if not np.array_equal(adr, np.arange(adr[0], adr[0] + len(adr))):
            raise ValueError("rangefinders must be declared one after another")
        self._beams = slice(int(adr[0]), int(adr[0]) + len(adr))
        # MuJoCo's own arrays, read and written every step without dm_control's wrappers.
        self._mj = (m.ptr, data.ptr)
        self._qpos, self._qvel = data.ptr.qpos, data.ptr.qvel
        self._ctrl, self._sensordata = data.ptr.ctrl, data.ptr.sensordata
        self._bad_qacc = data.ptr.warning[mujoco.mjtWarning.mjWARN_BADQACC]
        #: The room's timestep in seconds.
        self.timestep = float(m.opt.timestep)
        #: Substeps run so far, for benchmarks against raw mujoco.mj_step.
        self.substeps = 0
        goal = m.name2id("goal", "site")
        centre, half = m.site_pos[goal, :2] / UNIT, m.site_size[goal, :2] / UNIT
        self.goal_box = (centre - half, centre + half)
        #: Seconds of simulated time per agent step; set by the task.
        self.step_seconds = 1.0

    # -- read-outs ---------------------------------------------------------
    def robot_pose(self):
        """(x, y, heading) in paper units and radians; heading 0 for a robot without yaw."""
        q = self._qpos
        heading = float(q[self._qyaw]) if self._qyaw is not None else 0.0
        return float(q[self._qx]) / UNIT, float(q[self._qy]) / UNIT, heading

    def robot_velocity(self):
        """(vx, vy) in paper units per agent step."""
        v = self._qvel
        scale = self.step_seconds / UNIT
        return np.array([v[self._dx] * scale, v[self._dy] * scale])

    def ranges(self):
        """Distance from the body surface along each beam, in units; inf where nothing is hit."""
        raw = self._sensordata[self._beams]
        distance = raw * (1.0 / UNIT)
        distance -= self.robot_radius
        distance[raw < 0.0] = np.inf
        return distance

    def in_goal(self):
        """True when the robot's centre is inside the goal square."""
        x, y, _ = self.robot_pose()
        lo, hi = self.goal_box
        return bool(lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1])

    def step(self, nstep=1):
        """dm_control's legacy step (mj_step2, mj_step(n-1), mj_step1), so sensors and
        contacts describe the new state, without its per-call Python overhead.
        Raises PhysicsError when MuJoCo flags an unstable state."""
        model, data = self._mj
        before = self._bad_qacc.number
        mujoco.mj_step2(model, data)
        if nstep > 1:
            mujoco.mj_step(model, data, nstep - 1)
        mujoco.mj_step1(model, data)
        self.substeps += nstep
        if self._bad_qacc.number != before:
            raise control.PhysicsError(f"unstable simulation at t={data.time:.3f} s")

    # -- setters -----------------------------------------------------------
    def set_robot_pose(self, x, y, heading=0.0):
        """Places the robot at (x, y, heading), in units and radians, at rest."""
        q = self._qpos
        q[self._qx], q[self._qy] = x * UNIT, y * UNIT
        if self._qyaw is not None:
            q[self._qyaw] = heading
        self._qvel[:] = 0.0
        self._ctrl[:] = 0.0
        self.forward()


class Navigation(base.Task):
    """Reach the goal square from the jittered start; the robot class maps actions."""

    #: Action dimension, set by each robot.
    action_dim = 1

    def __init__(self, *, sensor_noise=SENSOR_NOISE, action_noise=ACTION_NOISE,
                 start_jitter=True, random=None):
        super().__init__(random=random)
        self.sensor_noise = float(sensor_noise)
        self.action_noise = float(action_noise)
        self.start_jitter = bool(start_jitter)

    # -- episode -------------------------------------------------------------
    def initialize_episode(self, physics):
        x, y, heading = START
        if self.start_jitter:
            jx, jy = self.random.uniform(-START_JITTER_XY, START_JITTER_XY, size=2)
            jh = self.random.uniform(-START_JITTER_HEADING, START_JITTER_HEADING)
            x, y, heading = x + jx, y + jy, heading + jh
        physics.set_robot_pose(x, y, heading)

    def get_observation(self, physics):
        obs = collections.OrderedDict()
        obs["range"] = self.sense(physics)
        return obs

    def sense(self, physics):
        """Encoded readings (Section 3.2) plus Gaussian noise, clipped to [0, 255]."""
        code = encode_range(physics.ranges())
        if self.sensor_noise > 0:
            code += self.random.normal(0.0, self.sensor_noise, size=code.shape)
            np.minimum(np.maximum(code, 0.0, out=code), SENSOR_LEVELS, out=code)
        return code

    def after_step(self, physics):
        self._at_goal = physics.in_goal()

    def get_reward(self, physics):
        return 1.0 if self._at_goal else 0.0

    def get_termination(self, physics):
        return 0.0 if self._at_goal else None

    # -- actions ---------------------------------------------------------------
    def action_spec(self, physics):
        return specs.BoundedArray((self.action_dim,), np.float64, -1.0, 1.0, name="action")

    def checked_action(self, action):
        """The action as a list of floats clipped to [-1, 1].

        NaN, inf or a shape other than (action_dim,) raise ValueError.
        """
        a = np.asarray(action, dtype=np.float64)
        if a.shape != (self.action_dim,) and not (a.ndim == 0 and self.action_dim == 1):
            raise ValueError(f"action must have shape ({self.action_dim},), got {a.shape}")
        values = a.tolist() if a.ndim else [a.item()]
        if not all(map(math.isfinite, values)):
            raise ValueError(f"action must be finite, got {values}")
        return [min(max(v, -1.0), 1.0) for v in values]

    def noise_factors(self):
        """Section 3.3: one factor per action part, drawn uniformly from [1 - noise, 1]."""
        if self.action_noise <= 0:
            return [1.0, 1.0]
        # RandomState.uniform(low, 1) computes low + (1 - low) u; written out, it skips
        # uniform's argument handling and gives the same numbers.
        low = 1.0 - self.action_noise
        u, v = self.random.random_sample(2).tolist()
        return [low + (1.0 - low) * u, low + (1.0 - low) * v]
