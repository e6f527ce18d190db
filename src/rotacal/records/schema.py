"""The records store's schema version: made on first use, checked on every opening, migrated by
``rotacal records upgrade`` (Alembic, ``migrations/``).

An empty database becomes a store at once (zero set-up). A store whose schema is older than this
rotacal's is not used until it is upgraded — silently reading an old layout could misread records —
and one made by a newer rotacal is refused with the advice to upgrade rotacal.
"""

from __future__ import annotations

from functools import lru_cache

import sqlalchemy as sa
from alembic import command
from alembic.config import Config
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory

from rotacal.errors import StoreError

__all__ = ["current_revision", "ensure_schema", "head_revision", "upgrade"]

#: Serialises the creation and upgrade of a PostgreSQL store among concurrent rotacal processes
#: (pg_advisory_xact_lock key; SQLite serialises them by its write lock).
_SCHEMA_LOCK = 0x524F5441  # "ROTA"


def _config(connection: sa.Connection | None = None) -> Config:
    config = Config()
    config.set_main_option("script_location", "rotacal.records:migrations")
    config.attributes["connection"] = connection
    return config


@lru_cache(maxsize=1)
def _scripts() -> ScriptDirectory:
    return ScriptDirectory.from_config(_config())


def head_revision() -> str:
    """The schema revision this rotacal reads and writes."""
    head = _scripts().get_current_head()
    assert head is not None
    return head


def current_revision(connection: sa.Connection) -> str | None:
    """The store's schema revision (None: no rotacal schema in it)."""
    return MigrationContext.configure(connection).get_current_revision()


def _lock(connection: sa.Connection) -> None:
    if connection.dialect.name == "postgresql":
        connection.execute(sa.text("SELECT pg_advisory_xact_lock(:key)"), {"key": _SCHEMA_LOCK})


def _known(revision: str) -> bool:
    try:
        return _scripts().get_revision(revision) is not None
    except Exception:  # alembic raises its own kinds for an unknown id
        return False


def ensure_schema(engine: sa.Engine, shown: str) -> None:
    """Make the schema in an empty store; refuse a store whose schema is not this rotacal's.

    Raises
    ------
    StoreError
        The database holds tables but no rotacal schema; the schema is older (run
        ``rotacal records upgrade``) or newer (upgrade rotacal) than this rotacal's.
    """
    head = head_revision()
    with engine.connect() as connection:
        revision = current_revision(connection)
    if revision == head:
        return
    if revision is None:
        with engine.begin() as connection:
            _lock(connection)
            revision = current_revision(connection)
            if revision is None:
                tables = set(sa.inspect(connection).get_table_names())
                if tables - {"alembic_version"}:
                    raise StoreError(
                        f"records store {shown}: the database holds other tables "
                        f"({', '.join(sorted(tables)[:4])}…) and no rotacal records; give an "
                        "empty database or a rotacal records store"
                    )
                command.upgrade(_config(connection), "head")
                return
    if revision == head:
        return
    if _known(revision):
        raise StoreError(
            f"records store {shown}: its schema is revision {revision}, this rotacal uses "
            f"{head}; run `rotacal records upgrade --db {shown}` (back the store up first: "
            "`rotacal records export`)"
        )
    raise StoreError(
        f"records store {shown}: made by a newer rotacal (schema revision {revision}, this "
        f"rotacal knows up to {head}); upgrade rotacal"
    )


def upgrade(engine: sa.Engine, shown: str, target: str = "head") -> tuple[str | None, str]:
    """Migrate the store to ``target`` (default: this rotacal's schema). Returns the revisions
    before and after. One transaction: an upgrade that fails leaves the store as it was."""
    with engine.begin() as connection:
        _lock(connection)
        before = current_revision(connection)
        if before is not None and not _known(before):
            raise StoreError(
                f"records store {shown}: made by a newer rotacal (schema revision {before}); "
                "upgrade rotacal, not the store"
            )
        command.upgrade(_config(connection), target)
        after = current_revision(connection)
    assert after is not None
    return before, after
