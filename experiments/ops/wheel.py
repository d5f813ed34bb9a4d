"""This checkout as a user installs it: a wheel, in a fresh virtual environment.

`python -m experiments.ops.wheel [--run]` (`make wheel-check`) copies the tracked files
(what a clone holds), builds the wheel from them (pip, the environment's own setuptools),
installs it into a new virtual environment whose other packages are this environment's
(the locks' versions: tests/test_lock.py), and there imports every module the wheel
holds, each from the wheel's copy, runs `ebrl --help` and `ebrl robots`, compiles the
vendored car in the room and finds the paper's behaviours by name. With --run it also
makes a short `ebrl run` there; its kernels compile anew in the new place (numba keys
its cache on each file's path), about 40 s of CPU, so tests/test_wheel.py runs the rest
and the run is this command's. A wheel once lacked `tasks.realisations` and
`ebrl.baselines` and did not import (issue 60); the editable install that `make` uses
hid it. One line on success; a failure raises with the failing step's output.
"""
import argparse
import json
import pathlib
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import venv
import zipfile

from experiments import ROOT

#: What the wheel's environment runs in the checks: its own and nothing of this shell's
#: (no PYTHONPATH, no editable install, no user site).
CLEAN_ENV = {"PATH": "/usr/bin:/bin", "PYTHONNOUSERSITE": "1"}

#: Run in the wheel's environment: every module it holds imported from its copy, then
#: the shipped mounts, the vendored car compiled in the room, the behaviours by name.
_CHECK = """
import importlib, json, sys
site, names = sys.argv[1], json.loads(sys.argv[2])
for name in names:
    module = importlib.import_module(name)
    assert module.__file__.startswith(site), (name, module.__file__)
import tasks, ebrl.behaviour as behaviour
assert sorted(tasks.MOUNTS) == ['ant', 'car', 'gym_ant', 'point', 'point_mass', 'quadruped']
assert tasks.resolve('car').model.is_relative_to(site)
model, _ = tasks.compiled_model(tasks.resolve('car'))
assert model.nu == 2 and model.nmesh > 0
print(behaviour.load('paper_eq8').behaviour, behaviour.load('behaviours/paper_eq9-10.json').behaviour)
"""


def _run(args, **kwargs):
    """A finished process, its output kept; a failure raises with it."""
    proc = subprocess.run([str(a) for a in args], capture_output=True, text=True, **kwargs)
    if proc.returncode != 0:
        what = " ".join(str(a) for a in args[:4]) + (" ..." if len(args) > 4 else "")
        raise RuntimeError(f"{what} failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    return proc


def tracked_copy(dest, root=ROOT):
    """The checkout's files as a clone holds them (tracked, and new ones git does not
    ignore) copied into dest; returns dest."""
    names = _run(["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z"],
                 cwd=root).stdout.split("\0")
    for name in filter(None, names):
        if (root / name).is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(root / name, dest / name)
    return dest


def build(source, dist):
    """The wheel of the project at source, built into dist (pip, no build isolation: the
    environment's setuptools, from the lock); returns its path."""
    _run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation",
          "-w", dist, source])
    (wheel,) = pathlib.Path(dist).glob("*.whl")
    return wheel


def modules(wheel):
    """The dotted names of every module the wheel holds (its `__main__` left out:
    importing it runs the command line)."""
    with zipfile.ZipFile(wheel) as z:
        files = [n for n in z.namelist() if n.endswith(".py") and ".dist-info/" not in n]
    names = [n[:-3].replace("/", ".").removesuffix(".__init__") for n in files]
    return sorted(n for n in names if not n.endswith("__main__"))


def install(wheel, folder):
    """A new virtual environment at folder with the wheel installed, whose other packages
    are this environment's (a .pth file naming its site-packages); returns (its python,
    its site-packages)."""
    venv.create(folder, with_pip=False)
    python = pathlib.Path(folder) / "bin" / "python"
    site = pathlib.Path(_run([python, "-c", "import sysconfig; print(sysconfig.get_paths()"
                                            "['purelib'])"], env=CLEAN_ENV).stdout.strip())
    ours = {sysconfig.get_paths()[k] for k in ("purelib", "platlib")}
    (site / "locked.pth").write_text("".join(f"{p}\n" for p in sorted(ours)))
    _run([sys.executable, "-m", "pip", "--python", python, "install", "-q", "--no-deps",
          wheel])
    return python, site


def check(folder, run=False):
    """Builds, installs and checks the wheel in folder (see the module's docstring);
    returns what was checked, in one line."""
    folder = pathlib.Path(folder)
    wheel = build(tracked_copy(folder / "source"), folder / "dist")
    python, site = install(wheel, folder / "venv")
    names = modules(wheel)
    env = dict(CLEAN_ENV, HOME=str(folder))
    found = _run([python, "-c", _CHECK, site, json.dumps(names)], cwd=folder, env=env).stdout
    if found.split() != ["eq8", "eq9-10"]:
        raise RuntimeError(f"the behaviours by name gave {found.split()}")
    ebrl = python.parent / "ebrl"
    if not _run([ebrl, "--help"], cwd=folder, env=env).stdout.startswith("usage: ebrl"):
        raise RuntimeError("ebrl --help printed no usage")
    if "two_wheel" not in _run([ebrl, "robots"], cwd=folder, env=env).stdout:
        raise RuntimeError("ebrl robots listed no two_wheel")
    said = (f"{wheel.name} in a fresh virtual environment: {len(names)} modules imported, "
            "ebrl --help and ebrl robots run")
    if run:
        results = folder / "results"
        _run([ebrl, "run", "--robot", "two_wheel", "--condition", "random", "--seeds", "0",
              "--steps", "20", "--workers", "1", "--no-progress", "--out", results],
             cwd=folder, env=env)
        if not (results / "two_wheel" / "random" / "seed_000" / "run.json").is_file():
            raise RuntimeError("ebrl run wrote no run.json")
        said += ", a short ebrl run made"
    return said


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m experiments.ops.wheel",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--run", action="store_true",
                        help="also a short ebrl run in the wheel's environment (~40 s)")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="ebrl-wheel-") as folder:
        print(check(folder, run=args.run))


if __name__ == "__main__":
    main()
