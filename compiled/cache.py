"""numba's on-disk cache, keyed on every source file a cached kernel compiles in.

numba keys a cached function (``@njit(cache=True)``) on its own file's content alone:
"changes in symbols defined in another file are not recognized" (numba's notes on
caching). A kernel compiles in the kernels it calls and the module constants it reads,
from other files too: ebrl.agent.act_step compiles in ebrl.kernels, and `ebrl run`'s
loop (experiments.running.fused.run) compiles in the agent's and the tasks' kernels. So
an edit of eq 6 in ebrl/kernels.py would leave the cached loop running the old eq 6,
silently, on every later run.

Importing this module puts in front of numba's cache locators one that adds to a file's
own stamp the content of every file its module reaches through its globals (modules,
compiled functions, other functions and classes), transitively, among the modules that
live outside the Python installation (this checkout's, installed in place). An edit of any
of them recompiles the kernels that may depend on it, once, on the next run; the cache
stays where numba puts it (`__pycache__` beside the file, NUMBA_CACHE_DIR, or the user's
cache folder where the file's own cannot be written; where none can, a temporary one per
process: TemporaryLocator). A cache entry that cannot be read
(truncated, an index naming a missing file) is discarded with one warning line naming
the file and the kernel compiled again (MendingCacheFile). It changes no compiled code.

The rule: every module that defines a cached kernel imports this module in its own
import block, ``from compiled import cache  # noqa: F401  numba's cache keyed on ...``,
so the locators are in place before its first decoration whatever was imported before
it, and the imports sort as any others. (`cache` is then in the module's globals: an
edit of this file recompiles the kernels, as it should.)
tests/test_compiled.py checks the rule over the checkout and, in a fresh process per
module, that each module's cached kernels are keyed here (covers()).

numba has no public form of this that holds here (below), so its private names are read
in this module and nowhere else (checked on numba 0.68.1; the CacheImpl/_CacheImpl
fallback follows numba's rename in 0.62, read in numba's source, not run here):
- ``numba.core.caching.CacheImpl._locator_classes`` (``_CacheImpl`` before 0.62): the
  list of locator classes numba tries, first to last, when a kernel is decorated; the
  two below are put first. (numba.config.CACHE_LOCATOR_CLASSES, the environment's
  NUMBA_CACHE_LOCATOR_CLASSES, names the same list publicly in numba 0.68.1, a recent
  addition not checked on the older numba pyproject.toml allows (0.60 on); numba resets
  the config value from the environment whenever a NUMBA_* variable changes, which would
  turn the keying off silently; and as an environment variable it reaches every child
  process, one without this checkout on its path included, whose first cached kernel
  then fails. Not used.)
- ``numba.core.caching.UserProvidedCacheLocator`` and ``InTreeCacheLocator`` (numba's
  NUMBA_CACHE_DIR and ``__pycache__`` locators), subclassed with numba's locator
  protocol, ``from_function(py_func, py_file)`` and ``get_source_stamp()``.
- in covers() only: ``Dispatcher._cache`` and its ``_impl``, numba's cache of a kernel
  and the CacheImpl that holds the locator it chose.
- ``numba.core.caching.UserWideCacheLocator`` (numba's user-wide cache folder, where a
  kernel caches when its own folder cannot be written: a read-only checkout), subclassed
  the same way, so a cache there is keyed on the dependencies too.
- ``numba.core.caching.IndexDataCacheFile`` (the index and data files of a kernel's
  cache entry, and its ``save``): replaced in numba's caching module by MendingCacheFile, which reads them
  through the class's own ``load``, ``_load_index``, ``_load_data`` and ``_data_path``.
  numba raises when an entry it reads is damaged (a truncated data file or index: an
  interrupted copy, a full disk, a shared filesystem), and every later run fails on it
  the same way; here the entry is discarded, the kernel compiled again (the same
  compiled code: the cache holds what a compile makes) and saved anew, with one line on
  stderr naming the file (see MendingCacheFile).
The public alternative (docs/speed.md, its timings): a NUMBA_CACHE_DIR named by the
content of all of ebrl/, tasks/ and experiments/ recompiles every kernel after any edit
(where this recompiles what depends on the edited file only, and nothing for a file no
kernel reaches), must be set before the first decoration as well, and displaces a user's
own NUMBA_CACHE_DIR.
"""
import ast
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


