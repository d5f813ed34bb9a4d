"""The navigation task shared by every robot (Unemi 2000, Sections 3.1-3.2).

`Physics` holds the named read-outs in paper units and builds the drive's record;
`Navigation` owns the reward at the goal, the start jitter, the rangefinder encoding
and noise, termination and the action noise's draws. Each drive's module (two_wheel,
floating, gait) adds its physics' parts and its episode's settings; the drive's step
itself is compiled (tasks.kernels), and the dm_env hooks here call it.

Read-outs come from the robot's base body (``robot/base``): position and heading
from its frame, planar velocity from its body velocity, so slide joints and free
joints work alike. The rest of the naming contract is in docs/adding_a_robot.md.
"""
import collections
import math

import numpy as np
from dm_control.rl import control
from dm_env import specs

from models import FRAME_SITE, NAMES_TEXT, PREFIX, UNIT, UNIT_NUMERIC, ContractError, \
    contract_names, rest_qpos, room_layout, unit_of
from tasks import placement
from tasks import render
from tasks.config import TaskConfig
from tasks.kernels import bindings, body, env_step, sensing
from tasks.kernels.stream import TaskStream
from tasks.simulator import dm_mujoco, mujoco

# Section 3.1: the start pose is the room's "start" site (5 units from the left edge,
# 25 below the top edge, heading right). The jitter, the sensors' range and noise and
# the action noise are fields of tasks.config.TaskConfig.

# Section 3.2: a reading is encoded 0 (nothing) .. 255 (touching).
SENSOR_LEVELS = 255
#: Section 3.4: the agent and the intrinsic behaviours read the codes scaled into [0, 1].
READING_SCALE = 1.0 / SENSOR_LEVELS

#: A 3D robot tilted more than this (degrees) has fallen over: the step raises.
MAX_TILT_DEGREES = 10.0


#: An empty draw: no noise (the kernels take an empty array for "off").
_NO_NOISE = np.zeros(0)


def encode_range(distance, noise=_NO_NOISE, sensor_range=TaskConfig.sensor_range):
    """Section 3.2: surface distance in units (inf = no hit) -> code in 0..255.

    0 when nothing is within sensor_range (14), else round(255 * (1 - d / 14)), so a
    touching beam (d <= 0) reads 255. With noise (one value per reading), the noisy
    code clipped to [0, 255].
    """
    return sensing.encode(np.asarray(distance, dtype=np.float64), noise, float(SENSOR_LEVELS),
                          -SENSOR_LEVELS / sensor_range)


#: The contract's word on a robot without its bumper.
NO_HULL = "no geom named 'hull' (the bumper; its radius is the robot's)"


def edit_model(spec, config):
    """The task config's changes to the composed model (an MjSpec): the robot's radius."""
    if config.radius is not None:
        unit = spec.numeric(UNIT_NUMERIC)
        unit = UNIT if unit is None else float(unit.data[0])
        for name, part in (("hull", True), ("shell", False)):
            geom = spec.geom(PREFIX + spec_name(spec, name))
            if geom is None:
                if part:
                    raise ContractError(NO_HULL, field="bumper")
                continue
            geom.size[0] = config.radius * unit


def spec_name(spec, name):
    """The file's name for a contract name in a composed spec (a mount's map, tasks.mount)."""
    text = spec.text(PREFIX + NAMES_TEXT)  # the robot's, attached under the prefix
    if text is None:
        return name
    return dict(pair.split("=", 1) for pair in text.data.split()).get(name, name)


def substeps(seconds, timestep):
    """Whole substeps of `timestep` in `seconds` (at least one)."""
    return max(1, round(seconds / timestep))


def named_id(model, kind, name):
    """The id of the robot's part with a contract name (its prefixed MJCF name, or its
    file's name where a mount maps it: models.contract_names), -1 for none. model: an
    MjModel or dm_control's wrapper."""
    m = getattr(model, "ptr", model)
    name = contract_names(m).get(name, name) if m.ntext else name
    return mujoco.mj_name2id(m, kind, PREFIX + name)


def robot_radius(model):
    """The robot's radius in units: its hull's (sphere or cylinder) radius, from a
    compiled room (an MjModel or dm_control's wrapper); ContractError without a hull."""
    hull = named_id(model, mujoco.mjtObj.mjOBJ_GEOM, "hull")
    if hull < 0:
        raise ContractError(NO_HULL, field="bumper")
    return getattr(model, "ptr", model).geom_size[hull, 0] / unit_of(model)


