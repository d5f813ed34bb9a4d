"""A study's storage (experiments.studies.study): the storage URL (SQLite by default,
PostgreSQL for several workers), its password hidden in every line, the lock around the
steps that must not interleave, Optuna's RDBStorage with heartbeats (made and kept in an
Opened record beside the Study: nothing is added to Optuna's objects), a lost storage as
one line (StorageError), and the seeded TPE sampler."""
import contextlib
import dataclasses
import pathlib
import re
import time
import warnings
import weakref
from typing import TYPE_CHECKING

from experiments.running import results

if TYPE_CHECKING:  # annotations only: Optuna is imported where it is used
    from collections.abc import Callable

    import optuna

#: The storage used when none is given: an SQLite file in the study's folder.
DEFAULT_STORAGE = "study.db"


def storage_url(storage, out):
    """--storage as an Optuna URL: a URL as it is, but postgresql:// (and postgres://)
    through psycopg 3, the cluster extra's driver (postgresql+psycopg://; a URL naming its
    driver, postgresql+psycopg2://, is kept); a plain path, an SQLite file."""
    storage = storage or str(pathlib.Path(out) / DEFAULT_STORAGE)
    if "://" not in storage:
        return f"sqlite:///{pathlib.Path(storage).resolve()}"
    scheme, rest = storage.split("://", 1)
    return f"postgresql+psycopg://{rest}" if scheme in ("postgresql", "postgres") else storage


def shown(url):
    """A storage URL with its password hidden (***), as every line and file shows it."""
    try:
        import sqlalchemy.engine
        return sqlalchemy.engine.make_url(url).render_as_string(hide_password=True)
    except Exception:  # not a URL SQLAlchemy reads: hide what looks like user:password@
        return re.sub(r"(://[^/@:]*:)[^@]*@", r"\1***@", str(url))


def hide(text, url):
    """text with the URL's password (as given, and %-encoded) replaced by ***."""
    try:
        import urllib.parse

        import sqlalchemy.engine
        password = sqlalchemy.engine.make_url(url).password
    except Exception:
        password = None
    text = str(text).replace(str(url), shown(url))
    if password:
        for form in {password, urllib.parse.quote(password, safe=""),
                     urllib.parse.quote_plus(password)}:
            text = text.replace(form, "***")
    return text


class StorageError(results.ResultsError):
    """The study's storage failed (a lost database connection, say): the message is one
    line, the URL's password hidden; the finished trials are kept."""


#: Seconds between a worker's heartbeats for its running trials, and the age of the last
#: heartbeat after which another worker takes a running trial as dead (a lost machine).
HEARTBEAT = 5
GRACE = 60
#: Seconds between looks at the study while other workers' trials run.
POLL = 0.5
#: The PostgreSQL advisory lock key of the studies' lock (any fixed 64-bit number).
LOCK_KEY = 0x65627231  # "ebr1"
WORKER = "ebrl:worker"  # the trial system attribute naming who runs it


def _is_postgres(url):
    return str(url).startswith(("postgresql", "postgres"))


