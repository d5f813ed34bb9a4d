"""A light core (issue 60, item 2): `ebrl --help`, a command's --help and a refused
argument load no simulator and no compiler (MuJoCo, dm_control, numba), and the registries
import without them. Each case runs in a fresh interpreter, which runs the command line's
`main` and then prints the heavy packages in its sys.modules."""
import json
import subprocess
import sys

import pytest

#: The slow tier (pyproject.toml's markers): each case starts an interpreter of its own.
pytestmark = pytest.mark.slow

#: The packages a light process never imports.
HEAVY = ("mujoco", "dm_control", "numba", "llvmlite")

#: Runs experiments.cli.main(argv) and prints (its exit status, the heavy packages loaded).
PROBE = """\
import json, sys
from experiments.cli import main
try:
    status = main({argv!r})
except SystemExit as e:
    status = e.code
loaded = sorted({{m.split(".")[0] for m in sys.modules}} & set({heavy!r}))
print(json.dumps([status, loaded]), file=sys.stderr)
"""


def _run(argv):
    """(exit status, heavy packages loaded, stdout, the stderr before the probe's line)."""
    done = subprocess.run([sys.executable, "-c", PROBE.format(argv=argv, heavy=HEAVY)],
                          capture_output=True, text=True, timeout=120)
    *said, probe = done.stderr.rstrip("\n").split("\n")
    status, loaded = json.loads(probe)
    return status, loaded, done.stdout, "\n".join(said)


@pytest.mark.parametrize("argv", [["--help"], ["run", "--help"], ["maze-study", "--help"],
                                  ["robots"]])
def test_help_loads_nothing_heavy(argv):
    """The help, and `ebrl robots`' list (the registries and the shipped mounts parsed,
    the gait's among them: tasks.realisations.gait_parameters)."""
    status, loaded, out, _ = _run(argv)
    assert status == 0 and ("usage: ebrl" in out if argv[-1] == "--help" else "quadruped" in out)
    assert loaded == [], f"ebrl {' '.join(argv)} imported {loaded}"


@pytest.mark.parametrize("argv, said", [
    (["run", "--seeds", "x"], "bad seed range 'x'"),
    (["run", "--set", "policy_threshold=abc"], "bad value for policy_threshold"),
    (["run", "--set", "no_such=1"], "bad --set 'no_such=1'"),
    (["run", "--robot", "no_such"], "unknown robot 'no_such'"),
    (["sweep", "--agent", "no_such"], "unknown 'no_such'"),
])
def test_a_refused_argument_loads_nothing_heavy(argv, said):
    """The argument checks (the registries of robots, readings, learners and settings)
    refuse without the simulator: exit status 2 and the one line."""
    status, loaded, _, err = _run(argv)
    assert status == 2 and said in err, err
    assert loaded == [], f"ebrl {' '.join(argv)} imported {loaded}"


def test_the_registries_import_nothing_heavy():
    modules = ("tasks", "tasks.robots", "tasks.protocols", "tasks.readings", "tasks.config",
               "tasks.realisations", "tasks.mount", "tasks.mount.kinds", "ebrl",
               "ebrl.readings", "ebrl.config", "ebrl.baselines",
               "experiments.running.learners", "experiments.running.settings",
               "experiments.running.execution", "experiments.checks.validate")
    code = (f"import importlib, sys\nfor m in {modules!r}: importlib.import_module(m)\n"
            f"print(sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r})))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=True)
    assert done.stdout.strip() == "[]", done.stdout


def test_the_heavy_names_come_at_first_use():
    """tasks.load, ebrl.Agent and the baselines' MFEC are still where they were: the
    package imports them (and the simulator or numba) when first asked."""
    code = ("import sys, tasks, ebrl, ebrl.baselines\n"
            "assert 'mujoco' not in sys.modules and 'numba' not in sys.modules\n"
            "print(tasks.load.__module__, ebrl.Agent.__module__, ebrl.baselines.MFEC.__module__,"
            " ebrl.baselines.AGENTS['mfec'].agent is ebrl.baselines.MFEC)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=True)
    assert done.stdout.split() == ["tasks.environment", "ebrl.agent", "ebrl.baselines.mfec",
                                   "True"]
