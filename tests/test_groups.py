"""make test's two workers keep tests/conftest.py's groups together (pytest -n 2 --dist
loadgroup). The grouping is silent when it fails: pytest-xdist 3.8 on pytest 9.2 ran every
group's tests on both workers (pytest-xdist issue 1386), the Ray and PostgreSQL tests two
at a time and each shared module fixture made twice, and every test still passed. Here a
folder of tests named as the conftest groups them runs on two real workers with the
conftest as its plugin; each test writes down the worker that ran it."""
import os
import subprocess
import sys

import pytest

from helpers import ROOT

#: Each test holds its worker a moment, so that tests left ungrouped go to both workers.
TEST = """
import os, pathlib, time
def test_{name}_{i}():
    time.sleep(0.2)
    folder = pathlib.Path(os.environ["EBRL_GROUPS_OUT"])
    (folder / "{name}_{i}").write_text(os.environ.get("PYTEST_XDIST_WORKER", "none"))
"""


@pytest.mark.slow
def test_the_conftests_groups_each_run_on_one_worker(tmp_path):
    tests, out = tmp_path / "tests", tmp_path / "out"
    tests.mkdir()
    out.mkdir()
    names = {"test_cluster.py": "processes", "test_cli_inputs.py": "one_module",
             "test_loose.py": "loose"}
    for module, name in names.items():
        (tests / module).write_text("".join(TEST.format(name=name, i=i) for i in range(6)))
    proc = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-n", "2", "--dist", "loadgroup",
         "-p", "no:cacheprovider", "-p", "conftest", "--rootdir", str(tmp_path), str(tests)],
        cwd=tmp_path, capture_output=True, text=True, timeout=300,
        env={**os.environ, "EBRL_GROUPS_OUT": str(out),
             "PYTHONPATH": str(ROOT / "tests")})
    assert proc.returncode == 0, proc.stdout + proc.stderr
    workers = {name: {p.read_text() for p in out.glob(f"{name}_*")} for name in names.values()}
    assert all(len(list(out.glob(f"{name}_*"))) == 6 for name in names.values())
    assert len(workers["processes"]) == 1 and len(workers["one_module"]) == 1, workers
    assert workers["loose"] == {"gw0", "gw1"}, workers  # two workers ran: the check can fail
