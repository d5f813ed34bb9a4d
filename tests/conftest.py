"""A throwaway PostgreSQL server for the tests of a study shared by several workers
(experiments.ops.pgserver: the server's own binaries, initdb into a temporary folder, a
unix socket there only, as the `postgres` user when run as root, stopped at the end).
`postgres_url` gives each test a fresh database. Where no server can be started the tests
skip with the reason; with EBRL_REQUIRE_POSTGRES=1 (.ci/run) they fail instead."""
import itertools
import os

import pytest


@pytest.fixture(scope="session")
def postgres_server():
    """The socket folder of a running throwaway server."""
    from experiments.ops import pgserver
    try:
        with pgserver.server() as folder:
            yield folder
    except pgserver.Unavailable as e:
        if os.environ.get("EBRL_REQUIRE_POSTGRES") == "1":
            pytest.fail(f"PostgreSQL is required here (EBRL_REQUIRE_POSTGRES=1): {e}")
        pytest.skip(str(e))


_databases = itertools.count(1)


@pytest.fixture
def postgres_url(postgres_server):
    """A fresh database on the server, as a plain postgresql:// URL (the user's form)."""
    from experiments.ops import pgserver
    return pgserver.database(postgres_server, f"ebrl_{next(_databases)}")


# -- two pytest-xdist workers (make test: pytest -n 2 --dist loadgroup) ------------------
#: Tests that start many processes of their own (a Ray cluster, PostgreSQL and its study
#: workers) run one at a time on one worker: two of them at once on two cores took 3-4x
#: their time alone. Modules whose module-scoped fixture is the bulk of their cost stay
#: on one worker, so the fixture is built once.
_ONE_WORKER_MODULES = ("test_cli_inputs.py", "test_rendering.py")
#: Module-scoped fixtures that make runs: the tests that use one go to one worker, so it
#: is made once (split across the two workers, each made it: measured, `reported` cost
#: 29 s of setup on each).
_SHARED_FIXTURES = {"test_experiments.py": ("clean_run", "kill_clean"),
                    "test_faults.py": ("clean",), "test_full_disk.py": ("reported",),
                    "test_protocol_rules.py": ("records",), "test_provenance.py": ("made",),
                    "test_pages.py": ("made",), "test_nothing_lost.py": ("reported_universe",)}


@pytest.hookimpl(tryfirst=True)  # before xdist's own, which reads the marks to group
def pytest_collection_modifyitems(config, items):
    for item in items:
        module = item.path.name
        fixtures = set(getattr(item, "fixturenames", ()))
        if (module == "test_cluster.py" or "_ray_" in f"_{item.name}"
                or fixtures & {"postgres_server", "postgres_url"}):
            item.add_marker(pytest.mark.xdist_group("processes"))
        elif module in _ONE_WORKER_MODULES:
            item.add_marker(pytest.mark.xdist_group(module))
        elif shared := [f for f in _SHARED_FIXTURES.get(module, ()) if f in fixtures]:
            item.add_marker(pytest.mark.xdist_group(f"{module}:{shared[0]}"))
