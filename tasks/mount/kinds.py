"""The action kinds of a mount's [action] table: how the drive's action reaches the
robot. One class per kind, its name a class attribute (the only place the name is
written), listed in KINDS below: each a record of its fields that knows their parsing,
which drives take it, what of the file it replaces, its edit of the robot's MjSpec, and
the realisation it runs on (tasks.realisations: a kind's name is its realisation's, but
`actuators`, which maps a file's actuators onto the servos' or the thrusters' contract
names); tasks.mount.parsed.Action gives the hooks. The kinds that give the paper's
drives' contract are in tasks.mount.drive_kinds, those that drive a file's own joints in
tasks.mount.joint_kinds. Adding a kind is a class in one of them and its row here.

The drive modules are imported inside the methods that need them: these modules import
nothing heavy (the registry reads mounts before any MuJoCo import)."""
from __future__ import annotations

from tasks.mount.drive_kinds import Actuators, Servos, Thrusters
from tasks.mount.joint_kinds import Gait, JointMotors, WheelMotors, Wheels
from tasks.mount.parsed import Action

#: The action kinds by name, in the order ACTIONS lists them.
KINDS: dict[str, type[Action]] = {
    kind.name: kind for kind in (Servos, Thrusters, Actuators, Wheels, WheelMotors,
                                 JointMotors, Gait)}
