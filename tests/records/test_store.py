"""The records store on both engines: what is kept is what was issued, issued rows never change,
numbers are never issued twice, and supersession keeps both certificates."""

from __future__ import annotations

import datetime as dt
import hashlib

import pytest
import sqlalchemy as sa
from sqlalchemy.orm import Session

from rotacal.errors import ConfigError, RecordImmutableError, StoreError
from rotacal.records import models as m
from rotacal.records import open_store
from rotacal.records.query import certificate_record, list_certificates
from rotacal.records.record import read_record

from .conftest import files_of, make_content, make_plan

VALUES = {"scale_factor_ppm": ("12.3", "0.52"), "bias_deg_h": ("-0.041", "0.012")}


def test_the_record_holds_exactly_what_was_issued(store_url: str, issue) -> None:
    store = open_store(store_url)
    content = issue(store, VALUES, number="RC-2026-0007", limits={"bias_deg_h": ("-0.1", "0.1")})
    with store.begin() as connection:
        record = read_record(connection, "RC-2026-0007")
    assert record is not None
    plan = content.plan
    assert record["plan"] == plan.text and record["plan_sha256"] == content.plan_sha256
    assert record["item"] == {
        "kind": "gyroscope",
        "manufacturer": "Gyro Maker Ltd",
        "model": "GM-300",
        "serial": "SN-0001",
    }
    assert [(p["name"], p["role"]) for p in record["persons"]] == [
        ("A. Operator", "performed"),
        ("B. Manager", "approved"),
    ]
    assert record["standards"] == [
        {"id": "STD-17", "name": "Rate table encoder", "certificate": "CAL-2026-123",
         "due": "2030-06-30"}
    ]  # fmt: skip
    files = files_of(content)
    assert {f["name"]: f["content"] for f in record["files"]} == files
    for f in record["files"]:
        assert f["sha256"] == hashlib.sha256(files[f["name"]]).hexdigest()
    assert record["inputs"] == [
        {"measurement": 1, "path": "rates.npz", "sha256": "ab" * 32, "bytes": 1234}
    ]
    printed = {v["quantity"]: (v["value"], v["expanded"], v["verdict"]) for v in record["values"]}
    assert printed == {
        "scale_factor_ppm": ("12.3", "0.52", None),
        "bias_deg_h": ("-0.041", "0.012", "pass"),
    }
    limited = [v for v in record["values"] if v["verdict"]]
    assert (limited[0]["limit_min"], limited[0]["limit_max"]) == ("-0.1", "0.1")
    shown = certificate_record(store, "RC-2026-0007")
    assert shown["conformity"] == [
        {"measurement": "Scale factor", "quantity": "bias_deg_h", "verdict": "pass",
         "limit_min": "-0.1", "limit_max": "0.1", "decision_rule": "simple"}
    ]  # fmt: skip
    assert shown["plan"]["text"] == plan.text.decode()
    assert shown["superseded_by"] is None


def test_issued_rows_refuse_update_and_delete_in_the_schema(store_url: str, issue) -> None:
    """Whatever program asks: the triggers refuse a change of every table of an issued record."""
    store = open_store(store_url)
    issue(store, VALUES, number="auto")
    store.void_number("RC-2026-0099", "test")
    with store.begin() as connection:
        tables = [t for t in m.IMMUTABLE_TABLES]
        counts = {
            t: connection.execute(sa.text(f"SELECT count(*) FROM {t}")).scalar() for t in tables
        }
    assert all(counts.values()), counts  # every table has a row to protect
    for table in tables:
        column = next(iter(sa.inspect(store.engine).get_columns(table)))["name"]
        for sql in (f"UPDATE {table} SET {column} = {column}", f"DELETE FROM {table}"):
            with pytest.raises(RecordImmutableError, match=r"immutable|append-only"):
                with store.begin() as connection:
                    connection.execute(sa.text(sql))
    if store.engine.dialect.name == "postgresql":
        for table in ("certificates", "audit_events"):
            with pytest.raises(RecordImmutableError):
                with store.begin() as connection:
                    connection.execute(sa.text(f"TRUNCATE {table} CASCADE"))
    with store.begin() as connection:
        after = {
            t: connection.execute(sa.text(f"SELECT count(*) FROM {t}")).scalar() for t in tables
        }
    assert after == counts


def test_the_code_refuses_a_change_before_the_database_sees_it(store_url: str, issue) -> None:
    store = open_store(store_url)
    issue(store, VALUES, number="RC-2026-0001")
    statements: list[str] = []
    sa.event.listen(store.engine, "before_cursor_execute", lambda *a: statements.append(a[2]))
    with Session(store.engine) as session:
        certificate = session.scalars(sa.select(m.Certificate)).one()
        certificate.title = "changed"
        statements.clear()
        with pytest.raises(RecordImmutableError):
            session.flush()
        session.rollback()
        session.delete(session.scalars(sa.select(m.Certificate)).one())
        with pytest.raises(RecordImmutableError):
            session.flush()
    assert not [s for s in statements if s.lstrip().upper().startswith(("UPDATE", "DELETE"))]


