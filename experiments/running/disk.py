"""The one atomic write of every file a command writes (atomic_file, atomic_write), and
the one-line error of a results folder that cannot take a write (WriteError). Re-exported
by experiments.running.results, where the run folders are written and read.
"""
import contextlib
import errno
import glob
import os
import pathlib
import socket
import tempfile


class ResultsError(RuntimeError):
    """A results folder that cannot be used as it is; the message names the file."""


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


_UMASK = _umask()


class WriteError(ResultsError, OSError):
    """A results folder that cannot take a write (full, read-only, gone): the message
    names the folder; what is already on disk stays complete. An OSError too, so that a
    command that does not catch it still ends in its one line (experiments.cli.main)."""


#: Test only: EBRL_TEST_DISK_FULL=N makes the disk "fill up" in the driver after N run
#: records: the next run.json write fails halfway with ENOSPC, and every write after it.
TEST_DISK_FULL = "EBRL_TEST_DISK_FULL"
#: Test only: EBRL_TEST_DISK_FULL_AT=PATTERN makes the disk "fill up" at the first file
#: whose name matches the shell pattern (summary.json, *.png, FIT.md, *.mp4, ...): its
#: write fails with ENOSPC after half of it is written, and every write after it.
TEST_DISK_FULL_AT = "EBRL_TEST_DISK_FULL_AT"
_records = 0  # run.json files this process wrote (for TEST_DISK_FULL)
_full = False  # the disk "filled up" (TEST_DISK_FULL_AT)


def _test_disk_full(path):
    global _full
    pattern = os.environ.get(TEST_DISK_FULL_AT)
    if pattern:
        import fnmatch
        _full = _full or fnmatch.fnmatch(path.name, pattern)
        return _full
    limit = os.environ.get(TEST_DISK_FULL)
    if not limit:
        return False
    return _records > int(limit) or (_records == int(limit) and path.name == "run.json")


def write_error(path, e):
    """The WriteError of an OSError met writing path: one line naming the folder."""
    what = errno.errorcode.get(getattr(e, "errno", None), "")
    return WriteError(f"cannot write {path.name} in {path.parent}: "
                      f"{getattr(e, 'strerror', None) or e}{f' ({what})' if what else ''}; "
                      "what is on disk is kept: free space (or make it writable) and rerun "
                      "the same command to finish")


def tmp_prefix(path, pid=None):
    """A temporary file's name before its random part: the file's, this host's and the
    writing process's, so that a later writer can tell a dead writer's leftover."""
    return f".{path.name}.{socket.gethostname()}.{os.getpid() if pid is None else pid}."


def _remove_dead_writers(path):
    """Removes the temporary files of path that a process of this host left when it was
    killed mid-write (SIGKILL runs no cleanup): those whose writer's pid no longer runs.
    A live writer's file, or another host's, is never touched."""
    host = f".{path.name}.{socket.gethostname()}."
    for tmp in path.parent.glob(f"{glob.escape(host)}*.tmp"):
        pid = tmp.name[len(host):].split(".", 1)[0]
        if not pid.isdigit() or int(pid) == os.getpid():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            tmp.unlink(missing_ok=True)
        except OSError:  # alive (another user's process), or not ours to judge
            pass


@contextlib.contextmanager
def atomic_file(path):
    """The one atomic write of every file a command writes (run records, summary.json,
    REPORT.md, the figures, FIT.md, EVOLVE.md, RESULTS.md, videos): yields a temporary
    path beside path to write; when the block ends, the file is synced and renamed over
    path, so that path is either its old self or complete. A write that fails (a full
    disk, a folder turned read-only or removed) raises WriteError naming the folder and
    the error, and leaves no temporary file; one a killed writer left (SIGKILL) is removed
    by the next write of the same file (_remove_dead_writers)."""
    global _records
    path = pathlib.Path(path)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        _remove_dead_writers(path)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=tmp_prefix(path), suffix=".tmp")
        os.close(fd)
        tmp = pathlib.Path(tmp)
        os.chmod(tmp, 0o666 & ~_UMASK)  # mkstemp makes 0600; results are for sharing
        yield tmp
        if _test_disk_full(path):
            with open(tmp, "r+b") as f:
                f.truncate(os.path.getsize(tmp) // 2)
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        with open(tmp, "rb") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException as e:
        if tmp is not None:
            try:
                pathlib.Path(tmp).unlink(missing_ok=True)
            except OSError:
                pass
        if isinstance(e, OSError) and not isinstance(e, WriteError):
            raise write_error(path, e) from e
        raise
    if path.name == "run.json":
        _records += 1


def atomic_write(path, data):
    """Writes bytes or text to path through atomic_file."""
    with atomic_file(path) as tmp:
        with open(tmp, "wb" if isinstance(data, bytes) else "w") as f:
            f.write(data)
