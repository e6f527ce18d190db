"""The store's schema: the migrations make exactly the models, an older store is upgraded (and
refused until it is), a newer one or a foreign database is refused."""

from __future__ import annotations

import pytest
import sqlalchemy as sa
from alembic import command
from alembic.autogenerate import compare_metadata
from alembic.runtime.migration import MigrationContext
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.errors import RecordImmutableError, StoreError
from rotacal.records import models as m
from rotacal.records import open_store
from rotacal.records.engine import make_engine
from rotacal.records.query import list_certificates
from rotacal.records.schema import _config, head_revision

VALUES = {"scale_factor_ppm": ("12.3", "0.52")}


def test_the_migrations_make_exactly_the_models(store_url: str) -> None:
    store = open_store(store_url)
    with store.engine.connect() as connection:
        differences = compare_metadata(MigrationContext.configure(connection), m.Base.metadata)
    assert differences == []


def _store_at(url: str, revision: str) -> None:
    with make_engine(url).begin() as connection:
        command.upgrade(_config(connection), revision)


def test_an_older_store_is_refused_until_upgraded_and_keeps_its_records(
    store_url: str, issue
) -> None:
    _store_at(store_url, "0001")  # before the immutability triggers
    with pytest.raises(
        StoreError, match=r"revision 0001, this rotacal uses 0002; run `rotacal records upgrade"
    ):
        open_store(store_url)
    older = open_store(store_url, check_schema=False)
    issue(older, VALUES, number="RC-2026-0001")  # a record the old schema let change
    result = CliRunner().invoke(cli, ["records", "upgrade", "--db", store_url])
    assert result.exit_code == 0, result.output
    assert "upgraded from revision 0001 to 0002" in result.output
    store = open_store(store_url)
    assert [r["number"] for r in list_certificates(store)] == ["RC-2026-0001"]
    with pytest.raises(RecordImmutableError):
        with store.begin() as connection:
            connection.execute(sa.text("DELETE FROM reported_values"))
    again = CliRunner().invoke(cli, ["records", "upgrade", "--db", store_url])
    assert again.exit_code == 0 and "already this rotacal's" in again.output


def test_a_store_of_a_newer_rotacal_is_refused(store_url: str) -> None:
    open_store(store_url)
    with make_engine(store_url).begin() as connection:
        connection.execute(sa.text("UPDATE alembic_version SET version_num = '0099'"))
    with pytest.raises(StoreError, match=r"newer rotacal.*0099.*upgrade rotacal"):
        open_store(store_url)
    result = CliRunner().invoke(cli, ["records", "upgrade", "--db", store_url])
    assert result.exit_code == 2 and "upgrade rotacal, not the store" in result.output


def test_a_database_of_something_else_is_not_taken_over(store_url: str) -> None:
    with make_engine(store_url).begin() as connection:
        connection.execute(sa.text("CREATE TABLE invoices (id INTEGER PRIMARY KEY)"))
    with pytest.raises(StoreError, match=r"other tables \(invoices"):
        open_store(store_url)


def test_the_head_is_the_newest_migration() -> None:
    assert head_revision() == "0002"