def test_a_correction_supersedes_and_both_stay(store_url: str, issue) -> None:
    store = open_store(store_url)
    issue(store, VALUES, number="auto")
    issue(store, VALUES, number="auto", supersedes="RC-2026-0001")
    assert certificate_record(store, "RC-2026-0001")["superseded_by"] == "RC-2026-0002"
    assert certificate_record(store, "RC-2026-0002")["supersedes"] == "RC-2026-0001"
    listed = list_certificates(store)
    assert [(r["number"], r["superseded_by"]) for r in listed] == [
        ("RC-2026-0002", None),
        ("RC-2026-0001", "RC-2026-0002"),
    ]
    again = make_plan(number="auto", supersedes="RC-2026-0001", text=b"third")
    with pytest.raises(
        ConfigError, match="already superseded by RC-2026-0002; supersede RC-2026-0002"
    ):
        store.check_plan(again)
    with pytest.raises(ConfigError, match="no certificate RC-1999-0001"):
        store.check_plan(make_plan(supersedes="RC-1999-0001"))


def test_numbers_are_never_issued_twice(store_url: str, issue) -> None:
    store = open_store(store_url)
    issue(store, VALUES, number="RC-2026-0002", text=b"explicit")
    with pytest.raises(ConfigError, match="RC-2026-0002 is already in the records"):
        store.check_plan(make_plan(number="RC-2026-0002", text=b"other"))
    drawn = [store.draw_number(dt.date(2026, 5, 1)) for _ in range(2)]
    assert drawn == ["RC-2026-0001", "RC-2026-0003"]  # 0002 was taken by the explicit plan
    store.void_number(drawn[0], "rendering failed")
    with pytest.raises(ConfigError, match=r"voided on .*\(rendering failed\)"):
        certificate_record(store, "RC-2026-0001")
    assert store.draw_number(dt.date(2027, 1, 1)) == "RC-2027-0001"  # a new year, a new count
    assert store.draw_number(dt.date(2026, 12, 31)) == "RC-2026-0004"


def test_a_plan_and_its_captures_are_certified_once(store_url: str, issue) -> None:
    store = open_store(store_url)
    first = issue(store, VALUES, number="auto")
    with pytest.raises(ConfigError, match="certified already as RC-2026-0001"):
        store.check_unissued(first.plan, first.plan_sha256)
    # and even past that check (two writers at once), the schema keeps one
    twin = make_content(VALUES, number="RC-2026-0002", plan_sha256=first.plan_sha256)
    with pytest.raises(StoreError, match="certified meanwhile"):
        with store.keep(twin, files_of(twin)):
            pass
    assert [r["number"] for r in list_certificates(store)] == ["RC-2026-0001"]


def test_a_failure_inside_keep_leaves_no_row(store_url: str) -> None:
    store = open_store(store_url)
    content = make_content(VALUES, number="RC-2026-0001")
    with pytest.raises(OSError, match="publishing failed"):
        with store.keep(content, files_of(content)):
            raise OSError("publishing failed")
    assert list_certificates(store) == []
    with store.begin() as connection:
        for table in m.IMMUTABLE_TABLES:
            assert connection.execute(sa.text(f"SELECT count(*) FROM {table}")).scalar() == 0


def test_the_number_series_is_the_laboratorys(store_url: str) -> None:
    store = open_store(store_url)
    assert store.settings() == {"number_format": "RC-{year}-{count:04d}", "interval_months": "12"}
    store.set_settings(number_format="LAB/{count:05d}", interval_months="6")
    assert store.draw_number(dt.date(2026, 1, 1)) == "LAB/00001"
    assert store.draw_number(dt.date(2027, 1, 1)) == "LAB/00002"  # no year: one count for all
    for bad in ("RC-{year}", "RC-{count}-{serial}", "RC-{count:q}"):
        with pytest.raises(ConfigError, match="number format"):
            store.set_settings(number_format=bad)
    for bad in ("0", "twelve", "241"):
        with pytest.raises(ConfigError, match="months"):
            store.set_settings(interval_months=bad)
    assert open_store(store_url).settings()["number_format"] == "LAB/{count:05d}"


def test_list_filters_by_serial_and_counts_verdicts(store_url: str, issue) -> None:
    store = open_store(store_url)
    issue(store, VALUES, number="auto", serial="A", limits={"bias_deg_h": ("", "0.1")})
    issue(store, VALUES, number="auto", serial="B", date=dt.date(2026, 11, 26))
    rows = list_certificates(store, "A")
    assert [r["number"] for r in rows] == ["RC-2026-0001"]
    assert rows[0]["conformity"] == {"pass": 1} and rows[0]["customer"] == "Gyro Maker Ltd"
    assert [r["item"]["serial"] for r in list_certificates(store)] == ["B", "A"]  # newest first


def test_readers_neither_wait_for_a_writer_nor_hold_it_up(tmp_path, issue) -> None:
    """SQLite: a writer holds the write lock; reading the records still answers at once (WAL
    snapshot), and a second writer is refused after its timeout with one line."""
    import sqlite3

    url = f"sqlite:///{tmp_path / 'records.sqlite'}"
    store = open_store(url, timeout_s=0.5)
    issue(store, VALUES, number="auto")
    writer = sqlite3.connect(tmp_path / "records.sqlite", isolation_level=None)
    writer.execute("BEGIN IMMEDIATE")
    try:
        assert [r["number"] for r in list_certificates(store)] == ["RC-2026-0001"]
        assert certificate_record(store, "RC-2026-0001")["number"] == "RC-2026-0001"
        with pytest.raises(StoreError, match=r"locked by another program \(waited 0.5 s\)"):
            store.draw_number(dt.date(2026, 11, 25))
    finally:
        writer.execute("ROLLBACK")
        writer.close()
    assert store.draw_number(dt.date(2026, 11, 25)) == "RC-2026-0002"
