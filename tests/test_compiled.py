"""ebrl.compiled: numba's on-disk cache follows every file a cached kernel compiles in,
in real processes on real files (a kernel in one module calling a kernel in another)."""
import re
import subprocess
import sys
import textwrap

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


def _run(folder):
    out = subprocess.run([sys.executable, "main.py"], cwd=folder, capture_output=True,
                         text=True, check=True).stdout.split()
    return float(out[0]), int(out[1])


def _project(folder, install):
    (folder / "caller.py").write_text(CALLER.format(
        install="import ebrl.compiled  # noqa: F401" if install else ""))
    (folder / "main.py").write_text(MAIN)


def test_a_change_in_a_called_kernels_file_recompiles_the_caller(tmp_path):
    _project(tmp_path, install=True)
    (tmp_path / "callee.py").write_text(CALLEE.format(scale=3.0))
    assert _run(tmp_path) == (7.0, 0)  # compiled, then cached on disk
    assert _run(tmp_path) == (7.0, 1)  # loaded from the cache
    (tmp_path / "callee.py").write_text(CALLEE.format(scale=10.0))  # only the callee changes
    assert _run(tmp_path) == (21.0, 0)  # the caller is recompiled


def test_numba_alone_keeps_the_stale_caller(tmp_path):
    """What ebrl.compiled is for: without it, numba loads the caller compiled with the
    old callee (if numba learns to track this, ebrl.compiled can go)."""
    _project(tmp_path, install=False)
    (tmp_path / "callee.py").write_text(CALLEE.format(scale=3.0))
    assert _run(tmp_path) == (7.0, 0)
    (tmp_path / "callee.py").write_text(CALLEE.format(scale=10.0))
    assert _run(tmp_path) == (7.0, 1)


def test_the_stamp_names_the_files_a_module_reaches():
    from ebrl import agent, compiled
    reached = compiled.reached(vars(agent), agent.__file__)
    names = {p.rsplit("/", 2)[-2] + "/" + p.rsplit("/", 1)[-1] for p in reached}
    assert {"ebrl/kernels.py", "ebrl/intrinsic.py", "ebrl/config.py"} <= names
    assert not any("site-packages" in p or p.endswith("agent.py") for p in reached)
    import experiments.running.fused as fused
    names = {p.rsplit("/", 2)[-2] + "/" + p.rsplit("/", 1)[-1]
             for p in compiled.reached(vars(fused), fused.__file__)}
    assert {"ebrl/agent.py", "ebrl/kernels.py", "kernels/steps.py", "kernels/gait.py",
            "kernels/two_wheel.py", "kernels/floating.py"} <= names


def _cached_kernel_modules():
    """{module name: path} of the checkout's modules that define a cached kernel."""
    from helpers import ROOT
    found = {}
    for package in ("ebrl", "tasks", "experiments", "models"):
        for path in sorted((ROOT / package).rglob("*.py")):
            if re.search(r"^@njit\(cache=True\)", path.read_text(), re.M) and path.name != "compiled.py":
                rel = path.relative_to(ROOT)
                found[".".join(rel.with_suffix("").parts)] = rel.as_posix()
    return found


#: Modules with cached kernels that do not import ebrl.compiled themselves yet (covered
#: through their package's or their imports' import of it): empty once each has the line.
NOT_YET = set()


def test_every_module_with_cached_kernels_imports_ebrl_compiled_itself():
    """The rule (ebrl.compiled's docstring): the hook is then in place before the module's
    first decoration, whatever was imported before it."""
    import ast
    from helpers import ROOT
    modules = _cached_kernel_modules()
    assert {"ebrl.kernels", "ebrl.agent", "tasks.kernels.steps"} <= set(modules)
    missing = set()
    for path in modules.values():
        tree = ast.parse((ROOT / path).read_text())
        imports = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
        if not any((isinstance(n, ast.ImportFrom) and n.module == "ebrl"
                    and any(a.name == "compiled" for a in n.names))
                   or (isinstance(n, ast.Import) and any(a.name == "ebrl.compiled" for a in n.names))
                   for n in imports):
            missing.add(path)
    assert missing == NOT_YET


def test_each_module_imported_first_has_its_cached_kernels_keyed_on_their_dependencies():
    """In a fresh process per module, imported before anything else: every cached kernel
    it defines has ebrl.compiled's locator."""
    from helpers import ROOT
    code = textwrap.dedent("""\
        import importlib, sys
        module = importlib.import_module(sys.argv[1])
        from ebrl import compiled
        cached = [v for v in vars(module).values() if hasattr(v, "py_func")
                  and v.__module__ == module.__name__ and v.stats.cache_path is not None]
        print(len(cached), sum(map(compiled.covers, cached)))
        """)
    for name in _cached_kernel_modules():
        out = subprocess.run([sys.executable, "-c", code, name], cwd=ROOT, capture_output=True,
                             text=True, check=True).stdout.split()
        assert int(out[0]) > 0 and out[0] == out[1], (name, out)
