"""The docs site (mkdocs.yml, `make docs`): built strictly, so a broken link or anchor, a
page left out of the nav or a docstring MkDocs cannot read fails make test; and the same
build of a copy of the repository's pages with a broken link, a broken anchor, a link out
of docs/ to a file that does not exist and a page out of the nav fails, naming each."""
import os
import re
import shutil
import subprocess
import sys

import pytest

from helpers import ROOT

# Two builds of the site in processes of their own (about 4 and 2 s on two idle cores).
pytestmark = pytest.mark.slow

#: What a copy of the repository takes as it is (read through links): everything but
#: these, which it copies (the pages it breaks, the config and hooks it reads its root
#: from) or leaves out.
COPIED = {"docs", "mkdocs_hooks.py", "README.md"}
LEFT_OUT = {".git", ".venv", "site", ".lock-tools", ".pytest_cache", ".hypothesis"}


def build(config, site):
    """`mkdocs build --strict` of config into site, as `make docs` runs it."""
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(config),
                           "-d", str(site)], cwd=config.parent, capture_output=True, text=True,
                          timeout=300)


def test_the_docs_site_builds_strictly(tmp_path):
    site = tmp_path / "site"
    proc = build(ROOT / "mkdocs.yml", site)
    assert proc.returncode == 0, proc.stderr
    # The README is the home page; the results, the pages per Gymnasium id and the API
    # (from the docstrings, and every command's help) are there; a file a page links to
    # outside docs/ is served beside them.
    assert "Quick start" in (site / "index.html").read_text()
    assert (site / "RESULTS" / "index.html").is_file() and (site / "CHANGELOG" / "index.html").is_file()
    assert "EBRL/TwoWheel-v1" in (site / "environments" / "two_wheel" / "index.html").read_text()
    api = (site / "api" / "tasks" / "index.html").read_text()
    assert 'id="tasks.environment.load"' in api and 'id="tasks.gym.NavigationEnv"' in api
    assert "usage: ebrl run" in (site / "api" / "experiments" / "index.html").read_text()
    assert (site / "examples" / "sb3_ppo.py").is_file()


def _copy(tmp_path):
    """The repository's pages and config copied into tmp_path, the rest linked. The
    config's plugins left out (the API from the docstrings and the search index, which
    test_the_docs_site_builds_strictly builds): its links, anchors and nav are checked as
    the real build checks them."""
    root = tmp_path / "repository"
    root.mkdir()
    config = (ROOT / "mkdocs.yml").read_text()
    (root / "mkdocs.yml").write_text(re.sub(r"^plugins:\n(?:(?: .*)?\n)*", "plugins: []\n", config,
                                            flags=re.MULTILINE))
    for entry in ROOT.iterdir():
        if entry.name in LEFT_OUT or entry.name == "mkdocs.yml":
            continue
        if entry.name == "docs":
            shutil.copytree(entry, root / "docs", symlinks=False,
                            copy_function=lambda src, dst: shutil.copy2(src, dst)
                            if src.endswith(".md") else os.symlink(src, dst))
        elif entry.name in COPIED:
            shutil.copy2(entry, root / entry.name)
        else:
            os.symlink(entry, root / entry.name)
    return root


def _append(path, text):
    path.write_text(path.read_text() + "\n" + text + "\n")


def test_a_broken_link_or_anchor_fails_the_build_naming_it(tmp_path):
    root = _copy(tmp_path)
    _append(root / "docs" / "running.md", "A [page that is not there](no-such-page.md).")
    _append(root / "docs" / "gymnasium.md", "A [heading that is not there](rooms.md#no-such-heading).")
    _append(root / "docs" / "rooms.md", "A [file out of docs/](../examples/no_such_example.py).")
    _append(root / "README.md", "A [page of docs/ from the README](docs/no_such_manual.md).")
    (root / "docs" / "orphan.md").write_text("# A page no nav names\n")
    proc = build(root / "mkdocs.yml", tmp_path / "site")
    assert proc.returncode != 0
    said = proc.stderr
    assert len(re.findall(r"^WARNING ", said, flags=re.MULTILINE)) == 5, said
    assert "'running.md' contains a link 'no-such-page.md'" in said, said
    assert "'gymnasium.md' contains a link 'rooms.md#no-such-heading'" in said, said
    assert "does not contain an anchor '#no-such-heading'" in said, said
    assert "'rooms.md' contains a link 'examples/no_such_example.py'" in said, said
    assert "'index.md' contains a link 'no_such_manual.md'" in said, said
    assert "orphan.md" in said, said
