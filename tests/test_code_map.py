"""docs/code.md names every module of the installed packages, one line each: a module
added, moved or removed without its line there fails here, and so does a line for a
module that no longer exists (the review that found sixteen modules the page never named
is why this test exists)."""
import re

from helpers import ROOT

PACKAGES = ("models", "tasks", "experiments", "ebrl", "compiled")
#: A module's line: a list item that opens with its path, "- `tasks/robots.py`: ...".
LINE = re.compile(r"^- `((?:%s)/[\w/]*\.py)`: \S" % "|".join(PACKAGES), re.MULTILINE)
#: Any path of a module of these packages written anywhere on the page.
PATH = re.compile(r"(?<![\w./-])((?:%s)/[\w/]*\.py)\b" % "|".join(PACKAGES))


def modules():
    """Every .py file of the packages, as a path from the repository's root."""
    return {p.relative_to(ROOT).as_posix() for package in PACKAGES
            for p in (ROOT / package).rglob("*.py") if "tests" not in p.parts}


def test_code_md_names_every_module_once_and_no_other():
    text = (ROOT / "docs" / "code.md").read_text()
    lines = LINE.findall(text)
    have = modules()
    missing = sorted(have - set(lines))
    twice = sorted({m for m in lines if lines.count(m) > 1})
    gone = sorted(set(PATH.findall(text)) - have)
    assert not missing, "docs/code.md has no line for: " + ", ".join(missing)
    assert not twice, "docs/code.md has more than one line for: " + ", ".join(twice)
    assert not gone, "docs/code.md names modules that do not exist: " + ", ".join(gone)
