"""Every registered robot and shipped mount steps as it did before its drive was compiled.

tests/data/step_digests_v<PROTOCOL_VERSION>.json holds, for each robot and mount (and a
few readings), the sha256 of 300 steps (the Ant: 25) of random actions: each step's
observation, pose, qpos, qvel, step type, reward and substep count, by the hooks
(`env.compiled = False`) and by the compiled step. Version 7's were made at 55615e7, where
the drives' steps were still written in Python beside their kernels; version 8's (issue 56:
a two-wheel move ends at the touch) by tests/data/make_golden.py, which makes them again.
Between the two, every robot that never touched a wall with a two-wheel move kept its
digests bit for bit (the floating robot, the hovercraft, the point mass, the Ant, the
quadruped); the two-wheel robots that touched one changed (two_wheel, diff_drive, the car,
the point)."""
import json
import pathlib

import pytest

from tasks.protocols import PROTOCOL_VERSION
from helpers import ROOT

#: The slow tier (pyproject.toml's markers): the golden digests of every robot.
pytestmark = pytest.mark.slow

DIGESTS = ROOT / "tests" / "data" / f"step_digests_v{PROTOCOL_VERSION}.json"


def _cases():
    return sorted(json.loads(pathlib.Path(DIGESTS).read_text()).items())


@pytest.mark.parametrize("key,digest", _cases())
def test_every_robot_steps_as_its_golden_digest(key, digest):
    import importlib.util
    spec = importlib.util.spec_from_file_location("make_golden", ROOT / "tests" / "data" / "make_golden.py")
    golden = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(golden)
    robot, path, fields = key.split("/", 2)
    assert golden.step_digest(robot, path == "compiled", **json.loads(fields)) == digest
