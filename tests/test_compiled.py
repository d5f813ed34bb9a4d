"""compiled.cache: numba's on-disk cache follows every file a cached kernel compiles in,
in real processes on real files (a kernel in one module calling a kernel in another)."""
import os
import pathlib
import re
import subprocess
import sys
import textwrap

import pytest

from experiments.running.learners import AGENTS

#: The slow tier (pyproject.toml's markers): fresh processes compiling and loading numba's cache.
pytestmark = pytest.mark.slow

CALLEE = "from numba import njit\n\nSCALE = {scale}\n\n\n@njit(cache=True)\ndef f(x):\n    return SCALE * x\n"
CALLER = textwrap.dedent("""\
    {install}
    from numba import njit

    import callee


    @njit(cache=True)
    def g(x):
        return callee.f(x) + 1.0
    """)
MAIN = textwrap.dedent("""\
    import caller
    print(caller.g(2.0), caller.g.stats.cache_hits.get(caller.g.signatures[0], 0))
    """)


def _run(folder, env=None):
    out = subprocess.run([sys.executable, "main.py"], cwd=folder, capture_output=True,
                         text=True, check=True, env=env).stdout.split()
    return float(out[0]), int(out[1])


def _project(folder, install):
    (folder / "caller.py").write_text(CALLER.format(
        install="from compiled import cache  # noqa: F401" if install else ""))
    (folder / "main.py").write_text(MAIN)


def test_a_change_in_a_called_kernels_file_recompiles_the_caller(tmp_path):
    _project(tmp_path, install=True)
    (tmp_path / "callee.py").write_text(CALLEE.format(scale=3.0))
    assert _run(tmp_path) == (7.0, 0)  # compiled, then cached on disk
    assert _run(tmp_path) == (7.0, 1)  # loaded from the cache
    (tmp_path / "callee.py").write_text(CALLEE.format(scale=10.0))  # only the callee changes
    assert _run(tmp_path) == (21.0, 0)  # the caller is recompiled


def test_numba_alone_keeps_the_stale_caller(tmp_path):
    """What compiled.cache is for: without it, numba loads the caller compiled with the
    old callee (if numba learns to track this, compiled.cache can go)."""
    _project(tmp_path, install=False)
    (tmp_path / "callee.py").write_text(CALLEE.format(scale=3.0))
    assert _run(tmp_path) == (7.0, 0)
    (tmp_path / "callee.py").write_text(CALLEE.format(scale=10.0))
    assert _run(tmp_path) == (7.0, 1)


def test_the_stamp_names_the_files_a_module_reaches():
    from compiled import cache
    from ebrl import agent
    reached = cache.reached(vars(agent), agent.__file__)
    names = {p.rsplit("/", 2)[-2] + "/" + p.rsplit("/", 1)[-1] for p in reached}
    assert {"ebrl/kernels.py", "ebrl/intrinsic.py", "ebrl/config.py"} <= names
    assert not any("site-packages" in p or p.endswith("agent.py") for p in reached)
    import experiments.running.fused as fused
    names = {p.rsplit("/", 2)[-2] + "/" + p.rsplit("/", 1)[-1]
             for p in cache.reached(vars(fused), fused.__file__)}
    assert {"ebrl/agent.py", "ebrl/kernels.py", "kernels/env_step.py", "kernels/gait.py",
            "kernels/two_wheel.py", "kernels/thrusters.py"} <= names


PACKAGE_MAIN = textwrap.dedent("""\
    import sys
    if sys.argv[1:]:
        import pkg.other  # binds `other` in pkg before caller's kernel is decorated
    import caller
    print(caller.g(2.0), caller.g.stats.cache_hits.get(caller.g.signatures[0], 0))
    """)