class Physics(dm_mujoco.Physics):
    """Named read-outs of the room with one robot, in paper units and radians.

    Sensors are computed once per agent step, not on every substep: MuJoCo's sensor
    stage is disabled and `ranges()` runs it at the state it reads (mj_sensorPos),
    which gives the same sensor values bit for bit."""

    def _reload_from_data(self, data):
        super()._reload_from_data(data)
        m = self.model
        mjm = m.ptr
        #: Metres per paper unit (models.unit_of: the paper's 0.1 unless the robot's own).
        self.unit = unit = unit_of(mjm)
        self._base = named_id(m, mujoco.mjtObj.mjOBJ_BODY, "base")
        if self._base < 0:
            raise ContractError("no body named 'base' (the robot's base body)", field="base")
        #: The robot's radius in units: its hull's (sphere or cylinder) radius.
        self.robot_radius = robot_radius(m)
        beams = np.flatnonzero(m.sensor_type == mujoco.mjtSensor.mjSENS_RANGEFINDER)
        if not len(beams):
            raise ContractError("no rangefinder sensors", field="beams")
        adr = m.sensor_adr[beams]
        if not np.array_equal(adr, np.arange(adr[0], adr[0] + len(adr))):
            raise ContractError("rangefinders must be declared one after another",
                                field="beams.sensors")
        self._beams = slice(int(adr[0]), int(adr[0]) + len(adr))
        #: The robot's rest pose (a qpos): its model's qpos0, or its mount's rest
        #: (models.rest_qpos); a pose is set from it, the drives read their rest from it.
        self.rest_qpos = rest_qpos(mjm)
        self._find_base_joints(m)
        # MuJoCo's own arrays, read and written every step without dm_control's wrappers.
        self._mj = (mjm, data.ptr)
        self._qpos, self._qvel = data.ptr.qpos, data.ptr.qvel
        self._ctrl, self._sensordata = data.ptr.ctrl, data.ptr.sensordata
        self._act = data.ptr.act
        # The robot's frame: its base's, or the site a mount adds with it (tasks.mount.frame)
        self._frame = named_id(m, mujoco.mjtObj.mjOBJ_SITE, FRAME_SITE)
        self._xpos, self._xmat = self.frame_at(data.ptr)
        self._placement = self._placed(mjm)
        self._body_velocity = np.zeros(6)
        mjm.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_SENSOR)
        #: The room's timestep in seconds.
        self.timestep = float(mjm.opt.timestep)
        #: Substeps run so far, for benchmarks against raw mujoco.mj_step.
        self.substeps = 0
        #: The room's floor (x0, x1, y0, y1) and obstacles (rectangles), in units.
        self.field, self.obstacles, goal, self.start = room_layout(m)
        field = self.field
        self.goal_box = (np.array(goal[::2]), np.array(goal[1::2]))
        #: Seconds of simulated time per agent step; set by the task.
        self.step_seconds = 1.0
        # The body's part of the drive's record (tasks.kernels.body.BODY_FIELDS): the
        # structs' addresses, views of the ints the kernels touch, MuJoCo's arrays; the
        # drive's Physics adds its own parts.
        (x0, y0), (x1, y1) = self.goal_box
        m_address, d_address = bindings.addresses(mjm, data.ptr)
        #: The body's values of the drive's record, by name.
        self.body = dict(
            m=m_address, d=d_address, flags=bindings.disable_flags(mjm),
            bad_qacc=bindings.warning_count(data.ptr, mujoco.mjtWarning.mjWARN_BADQACC),
            ctrl=self._ctrl, qpos=self._qpos, qvel=self._qvel, act=self._act,
            sensordata=self._sensordata, xpos=self._xpos, xmat=self._xmat,
            qyaw=-1 if self._qyaw is None or self._own_joints or self._placement else self._qyaw,
            free=int(self._free is not None),
            base=int(self._base), beam0=self._beams.start, beam1=self._beams.stop, unit=unit,
            metres_to_units=1.0 / unit, radius=float(self.robot_radius),
            timestep=self.timestep, min_cos_tilt=float(self._min_cos_tilt), x0=float(x0),
            x1=float(x1), y0=float(y0), y1=float(y1), room_x0=float(field[0]),
            room_x1=float(field[1]), room_y0=float(field[2]), room_y1=float(field[3]))
        #: The drive's own parts of its record (each drive's Physics fills them), by name.
        self.parts = {}
        #: The drive's record (Record), built at each episode's start (set_drive).
        self.record = None
        #: Rangefinders (the sensor noise draws one normal for each).
        self.n_beams = len(adr)

    #: The realisation's record class (a compiled.records.Record of BODY_FIELDS and its own:
    #: its row's record in tasks.realisations.REALISATIONS).
    Record = None

    def phase_settings(self, n_turn, n_move):
        """The realisation's settings for the episode's two-wheel phases (its ramps): none
        by default."""
        return {}

    def set_drive(self, **settings):
        """The drive's record (`record`, a `Record`) of the body, the physics' parts and
        the episode's settings (the task's), by name."""
        self.record = self.Record.build(**{**self.body, **self.parts, **settings})
        return self.record

    def _find_base_joints(self, m):
        """The base's joints (tasks.placement.base_joints): one free joint, or slide x and
        slide y (and a hinge about z or -z), besides any of its own."""
        self._joints = found = placement.base_joints(m.ptr, self._base, self.rest_qpos)
        #: The base's free joint's first dof (x, then y), None for a planar base.
        self.free_dof = found.free_dof
        #: The base's planar joints by role ("x", "y", "yaw"), as joint ids.
        self.base_joints = found.roles
        #: The sense of the base's yaw hinge: 1 about z, -1 about -z.
        self.yaw_sign = found.yaw_sign
        self._free, self._rest_height, self._own_joints = found.free_q, found.rest_height, found.own
        self._qx, self._qy, self._qyaw = found.qx, found.qy, found.qyaw

    def frame_at(self, d):
        """(position, rotation): the robot's frame's rows of an MjData d of the model (its
        xpos and row-major xmat: the base's, or the frame site's)."""
        if self._frame >= 0:
            return d.site_xpos[self._frame], d.site_xmat[self._frame]
        return d.xpos[self._base], d.xmat[self._base]

    def _placed(self, mjm):
        """The robot's Placement, None where its pose is set the plain way."""
        if placement.Placement.plain(mjm, self.frame_at, self._joints, self._frame >= 0,
                                     self.rest_qpos):
            return None
        return placement.Placement(mjm, self.frame_at, self._joints, self.rest_qpos)

    # -- read-outs ---------------------------------------------------------
    def robot_pose(self):
        """(x, y, heading) of the base body's frame in paper units and radians.

        A base turning on a hinge about z reports the hinge's angle, which is the frame's
        heading exactly (the frame's rotation matrix, made through a quaternion, rounds
        it in the last bits); any other base, its frame's x axis in the plane."""
        return sensing.pose(self._xpos, self._xmat, self._qpos, self.body["qyaw"], self.unit)

    def tilt(self):
        """Angle in radians between the base's z axis and the vertical."""
        return math.acos(min(1.0, max(-1.0, float(self._xmat[8]))))

    def robot_velocity(self):
        """(vx, vy) of the base body's frame in paper units per agent step."""
        return sensing.velocity(self.body["m"], self.body["d"], self._base,
                                self.step_seconds / self.unit, self._body_velocity)

    def ranges(self):
        """Distance from the body surface along each beam, in units; inf where nothing is
        hit. Runs the sensor stage once, at the current state."""
        b = self.body
        return sensing.ranges(b["m"], b["d"], b["flags"], b["sensordata"], b["beam0"], b["beam1"],
                              b["metres_to_units"], b["radius"])

    def render(self, height=240, width=320, camera_id=-1, scene_option=None,
               scene_callback=None):
        """A frame, as dm_control's render, through tasks.render: the OpenGL context is
        made at the first frame, never at import."""
        return render.frame(self, height, width, camera_id, scene_option=scene_option,
                            scene_callback=scene_callback)

    def in_goal(self):
        """True when the robot's centre is inside the goal square."""
        x, y, _ = self.robot_pose()
        b = self.body
        return body.in_box(x, y, b["x0"], b["x1"], b["y0"], b["y1"])

    def step(self, nstep=1):
        """dm_control's legacy step (mj_step2, mj_step(n-1), mj_step1), so contacts and
        kinematics describe the new state, without its per-call Python overhead; none
        for nstep 0 (the Environment's, whose drive's step ran its own substeps).
        Raises PhysicsError when MuJoCo flags an unstable state or a 3D robot tips over."""
        if nstep <= 0:
            return
        b = self.body
        status = bindings.run(b["m"], b["d"], nstep, b["bad_qacc"], b["xmat"], b["free"] != 0,
                              b["min_cos_tilt"])
        self.substeps += nstep
        if status != bindings.OK:
            self.raise_for(status)

    def raise_for(self, status):
        """The PhysicsError of a kernel's status (tasks.kernels.bindings: UNSTABLE, TIPPED,
        OUTSIDE)."""
        t = self._mj[1].time
        if status == bindings.NOT_FINITE:
            raise ValueError("action must be finite")
        if status == bindings.UNSTABLE:
            raise control.PhysicsError(f"unstable simulation at t={t:.3f} s")
        if status == bindings.OUTSIDE:
            x, y, _ = self.robot_pose()
            raise control.PhysicsError(f"the robot left the room at t={t:.3f} s (at "
                                       f"({x:.1f}, {y:.1f}) units, off its floor)")
        raise control.PhysicsError(f"the robot tipped over at t={t:.3f} s "
                                   f"(tilt {math.degrees(self.tilt()):.0f} degrees)")

    _min_cos_tilt = math.cos(math.radians(MAX_TILT_DEGREES))

    # -- setters -----------------------------------------------------------
    def set_robot_pose(self, x, y, heading=0.0):
        """Places the robot at (x, y, heading), in units and radians, at rest; a free-joint
        robot upright at the height its file gives it, every other joint at its rest; a
        robot whose frame in its file is not the plain one, by its tasks.placement.Placement."""
        q = self._qpos
        if self._placement is not None:   # a frame of its own in its file
            self._placement.place(self._mj[1], x * self.unit, y * self.unit, heading)
        elif self._free is not None:
            model, _ = self._mj
            q[:] = self.rest_qpos
            a = self._free
            q[a: a + 3] = x * self.unit, y * self.unit, self._rest_height
            q[a + 3: a + 7] = math.cos(heading / 2), 0.0, 0.0, math.sin(heading / 2)
        else:
            if self._own_joints:
                q[:] = self.rest_qpos
            q[self._qx], q[self._qy] = x * self.unit, y * self.unit
            if self._qyaw is not None:
                q[self._qyaw] = heading
        self._qvel[:] = 0.0
        self._ctrl[:] = 0.0
        self._act[:] = 0.0
        self.forward()


