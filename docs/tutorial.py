# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Tutorial: the task, the agent, a robot file and a frame
#
# A tour of the Python API in about half a minute: make the paper's task, step it, run the
# episode-based learner (EBRL) with its intrinsic avoidance behaviour on it for a few
# thousand steps, plot its path and its cumulative reward, enter a third-party robot file
# through a mount, and render a frame offscreen.
#
# This file is `docs/tutorial.py`, paired with `docs/tutorial.ipynb` by
# [jupytext](https://jupytext.readthedocs.io) (`jupytext --sync docs/tutorial.py` after an
# edit of either). `make test` runs it (`tests/test_tutorial.py`), so it stays true. Run it
# as a script (`.venv/bin/python docs/tutorial.py`) or open the notebook in Jupyter (not in
# the lock: `pip install jupyterlab`). The figures and the frame are also written to a
# folder, `EBRL_TUTORIAL_OUT` or a new temporary one. The layout of the code and the rest
# of the API: [code.md](code.md).

# %%
import os
import pathlib
import tempfile
import time

import matplotlib.pyplot as plt
import numpy as np

import ebrl
import models
import tasks
from experiments.outputs import plots, rendering

OUT = pathlib.Path(os.environ.get("EBRL_TUTORIAL_OUT") or tempfile.mkdtemp(prefix="ebrl_tutorial_"))
OUT.mkdir(parents=True, exist_ok=True)
started = time.perf_counter()

# %% [markdown]
# ## 1. The task
#
# `tasks.load` makes a dm_control environment: a robot of the registry (`ebrl robots`
# lists them) in a room (the paper's, Sutton's maze, unless `room=` names another). The
# paper's two-wheel robot takes one action in [-1, 1]: turn |a| radians (left for a
# negative a), then move 2(1 - |a|) units. It observes seven range codes, 0 (nothing
# within 14 units) to 255 (touching), leftmost beam first.

# %%
env = tasks.load("two_wheel", seed=0)
ts = env.reset()
print("observations:", {k: v.shape for k, v in ts.observation.items()})
print("range codes: ", ts.observation["range"])
print("pose (x, y, heading):", np.round(env.physics.robot_pose(), 2))
for action in (0.0, 0.0, -0.4, 0.0):  # two moves straight on, a turn left, one more move
    ts = env.step([action])
    print(f"action {action:+.1f} -> pose", np.round(env.physics.robot_pose(), 2),
          "reward", ts.reward)

# %% [markdown]
# ## 2. The agent on the task
#
# `ebrl` is standalone numpy and numba: it acts on observation arrays and learns from a
# reward. Table 1's column T is the two-wheel robot's; its fallback, when the memory has
# nothing to say, is the avoidance behaviour of eq 8 (with its random action). The range
# codes are scaled to [0, 1]. A trial ends at the goal: `learn(reward, last=True)`, and
# the task starts again from its start.

# %%
STEPS = 4000
config = ebrl.paper_config("T")
agent = ebrl.Agent(config, obs_dim=7, action_dim=1,
                   fallback=ebrl.intrinsic.fallback_for("eq8", "avoidance"), seed=0)
ts = env.reset()
path, rewards, goals_at = [env.physics.robot_pose()[:2]], [], []
for step in range(1, STEPS + 1):
    obs = ts.observation["range"] / 255.0
    ts = env.step(agent.act(obs, ranges=obs))  # the memory (eq 5) or the fallback
    agent.learn(ts.reward, ts.last())          # store the step, eq 6-7, the discount
    rewards.append(ts.reward)
    path.append(env.physics.robot_pose()[:2])
    if ts.last():                              # at the goal: the next trial
        goals_at.append(step)
        ts = env.reset()
path, rewards = np.array(path), np.array(rewards)
trials = np.diff([0] + goals_at)
print(f"{STEPS} steps: {len(goals_at)} goals; trial lengths {trials.tolist()}")
print(f"the memory chose {agent.memory_decisions} of the {STEPS} actions")

# %% [markdown]
# ## 3. A trace and the cumulative reward
#
# The path of the first trial and of the last complete one, in the room as the paper's
# Figure 2 draws it, and the reward summed over the steps as its Figure 3 does.
# `experiments.outputs.plots.draw_room` draws any room's map (walls and goal).

# %%
ends = [0] + goals_at
fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 3.6))
plots.draw_room(ax)
first = path[: ends[1] + 1] if len(goals_at) else path
ax.plot(*first.T, lw=0.5, color="0.6", label=f"first trial ({len(first) - 1} steps)")
if len(goals_at) >= 2:
    last = path[ends[-2] + 1: ends[-1] + 1]
    ax.plot(*last.T, lw=1.5, color="tab:red", label=f"trial {len(goals_at)} ({len(last)} steps)")
ax.plot(*path[0], "o", color="tab:blue")
plots.legend_below(ax, fontsize=8)
bx.plot(np.arange(1, STEPS + 1), np.cumsum(rewards), color="tab:blue")
bx.set_xlabel("steps")
bx.set_ylabel("cumulative reward (goals)")
bx.set_title("EBRL with avoidance, seed 0")
fig.tight_layout()
fig.savefig(OUT / "trace_and_reward.png", dpi=80)

# %% [markdown]
# ## 4. A robot file, through a mount
#
# A third-party robot file enters unchanged through a small TOML mount
# ([adding_a_robot.md](adding_a_robot.md)): which body is the base, its bumper, its
# beams and how the drive reaches its actuators. The shipped mounts are robot names
# too: `point` is Gymnasium's point robot with the two-wheel drive's servos added. Its
# pose is in paper units like the paper robot's, so the same agent can drive it.

# %%
mount = pathlib.Path(models.__file__).parent / "mounts" / "point.toml"
print("\n".join(mount.read_text().splitlines()[5:13]))
point = tasks.load("point", seed=0)
ts = point.reset()
print("point's range codes:", ts.observation["range"])
for action in (0.0, -0.4, 0.0):
    ts = point.step([action])
    print(f"action {action:+.1f} -> pose", np.round(point.physics.robot_pose(), 2))

# %% [markdown]
# ## 5. A frame, rendered offscreen
#
# Frames render headless (EGL, or OSMesa: `MUJOCO_GL`, [videos.md](videos.md)).
# `physics.render` gives a plain frame from a camera of the room (`top`, `perspective`)
# or of the robot; `experiments.outputs.rendering.frame` adds what `ebrl render` draws:
# a path, the beams, a caption. Here, the two-wheel robot's trial under way, its beams,
# and the mounted point robot from the room's perspective camera (MuJoCo draws its
# rangefinders' rays in yellow).

# %%
trial = path[ends[-1] + 1:] if goals_at else path  # the trial under way (from its first step)
frame = rendering.frame(env.physics, trial, camera="top", sensor_range=14.0,
                        caption=f"step {STEPS}   goals {len(goals_at)}")
plain = point.physics.render(height=240, width=320, camera_id="perspective")
fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4))
ax.imshow(frame)
bx.imshow(plain)
for a in (ax, bx):
    a.set_axis_off()
fig.tight_layout()
fig.savefig(OUT / "frames.png", dpi=80)
print("frames:", frame.shape, plain.shape)
env.close()
point.close()

# %%
print(f"done in {time.perf_counter() - started:.1f} s; figures in {OUT}")
