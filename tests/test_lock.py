"""The exact environment: the locks pin what pyproject.toml asks for, with hashes, the same
versions in both; a run's config.json and the report's summary name the lock's digest."""
import hashlib
import json
import os

import pytest
from packaging.requirements import Requirement

import helpers
from experiments.running import lock, results
from helpers import ROOT

tomllib = pytest.importorskip("tomllib")  # Python 3.11 on, as the lock
BASE, TEST = ROOT / "requirements.lock", ROOT / "requirements-test.lock"


def requirements(*extras):
    """pyproject.toml's requirements: the dependencies and those of the extras named."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    return [Requirement(r) for r in project["dependencies"]
            + [r for e in extras for r in project["optional-dependencies"][e]]]


@pytest.mark.parametrize("path, extras", [(BASE, ()), (TEST, ("test", "ray"))])
def test_each_lock_pins_every_requirement_within_its_range(path, extras):
    """`make lock` after every change of pyproject.toml's ranges: else this fails."""
    pinned = lock.pins(path)
    for req in requirements(*extras):
        name = lock.normalise(req.name)
        assert name in pinned, f"{path.name} lacks {req.name}: run make lock"
        assert req.specifier.contains(pinned[name], prereleases=True), \
            f"{path.name}: {req.name}=={pinned[name]} is outside {req.specifier}: run make lock"


def test_the_locks_agree_and_every_pin_has_its_hashes():
    base, test = lock.pins(BASE), lock.pins(TEST)
    assert base and {n: test.get(n) for n in base} == base  # the test lock adds, never changes
    assert set(test) - set(base) >= {"pytest", "ray"}
    # Every pinned line is followed by its hashes (pip refuses a hashed file with one bare).
    for path in (BASE, TEST):
        lines = path.read_text().splitlines()
        for i, line in enumerate(lines):
            if "==" in line and not line.startswith("#"):
                assert line.endswith("\\") and lines[i + 1].strip().startswith("--hash=sha256:"), line


def test_describe_names_the_digest_and_what_differs(tmp_path):
    sha = hashlib.sha256(BASE.read_bytes()).hexdigest()[:12]
    assert lock.digest() == sha and results.versions()["lock"] == sha
    # A lock that pins another numpy (and a package that is not installed): both named.
    import numpy
    text = BASE.read_text().replace(f"numpy=={numpy.__version__} ", "numpy==1.0.0 ")
    text += "not-a-package-here==1.0 \\\n    --hash=sha256:" + "0" * 64 + "\n"
    other = tmp_path / "requirements.lock"
    other.write_text(text)
    got = lock.describe(other)
    assert got["lock"] == hashlib.sha256(text.encode()).hexdigest()[:12] != sha
    assert got["lock_installed"].startswith("differs: ")
    assert f"numpy {numpy.__version__} (locked 1.0.0)" in got["lock_installed"]
    assert "not-a-package-here missing (locked 1.0)" in got["lock_installed"]
    assert lock.describe(tmp_path / "none.lock") == {"lock": "none", "lock_installed": "no lock file"}


def test_the_installed_packages_are_the_locks():
    """make test installs from requirements-test.lock: here, every base pin is what is
    installed (.ci/run requires it; a venv made with LOCK=no skips)."""
    got = lock.describe()["lock_installed"]
    if got != "exact" and os.environ.get("EBRL_REQUIRE_LOCK") != "1":
        pytest.skip(f"this venv is not the lock's ({got}); make clean && make test installs it")
    assert got == "exact"
    assert lock.differences(TEST) == []


@pytest.mark.slow
def test_a_run_and_its_report_name_the_lock(tmp_path):
    out = tmp_path / "results"
    helpers.ebrl_here("run", "--robot", "two_wheel", "--condition", "avoidance", "--seeds", "0",
                      "--steps", "200", "--workers", "1", "--no-progress", "--out", out, check=True)
    config = json.loads(next(out.glob("*/*/seed_*/config.json")).read_text())
    assert config["versions"]["lock"] == lock.digest()
    assert config["versions"]["lock_installed"] == lock.describe()["lock_installed"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["locks"] == [lock.digest()]
    assert f"requirements.lock {lock.digest()}" in (out / "REPORT.md").read_text()