class Navigation(control.Task):
    """Reach the goal square from the jittered start; the realisation's compiled step acts.

    An agent step is tasks.kernels.env_step.step, one compiled call: the action clipped, the
    realisation's action, the goal test, the range codes (and, floating, the velocity),
    on the step's draws from the task's buffered random stream (`draws`: the action
    noise's two uniforms, the sensor noise's normals, the velocity noise's). The dm_env
    hooks run it too: before_step runs the whole step, after_step and get_observation
    hand on what it found; an episode's first observation is env_step.observe. So the hooks
    and tasks.Environment's compiled step (`compiled_step`, the same call without
    dm_control's Python around it) are the same step, bit for bit. Each drive's task
    sets its episode's settings in initialize_episode (start_drive).

    A dm_control task (control.Task, as dm_control.suite.base.Task is, whose only part used
    here is its RandomState: importing dm_control.suite imports every suite domain and
    SciPy, a third of a second per process)."""

    #: Action dimension, set by each robot.
    action_dim = 1
    #: The observation's modalities in order, each a key of get_observation's.
    observation_keys = ("range",)
    #: The drive's edit of the composed model for its task config (tasks.compile_robot).
    edit_model = staticmethod(edit_model)

    def __init__(self, config=TaskConfig(), *, time_scale=1.0, random=None):
        if not isinstance(random, np.random.RandomState):  # as suite.base.Task takes it
            random = np.random.RandomState(random)
        #: The task's random stream as the compiled draws read it; `random` settles it.
        self.stream = TaskStream(random)
        self.config = config
        #: Seconds of an agent step over the drive's own (1 for the paper's robots).
        self.time_scale = float(time_scale)
        self.sensor_noise = float(config.sensor_noise)
        self.action_noise = float(config.action_noise)
        self.velocity_noise = float(config.velocity_noise) if "velocity" in self.observation_keys \
            else 0.0
        self._jitter_xy = config.start_jitter_xy
        self._jitter_heading = np.deg2rad(config.start_jitter_heading)
        #: The observation the last step sensed, until get_observation hands it on.
        self._pending = None

    @property
    def random(self):
        """The task's RandomState (dm_control's), wound to where the draws left it."""
        return self.stream.settled()

    def reseed(self, seed):
        """A new random stream for the task: np.random.RandomState(seed)."""
        self.stream = TaskStream(np.random.RandomState(seed))

    # -- episode -------------------------------------------------------------
    def body_settings(self):
        """The task's part of every drive's record (tasks.kernels.body.BODY_FIELDS):
        Section 3.2's code and Section 3.3's action noise."""
        return dict(levels=float(SENSOR_LEVELS), per_unit=-SENSOR_LEVELS / self.config.sensor_range,
                    action_noise=self.action_noise)

    def draw_buffers(self, n_beams):
        """Arrays for one step's draws (u, z, vz), each empty where its noise is off."""
        return (np.zeros(2 if self.action_noise > 0 else 0),
                np.zeros(n_beams if self.sensor_noise > 0 else 0),
                np.zeros(2 if self.velocity_noise > 0 else 0))

    def draws(self, acting=True):
        """One step's random draws, in their order: the action noise's two uniforms (none
        when not `acting`: an episode's first observation), the sensor noise's normals,
        the floating velocity noise's normals."""
        u, z, vz = self._draws
        self.stream.draws(u if acting else _NO_NOISE, z, self.sensor_noise, vz,
                          self.velocity_noise)
        return u, z, vz

    def action_array(self, action):
        """The action as a fresh float64 array of shape (action_dim,) (a scalar for a
        one-part action), clipped to [-1, 1] (tasks.kernels.body.clip_finite, which the
        step runs again); ValueError for another shape, NaN or inf, before any draw."""
        a = np.array(action, dtype=np.float64)
        if a.shape != (self.action_dim,):
            if not (a.ndim == 0 and self.action_dim == 1):
                raise ValueError(f"action must have shape ({self.action_dim},), got {a.shape}")
            a = a.reshape(1)
        if not body.clip_finite(a):
            raise ValueError(f"action must be finite, got {a.tolist()}")  # nothing clipped
        return a

    def act(self, action, physics):
        """The agent step (tasks.kernels.env_step.step) on the checked action: the goal kept
        for get_reward and get_termination; returns its observation."""
        a = self.action_array(action)
        u, z, vz = self.draws()
        codes, velocity = self._sensed
        status, n, goal = env_step.step(physics.record, a, u, z, vz, codes, velocity)
        self.finish(n, goal, physics, status)
        return self._observation()

    def compiled_step(self, action, physics):
        """An agent step (`act`) without dm_control's hooks around it: returns (reward,
        observation, termination)."""
        observation = self.act(action, physics)
        goal = self._at_goal
        return (1.0 if goal else 0.0), observation, (0.0 if goal else None)

    def finish(self, substeps, goal, physics, status=bindings.OK):
        """The end of compiled steps (this task's or a compiled loop's): the substeps
        counted, MuJoCo's refusal raised, the goal kept for the reward."""
        physics.substeps += substeps
        if status != bindings.OK:
            physics.raise_for(status)
        self._at_goal = goal

    def start_drive(self, physics, **settings):
        """The episode's drive settings (body_settings' and the drive's) into the
        physics' record, and the arrays of the step's draws and sensor values."""
        physics.set_drive(**self.body_settings(), **settings)
        self._draws = self.draw_buffers(physics.n_beams)
        self._sensed = (np.zeros(physics.n_beams), np.zeros(2))

    def drive_settings(self, physics):
        """The drive's settings for an episode (its phases' substeps, its readings; the
        drive's task gives them, setting physics.step_seconds)."""
        raise NotImplementedError

    def initialize_episode(self, physics):
        self.start_drive(physics, **self.drive_settings(physics))
        self._pending = None
        x, y, heading = physics.start
        if self.config.start_jitter:
            jx, jy = self.random.uniform(-self._jitter_xy, self._jitter_xy, size=2)
            jh = self.random.uniform(-self._jitter_heading, self._jitter_heading)
            x, y, heading = x + jx, y + jy, heading + jh
        physics.set_robot_pose(x, y, heading)

    def before_step(self, action, physics):
        """The whole agent step (`act`): its goal kept for get_reward and
        get_termination, its observation for get_observation."""
        self._pending = self.act(action, physics)

    def get_observation(self, physics):
        """The last step's observation; without one (an episode's first, or dm_control's
        observation_spec before any episode), env_step.observe at the current state."""
        if self._pending is not None:
            obs, self._pending = self._pending, None
            return obs
        if physics.record is None:
            # dm_control's observation_spec reads an observation before any episode (its
            # noise draws included): the drive's record is made for it.
            self.start_drive(physics, **self.drive_settings(physics))
        _, z, vz = self.draws(acting=False)
        codes, velocity = self._sensed
        env_step.observe(physics.record, z, vz, codes, velocity)
        return self._observation()

    def _observation(self):
        """The sensed values as dm_env's observation: a fresh copy of each modality."""
        codes, velocity = self._sensed
        obs = collections.OrderedDict()
        for key in self.observation_keys:
            obs[key] = (codes if key == "range" else velocity).copy()
        return obs

    def get_reward(self, physics):
        return 1.0 if self._at_goal else 0.0

    def get_termination(self, physics):
        return 0.0 if self._at_goal else None

    # -- actions ---------------------------------------------------------------
    def action_spec(self, physics):
        return specs.BoundedArray((self.action_dim,), np.float64, -1.0, 1.0, name="action")
