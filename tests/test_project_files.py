"""The files that say how the project may be used and cited: LICENSE is the standard
Apache-2.0 text with the project's copyright line, and CITATION.cff names the version and
license pyproject.toml gives."""
import re

from helpers import ROOT


def _field(text, name):
    """The value of a top-level `name = "..."` (TOML) or `name: ...` (YAML) line."""
    found = re.search(rf'^{name}\s*[=:]\s*"?([^"\n]+?)"?\s*$', text, flags=re.M)
    assert found, name
    return found.group(1)


def test_the_license_is_apache_2_with_the_projects_copyright():
    ours = (ROOT / "LICENSE").read_text().splitlines()
    standard = (ROOT / "models" / "vendor" / "mujoco_car" / "LICENSE").read_text().splitlines()
    assert "Apache License" in standard[1] and "Version 2.0, January 2004" in standard[2]
    differ = [(a, b) for a, b in zip(ours, standard) if a != b]
    assert len(ours) == len(standard)
    assert differ == [("   Copyright 2026 The EBRL replication authors",
                       "   Copyright [yyyy] [name of copyright owner]")]


def test_citation_names_pyprojects_version_and_license():
    pyproject = (ROOT / "pyproject.toml").read_text()
    citation = (ROOT / "CITATION.cff").read_text()
    assert _field(citation, "cff-version") == "1.2.0"
    assert _field(citation, "version") == _field(pyproject, "version")
    assert _field(citation, "license") == _field(pyproject, "license") == "Apache-2.0"
    assert "A method to embed human knowledge to reinforcement learning method" in citation