def test_a_kernels_stamp_is_the_same_whatever_else_the_process_imported(tmp_path):
    """A package's globals gain each submodule anyone imports: were they followed, a
    process that imported one more (another command, a test) saved another stamp, and the
    next process compiled the kernel again (measured: the loop, 10 s, in half the tests'
    processes). Here a kernel reaching a package through its module's globals is loaded
    from the cache by a process that imported another submodule of the package, and
    still compiled again when a file it reaches changes."""
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "__init__.py").write_text("from pkg.callee import f\n")
    (tmp_path / "pkg" / "callee.py").write_text(CALLEE.format(scale=3.0))
    (tmp_path / "pkg" / "other.py").write_text("X = 1\n")
    (tmp_path / "caller.py").write_text(CALLER.replace("import callee", "import pkg")
                                        .replace("callee.f", "pkg.f")
                                        .format(install="from compiled import cache  # noqa: F401"))
    (tmp_path / "main.py").write_text(PACKAGE_MAIN)

    def run(*other):
        out = subprocess.run([sys.executable, "main.py", *other], cwd=tmp_path,
                             capture_output=True, text=True, check=True).stdout.split()
        return float(out[0]), int(out[1])

    assert run() == (7.0, 0)
    assert run("other") == (7.0, 1)  # another submodule imported: the same stamp
    assert run() == (7.0, 1)
    (tmp_path / "pkg" / "callee.py").write_text(CALLEE.format(scale=10.0))
    assert run("other") == (21.0, 0)


def test_no_kernel_reaches_a_submodule_through_its_package():
    """What the stamp leaves out (a package's submodules that its __init__ does not bind
    itself) no cached kernel reads: no jitted function names `package.submodule`."""
    import ast
    import importlib
    from helpers import ROOT
    from compiled import cache
    found = []
    for name, rel in _cached_kernel_modules().items():
        module = importlib.import_module(name)
        tree = ast.parse((ROOT / rel).read_text())
        for node in ast.walk(tree):
            if not (isinstance(node, ast.FunctionDef) and any(
                    "njit" in ast.unparse(d) for d in node.decorator_list)):
                continue
            for attr in ast.walk(node):
                if isinstance(attr, ast.Attribute) and isinstance(attr.value, ast.Name):
                    package = vars(module).get(attr.value.id)
                    if (hasattr(package, "__path__") and cache._tracked(package.__file__)
                            and attr.attr not in cache._own_names(package)):
                        found.append(f"{rel}: {node.name}: {attr.value.id}.{attr.attr}")
    assert found == []


def _cached_kernel_modules():
    """{module name: path} of the checkout's modules that define a cached kernel."""
    from helpers import ROOT
    found = {}
    for package in ("compiled", "ebrl", "tasks", "experiments", "models"):
        for path in sorted((ROOT / package).rglob("*.py")):
            if re.search(r"^@njit\(cache=True\)", path.read_text(), re.M):
                rel = path.relative_to(ROOT)
                found[".".join(rel.with_suffix("").parts)] = rel.as_posix()
    return found


#: Modules with cached kernels that do not import compiled.cache themselves yet (covered
#: through their package's or their imports' import of it): empty once each has the line.
NOT_YET = set()


def test_every_module_with_cached_kernels_imports_the_cache_itself():
    """The rule (compiled.cache's docstring): the hook is then in place before the module's
    first decoration, whatever was imported before it."""
    import ast
    from helpers import ROOT
    modules = _cached_kernel_modules()
    assert {"ebrl.kernels", "ebrl.agent", "tasks.kernels.env_step"} <= set(modules)
    missing = set()
    for path in modules.values():
        tree = ast.parse((ROOT / path).read_text())
        imports = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
        if not any((isinstance(n, ast.ImportFrom) and n.module == "compiled"
                    and any(a.name == "cache" for a in n.names))
                   or (isinstance(n, ast.Import) and any(a.name == "compiled.cache" for a in n.names))
                   for n in imports):
            missing.add(path)
    assert missing == NOT_YET


