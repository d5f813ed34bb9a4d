"""Makes the golden test data again: `python tests/data/make_golden.py [--check]`.

- step_digests_v<PROTOCOL_VERSION>.json: for every registered robot and shipped mount
  (and a few readings), the sha256 of its steps under random actions, by the hooks and
  by the compiled step (tests/test_step_digests.py).

--check makes them into memory and compares them with the committed files (exit 1 on a
difference); without it, the files are written anew.
"""
import hashlib
import json
import pathlib
import sys

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
#: Readings tried beyond each robot's own, by robot.
EXTRA_FIELDS = {"two_wheel": [{"blocked_move": "refuse"}], "diff_drive": [{"blocked_move": "refuse"}],
                "floating": [{"bump": "bounce", "velocity_noise": 0.1}],
                "hovercraft": [{"bump": "bounce", "velocity_noise": 0.1}]}


def step_digest(robot, compiled, **fields):
    """sha256 of 300 steps (the Ant's gait: 25) of random actions in [-1.2, 1.2] (seed 5)
    from tasks.load(robot, seed=11, **fields): each step's observation, pose, qpos,
    qvel, step type, reward and substeps; a new episode after the last step of one."""
    import tasks
    env = tasks.load(robot, seed=11, **fields)
    env.compiled = compiled
    h = hashlib.sha256()
    rng = np.random.default_rng(5)
    env.reset()
    dim = env.action_spec().shape[0]
    for _ in range(25 if robot == "ant" else 300):
        ts = env.step(rng.uniform(-1.2, 1.2, dim))
        for k in sorted(ts.observation):
            h.update(ts.observation[k].tobytes())
        h.update(np.array(env.physics.robot_pose()).tobytes())
        h.update(env.physics.data.qpos.tobytes())
        h.update(env.physics.data.qvel.tobytes())
        h.update(str((ts.step_type, ts.reward, env.physics.substeps)).encode())
        if ts.last():
            env.reset()
    env.close()
    return h.hexdigest()


def step_digests():
    """{robot/hooks|compiled/fields: digest} for every robot and mount."""
    import tasks
    out = {}
    for name in list(tasks.ROBOTS) + [m for m in tasks.MOUNTS if m not in tasks.ROBOTS]:
        for compiled in (False, True):
            for fields in [{}] + EXTRA_FIELDS.get(name, []):
                key = f"{name}/{'compiled' if compiled else 'hooks'}/{json.dumps(fields, sort_keys=True)}"
                out[key] = step_digest(name, compiled, **fields)
    return out


def main(argv):
    from experiments.running import protocol
    check = "--check" in argv
    path = HERE / f"step_digests_v{protocol.PROTOCOL_VERSION}.json"
    made = step_digests()
    if check:
        committed = json.loads(path.read_text())
        differ = sorted(k for k in set(made) | set(committed) if made.get(k) != committed.get(k))
        print(f"{path.name}: {'differs at ' + ', '.join(differ) if differ else 'the same'}")
        return 1 if differ else 0
    path.write_text(json.dumps(made, indent=1, sort_keys=True) + "\n")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