@functools.lru_cache(maxsize=None)
def _realpath(path):
    """os.path.realpath, once per path and process: each kernel's stamp walks the same
    few hundred module files, and realpath's system calls on each of them would be a large
    part of importing the kernels from the cache (docs/speed.md)."""
    return os.path.realpath(path)


def _tracked(path):
    """True for a source file outside the Python installation and any installed
    package's folder."""
    if path is None or not path.endswith(".py"):
        return False
    real = _realpath(path)
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


def _bound(statements, names):
    """Adds to `names` what `statements` bind at their level (imports, definitions,
    assignments), into compound statements but not into functions and classes; False
    where a star import binds what the text does not name."""
    for node in statements:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            for alias in node.names:
                if alias.name == "*":
                    return False
                names.add(alias.asname or alias.name.split(".")[0])
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names.update(n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name))
        else:
            for field in ("body", "orelse", "finalbody", "handlers"):
                if not _bound(getattr(node, field, ()) or (), names):
                    return False
    return True


@functools.lru_cache(maxsize=None)
def _package_names(path, mtime, size):
    """The names a package's __init__.py binds itself, or None (a star import)."""
    with open(path, "rb") as f:
        names = set()
        return frozenset(names) if _bound(ast.parse(f.read()).body, names) else None


def _own_names(module):
    """A module's globals as its import leaves them whatever else was imported: a
    package's without the submodules that the import system binds in it when a submodule
    is imported (by anyone, later; its own imports' bindings kept), so a kernel's stamp is
    the same in every process (otherwise a process that imported one more submodule, or
    one fewer, saved a different stamp and the next process compiled the kernel again)."""
    namespace = vars(module)
    path = getattr(module, "__file__", None)
    if not hasattr(module, "__path__") or not path:
        return namespace
    st = os.stat(path)
    names = _package_names(path, st.st_mtime, st.st_size)
    return namespace if names is None else {k: v for k, v in namespace.items() if k in names}


#: reached's answers in this process, by (own file, globals, their count): the kernels of
#: one module share them, and a process that loads its kernels from the cache would
#: otherwise walk the same modules' globals once per kernel (125 walks in one run).
_REACHED = {}


def reached(namespace, own_file):
    """The tracked source files, other than own_file, that a module with globals
    `namespace` reaches through its globals, transitively (sorted): the same files
    whatever the process has imported (_own_names). Once per module and process while
    its globals stay as many (a module fully imported)."""
    key = (own_file, id(namespace), len(namespace))
    if key not in _REACHED:
        _REACHED[key] = _reached(namespace, own_file)
    return list(_REACHED[key])


def _reached(namespace, own_file):
    modules = {getattr(m, "__file__", None): m for m in list(sys.modules.values())}
    own = _realpath(own_file)
    seen, todo = {own}, [namespace]
    while todo:
        for value in list(todo.pop().values()):
            path = _module_file(value)
            if not _tracked(path) or (real := _realpath(path)) in seen:
                continue
            seen.add(real)
            if path in modules:
                todo.append(_own_names(modules[path]))
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
        return super().get_source_stamp(), dependency_stamp(self.ebrl_namespace, self.ebrl_file)

    @classmethod
    def from_function(cls, py_func, py_file):
        if not _tracked(py_file):
            return None
        self = super().from_function(py_func, py_file)
        if self is not None:
            self.ebrl_namespace, self.ebrl_file = py_func.__globals__, py_file
        return self


class UserWideLocator(_Dependent, caching.UserWideCacheLocator):
    """The user-wide cache folder's locator (where a kernel whose own folder cannot be
    written caches), with the dependencies in its stamp."""


class TemporaryLocator(_Dependent, caching.InTreeCacheLocator):
    """The last resort, where no cache folder can be written: a temporary folder of this
    process's own (removed at its exit), so the kernels compile once per process."""

    def get_cache_path(self):
        return _temporary_folder()


