"""Where the records store is and how rotacal talks to it: the URL, the engine, and the one-line
errors of a store that cannot be used.

The store is named by an SQLAlchemy URL (INTERFACE.md, "Records of calibrations"): ``--db URL``,
else the environment variable ``ROTACAL_DB``, else an SQLite file ``records.sqlite`` in the user's
data folder (``platformdirs``; ``ROTACAL_DATA_DIR`` overrides the folder). Two engines are
supported: SQLite (zero set-up, one computer) and PostgreSQL through psycopg 3 (a laboratory with
several test stations).

SQLite is opened so that several processes can write at once without losing anything: write-ahead
logging, every transaction begun with ``BEGIN IMMEDIATE`` (the write lock is taken at the start, so
two writers never deadlock on a lock upgrade) and a busy timeout after which the store is reported
as locked. Foreign keys are enforced on every connection.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import sqlalchemy as sa
from sqlalchemy import event
from sqlalchemy.engine import URL, Engine

from rotacal.errors import ConfigError, RecordImmutableError, StoreError

__all__ = [
    "DEFAULT_TIMEOUT_S",
    "data_dir",
    "default_url",
    "display_url",
    "make_engine",
    "resolve_url",
    "store_errors",
    "timeout_from_environment",
]

#: How long a writer waits for another one before the store is reported as locked [s]
#: (``ROTACAL_DB_TIMEOUT`` overrides it for the commands).
DEFAULT_TIMEOUT_S = 30.0

#: The word the schema's triggers put in their refusal (migrations/versions/0002).
IMMUTABLE_MARK = "issued records are immutable"
#: The words of the audit trail's triggers (migrations/versions/0003).
APPEND_ONLY_MARK = "the audit trail is append-only"


def data_dir() -> Path:
    """The folder where rotacal keeps its state: ``ROTACAL_DATA_DIR`` or the user's data folder."""
    given = os.environ.get("ROTACAL_DATA_DIR")
    if given:
        return Path(given)
    import platformdirs

    return Path(platformdirs.user_data_dir("rotacal", appauthor=False))


def default_url() -> str:
    """The default store: ``records.sqlite`` in :func:`data_dir`."""
    return f"sqlite:///{data_dir() / 'records.sqlite'}"


def timeout_from_environment() -> float:
    """``ROTACAL_DB_TIMEOUT`` in seconds, else :data:`DEFAULT_TIMEOUT_S`."""
    given = os.environ.get("ROTACAL_DB_TIMEOUT", "").strip()
    if not given:
        return DEFAULT_TIMEOUT_S
    try:
        value = float(given)
    except ValueError:
        value = -1.0
    if not 0 < value <= 3600:
        raise ConfigError(
            f"ROTACAL_DB_TIMEOUT={given!r}: give the seconds to wait for a locked store (0 to 3600)"
        )
    return value


def resolve_url(given: str | None) -> str:
    """The store's URL: ``given`` (``--db``), else ``ROTACAL_DB``, else :func:`default_url`."""
    if given is not None and not given.strip():
        raise ConfigError(
            "--db is empty; give the records store's URL (sqlite:///path/records.sqlite or "
            "postgresql+psycopg://user@host/dbname), or leave --db out for the default store"
        )
    return given or os.environ.get("ROTACAL_DB", "").strip() or default_url()


