"""Makes the golden test data again, or checks the committed copy against a fresh one.

    python tests/data/make_golden.py           # writes tests/data/planar_traces_v<N>.npz
                                               # and step_digests_v<N>.json, prints the
                                               # readings digests to paste
    python tests/data/make_golden.py --check   # regenerates into a temporary folder and
                                               # compares; exit status 1 on a difference

What it makes, and which test reads it:

- tests/data/planar_traces_v<PROTOCOL_VERSION>.npz (tests/test_robots.py,
  test_planar_trajectories_unchanged_by_the_registry): the first STEPS steps of seeds
  SEEDS, every paper robot and condition, each the int16 trace of execution.execute, keyed
  "<robot>__<condition>__seed_NNN". A run's first steps are the same whatever its budget
  (the full run behind RESULTS.md's first steps too), which the test checks.
- tests/data/step_digests_v<PROTOCOL_VERSION>.json (tests/test_step_digests.py): for
  every registered robot and shipped mount (and a few readings), the sha256 of its steps
  under random actions (`step_digest`), by the hooks and by the compiled step. The
  committed file of version 8 was made by this script at protocol 8's body (version 7's at
  55615e7, before the drives' Python twins went and the car and the Ant were compiled).
- BEFORE, the readings digests in tests/test_ebrl_readings.py (sha256 of the actions
  rounded to 1e-9 and of the memory's final state, of the test's fixed input stream with
  protocol 3's readings), computed by that test file's own `stream` and `digests`. Being
  source, they are printed rather than written.

Both are bit for bit on one kind of machine only (numpy's BLAS and math kernels round the
last bit per CPU): remake them on the machine kind the tests run on, and only when a
change is meant to alter what a run computes (a new PROTOCOL_VERSION).
"""
import argparse
import hashlib
import json
import pathlib
import sys
import tempfile

import numpy as np

from tasks.protocols import PROTOCOL_VERSION

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[1]
for _path in (ROOT, ROOT / "tests"):  # the packages, and the test module the digests live in
    if str(_path) not in sys.path:
        sys.path.insert(0, str(_path))

#: The traces: the first STEPS agent steps of these seeds.
STEPS = 3000
SEEDS = (0, 1)


def traces_name():
    return f"planar_traces_v{PROTOCOL_VERSION}.npz"


def make_traces():
    """{key: int16 trace of STEPS + 1 positions} for every paper robot and condition."""
    from ebrl.config import CONDITIONS
    from experiments.running import execution
    from tasks.robots import PAPER_ROBOTS
    out = {}
    for robot in PAPER_ROBOTS:
        for condition in CONDITIONS:
            for seed in SEEDS:
                spec = execution.RunSpec(robot, condition, seed, STEPS)
                out[f"{robot}__{condition}__seed_{seed:03d}"] = execution.execute(spec)["trace"]
    return out


def write_traces(folder):
    path = pathlib.Path(folder) / traces_name()
    np.savez_compressed(path, **make_traces())
    return path


#: Readings tried beyond each robot's own, by robot (the step digests).
EXTRA_FIELDS = {"two_wheel": [{"blocked_move": "stop"}], "diff_drive": [{"blocked_move": "refuse"}],
                "floating": [{"bump": "bounce", "velocity_noise": 0.1}],
                "hovercraft": [{"bump": "bounce", "velocity_noise": 0.1}]}


def step_digests_name():
    return f"step_digests_v{PROTOCOL_VERSION}.json"


def step_digest(robot, compiled, **fields):
    """sha256 of 300 steps (a gait's, as the Ant's and the quadruped's: 25) of random
    actions in [-1.2, 1.2] (seed 5) from tasks.load(robot, seed=11, **fields): each
    step's observation, pose, qpos,
    qvel, step type, reward and substeps; a new episode after the last step of one."""
    import tasks
    env = tasks.load(robot, seed=11, **fields)
    env.compiled = compiled
    h = hashlib.sha256()
    rng = np.random.default_rng(5)
    env.reset()
    dim = env.action_spec().shape[0]
    from tasks.realisations import gait
    for _ in range(25 if isinstance(env.task, gait.GaitTask) else 300):
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


def make_step_digests():
    """{robot/hooks|compiled/fields: digest} for every robot and mount."""
    import tasks
    out = {}
    for name in list(tasks.ROBOTS) + [m for m in tasks.MOUNTS if m not in tasks.ROBOTS]:
        for compiled in (False, True):
            for fields in [{}] + EXTRA_FIELDS.get(name, []):
                key = f"{name}/{'compiled' if compiled else 'hooks'}/{json.dumps(fields, sort_keys=True)}"
                out[key] = step_digest(name, compiled, **fields)
    return out


def make_digests():
    """{stream name: (actions digest, state digest)}, as tests/test_ebrl_readings.py's
    BEFORE holds them."""
    import test_ebrl_readings as t
    return {name: t.digests(*t.stream(name, **t.PROTOCOL3)) for name in t.STREAMS}


def check():
    """The differences between the committed data and a fresh copy, one line each."""
    import test_ebrl_readings
    problems = []
    committed = HERE / traces_name()
    with tempfile.TemporaryDirectory() as scratch:
        fresh = write_traces(scratch)
        if not committed.is_file():
            problems.append(f"{committed} is missing")
        else:
            with np.load(committed) as old, np.load(fresh) as new:
                if set(old.files) != set(new.files):
                    problems.append(f"{committed.name}: keys {sorted(old.files)} "
                                    f"against {sorted(new.files)}")
                for key in sorted(set(old.files) & set(new.files)):
                    a, b = old[key], new[key]
                    if a.dtype != b.dtype or a.shape != b.shape:
                        problems.append(f"{committed.name} {key}: {a.dtype}{a.shape} "
                                        f"against {b.dtype}{b.shape}")
                    elif not np.array_equal(a, b):
                        first = int(np.flatnonzero((a != b).any(axis=1))[0])
                        problems.append(f"{committed.name} {key}: differs from step {first}")
    committed = json.loads((HERE / step_digests_name()).read_text())
    made = make_step_digests()
    for key in sorted(set(made) | set(committed)):
        if made.get(key) != committed.get(key):
            problems.append(f"{step_digests_name()} {key}: {made.get(key)} against {committed.get(key)}")
    for name, got in make_digests().items():
        if got != test_ebrl_readings.BEFORE[name]:
            problems.append(f"test_ebrl_readings.BEFORE[{name!r}]: {got} against "
                            f"{test_ebrl_readings.BEFORE[name]}")
    return problems


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true",
                        help="regenerate into a temporary folder and compare with the "
                             "committed data; nothing is written here")
    args = parser.parse_args(argv)
    if args.check:
        problems = check()
        for line in problems:
            print(line, file=sys.stderr)
        print("golden data: " + (f"{len(problems)} differences" if problems
                                 else f"{traces_name()}, {step_digests_name()} and the "
                                      "readings digests match"))
        return 1 if problems else 0
    print(f"wrote {write_traces(HERE)}")
    path = HERE / step_digests_name()
    path.write_text(json.dumps(make_step_digests(), indent=1, sort_keys=True) + "\n")
    print(f"wrote {path}")
    print("tests/test_ebrl_readings.py, BEFORE = {")
    for name, (actions, state) in make_digests().items():
        print(f'    "{name}": ("{actions}",\n{" " * (len(name) + 9)}"{state}"),')
    print("}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