@contextlib.contextmanager
def lock(url):
    """The studies' lock in this storage: a PostgreSQL advisory lock (released also when
    the worker's connection dies), or a file lock beside an SQLite file; none otherwise."""
    if _is_postgres(url):
        import sqlalchemy
        engine = _lock_engine(url)
        with engine.connect() as c:
            c.execute(sqlalchemy.text("SELECT pg_advisory_lock(:k)"), {"k": LOCK_KEY})
            c.commit()
            try:
                yield
            finally:
                c.execute(sqlalchemy.text("SELECT pg_advisory_unlock(:k)"), {"k": LOCK_KEY})
                c.commit()
    elif str(url).startswith("sqlite:///"):
        import fcntl
        path = pathlib.Path(str(url)[len("sqlite:///"):].split("?")[0])
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(f"{path}.lock", "a") as f:
            fcntl.flock(f, fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(f, fcntl.LOCK_UN)
    else:
        yield


_ENGINES = {}


def _lock_engine(url):
    if url not in _ENGINES:
        import sqlalchemy
        _ENGINES[url] = sqlalchemy.create_engine(url, poolclass=sqlalchemy.pool.NullPool)
    return _ENGINES[url]


def _storage_failures():
    """The exception types of a storage that fails (SQLAlchemy's, Optuna's, the driver's)."""
    import optuna
    import sqlalchemy.exc
    kinds = [sqlalchemy.exc.SQLAlchemyError, optuna.exceptions.StorageInternalError]
    try:
        import psycopg
        kinds.append(psycopg.Error)
    except ImportError:
        pass
    return tuple(kinds)


@dataclasses.dataclass(eq=False)
class Opened:
    """What load() knows of a study beside Optuna's Study: its storage URL, the RDBStorage
    it opened (the one the Study reads, through Optuna's cache of finished trials), the
    study's id in it, and the sampler of a batch that starts when the study holds n trials
    (None: the study keeps its sampler)."""
    url: str
    storage: "optuna.storages.RDBStorage"
    study_id: int
    reseed: "Callable[[int], optuna.samplers.BaseSampler] | None" = None

    def trial_id(self, trial):
        """The storage's id of a trial (a Trial or a FrozenTrial) of this study."""
        return self.storage.get_trial_id_from_study_id_trial_number(self.study_id, trial.number)


#: Each Study load() made -> its Opened (no attribute is added to Optuna's objects).
_OPENED = weakref.WeakKeyDictionary()


def opened(study):
    """The Opened record of a Study made by load(); ValueError for any other Study."""
    try:
        return _OPENED[study]
    except (KeyError, TypeError):
        raise ValueError(f"study {getattr(study, 'study_name', study)!r} was not opened by "
                         "experiments.studies.study.load") from None


@contextlib.contextmanager
def storage_errors(study):
    """A storage failure inside the block as StorageError (one line, password hidden)."""
    try:
        yield
    except _storage_failures() as e:
        url = _OPENED[study].url if study in _OPENED else ""
        raise StorageError(hide(f"lost the study storage {shown(url)}: "
                                f"{results.error_line(e)}; the finished trials are kept: "
                                "rerun the same command when it answers again", url)) from None


def load(name, storage, out, seed=0, create=True, sampler=None, first=None):
    """The study `name` in the storage (made when missing and create), minimising; with
    the sampler given, else a seeded TPE sampler. `first`: the settings of the study's
    first trial, enqueued when the study holds none (under the lock, so that two workers
    starting together enqueue it once)."""
    import optuna
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    reseeded = sampler is None
    if sampler is None:
        sampler = tpe(seed, 0)
    url = storage_url(storage, out)
    try:
        with lock(url):  # two workers on a fresh database race to make its tables
            rdb = _rdb(url)
            if not create:
                s = optuna.load_study(study_name=name, storage=rdb, sampler=sampler)
            else:
                s = optuna.create_study(study_name=name, storage=rdb, sampler=sampler,
                                        direction="minimize", load_if_exists=True)
            if first is not None and not s.get_trials(deepcopy=False):
                s.enqueue_trial(first)
    except ModuleNotFoundError as e:
        if e.name in ("psycopg", "psycopg2"):
            raise ModuleNotFoundError(f"no PostgreSQL driver ({e.name}): install the "
                                      "cluster extra, pip install -e '.[cluster]'") from None
        raise
    _OPENED[s] = Opened(url, rdb, rdb.get_study_id_from_name(s.study_name),
                        (lambda n: tpe(seed, n)) if reseeded else None)
    return s


def tpe(seed, n_trials):
    """The seeded TPE sampler of a batch that starts when the study holds n_trials: seeded
    from both, so that two workers (whose batches start at other counts) never draw the
    same settings, and one worker's study is the same on every run."""
    import optuna
    return optuna.samplers.TPESampler(seed=(seed * 1_000_003 + n_trials) % 2**31,
                                      multivariate=True, constant_liar=True,
                                      n_startup_trials=20)


def _ask_again(study, trial):
    """A trial failed by its stale heartbeat (fail_stale_trials): its settings asked again."""
    study.enqueue_trial(trial.params, skip_if_exists=False)


def _rdb(url, tries=5):
    """Optuna's storage at url, its tables made if missing, with heartbeats, a trial whose
    heartbeat went stale asked again (_ask_again). Making the tables is retried: a program
    that opens the storage without the lock (Optuna's own tools) may make them at the same
    moment (a unique violation on PostgreSQL's catalog)."""
    import inspect

    import optuna
    import sqlalchemy.exc
    # Optuna 4.9 renamed failed_trial_callback (removed in 6.0) heartbeat_stale_trial_callback.
    stale = "heartbeat_stale_trial_callback"
    if stale not in inspect.signature(optuna.storages.RDBStorage).parameters:
        stale = "failed_trial_callback"
    for attempt in range(tries):
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
                return optuna.storages.RDBStorage(
                    url, heartbeat_interval=HEARTBEAT, grace_period=GRACE,
                    engine_kwargs={"pool_pre_ping": True}, **{stale: _ask_again})
        except (sqlalchemy.exc.IntegrityError, sqlalchemy.exc.ProgrammingError):
            if attempt + 1 == tries:
                raise
            time.sleep(0.2 * (attempt + 1))