def _parse(url: str) -> URL:
    try:
        parsed = sa.engine.make_url(url)
    except (sa.exc.ArgumentError, ValueError):
        parsed = None
    if parsed is None and "://" not in url:
        path = Path(url).expanduser().resolve()
        raise ConfigError(
            f"records store {url!r}: a file path, not a database URL; give sqlite:///{path} "
            "(--db or ROTACAL_DB)"
        )
    if parsed is not None and parsed.get_backend_name() == "postgres":
        raise ConfigError(
            f"records store {display_url(parsed)}: write the URL as postgresql+psycopg://… "
            "(postgres:// is not a name the database library knows)"
        )
    if parsed is None or parsed.get_backend_name() not in ("sqlite", "postgresql"):
        kind = f"the database kind {parsed.get_backend_name()!r}" if parsed else "this URL"
        raise ConfigError(
            f"records store {display_url(url)}: {kind} is not supported; rotacal keeps its "
            "records in SQLite or PostgreSQL: give sqlite:///path/records.sqlite or "
            "postgresql+psycopg://user@host/dbname (--db or ROTACAL_DB)"
        )
    if parsed.get_backend_name() == "postgresql":
        if parsed.get_driver_name() not in ("psycopg", "psycopg2"):
            raise ConfigError(
                f"records store {display_url(parsed)}: the driver "
                f"{parsed.get_driver_name()!r} is not supported; use postgresql+psycopg://…"
            )
        parsed = parsed.set(drivername="postgresql+psycopg")  # psycopg 3 is what rotacal installs
    elif parsed.get_driver_name() != "pysqlite":
        raise ConfigError(
            f"records store {display_url(url)}: use sqlite:///path/records.sqlite (the driver "
            f"{parsed.get_driver_name()!r} is not supported)"
        )
    elif not parsed.database or parsed.database == ":memory:":
        raise ConfigError(
            f"records store {display_url(url)}: an SQLite store needs a file "
            "(sqlite:///path/records.sqlite); "
            "a store in memory would keep nothing"
        )
    elif parsed.username or parsed.password or parsed.host or parsed.port:
        raise ConfigError(
            f"records store {display_url(url)}: an SQLite store is a file and takes no user, "
            "password or host; give sqlite:////abs/path/records.sqlite"
        )
    return parsed


def display_url(url: URL | str) -> str:
    """The URL as messages print it: without its password."""
    if isinstance(url, str):
        try:
            parsed = sa.engine.make_url(url)
        except (sa.exc.ArgumentError, ValueError):
            return url
    else:
        parsed = url
    return parsed.render_as_string(hide_password=True)


def _sqlite_connect(dbapi_connection: Any, _record: Any) -> None:
    # The driver's own transaction handling is switched off: every transaction is begun
    # explicitly in _sqlite_begin, so that the write lock is taken at its start.
    dbapi_connection.isolation_level = None
    cursor = dbapi_connection.cursor()
    cursor.execute("PRAGMA foreign_keys = ON")
    cursor.execute("PRAGMA journal_mode = WAL")
    cursor.execute("PRAGMA synchronous = FULL")  # a record, once committed, survives a power cut
    cursor.close()


#: The execution option that marks a reading transaction (Store.begin(read_only=True)).
READ_ONLY = "rotacal_read_only"


def _sqlite_begin(connection: sa.Connection) -> None:
    # A reader takes no lock until it reads, and then a snapshot (write-ahead log): it never
    # waits for a writer. A writer takes the write lock at once.
    read_only = connection.get_execution_options().get(READ_ONLY, False)
    connection.exec_driver_sql("BEGIN" if read_only else "BEGIN IMMEDIATE")


def make_engine(url: str, *, timeout_s: float = DEFAULT_TIMEOUT_S) -> Engine:
    """An engine for the store at ``url`` (see :func:`resolve_url`).

    Parameters
    ----------
    url : str
        An SQLAlchemy URL: ``sqlite:///path`` or ``postgresql+psycopg://user@host/dbname``.
    timeout_s : float
        How long to wait for a locked SQLite store, or for a PostgreSQL server to answer the
        connection [s].

    Raises
    ------
    ConfigError
        The URL is not an SQLite file or PostgreSQL URL; the SQLite file's folder does not exist.
    """
    try:
        return _make_engine(_parse(url), url, timeout_s)
    except sa.exc.ArgumentError as e:  # a URL the database library refuses after all
        raise ConfigError(
            f"records store {display_url(url)}: not a usable database URL ({_reason(e)})"
        ) from None


