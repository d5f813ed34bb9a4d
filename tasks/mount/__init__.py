"""Mounts: an unchanged robot file entered into the room by a small TOML file.

A robot file of the naming contract (docs/adding_a_robot.md: a body ``base``, a geom
``hull``, rangefinders, the drive's actuators) needs no mount. Any other file does: its
mount says which body is the base, its root joints, its bumper, its beams, how the
drive's action reaches it and what of the file to drop. The file is read where it lies
(a path beside the mount, or ``package:path`` inside an installed package, resolved at
load time, never copied) and edited only in memory, as an MjSpec, before it is attached
to the room (models.compose). What the mount adds carries the contract's names; what it
names of the file is mapped in the model's text element models.NAMES_TEXT, which
tasks.navigation reads, so a mounted model is as self-describing as a contract file.

    name = "point"                      # default: the mount file's stem
    description = "..."
    file = "gymnasium:envs/mujoco/assets/point.xml"
    drive = "two_wheel"                 # a key of ACTIONS (tasks.robots.DRIVES)
    unit = 0.3333333333333333           # metres per paper unit (default 0.1)
    base = "torso"                      # the body whose frame is the robot's pose (turned
                                        # or moved in its file: placed all the same)
    forward = "x"                       # the base's axis it faces (x, y, z, -x, -y, -z)
    rest = "a keyframe"                 # or [rest] joint = value: its rest pose (rad, m),
                                        # checked against the joints' ranges
    joints = "file"                     # "file" (the base's own), "free", "planar",
                                        # "slides", "slides_z" (added beside the base's own)
    drop = ["world", "lights", "skybox", "actuators"]
    keep_options = []                   # of the file's <option>: timestep, integrator, flags
    time_scale = 1.0                    # also timestep, integrator: the registry's fields
    condim = 3                          # the robot geoms' condim (default: the file's)
    [bumper]                            # geom = "a geom of the file", or an added shape:
    geom = "pointbody"                  # shape = "sphere" | "capsule", radius, height (m)
    [beams]                             # height = 0.5 (added, the drive's arrangement), or
    height = 0.5                        # sensors = [the file's rangefinders, in order]
    [action]
    kind = "servos"                     # a kind of KINDS: servos, thrusters,
                                        # actuators, wheels, wheel_motors,
                                        # joint_motors, gait ([[action.legs]]); the
                                        # kind's fields (joint_motors' kp, kv: one
                                        # number, or [forward's, turn's])
    [readings]                          # TaskConfig or agent fields (Robot.readings)

Every error is one line, ``<mount file>: <field>: <what is wrong>``: a MountError when the
mount is read or its file edited, a models.ContractError (its `field`) when the robot is
refused at load (tasks.load); the mount file's full path, and where a value is wrong for
this robot, the one that fits (tasks.mount.spec.fitting_joints).

The package: `fields` (the one-line checks), `records` (Mount, Bumper, Beams, the Action
base), `kinds` (one Action class per action kind, registered by name: its fields, its
edit of the spec, its realisation: tasks.realisations), `parsing` (the TOML file to a Mount),
`frame` (the file's own frame and rest: the base's rotation in its file, the robot's
frame by its forward axis, the rest pose checked against the ranges), `spec` (the Mount
to the robot's MjSpec).
"""
from tasks.mount.fields import MountError
from tasks.mount.kinds import KINDS
from tasks.mount.parsing import ACTIONS, DROPS, JOINTS, OPTIONS, parse, resolve_file
from tasks.mount.parsed import Action, Beams, Bumper, Mount
from tasks.mount.spec import BEAMS, robot_spec

__all__ = ["parse", "robot_spec", "Mount", "MountError", "Bumper", "Beams",
           "Action", "KINDS", "ACTIONS", "JOINTS", "DROPS", "OPTIONS", "BEAMS",
           "resolve_file"]