def test_each_module_imported_first_has_its_cached_kernels_keyed_on_their_dependencies():
    """In a fresh process per module, imported before any other of the checkout's: every
    cached kernel it defines has compiled.cache's locator. (The processes are forked from
    one that imported only the libraries, numba, MuJoCo and dm_control: each module is
    still the first of the checkout's in its process.)"""
    from helpers import ROOT
    code = textwrap.dedent("""\
        import importlib, os, sys
        import dm_control.mjcf, dm_control.rl.control, mujoco, numba, numpy  # noqa: F401
        assert not any(m.split(".")[0] in ("compiled", "ebrl", "tasks", "experiments", "models")
                       for m in sys.modules)
        for name in sys.argv[1:]:
            read, write = os.pipe()
            if os.fork() == 0:
                try:
                    os.close(read)
                    module = importlib.import_module(name)
                    from compiled import cache
                    cached = [v for v in vars(module).values() if hasattr(v, "py_func")
                              and v.__module__ == module.__name__
                              and v.stats.cache_path is not None]
                    os.write(write, f"{name} {len(cached)} "
                                    f"{sum(map(cache.covers, cached))}".encode())
                    os._exit(0)
                finally:
                    os._exit(1)
            os.close(write)
            with os.fdopen(read) as answer:
                print(answer.read(), flush=True)
            assert os.wait()[1] == 0, name
        """)
    names = list(_cached_kernel_modules())
    out = subprocess.run([sys.executable, "-c", code, *names], cwd=ROOT, capture_output=True,
                         text=True, check=True).stdout.splitlines()
    assert [line.split()[0] for line in out] == names
    for name, n, covered in (line.split() for line in out):
        assert int(n) > 0 and n == covered, (name, n, covered)


# -- a damaged cache entry mends itself ----------------------------------------------
def test_a_folder_that_cannot_be_written_caches_elsewhere_still_keyed(tmp_path):
    """`__pycache__` unwritable (here a file in its place: unwritable for root too): the
    kernels cache in the user's cache folder, keyed on their dependencies there as well;
    no folder writable at all: they compile in every process, one warning line."""
    _project(tmp_path, install=True)
    (tmp_path / "callee.py").write_text(CALLEE.format(scale=3.0))
    (tmp_path / "__pycache__").write_text("")
    user = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "user"))
    assert _run(tmp_path, user) == (7.0, 0)
    assert _run(tmp_path, user) == (7.0, 1)
    assert list((tmp_path / "user" / "numba").glob("*/caller.g-*.nbc"))
    (tmp_path / "callee.py").write_text(CALLEE.format(scale=10.0))
    assert _run(tmp_path, user) == (21.0, 0)
    nowhere = dict(os.environ, XDG_CACHE_HOME=str(tmp_path / "__pycache__"))
    proc = subprocess.run([sys.executable, "main.py"], cwd=tmp_path, capture_output=True,
                          text=True, check=True, env=nowhere)
    assert proc.stdout.split()[:2] == ["21.0", "0"]
    assert proc.stderr.count("ebrl: warning: no numba cache folder can be written") == 1
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr


#: One run of the paper's two-wheel robot in a fresh process (the agent's, the task's
#: and the loop's cached kernels): its result's digest and whether the loop came from the
#: cache. Given "NAME:FILE:KIND" arguments, first the checkout's own cache of the kernels'
#: modules is copied into NUMBA_CACHE_DIR's folders for them (numba's layout) and kernel
#: NAME's FILE ("data" or "index") damaged as an interrupted copy or a full disk leaves
#: it: cut to half its length ("truncated") or gone while its index names it ("missing").
PROBE = textwrap.dedent("""\
    import hashlib, pathlib, shutil, sys
    from ebrl import steps
    from experiments.running import fused, execution, runner
    from tasks.kernels import body
    folders = {}
    for kernel in (steps.learn_step, body.base_pose, fused.run):
        folder = folders[kernel.py_func.__module__.rpartition(".")[2]] = pathlib.Path(
            kernel.stats.cache_path)
        source = pathlib.Path(kernel.py_func.__code__.co_filename).parent / "__pycache__"
        for path in source.glob("*.nb[ic]") if sys.argv[1:] else ():
            shutil.copy2(path, folder / path.name)
    for what in sys.argv[1:]:
        name, part, kind = what.split(":")
        # every data file of the kernel (one per signature the checkout's tests compiled,
        # in the order they did), so that the one this run loads is damaged
        for path in sorted(folders[name.split(".")[0]].glob(
                f"{name}-*.py*{'.nbc' if part == 'data' else '.nbi'}")):
            if kind == "missing":
                path.unlink()
            else:
                path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
            print(name, path)
    spec = runner.plan(["two_wheel"], ["avoidance"], [0], 600)[0]
    result = execution.execute(spec)
    digest = hashlib.sha256()
    for key in ("trial_ends", "trace", "starts"):
        digest.update(result[key].tobytes())
    print(digest.hexdigest(), sum(fused.run.stats.cache_hits.values()))
    """)


