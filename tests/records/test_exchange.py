"""Export and import: a store moved between engines comes out byte for byte the same; an import
is all of the file or nothing, and a damaged file is named by line."""

from __future__ import annotations

import datetime as dt
import io
import json
from pathlib import Path

import pytest

from rotacal.errors import ConfigError, StoreError
from rotacal.records import open_store
from rotacal.records.exchange import export_lines, import_lines
from rotacal.records.query import audit_trail, list_certificates

VALUES = {"scale_factor_ppm": ("12.3", "0.52"), "bias_deg_h": ("-0.041", "0.012")}


@pytest.fixture
def source(tmp_path: Path, issue) -> str:
    """An SQLite store with two items, a correction, a voided number and its own settings."""
    url = f"sqlite:///{tmp_path / 'source.sqlite'}"
    store = open_store(url)
    store.set_settings(interval_months="6")
    issue(store, VALUES, number="auto", limits={"bias_deg_h": ("-0.1", "0.1")})
    store.void_number(store.draw_number(dt.date(2026, 11, 25)), "rendering failed: ünïcode")
    issue(store, VALUES, number="auto", supersedes="RC-2026-0001")
    issue(store, VALUES, number="auto", serial="SN-0002", date=dt.date(2027, 2, 3))
    return url


def _export(url: str) -> str:
    return "".join(export_lines(open_store(url)))


def test_a_store_moves_to_either_engine_without_loss(source: str, store_url: str) -> None:
    text = _export(source)
    summary = import_lines(open_store(store_url), io.StringIO(text), "backup.jsonl")
    assert summary == {"imported": 3, "unchanged": 0, "warnings": []}
    assert _export(store_url) == text
    target = open_store(store_url)
    assert target.settings()["interval_months"] == "6"
    # the series goes on where it was: the voided 0002 is not drawn again either
    assert target.draw_number(dt.date(2026, 12, 1)) == "RC-2026-0004"
    lines = [json.loads(line) for line in text.splitlines()]
    assert [line["type"] for line in lines] == [
        "rotacal-records", "setting", "counter", "counter", "voided",
        "certificate", "certificate", "certificate", *["audit"] * 9,
    ]  # fmt: skip
    assert lines[4]["reason"] == "rendering failed: ünïcode"


def test_importing_twice_changes_nothing(source: str, store_url: str) -> None:
    text = _export(source)
    store = open_store(store_url)
    import_lines(store, io.StringIO(text), "b.jsonl")
    again = import_lines(store, io.StringIO(text), "b.jsonl")
    assert again["imported"] == 0 and again["unchanged"] == 3
    assert _export(store_url) == text


def test_a_differing_certificate_stops_the_whole_import(source: str, store_url: str, issue) -> None:
    store = open_store(store_url)
    issue(store, {"scale_factor_ppm": ("99", "1")}, number="RC-2026-0003", text=b"other")
    before = _export(store_url)
    with pytest.raises(StoreError, match="line 7: certificate RC-2026-0003 differs"):
        import_lines(store, io.StringIO(_export(source)), "b.jsonl")
    assert _export(store_url) == before
    assert [r["number"] for r in list_certificates(store)] == ["RC-2026-0003"]


def _damage(text: str, line: int, change) -> str:
    lines = text.splitlines(keepends=True)
    obj = json.loads(lines[line - 1])
    change(obj)
    lines[line - 1] = json.dumps(obj) + "\n"
    return "".join(lines)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda o: o["files"][0].update(content="AAAA" + o["files"][0]["content"][4:]),
         "line 6: certificate RC-2026-0001: certificate.pdf does not match its SHA-256"),
        (lambda o: o["inputs"][0].update(sha256="cd" * 32),
         "line 6: certificate RC-2026-0001: plan_sha256 does not match its plan and inputs"),
        (lambda o: o.pop("values"), "line 6: a certificate without values"),
        (lambda o: o.update(type="invoice"), "line 6: unknown record type 'invoice'"),
    ],
)  # fmt: skip
def test_a_damaged_export_is_refused_by_line(source: str, tmp_path: Path, change, message) -> None:
    text = _damage(_export(source), 6, change)
    target = open_store(f"sqlite:///{tmp_path / 'target.sqlite'}")
    with pytest.raises(ConfigError, match=message.replace("(", r"\(").replace(")", r"\)")):
        import_lines(target, io.StringIO(text), "b.jsonl")
    assert list_certificates(target) == []


def test_a_file_that_is_not_an_export_is_named(tmp_path: Path) -> None:
    target = open_store(f"sqlite:///{tmp_path / 'target.sqlite'}")
    with pytest.raises(ConfigError, match=r"b\.jsonl line 1: not a rotacal records export"):
        import_lines(target, io.StringIO('{"type": "something"}\n'), "b.jsonl")
    with pytest.raises(ConfigError, match=r"b\.jsonl line 2: not JSON"):
        header = '{"type": "rotacal-records", "version": 1}\n'
        import_lines(target, io.StringIO(header + "{oops\n"), "b.jsonl")
    with pytest.raises(ConfigError, match=r"b\.jsonl: empty"):
        import_lines(target, io.StringIO(""), "b.jsonl")


def test_the_audit_trail_travels_whole_and_a_changed_event_is_refused(
    source: str, tmp_path: Path
) -> None:
    text = _export(source)
    lines = text.splitlines(keepends=True)
    audit = [i for i, line in enumerate(lines) if json.loads(line)["type"] == "audit"]
    forged = json.loads(lines[audit[1]])
    forged["who"] = "Mallory"  # the issue of RC-2026-0001, approved by someone else
    changed = [*lines[: audit[1]], json.dumps(forged) + "\n", *lines[audit[1] + 1 :]]
    target = open_store(f"sqlite:///{tmp_path / 't.sqlite'}")
    with pytest.raises(StoreError, match=r"RC-2026-0001 event 2 .*does not match its hash"):
        import_lines(target, io.StringIO("".join(changed)), "forged.jsonl")
    assert list_certificates(target) == []  # all or nothing
    # an export made before the audit trail (version 1): its events are reconstructed
    old = [line for i, line in enumerate(lines) if i not in audit]
    old[0] = old[0].replace('"version":2', '"version":1')
    import_lines(target, io.StringIO("".join(old)), "v1.jsonl")
    trail = audit_trail(target)
    assert trail["intact"], trail["problems"]
    assert len(trail["events"]) == 9
    assert all("reconstructed on import of v1.jsonl" in e["reason"] for e in trail["events"])
    # a chain that is not the beginning of the store's (here: other events) is refused
    with pytest.raises(StoreError, match=r"audit trail of RC-2026-0001 differs"):
        import_lines(target, io.StringIO(text), "backup.jsonl")