@functools.lru_cache(maxsize=None)
def _temporary_folder():
    import atexit
    import shutil
    import tempfile
    folder = tempfile.mkdtemp(prefix="ebrl-numba-")
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    print("ebrl: warning: no numba cache folder can be written (beside the source, "
          "NUMBA_CACHE_DIR, the user's cache folder): the kernels compile in every process",
          file=sys.stderr, flush=True)
    return folder


class UserDirLocator(_Dependent, caching.UserProvidedCacheLocator):
    """NUMBA_CACHE_DIR's locator, with the dependencies in its stamp."""


class InTreeLocator(_Dependent, caching.InTreeCacheLocator):
    """The __pycache__ locator, with the dependencies in its stamp."""


#: What a damaged cache file is renamed to (path + DISCARDED) until the entry is saved
#: again: the process that renames it is the one that says so.
DISCARDED = ".discarded"


def mended(path, error, left=None):
    """The one line a damaged cache entry gives (stderr)."""
    what = "discarded" if left is None else f"left in place ({left})"
    print(f"ebrl: warning: numba cache file {path} could not be read ({error}); {what}, "
          "compiling the kernel again", file=sys.stderr, flush=True)


class MendingCacheFile(caching.IndexDataCacheFile):
    """numba's index and data files of one kernel's cache entry, where an entry that
    cannot be read (a truncated or garbled index, a truncated data file, an index naming
    a missing data file) is discarded with one warning line (mended()) and reads as
    absent: numba then compiles the kernel and saves the entry again.

    One line however many processes read the damaged file at once (the runner's
    workers): the damaged file is renamed to file + DISCARDED, and only the process
    whose rename succeeds says so; a data file missing while its DISCARDED copy is there
    is one that another process is compiling again, silently. save() removes the
    DISCARDED copies. Where the file cannot be renamed (a folder that cannot be written)
    it is left, the warning says so, and each process that reads it compiles the kernel."""

    def _load_index(self):
        try:
            return super()._load_index()
        except Exception as error:  # the index, not the kernel: any unpickling error
            self._discard(self._index_path, error)
            return {}

    def save(self, key, data):
        try:
            super().save(key, data)
        except OSError as error:  # a full disk, a folder turned read-only: run uncached
            print(f"ebrl: warning: numba cache entry in {self._cache_path} could not be "
                  f"saved ({type(error).__name__}: {error.strerror or error}); the kernel "
                  "runs compiled but uncached", file=sys.stderr, flush=True)
            return
        for path in (self._index_path, self._data_path(self._load_index().get(key, ""))):
            try:
                os.unlink(path + DISCARDED)
            except OSError:  # none (the common case)
                pass

    def load(self, key):
        name = self._load_index().get(key)
        if name is None:
            return None
        path = self._data_path(name)
        try:
            return self._load_data(name)
        except FileNotFoundError:  # numba returns None here, silently
            if not os.path.exists(path + DISCARDED):
                mended(path, f"missing, named by {os.path.basename(self._index_path)}")
            return None
        except Exception as error:
            self._discard(path, error)
            return None

    @staticmethod
    def _discard(path, error):
        error = f"{type(error).__name__}: {str(error).strip() or 'no message'}"
        try:
            os.replace(path, path + DISCARDED)
        except FileNotFoundError:  # another process discarded it first, and said so
            return
        except OSError as e:
            mended(path, error, f"{type(e).__name__}: {e.strerror or e}")
            return
        mended(path, error)


def install():
    """Puts the locators first among numba's, and MendingCacheFile in place of numba's
    cache files (once per process)."""
    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl  # numba < 0.62
    classes = impl._locator_classes
    for cls in (InTreeLocator, UserDirLocator):  # UserDirLocator ends up first
        if cls not in classes:
            classes.insert(0, cls)
    wide = classes.index(caching.UserWideCacheLocator)
    if UserWideLocator not in classes:
        classes.insert(wide, UserWideLocator)  # just before numba's own
    if TemporaryLocator not in classes:
        classes.append(TemporaryLocator)
    caching.IndexDataCacheFile = MendingCacheFile


def covers(dispatcher):
    """Whether a cached kernel's cache is keyed here (its locator one of this module's)."""
    impl = getattr(getattr(dispatcher, "_cache", None), "_impl", None)
    return isinstance(getattr(impl, "locator", None), _Dependent)


install()
