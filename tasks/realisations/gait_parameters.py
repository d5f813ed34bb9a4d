"""The gait's parameters (tasks.realisations.gait) as a table a mount's [action.gait] is
parsed against: their defaults and allowed values, in a module that imports no simulator
(tasks.mount.joint_kinds reads it when a mount is parsed, `ebrl robots` included)."""
import math

from ebrl.readings import Range

#: The gait's parameters (a mount's [action.gait] may set any of them) and defaults.
PARAMETERS = {
    "frequency": 1.0,          # CPG cycles per second
    "amplitude": 0.45,         # hip sweep, rad (the ant's hips reach +-0.52)
    "lift": 0.35,              # ankle lift in the swing, rad (the ant's ankles reach +-0.35)
    "kp": 15.0,                # PD gain, control per rad
    "kd": 1.0,                 # PD damping, control per rad/s
    "heading_gain": 2.0,       # turn command per rad of heading error
    "turn_tolerance": 0.01,    # rad: a turn ends within this of its target
    "slow_down": 0.5,          # units: the move's forward command ramps down over these
    "coast": 0.06,             # units: a move stops this short of its target (the body
                               # coasts on as the legs return to rest)
    "max_turn_seconds": 4.0,
    "max_move_seconds": 6.0,
    "settle_seconds": 0.3,     # at the end of each phase the legs return to rest
    "control_substeps": 1,     # substeps per CPG and PD update
    "feedback_seconds": 0.05,  # seconds between heading and distance feedback updates
    "max_tilt": 30.0,          # degrees: a base tilted further at a phase's end has fallen
}

#: Each parameter's allowed values (a mount's [action.gait] is checked against them when
#: it is parsed, tasks.mount.joint_kinds.Gait).
RANGES = {
    "frequency": Range(float, 0.0, 100.0, low_open=True, high_note=" cycles per second"),
    "amplitude": Range(float, 0.0, math.pi, high_note=" rad"),
    "lift": Range(float, 0.0, math.pi, high_note=" rad"),
    "kp": Range(float, 0.0, low_open=True),
    "kd": Range(float, 0.0),
    "heading_gain": Range(float, 0.0, low_open=True),
    "turn_tolerance": Range(float, 0.0, math.pi, low_open=True, high_note=" rad"),
    "slow_down": Range(float, 0.0),
    "coast": Range(float, 0.0, 2.0, high_open=True, high_note=" units (a move is 2 at most)"),
    "max_turn_seconds": Range(float, 0.0, 3600.0, low_open=True),
    "max_move_seconds": Range(float, 0.0, 3600.0, low_open=True),
    "settle_seconds": Range(float, 0.0, 3600.0),
    "control_substeps": Range(int, 1, 1000),
    "feedback_seconds": Range(float, 0.0, 3600.0, low_open=True),
    "max_tilt": Range(float, 0.0, 180.0, low_open=True, high_note=" degrees"),
}