def _make_engine(parsed: URL, url: str, timeout_s: float) -> Engine:
    if parsed.get_backend_name() == "sqlite":
        path = Path(str(parsed.database)).expanduser()
        if url == default_url():
            path.parent.mkdir(parents=True, exist_ok=True)
        elif not path.parent.is_dir():
            raise ConfigError(
                f"records store {url}: the folder {path.parent.resolve()} does not exist; create "
                "it or give another path"
            )
        engine = sa.create_engine(
            parsed.set(database=str(path)),
            # pooled: an idle connection holds no lock (no open transaction), and keeping it
            # open spares each transaction the write-ahead log's flush at the last close
            connect_args={"timeout": timeout_s, "check_same_thread": False},
        )
        event.listen(engine, "connect", _sqlite_connect)
        event.listen(engine, "begin", _sqlite_begin)
        return engine
    return sa.create_engine(
        parsed,
        connect_args={"connect_timeout": max(1, round(timeout_s))},
        pool_pre_ping=True,
    )


def _reason(e: BaseException) -> str:
    """The database's own first line of an error, without SQLAlchemy's statement dump."""
    inner = getattr(e, "orig", None) or e
    text = str(inner).strip().splitlines()
    return text[0] if text else type(inner).__name__


@contextlib.contextmanager
def store_errors(url: str, timeout_s: float = DEFAULT_TIMEOUT_S) -> Iterator[None]:
    """Turn what the database driver raises into one line that names the store and what to do
    (:class:`StoreError`); a refused change of an issued record becomes
    :class:`RecordImmutableError`."""
    shown = display_url(url)
    try:
        yield
    except sa.exc.DBAPIError as e:
        reason = _reason(e)
        lower = reason.lower()
        if IMMUTABLE_MARK in lower:
            raise RecordImmutableError(
                f"records store {shown}: {IMMUTABLE_MARK}; a correction is a new certificate "
                'whose plan says supersedes = "NUMBER"'
            ) from None
        if APPEND_ONLY_MARK in lower:
            raise RecordImmutableError(
                f"records store {shown}: {APPEND_ONLY_MARK}; its events are never changed or "
                "removed (`rotacal records audit` checks them)"
            ) from None
        if "database is locked" in lower or "database table is locked" in lower:
            raise StoreError(
                f"records store {shown}: locked by another program (waited {timeout_s:g} s); "
                "try again when it has finished"
            ) from None
        if "file is not a database" in lower or "malformed" in lower:
            raise StoreError(
                f"records store {shown}: the file is not an SQLite database (or it is damaged); "
                "give the path of a records store"
            ) from None
        if isinstance(e, (sa.exc.OperationalError, sa.exc.InterfaceError)):
            raise StoreError(f"records store {shown}: {_advice(url, reason)}") from None
        raise StoreError(f"records store {shown}: {reason}") from None


def _advice(url: str, reason: str) -> str:
    """What a store that cannot be opened or used says: the database's reason, and what to do
    about it — for SQLite the file, for PostgreSQL the server, the database or the user."""
    lower = reason.lower()
    try:
        parsed = sa.engine.make_url(url)
    except (sa.exc.ArgumentError, ValueError):
        return f"cannot be used ({reason})"
    if parsed.get_backend_name() == "sqlite":
        return (
            f"cannot be used ({reason}); check the path, and that you may read and write the "
            "file and its folder"
        )
    if "deadlock detected" in lower or "could not serialize" in lower:
        return (
            f"another writer changed the same rows at the same moment ({reason}); nothing of "
            "this certificate was kept: run it again"
        )
    where = f"{parsed.host or 'localhost'}:{parsed.port or 5432}"
    if "database" in lower and "does not exist" in lower:
        return (
            f"the PostgreSQL server at {where} has no database {parsed.database!r}; create it "
            f"(createdb {parsed.database}) or correct the database name in the URL"
        )
    if ("role" in lower and "does not exist" in lower) or "authentication failed" in lower:
        return (
            f"the PostgreSQL server at {where} refuses the user {parsed.username!r} ({reason}); "
            "check the user and the password in the URL"
        )
    if any(
        word in lower
        for word in (
            "refused",
            "timeout",
            "timed out",
            "resolve host",
            "translate host",
            "no route",
        )
    ):
        return (
            f"no PostgreSQL server answers at {where} ({reason}); start the server, or correct "
            "the host and the port in the URL"
        )
    return (
        f"cannot be used ({reason}); check that the server runs, the URL, the user and the password"
    )
