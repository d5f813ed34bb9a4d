"""The checkout as a user installs it (issue 60, item 1): experiments.ops.wheel builds the
wheel from a copy of the tracked files, installs it into a fresh virtual environment with
the locked packages, imports every module it holds from there, runs `ebrl --help` and
`ebrl robots`, compiles the vendored car and finds the behaviours by name. A short `ebrl
run` from the wheel compiles every kernel anew there (about 40 s): `make wheel-check`."""
import zipfile

import pytest

from experiments.ops import wheel


@pytest.mark.slow
def test_a_wheel_of_the_tracked_files_installs_imports_and_runs_its_command(tmp_path):
    def left(name):  # what a build in the checkout itself would write or touch
        path = wheel.ROOT / name
        return path.stat().st_mtime_ns if path.exists() else None
    before = {name: left(name) for name in ("build", "dist", "ebrl_replication.egg-info")}
    said = wheel.check(tmp_path)
    (built,) = (tmp_path / "dist").glob("*.whl")
    names = wheel.modules(built)
    assert said == (f"{built.name} in a fresh virtual environment: {len(names)} modules "
                    "imported, ebrl --help and ebrl robots run")
    # every package of the source is in the wheel (it once lacked tasks.realisations and
    # ebrl.baselines), and the data a run reads beside them
    source = tmp_path / "source"
    packages = {".".join(p.parent.relative_to(source).parts) for p in source.glob("**/__init__.py")
                if p.parent.relative_to(source).parts[0] in
                ("compiled", "ebrl", "tasks", "models", "behaviours", "experiments")}
    assert {"tasks.realisations", "ebrl.baselines", "compiled"} <= packages <= set(names)
    with zipfile.ZipFile(built) as z:
        held = set(z.namelist())
    assert {"models/mounts/car.toml", "behaviours/paper_eq8.json", "models/two_wheel.xml"} <= held
    # the checkout itself is left as it was: the build ran in the copy
    assert {name: left(name) for name in before} == before


def test_the_modules_of_a_wheel_are_its_python_files_but_main(tmp_path):
    path = tmp_path / "x-0-py3-none-any.whl"
    with zipfile.ZipFile(path, "w") as z:
        for name in ("a/__init__.py", "a/b.py", "a/__main__.py", "a/c/__init__.py", "a/d.json",
                     "x-0.dist-info/RECORD"):
            z.writestr(name, "")
    assert wheel.modules(path) == ["a", "a.b", "a.c"]
