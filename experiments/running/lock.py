"""The exact environment: requirements.lock at the repository's root (make lock) pins
every package of the base install with its hashes, and `make demo` and `make test`
install from it (requirements-test.lock: the same pins and the test and Ray extras).

A run's config.json names the lock by the first 12 hex digits of its sha256 and says
whether the packages installed are the lock's (`describe`); summary.json names the
locks of the runs it summarises (`of_runs`)."""
import hashlib
import json
import pathlib
import re

from experiments import ROOT

LOCK = ROOT / "requirements.lock"
#: A pinned line of a lock: name==version, then an environment marker after ';'.
_PIN = re.compile(r"^([A-Za-z0-9][A-Za-z0-9._-]*)==([^\s;\\]+)\s*(?:;\s*([^\\]+?))?\s*\\?$")


def digest(path=LOCK):
    """The first 12 hex digits of the file's sha256; None when there is no such file (an
    install from a wheel or an sdist, which carries no lock)."""
    try:
        return hashlib.sha256(pathlib.Path(path).read_bytes()).hexdigest()[:12]
    except FileNotFoundError:
        return None


def pins(path=LOCK):
    """{normalised name: version} of the lock's lines whose marker holds here."""
    out = {}
    for line in pathlib.Path(path).read_text().splitlines():
        m = _PIN.match(line)
        if m is None:
            continue
        name, version, marker = m.groups()
        if marker and not _marker_holds(marker):
            continue
        out[normalise(name)] = version
    return out


def normalise(name):
    """A package name as PEP 503 compares it."""
    return re.sub(r"[-_.]+", "-", name).lower()


def _marker_holds(marker):
    from packaging.markers import Marker
    return Marker(marker).evaluate()


def differences(path=LOCK):
    """'name installed (locked version)' for each package the lock pins here whose
    installed version differs or that is not installed."""
    from importlib import metadata
    out = []
    for name, version in sorted(pins(path).items()):
        try:
            installed = metadata.version(name)
        except metadata.PackageNotFoundError:
            installed = "missing"
        if installed != version:
            out.append(f"{name} {installed} (locked {version})")
    return out


def describe(path=LOCK):
    """What a run records of the environment: {"lock": the digest or "none",
    "lock_installed": "exact", or what differs from it}."""
    sha = digest(path)
    if sha is None:
        return {"lock": "none", "lock_installed": "no lock file"}
    diff = differences(path)
    return {"lock": sha, "lock_installed": "exact" if not diff else "differs: " + ", ".join(diff)}


def of_runs(root, runs):
    """The lock digests named by the config.json of runs (keys of results.load_runs:
    (label, condition, seed)) under root, sorted; "unknown" for runs recorded before runs
    named their lock."""
    found = set()
    for label, condition, seed in runs:
        path = pathlib.Path(root) / label / condition / f"seed_{seed:03d}" / "config.json"
        try:
            versions = json.loads(path.read_text()).get("versions", {})
        except (OSError, ValueError):
            versions = {}
        found.add(versions.get("lock", "unknown"))
    return sorted(found)
