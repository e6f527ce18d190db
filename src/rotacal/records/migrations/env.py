"""Alembic's environment for the records store: migrations run on the connection rotacal hands
over (``config.attributes["connection"]``), inside its transaction — never from an alembic.ini.
"""

from __future__ import annotations

from alembic import context

from rotacal.records.models import Base

connection = context.config.attributes["connection"]
context.configure(
    connection=connection,
    target_metadata=Base.metadata,
    # SQLite changes a table by copying it ("batch" mode); PostgreSQL alters it in place
    render_as_batch=connection.dialect.name == "sqlite",
    transaction_per_migration=False,
)
with context.begin_transaction():
    context.run_migrations()
