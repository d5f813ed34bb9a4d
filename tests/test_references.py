"""Every dotted reference to the project's own modules and names (ebrl.*, tasks.*,
experiments.*, models.*) in its code, comments, docstrings and docs resolves: a reader who
follows one finds what it names. A module or a name moved, renamed or removed leaves no
reference behind (the review that found fifteen is why this test exists)."""
import importlib
import re

from helpers import ROOT

PACKAGES = ("ebrl", "tasks", "experiments", "models")
REFERENCE = re.compile(r"(?<![\w./-])((?:%s)(?:\.[A-Za-z_][A-Za-z0-9_]*)+)" % "|".join(PACKAGES))
#: File name endings written after a dotted module path ("tasks/robots.py" is a path).
SUFFIXES = {"py", "toml", "md", "xml", "json", "txt", "csv", "npz", "png"}


def resolves(dotted):
    """Whether the longest importable prefix of `dotted` has the rest as attributes (a
    dataclass field read from an instance counts: its class's __dataclass_fields__)."""
    parts = dotted.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        for name in parts[i:]:
            fields = getattr(obj, "__dataclass_fields__", {})
            if not hasattr(obj, name) and name not in fields:
                return name in SUFFIXES
            obj = getattr(obj, name, None)
        return True
    return False


def test_every_dotted_reference_in_code_and_docs_resolves():
    files = [f for p in PACKAGES for f in sorted((ROOT / p).rglob("*.py"))]
    files += sorted((ROOT / "docs").rglob("*.md")) + [ROOT / "README.md", ROOT / "Makefile"]
    files += sorted((ROOT / "tests").glob("*.py")) + sorted((ROOT / "models" / "mounts").glob("*.toml"))
    dead = {}
    for path in files:
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            for ref in REFERENCE.findall(line.replace("`", " ")):
                ref = ref.rstrip(".")
                if ref not in dead and not resolves(ref):
                    dead[ref] = f"{path.relative_to(ROOT)}:{number}"
    assert not dead, "\n".join(f"{where}: {ref}" for ref, where in dead.items())
