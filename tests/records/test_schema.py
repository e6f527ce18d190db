"""The store's schema: the migrations make exactly the models, an older store is upgraded (and
refused until it is), a newer one or a foreign database is refused."""

from __future__ import annotations

import datetime as dt

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
from rotacal.records.query import audit_trail, list_certificates
from rotacal.records.record import insert_record, record_of
from rotacal.records.schema import _config, head_revision

from .conftest import files_of, make_content

VALUES = {"scale_factor_ppm": ("12.3", "0.52")}


def test_the_migrations_make_exactly_the_models(store_url: str) -> None:
    store = open_store(store_url)
    with store.engine.connect() as connection:
        differences = compare_metadata(MigrationContext.configure(connection), m.Base.metadata)
    assert differences == []


def _store_at(url: str, revision: str) -> None:
    with make_engine(url).begin() as connection:
        command.upgrade(_config(connection), revision)


def _keep_as_before(url: str, content, *, voided: str | None = None) -> None:
    """Keep a certificate the way a rotacal of schema 0002 did: its rows, no audit events."""
    with make_engine(url).begin() as connection:
        record = record_of(content, files_of(content))
        record["recorded_at"] = "2026-11-25T09:00:00+00:00"
        insert_record(connection, record)
        if voided:
            connection.execute(
                sa.insert(m.VoidedNumber).values(
                    number=voided, voided_at=dt.datetime(2026, 11, 25, 9, 30), reason="pdf failed"
                )
            )


def test_an_older_store_is_refused_until_upgraded_and_gets_its_trail(store_url: str) -> None:
    _store_at(store_url, "0002")  # the previous revision: before the audit trail
    with pytest.raises(
        StoreError, match=r"revision 0002, this rotacal uses 0003; run `rotacal records upgrade"
    ):
        open_store(store_url)
    _keep_as_before(store_url, make_content(VALUES, number="RC-2026-0001"), voided="RC-2026-0002")
    _keep_as_before(
        store_url, make_content(VALUES, number="RC-2026-0003", supersedes="RC-2026-0001")
    )
    result = CliRunner().invoke(cli, ["records", "upgrade", "--db", store_url])
    assert result.exit_code == 0, result.output
    assert "upgraded from revision 0002 to 0003" in result.output
    store = open_store(store_url)
    assert [r["number"] for r in list_certificates(store)] == ["RC-2026-0003", "RC-2026-0001"]
    trail = audit_trail(store)
    assert trail["intact"], trail["problems"]
    states = [(e["number"], e["from_state"], e["to_state"], e["who"]) for e in trail["events"]]
    assert states == [
        ("RC-2026-0001", None, "draft", "A. Operator"),
        ("RC-2026-0001", "draft", "issued", "B. Manager"),
        ("RC-2026-0001", "issued", "superseded", "B. Manager"),
        ("RC-2026-0002", None, "draft", "unknown"),
        ("RC-2026-0002", "draft", "voided", "unknown"),
        ("RC-2026-0003", None, "draft", "A. Operator"),
        ("RC-2026-0003", "draft", "issued", "B. Manager"),
    ]
    assert all("reconstructed by the upgrade" in e["reason"] for e in trail["events"])
    assert trail["events"][1]["at"] == "2026-11-25T09:00:00+00:00"  # when it was recorded
    for table in ("reported_values", "audit_events"):
        with pytest.raises(RecordImmutableError):
            with store.begin() as connection:
                connection.execute(sa.text(f"DELETE FROM {table}"))
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
    assert head_revision() == "0003"
