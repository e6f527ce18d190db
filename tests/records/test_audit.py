"""The audit trail on both engines: every state change is an event written with it, chained by
SHA-256; the database refuses to change or remove an event; a chain changed behind the
triggers' back is found and the event named; no issued event without an issued record."""

from __future__ import annotations

import dataclasses
import datetime as dt
import hashlib
import json
from pathlib import Path

import pytest
import sqlalchemy as sa
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.errors import ConfigError, RecordImmutableError
from rotacal.plan.model import Person
from rotacal.records import open_store
from rotacal.records.query import audit_trail, certificate_record
from rotacal.records.record import station

from .conftest import files_of, make_content

VALUES = {"scale_factor_ppm": ("12.3", "0.52")}
T0 = dt.datetime(2026, 11, 25, 14, 0, 0, 250000, tzinfo=dt.timezone.utc)


def _clock(start: dt.datetime = T0):
    """A clock that advances one minute per reading (reproducible records and events)."""
    ticks = iter(range(10**6))
    return lambda: start + dt.timedelta(minutes=next(ticks))


def _sha(event: dict) -> str:
    """The hash as the documentation states it, written out here (not the store's function)."""
    content = {k: v for k, v in event.items() if k != "hash"} | {"form": 1}
    text = json.dumps(content, ensure_ascii=False, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def test_issue_supersede_and_a_failed_issue_are_events_of_one_chain_each(
    store_url: str, issue
) -> None:
    store = open_store(store_url, clock=_clock())
    first = issue(store, VALUES, number="auto")  # draft at 14:00, issued 14:01
    store.void_number(store.draw_number(first.plan.issue_date), "pdf failed")  # 14:02, 14:03
    issue(store, VALUES, number="RC-2026-0100", supersedes="RC-2026-0001")  # 14:04
    trail = audit_trail(store)
    assert trail["intact"], trail["problems"]
    got = [
        (e["number"], e["seq"], e["from_state"], e["to_state"], e["who"], e["at"][11:16])
        for e in trail["events"]
    ]
    here = station()
    assert got == [
        ("RC-2026-0001", 1, None, "draft", here, "14:00"),  # drawn by the API: the station
        ("RC-2026-0001", 2, "draft", "issued", "B. Manager", "14:01"),
        ("RC-2026-0001", 3, "issued", "superseded", "B. Manager", "14:04"),
        ("RC-2026-0002", 1, None, "draft", here, "14:02"),
        ("RC-2026-0002", 2, "draft", "voided", here, "14:03"),
        ("RC-2026-0100", 1, None, "draft", "A. Operator", "14:04"),
        ("RC-2026-0100", 2, "draft", "issued", "B. Manager", "14:04"),
    ]
    # supersession: the old certificate's event and the new one's issue in one transaction
    assert trail["events"][2]["reason"] == "superseded by RC-2026-0100"
    chains: dict[str, str] = {}
    for event in trail["events"]:
        assert event["prev_hash"] == chains.get(event["number"], "0" * 64)
        assert event["hash"] == _sha(event)
        chains[event["number"]] = event["hash"]
    record = certificate_record(store, "RC-2026-0001")
    assert (record["approved_by"], record["approved_at"]) == (
        "B. Manager",
        "2026-11-25T14:01:00.250000+00:00",
    )
    assert record["recorded_at"] == record["approved_at"]  # one clock, one transaction
    assert [e["to_state"] for e in record["audit"]] == ["draft", "issued", "superseded"]
    assert record["audit_intact"] is True
    # an issue that fails (publishing its folder): rolled back, no issued event; then voided
    content = make_content(VALUES, number="auto")
    number = store.draw_number(content.plan.issue_date, plan=content.plan)
    content = dataclasses.replace(content, number=number)
    with pytest.raises(OSError, match="disk full"):
        with store.keep(content, files_of(content)):
            raise OSError("disk full")
    store.void_number(number, "not issued: OSError: disk full")
    trail = audit_trail(store, number)
    assert trail["intact"], trail["problems"]
    assert [(e["to_state"], e["who"], e["reason"]) for e in trail["events"]] == [
        ("draft", "A. Operator", "measured; number drawn from the series"),
        ("voided", here, "not issued: OSError: disk full"),
    ]


def test_the_database_refuses_to_change_an_event_and_a_change_behind_its_back_is_found(
    store_url: str, issue
) -> None:
    store = open_store(store_url, clock=_clock())
    issue(store, VALUES, number="RC-2026-0001")
    issue(store, VALUES, number="RC-2026-0002")
    for sql in ("UPDATE audit_events SET who = 'Mallory'", "DELETE FROM audit_events"):
        with pytest.raises(RecordImmutableError, match="append-only"):
            with store.begin() as connection:
                connection.execute(sa.text(sql))
    # someone with the database owner's rights switches the triggers off and rewrites history
    postgres = store.engine.dialect.name == "postgresql"
    with store.begin() as connection:
        if postgres:
            connection.execute(sa.text("ALTER TABLE audit_events DISABLE TRIGGER USER"))
        else:
            connection.execute(sa.text("DROP TRIGGER audit_events_no_update"))
            connection.execute(sa.text("DROP TRIGGER audit_events_no_delete"))
        connection.execute(
            sa.text(
                "UPDATE audit_events SET who = 'Mallory' "
                "WHERE number = 'RC-2026-0001' AND to_state = 'issued'"
            )
        )
        connection.execute(sa.text("DELETE FROM audit_events WHERE number = 'RC-2026-0002'"))
    trail = audit_trail(store)
    assert not trail["intact"]
    assert trail["problems"][0].startswith("RC-2026-0001 event 2 (draft → issued, 2026-11-25T")
    assert "does not match its hash" in trail["problems"][0]
    assert any(
        p.startswith("RC-2026-0002: the records say issued, but its trail has no issued event")
        for p in trail["problems"]
    )
    result = CliRunner().invoke(cli, ["records", "audit", "RC-2026-0001", "--db", store_url])
    assert result.exit_code == 1
    assert "audit trail broken: RC-2026-0001 event 2" in result.output
    shown = certificate_record(store, "RC-2026-0001")
    assert shown["audit_intact"] is False and shown["approved_by"] == "Mallory"


def test_a_plan_without_an_approver_or_approved_by_its_performer_is_not_kept(
    tmp_path: Path,
) -> None:
    store = open_store(f"sqlite:///{tmp_path / 'records.sqlite'}")  # refused before any SQL
    for persons, needle in (
        (
            (Person("A. Operator", "performed"),),
            r'person: needs a \[\[person\]\] with role = "approved"',
        ),
        (
            (Person("A. Operator", "performed"), Person("a. operator", "approved")),
            r"person\[2\]: a. operator both performed the calibration and approves it",
        ),
    ):
        content = make_content(VALUES, number="RC-2026-0001")
        content = dataclasses.replace(
            content, plan=dataclasses.replace(content.plan, persons=persons)
        )
        with pytest.raises(ConfigError, match=r"plan.toml: " + needle):
            store.check_plan(content.plan)
        with pytest.raises(ConfigError, match=needle):
            with store.keep(content, files_of(content)):
                pass
    assert audit_trail(store)["events"] == []
