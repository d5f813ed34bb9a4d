"""numba's on-disk cache, keyed on every source file a cached kernel compiles in.

numba keys a cached function (``@njit(cache=True)``) on its own file's content alone:
"changes in symbols defined in another file are not recognized" (numba's notes on
caching). A kernel compiles in the kernels it calls and the module constants it reads,
from other files too: ebrl.agent.act_step compiles in ebrl.kernels, and `ebrl run`'s
loop (experiments.running.fused.run) compiles in the agent's and the tasks' kernels. So
an edit of eq 6 in ebrl/kernels.py would leave the cached loop running the old eq 6,
silently, on every later run.

Importing this module (ebrl and tasks do, before their kernels) puts in front of
numba's cache locators one that adds to a file's own stamp the content of every file its
module reaches through its globals (modules, compiled functions, other functions and
classes), transitively, among the modules that live outside the Python installation
(this checkout's, installed in place). An edit of any of them recompiles the kernels
that may depend on it, once, on the next run; the cache stays where numba puts it
(`__pycache__` beside the file, or NUMBA_CACHE_DIR). It changes no compiled code.
"""
import functools
import hashlib
import os
import sys
import sysconfig
import types

from numba.core import caching

#: Where the Python installation's own modules live; a module there is numba's to track.
_INSTALLED = tuple(sorted({os.path.realpath(p) + os.sep for key in
                           ("stdlib", "platstdlib", "purelib", "platlib")
                           if (p := sysconfig.get_paths().get(key))}))
#: Folders of installed packages wherever they are (a user's, a system's).
_PACKAGE_FOLDERS = {"site-packages", "dist-packages"}


def _tracked(path):
    """True for a source file outside the Python installation and any installed
    package's folder."""
    if path is None or not path.endswith(".py"):
        return False
    real = os.path.realpath(path)
    return not real.startswith(_INSTALLED) and _PACKAGE_FOLDERS.isdisjoint(real.split(os.sep))


def _module_file(value):
    """The source file of the module that defines `value` (a module, a compiled
    function, a function or a class), or None."""
    try:
        if isinstance(value, types.ModuleType):
            return getattr(value, "__file__", None)
        value = getattr(value, "py_func", None) or value  # a numba dispatcher's function
        name = getattr(value, "__module__", None)
    except Exception:  # an object whose attribute lookup misbehaves: not a dependency
        return None
    module = sys.modules.get(name) if isinstance(name, str) else None
    return getattr(module, "__file__", None)


@functools.lru_cache(maxsize=None)
def _content(path, mtime, size):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def reached(namespace, own_file):
    """The tracked source files, other than own_file, that a module with globals
    `namespace` reaches through its globals, transitively (sorted)."""
    modules = {getattr(m, "__file__", None): m for m in list(sys.modules.values())}
    own = os.path.realpath(own_file)
    seen, todo = {own}, [namespace]
    while todo:
        for value in list(todo.pop().values()):
            path = _module_file(value)
            if not _tracked(path) or (real := os.path.realpath(path)) in seen:
                continue
            seen.add(real)
            if path in modules:
                todo.append(vars(modules[path]))
    return sorted(seen - {own})


def dependency_stamp(namespace, own_file):
    """(file, content hash) for every file `reached` finds: what a kernel's cache entry
    is valid for, beside its own file's content."""
    stamp = []
    for path in reached(namespace, own_file):
        st = os.stat(path)
        stamp.append((path, _content(path, st.st_mtime, st.st_size)))
    return tuple(stamp)


class _Dependent:
    """A locator mixin: numba's stamp of the function's file, then dependency_stamp."""

    def get_source_stamp(self):
        return super().get_source_stamp(), dependency_stamp(self._namespace, self._py_file)

    @classmethod
    def from_function(cls, py_func, py_file):
        if not _tracked(py_file):
            return None
        self = super().from_function(py_func, py_file)
        if self is not None:
            self._namespace = py_func.__globals__
        return self


class UserDirLocator(_Dependent, caching.UserProvidedCacheLocator):
    """NUMBA_CACHE_DIR's locator, with the dependencies in its stamp."""


class InTreeLocator(_Dependent, caching.InTreeCacheLocator):
    """The __pycache__ locator, with the dependencies in its stamp."""


def install():
    """Puts the two locators first among numba's (once per process)."""
    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl  # numba < 0.62: private
    classes = impl._locator_classes
    for cls in (InTreeLocator, UserDirLocator):  # UserDirLocator ends up first
        if cls not in classes:
            classes.insert(0, cls)


install()
