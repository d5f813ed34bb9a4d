"""A throwaway PostgreSQL server, for the tests (tests/conftest.py) and the study soak
(experiments.ops.studysoak): the server's own binaries (Debian's postgresql package,
/usr/lib/postgresql/<version>/bin), initdb into a temporary folder, a unix socket in that
folder only (no TCP port), stopped and removed at the end. initdb refuses root, so as root
the server runs as the package's `postgres` user (runuser)."""
import contextlib
import glob
import os
import pathlib
import pwd
import shutil
import subprocess
import tempfile


class Unavailable(RuntimeError):
    """No server can be started here (the reason is the message)."""


def bindir():
    """The newest installed server's bin folder, or None."""
    def version(path):
        v = pathlib.Path(path).parts[-3]
        return int(v) if v.isdigit() else 0
    found = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"), key=version)
    if found:
        return pathlib.Path(found[-1]).parent
    initdb = shutil.which("initdb")
    return pathlib.Path(initdb).resolve().parent if initdb else None


@contextlib.contextmanager
def server():
    """Yields the socket folder of a running throwaway server (user postgres, trust)."""
    try:
        import psycopg  # noqa: F401
    except ImportError:
        raise Unavailable("no psycopg (pip install -e '.[cluster]')") from None
    bins = bindir()
    if bins is None:
        raise Unavailable("no PostgreSQL server installed (Debian: apt-get install postgresql)")
    as_user = []
    folder = pathlib.Path(tempfile.mkdtemp(prefix="ebrl-pg-"))
    if os.geteuid() == 0:  # initdb refuses root: the package's user runs the server
        try:
            user = pwd.getpwnam("postgres")
        except KeyError:
            shutil.rmtree(folder)
            raise Unavailable("running as root and no `postgres` user to run the server as") from None
        if not shutil.which("runuser"):
            shutil.rmtree(folder)
            raise Unavailable("running as root and no runuser to run the server as postgres")
        os.chown(folder, user.pw_uid, user.pw_gid)
        as_user = [shutil.which("runuser"), "-u", "postgres", "--"]
    data, log = folder / "data", folder / "server.log"

    def run(*cmd):
        return subprocess.run(as_user + [str(c) for c in cmd], capture_output=True, text=True,
                              timeout=120)
    try:
        made = run(bins / "initdb", "-D", data, "-U", "postgres", "-A", "trust", "-N",
                   "-E", "UTF8", "--locale=C")
        if made.returncode != 0:
            raise RuntimeError(f"initdb failed: {made.stderr.strip()[-500:]}")
        options = (f"-k {folder} -c listen_addresses='' -c fsync=off "
                   "-c synchronous_commit=off -c full_page_writes=off -c max_connections=100")
        started = run(bins / "pg_ctl", "-D", data, "-l", log, "-o", options, "-w", "-t", "60",
                      "start")
        if started.returncode != 0:
            text = log.read_text() if log.exists() else ""
            raise RuntimeError(f"the PostgreSQL server did not start: "
                               f"{started.stderr.strip()} {text[-500:]}")
        try:
            yield folder
        finally:
            run(bins / "pg_ctl", "-D", data, "-m", "immediate", "-w", "stop")
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def database(folder, name):
    """Makes database `name` on the server at folder; returns its plain postgresql:// URL."""
    import psycopg
    with psycopg.connect(host=str(folder), user="postgres", dbname="postgres",
                         autocommit=True) as c:
        c.execute(f"CREATE DATABASE {name}")
    return f"postgresql://postgres@/{name}?host={folder}"
