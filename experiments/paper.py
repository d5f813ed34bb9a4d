"""Section 3.6's reported figures, the yardstick of every report.

The paper's "two wheels robot" is the two_wheel drive, its "floating robot" the
floating drive: every registered robot is compared with the figures of its drive.
The step budgets live with the drives, in tasks/robots.py.
"""
from ebrl.config import CONDITIONS  # noqa: F401  (the paper's two conditions)

SEEDS = 50

#: (drive, condition) -> figures reported in Section 3.6.
RESULTS = {
    ("two_wheel", "random"): {
        "first_trial_steps": {"mean": 6087, "sd": 5789, "reached": 49},
        "steps_per_trial": {"mean": 3844, "sd": 3336},
        "shrink": 0.63,
    },
    ("two_wheel", "avoidance"): {
        "first_trial_steps": {"mean": 956, "sd": 954, "reached": 50},
        "steps_per_trial": {"mean": 283, "sd": 98},
        "shrink": 0.30,
    },
    ("floating", "random"): {
        "first_trial_steps": {"mean": 11129, "sd": 9909, "reached": 50},
        "steps_per_trial": {"mean": 8426, "sd": 2630},
        "shrink": 0.76,
    },
    ("floating", "avoidance"): {
        "first_trial_steps": {"mean": 5433, "sd": 3977, "reached": 50},
        "steps_per_trial": {"mean": 1869, "sd": 699},
        "shrink": 0.34,
    },
}

#: Two-wheel goals at 30,000 steps: "less than 30 in 43 cases out of 50 cases
#: without avoidance, though the number is 49 in the worst case with avoidance".
TWO_WHEEL_GOALS = {"random_below_30": 43, "avoidance_min": 49}

#: Section 3.6's first trials, which are the physics and the fallback alone (before the
#: first reward every utility is 0, so eq 5's min(W, U) never exceeds the threshold and
#: memory never acts): per (drive, condition) the mean and sd of the first trial's steps
#: over the runs that reached the goal within the budget (the drive's: 30,000 and
#: 100,000), the runs (SEEDS) and how many of them reached it ("over 49 cases"; footnote
#: 2: "in one of 50 cases, it could not reach at the goal within 30,000 steps").
FIRST_TRIALS = {key: dict(figures["first_trial_steps"], runs=SEEDS)
                for key, figures in RESULTS.items()}


def reported(group, condition=None):
    """Section 3.6's figures (RESULTS) for a summary group's drive and condition; None in
    a room other than the paper's (the paper ran its own room only)."""
    if group.get("room"):
        return None
    return RESULTS.get((group.get("drive"), condition or group["condition"]))
