"""The summary over seeds (summary.json's content): each robot and condition's figures
with 95% percentile bootstrap intervals over its seeds, deterministic for the same runs."""
import numpy as np

from experiments import paper
from experiments.running import execution
from experiments.running.learners import AGENTS
from tasks.robots import ROBOTS

BOOTSTRAP_SAMPLES = 10_000
BOOTSTRAP_SEED = 20000  # the paper's year: any fixed number makes summaries reproducible


def robot_order(label):
    """Group labels ("robot" or "robot.agent") in the registry's order of robots, then
    by learner (EBRL first); robots not in the registry after them."""
    names = list(ROBOTS)
    robot, _, agent = label.removesuffix(execution.FIRST_TRIAL).partition(".")
    return (names.index(robot) if robot in names else len(names),
            AGENTS.index(agent or "ebrl") if (agent or "ebrl") in AGENTS else len(AGENTS))


def bootstrap_ci(values, rng, stat=np.mean):
    """95% percentile bootstrap interval of stat over values (None if < 2 values)."""
    values = np.asarray(values, dtype=np.float64)
    if len(values) < 2:
        return None
    idx = rng.integers(0, len(values), size=(BOOTSTRAP_SAMPLES, len(values)))
    stats = stat(values[idx], axis=1)
    lo, hi = np.percentile(stats, [2.5, 97.5])
    return [float(lo), float(hi)]


def _stats(values, rng):
    v = np.asarray(values, dtype=np.float64)
    if not len(v):
        return {"mean": None, "sd": None, "ci95": None}
    return {"mean": float(v.mean()), "sd": float(v.std(ddof=1)) if len(v) > 1 else 0.0,
            "ci95": bootstrap_ci(v, rng)}


def summarize(runs):
    """summary.json's content from load_runs()' runs. Deterministic for the same runs."""
    groups = []
    keys = sorted({(r, c) for r, c, _ in runs}, key=lambda k: (robot_order(k[0]), k[0],
                  paper.CONDITIONS.index(k[1]) if k[1] in paper.CONDITIONS else 9))
    for robot, condition in keys:
        rng = np.random.default_rng(BOOTSTRAP_SEED)
        seeds = sorted(s for r, c, s in runs if (r, c) == (robot, condition))
        ms = [runs[(robot, condition, s)]["metrics"] for s in seeds]
        steps = sorted({runs[(robot, condition, s)]["parameters"]["steps"] for s in seeds})
        first = [m["first_trial_steps"] for m in ms if m["first_trial_steps"] is not None]
        per_trial = [m["steps_per_trial"] for m in ms if m["steps_per_trial"] is not None]
        goals = [m["goals"] for m in ms]
        f = dict(_stats(first, rng), reached=len(first))
        p = dict(_stats(per_trial, rng), seeds=len(per_trial))
        shrink = (p["mean"] / f["mean"]) if f["mean"] and p["mean"] is not None else None
        shrink_ci = None
        if len(first) > 1 and len(per_trial) > 1:
            # Resample seeds that reached the goal at least once, keeping pairs together.
            pairs = np.array([[m["first_trial_steps"], m["steps_per_trial"]] for m in ms
                              if m["first_trial_steps"] is not None], dtype=np.float64)
            idx = rng.integers(0, len(pairs), size=(BOOTSTRAP_SAMPLES, len(pairs)))
            ratios = pairs[idx, 1].mean(axis=1) / pairs[idx, 0].mean(axis=1)
            shrink_ci = [float(x) for x in np.percentile(ratios, [2.5, 97.5])]
        room = runs[(robot, condition, seeds[0])]["parameters"].get("room")
        groups.append({
            "robot": robot, "condition": condition, **({"room": room} if room else {}),
            "drive": runs[(robot, condition, seeds[0])]["parameters"].get("drive"),
            "agent": runs[(robot, condition, seeds[0])]["parameters"].get("learner", "ebrl"),
            "steps": steps[0] if len(steps) == 1 else steps,
            "seeds": len(seeds),
            "first_trial_steps": f,
            "steps_per_trial": p,
            "shrink": shrink, "shrink_ci95": shrink_ci,
            "goals": {"min": int(min(goals)), "median": float(np.median(goals)),
                      "max": int(max(goals)), "mean": float(np.mean(goals)),
                      "below_30": int(sum(g < 30 for g in goals)),
                      "below_49": int(sum(g < paper.TWO_WHEEL_GOALS["avoidance_min"]
                                          for g in goals))},
            "memory_decision_rate": float(np.mean([
                runs[(robot, condition, s)]["memory_decisions"]
                / runs[(robot, condition, s)]["parameters"]["steps"] for s in seeds])),
        })
    return {"groups": groups,
            "bootstrap": {"samples": BOOTSTRAP_SAMPLES, "seed": BOOTSTRAP_SEED,
                          "interval": "95% percentile, resampling seeds"}}
