"""The ``--db`` option of the commands that use the records store, and opening the store."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

import click

if TYPE_CHECKING:
    from rotacal.records import Store

F = TypeVar("F", bound=Callable[..., Any])

db_option: Callable[[F], F] = click.option(
    "--db",
    metavar="URL",
    default=None,
    help="The records store: sqlite:///path/records.sqlite or "
    "postgresql+psycopg://user@host/dbname [default: $ROTACAL_DB, else records.sqlite in the "
    "user's data folder].",
)


def open_db(url: str | None, *, check_schema: bool = True) -> Store:
    """The store of ``--db`` (a fault becomes one line and exit 2 through the command group)."""
    from rotacal.records import open_store

    store = open_store(url, check_schema=check_schema)
    # the pool's connections close with the command, not whenever the store is collected: a
    # PostgreSQL connection left to the garbage collector is an unclosed socket (ResourceWarning)
    context = click.get_current_context(silent=True)
    if context is not None:
        context.call_on_close(store.close)
    return store