def _probe(env, *damage):
    """({kernel: its damaged files}, the digest, the loop's cache hits), and stderr."""
    from helpers import ROOT
    proc = subprocess.run([sys.executable, "-c", PROBE, *damage], cwd=ROOT, capture_output=True,
                          text=True, check=True, env=env)
    *lines, last = proc.stdout.splitlines()
    damaged = {}
    for line in lines:
        name, path = line.split(" ", 1)
        damaged.setdefault(name, []).append(path)
    digest, hits = last.split()
    return (damaged, digest, int(hits)), proc.stderr


def test_the_agents_the_tasks_and_the_loops_damaged_entries_mend_with_the_same_bits(tmp_path):
    """In real processes on a copy of the checkout's cache (NUMBA_CACHE_DIR): the loop
    (experiments/running/fused.py) with its data file cut to half (issue 40's case: every
    run failed, UnpicklingError), the agent's learn_step (ebrl/steps.py) with its data
    file missing, the task's base_pose (tasks/kernels/body.py) with its index cut to half.
    The loop compiles again, reading the other two as it does: a warning line for each,
    the run's bits unchanged, and the next process loads all from the rebuilt cache,
    silently."""
    plain = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    (_, expected, _), _ = _probe(plain)  # the checkout's own cache (compiled if cold)
    copy = dict(plain, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    (damaged, digest, hits), err = _probe(copy, "fused.run:data:truncated",
                                          "steps.learn_step:data:missing",
                                          "body.base_pose:index:truncated")
    assert digest == expected and hits == 0
    truncated = "(UnpicklingError: pickle data was truncated)"
    warned = err.strip().splitlines()
    assert len(warned) == 3, err  # one line per damaged kernel, naming the file it read
    for name, why in (("fused.run", truncated), ("body.base_pose", truncated),
                      ("steps.learn_step", None)):
        lines = [line for line in warned if any(f" {path} could" in line for path in damaged[name])]
        assert len(lines) == 1, (name, err)
        path = lines[0].split("numba cache file ", 1)[1].split(" could not be read", 1)[0]
        if why is None:
            why = f"(missing, named by {pathlib.Path(path).name.rsplit('.', 2)[0]}.nbi)"
        assert lines[0] == (f"ebrl: warning: numba cache file {path} could not be read {why}; "
                            "discarded, compiling the kernel again"), err
    (_, digest, hits), err = _probe(copy)
    assert digest == expected and hits == 1 and err == ""


def test_the_warm_up_reaches_every_realisation_and_learner():
    """make test's warm-up (experiments.ops.warm) runs the kernels of every realisation
    a shipped robot or mount uses, both loops and every learner, so that no test process
    compiles what another is compiling; one realisation's runs in one process. joint_motors
    is no shipped file's: its tests mount their own."""
    from experiments.ops import warm
    from helpers import ROOT
    from tasks.realisations import REALISATIONS
    from tasks.robots import resolve
    groups = warm.specs()
    assert all(len({resolve(s.robot).realisation for s, _ in group}) == 1 for group in groups)
    pairs = [pair for group in groups for pair in group]
    assert set(REALISATIONS) - {resolve(s.robot).realisation for s, _ in pairs} == {"joint_motors"}
    boxhead = ROOT / "tests" / "mounts" / "boxhead.toml"  # the Makefile's warm-up gives it
    assert [resolve(s.robot).realisation for s, _ in warm.specs([boxhead])[-1]] == [
        "joint_motors", "joint_motors"]
    assert str(boxhead.relative_to(ROOT)) in (ROOT / "Makefile").read_text()
    assert {s.agent for s, _ in pairs} == set(AGENTS)
    assert {fused for _, fused in pairs} == {True, False}
    # The agent and the loop compiled by one process (the first group's run) before any
    # other realisation's run; that realisation's environment stepped before it, no agent.
    order = list(warm.jobs(groups))
    assert order[0] == (("run", groups[0]), ())
    first = ("run", groups[0][0][0].robot)
    for group in groups[1:]:
        robot = group[0][0].robot
        env, run = order.index((("env", robot), ())), order.index((("run", group), (first, ("env", robot))))
        assert env < run
