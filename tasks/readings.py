"""The task's readings of the paper, one record each (ebrl.readings.Reading, the agent's
record), and every reading of both for the commands (EVERY, READING_BY_NAME, applies).

tasks.TaskConfig takes its reading fields' defaults from TASK and checks them with
Reading.check; the kernels receive a switch as its code (Reading.code: its index in
the values) and name their constants by `codes`.
A new task reading is an entry here, the TaskConfig field of its name (default from its
entry), its kernel and its test. A task reading's scope is the drives it acts on
(tasks.robots.DRIVES; all when empty); the agent's are scoped by fallback behaviour,
which a robot's entry names too (Robot.avoidance).
"""
from ebrl import readings as agent_readings
from ebrl.readings import Range, Reading

#: The task's readings (every reading field of tasks.TaskConfig), in its field order.
TASK = (
    Reading("action_noise", "task", Range(float, 0.0, 1.0, high_open=True), 0.05,
            "each action part scaled by a factor drawn uniformly from [1 - n, 1]",
            paper='Section 3.3: "the action also includes some amount of fluctuation by '
                  'maximum 5% discount from demanded value in both turning angle and moving '
                  'length" (the two wheels robot; the floating robot\'s is open)'),
    # "stop": the velocity set to zero at contact (the literal protocol's: "moves ...
    # until it bumps"); "grip": the bumper's friction takes the motion into the wall and
    # most along it; "slide": frictionless walls, the motion along the wall kept;
    # "bounce": the velocity reflected off the wall (restitution).
    Reading("bump", "task", ("stop", "grip", "slide", "bounce"), "stop",
            "the floating robot at a wall",
            drives=("floating",)),
    Reading("radius", "task",
            Range(float, 0.0, 5.0, low_open=True, none="the robot file's",
                  high_note=" units (the corridors are 10 wide)"), None,
            "the robot's radius in units (None: its file's 1.5)"),
    # The velocity change per step for a demand a in [-1, 1]: "scaled" 0.2 a (Section
    # 3.3's maximum), "demand" a itself (Section 3.3's example read literally), "clipped"
    # a clipped to [-0.2, 0.2].
    Reading("thrust", "task", ("scaled", "demand", "clipped"), "scaled",
            "the floating robot's velocity change for a demand a: 0.2 a, a, or a clipped",
            paper='Section 3.3: "We set the maximum value of acceleration as 0.2 units per '
                  'square step."',
            drives=("floating",)),
    Reading("wall_friction", "task", Range(float, 0.0, none="the robot file's, 1"), None,
            "the floating bumper's sliding friction on the walls (acts with bump=grip)",
            drives=("floating",)),
    # 0: the motion into the wall stops, the motion along it is kept.
    Reading("restitution", "task", Range(float, 0.0, 1.0), 1.0,
            "the share of the speed into a wall that bump=bounce reflects (1: elastic)",
            drives=("floating",)),
    Reading("velocity_noise", "task", Range(float, 0.0), 0.0,
            "the sd of the Gaussian noise on the floating robot's velocity reading, units/step",
            drives=("floating",)),
    # "code": the 0-255 code of the velocity over +-VELOCITY_FULL_SCALE, decoded back to
    # units/step, as the rangefinders' readings are coded.
    Reading("velocity_code", "task", ("none", "code"), "none",
            "the floating robot's velocity reading as it is, or through a 0-255 code",
            drives=("floating",)),
    # Section 3.3's blocked move, stated: "stop" where the body touches and turn the rest
    # (every protocol's). "refuse" (the move undone, all of it turned) is no reading of the
    # sentence: protocol 7's compensation for a body that slid along walls, kept only to
    # remake protocol 7's runs. The rest turns the commanded turn's way ("commanded",
    # right when a = 0) or "away" from the side whose beams read nearer at the blocked pose.
    Reading("blocked_move", "task", ("stop", "refuse"), "stop",
            "a blocked two-wheel move stops at contact and turns the rest (stated); "
            "refuse: protocol 7's, not Section 3.3",
            paper='Section 3.3: "If the agent cannot move any more because of collision with '
                  'an object, the rest portion of move is transferred into the angle of turn."',
            drives=("two_wheel",)),
    Reading("leftover_turn", "task", ("commanded", "away"), "commanded",
            "a blocked move's rest turns the commanded way, or away from the nearer side",
            drives=("two_wheel",)),
)

#: Every reading, the agent's then the task's.
EVERY = agent_readings.AGENT + TASK
READING_BY_NAME = {r.name: r for r in EVERY}  # the agent's and the task's


def applies(reading, robot, condition=None):
    """Whether a reading acts on a robot (its tasks.robots entry: its drive and its
    fallback behaviour) and, given one, a condition."""
    return ((not reading.drives or robot.drive in reading.drives)
            and (not reading.behaviours or robot.avoidance in reading.behaviours)
            and (condition is None or not reading.conditions or condition in reading.conditions))


def codes(name, *values):
    """The codes (ebrl.readings.Reading.code) of a switch's values, in the order asked:
    what a kernel module names its switch constants by, so they follow the registry."""
    reading = READING_BY_NAME[name]
    return reading.code(values[0]) if len(values) == 1 else tuple(map(reading.code, values))
