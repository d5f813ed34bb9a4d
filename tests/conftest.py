"""A throwaway PostgreSQL server for the tests of a study shared by several workers.

`postgres_server` (one per test session) makes a cluster with the server's own binaries
(Debian's postgresql package: /usr/lib/postgresql/<version>/bin), initdb into a temporary
folder, listening on a unix socket in that folder only (no TCP port), and stops it at the
end. initdb refuses root, so as root the server runs as the package's `postgres` user.
`postgres_url` gives each test a fresh database. Where the server is not installed the
tests skip with the reason; with EBRL_REQUIRE_POSTGRES=1 (.ci/run) they fail instead."""
import glob
import os
import pathlib
import pwd
import shutil
import subprocess
import tempfile

import pytest


def _bindir():
    """The newest installed server's bin folder, or None."""
    found = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"),
                   key=lambda p: int(pathlib.Path(p).parts[-3]) if pathlib.Path(p).parts[-3].isdigit() else 0)
    if found:
        return pathlib.Path(found[-1]).parent
    initdb = shutil.which("initdb")
    return pathlib.Path(initdb).resolve().parent if initdb else None


def _absent(reason):
    if os.environ.get("EBRL_REQUIRE_POSTGRES") == "1":
        pytest.fail(f"PostgreSQL is required here (EBRL_REQUIRE_POSTGRES=1): {reason}")
    pytest.skip(reason)


@pytest.fixture(scope="session")
def postgres_server():
    """(socket folder, run-as prefix) of a running throwaway server."""
    try:
        import psycopg  # noqa: F401
    except ImportError:
        _absent("no psycopg (pip install -e '.[cluster]')")
    bindir = _bindir()
    if bindir is None:
        _absent("no PostgreSQL server installed (Debian: apt-get install postgresql)")
    as_user = []
    folder = pathlib.Path(tempfile.mkdtemp(prefix="ebrl-pg-"))
    if os.geteuid() == 0:  # initdb refuses root: the package's user runs the server
        try:
            user = pwd.getpwnam("postgres")
        except KeyError:
            shutil.rmtree(folder)
            _absent("running as root and no `postgres` user to run the server as")
        os.chown(folder, user.pw_uid, user.pw_gid)
        runuser = shutil.which("runuser")
        as_user = [runuser, "-u", "postgres", "--"] if runuser else ["su", "postgres", "-c"]
    data, log = folder / "data", folder / "server.log"

    def run(*cmd):
        cmd = [str(c) for c in cmd]
        if as_user[:1] == ["su"]:
            import shlex
            cmd = as_user + [shlex.join(cmd)]
        else:
            cmd = as_user + cmd
        return subprocess.run(cmd, capture_output=True, text=True, timeout=120)

    made = run(bindir / "initdb", "-D", data, "-U", "postgres", "-A", "trust", "-N",
               "-E", "UTF8", "--locale=C")
    if made.returncode != 0:
        shutil.rmtree(folder, ignore_errors=True)
        pytest.fail(f"initdb failed: {made.stderr.strip()[-500:]}")
    options = (f"-k {folder} -c listen_addresses='' -c fsync=off -c synchronous_commit=off "
               "-c full_page_writes=off -c max_connections=100")
    started = run(bindir / "pg_ctl", "-D", data, "-l", log, "-o", options, "-w", "-t", "60",
                  "start")
    if started.returncode != 0:
        text = log.read_text() if log.exists() else ""
        shutil.rmtree(folder, ignore_errors=True)
        pytest.fail(f"the PostgreSQL server did not start: {started.stderr.strip()} {text[-500:]}")
    try:
        yield folder
    finally:
        run(bindir / "pg_ctl", "-D", data, "-m", "immediate", "-w", "stop")
        shutil.rmtree(folder, ignore_errors=True)


_databases = iter(range(1, 10**6))


@pytest.fixture
def postgres_url(postgres_server):
    """A fresh database on the server, as a plain postgresql:// URL (the user's form)."""
    import psycopg
    name = f"ebrl_{next(_databases)}"
    with psycopg.connect(host=str(postgres_server), user="postgres", dbname="postgres",
                         autocommit=True) as c:
        c.execute(f"CREATE DATABASE {name}")
    return f"postgresql://postgres@/{name}?host={postgres_server}"
