"""Reading the records: the certificates issued (``records list``), one certificate's whole
record (``records show``), with the supersession both ways and its audit trail, and the audit
trail checked (``records audit``)."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from collections import Counter
from pathlib import Path
from typing import Any

import sqlalchemy as sa

from rotacal.errors import ConfigError

from . import models as m
from .audit import approval_of, check_trail
from .record import read_record, utc_text
from .store import Store

__all__ = ["audit_trail", "certificate_record", "list_certificates", "restore_files"]


def list_certificates(store: Store, serial: str | None = None) -> list[dict[str, Any]]:
    """The certificates issued, newest first (by date of issue, then by the order of recording):
    each ``number``, ``issue_date``, ``calibration_date``, ``item``, ``customer``,
    ``conformity`` (verdict → count), ``supersedes``, ``superseded_by``. ``serial`` keeps those of
    items with that serial number."""
    c, i, v = m.Certificate, m.Item, m.ReportedValue
    query = (
        sa.select(
            c.id,
            c.number,
            c.issue_date,
            c.end_date,
            c.customer,
            c.supersedes,
            c.recorded_at,
            i.kind,
            i.manufacturer,
            i.model,
            i.serial,
        )
        .join(i, i.id == c.item_id)
        .order_by(c.issue_date.desc(), c.id.desc())
    )
    if serial is not None:
        query = query.where(i.serial == serial)
    with store.begin(read_only=True) as connection:
        rows = connection.execute(query).all()
        verdicts = connection.execute(
            sa.select(v.certificate_id, v.verdict).where(v.verdict.is_not(None))
        ).all()
        successors = dict(
            connection.execute(
                sa.select(c.supersedes, c.number).where(c.supersedes.is_not(None))
            ).all()
        )
    tally: dict[int, Counter[str]] = {}
    for certificate_id, verdict in verdicts:
        tally.setdefault(certificate_id, Counter())[str(verdict)] += 1
    return [
        {
            "number": r.number,
            "issue_date": r.issue_date.isoformat(),
            "calibration_date": r.end_date.isoformat(),
            "item": {
                "kind": r.kind,
                "manufacturer": r.manufacturer,
                "model": r.model,
                "serial": r.serial,
            },
            "customer": json.loads(r.customer).get("name", ""),
            "conformity": dict(sorted(tally.get(r.id, Counter()).items())),
            "supersedes": r.supersedes,
            "superseded_by": successors.get(r.number),
            "recorded_at": utc_text(r.recorded_at),
        }
        for r in rows
    ]


def _missing(store: Store, connection: sa.Connection, number: str) -> ConfigError:
    voided = connection.execute(
        sa.select(m.VoidedNumber.voided_at, m.VoidedNumber.reason).where(
            m.VoidedNumber.number == number
        )
    ).first()
    if voided is not None:
        return ConfigError(
            f"{number} was drawn and voided on {utc_text(voided.voided_at)[:10]} ({voided.reason});"
            f" no certificate bears it ({store.shown})"
        )
    return ConfigError(
        f"no certificate {number} in the records ({store.shown}); `rotacal records list` lists them"
    )


def _raw_record(store: Store, number: str) -> dict[str, Any]:
    with store.begin(read_only=True) as connection:
        record = read_record(connection, number)
        if record is None:
            raise _missing(store, connection, number)
        record["superseded_by"] = connection.execute(
            sa.select(m.Certificate.number).where(m.Certificate.supersedes == number)
        ).scalar()
        trail = check_trail(connection, number)
    record["approved_by"], record["approved_at"] = approval_of(trail["events"])
    record["audit"] = trail["events"]
    record["audit_intact"] = trail["intact"]
    record["audit_problems"] = trail["problems"]
    return record


def certificate_record(store: Store, number: str) -> dict[str, Any]:
    """Certificate ``number``'s record for a reader (``records show``): what the record holds,
    with the plan as text, ``results`` as the JSON object it is, ``conformity`` (each
    ``measurement``, ``quantity``, ``verdict``, limits and decision rule), the files by name with
    SHA-256 and size (``restore_files`` gives their bytes), ``superseded_by``, who approved it
    and when (``approved_by``, ``approved_at``: UTC), and its audit trail (``audit``: the events of
    :mod:`rotacal.records.audit`, checked: ``audit_intact``, ``audit_problems``)."""
    record = _raw_record(store, number)
    plan: bytes = record.pop("plan")
    values = record.pop("values")
    files = record.pop("files")
    record["plan"] = {
        "name": record.pop("plan_name"),
        "sha256": hashlib.sha256(plan).hexdigest(),
        "text": plan.decode("utf-8", errors="replace"),
    }
    record["results"] = json.loads(record["results"])
    record["conformity"] = [
        {
            "measurement": v["measurement_name"],
            "quantity": v["quantity"],
            "verdict": v["verdict"],
            "limit_min": v["limit_min"],
            "limit_max": v["limit_max"],
            "decision_rule": v["decision_rule"],
        }
        for v in values
        if v["verdict"] is not None
    ]
    record["files"] = [
        {"name": f["name"], "sha256": f["sha256"], "bytes": len(f["content"])} for f in files
    ]
    return record


def audit_trail(store: Store, number: str | None = None) -> dict[str, Any]:
    """The audit trail of certificate ``number`` (of the whole store when None), checked
    (``records audit``): ``store``, ``number``, ``events``, ``intact`` and ``problems``
    (:func:`rotacal.records.audit.check_trail`).

    Raises
    ------
    ConfigError
        ``number`` was never drawn, issued or voided in this store.
    """
    with store.begin(read_only=True) as connection:
        trail = check_trail(connection, number)
        if number is not None and not trail["events"] and not trail["problems"]:
            raise _missing(store, connection, number)
    return {"store": store.shown, "number": number, **trail}


def restore_files(store: Store, number: str, folder: Path) -> list[Path]:
    """Write certificate ``number``'s folder as issued to ``folder`` (which must not exist),
    each file checked against the SHA-256 recorded with it; the folder appears whole or not at
    all. Returns the files written."""
    record = _raw_record(store, number)
    folder = folder.resolve()
    if folder.exists():
        raise ConfigError(
            f"--files {folder}: exists; give a new folder for the certificate's files"
        )
    if not folder.parent.is_dir():
        raise ConfigError(f"--files {folder}: the folder {folder.parent} does not exist")
    for f in record["files"]:
        if hashlib.sha256(f["content"]).hexdigest() != f["sha256"]:
            raise ConfigError(
                f"{number}: the stored {f['name']} does not match its SHA-256; the store is "
                "damaged — restore it from an export"
            )
    staging = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", dir=folder.parent))
    try:
        for f in record["files"]:
            (staging / f["name"]).write_bytes(f["content"])
        os.rename(staging, folder)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return [folder / f["name"] for f in record["files"]]
