"""One certificate's record in one form — the form the store writes, ``records show`` reads and
``records export``/``import`` carry — so that a record survives every round trip unchanged.

A record is a plain dict (JSON-able but for the ``bytes`` of the plan and of the files):

``number``, ``title``, ``laboratory``/``customer`` (contact dicts), ``start_date``, ``end_date``,
``issue_date`` (ISO dates), ``item`` ({kind, manufacturer, model, serial}), ``plan_name``,
``plan`` (the plan file's bytes), ``plan_sha256``, ``results`` (results.json as issued, text),
``software_version``, ``supersedes``, ``recorded_at`` (ISO, UTC), ``recorded_by``, ``persons``
({name, title, role}), ``standards`` ({id, name, certificate, due}), ``inputs`` ({measurement, path,
sha256, bytes}), ``files`` ({name, sha256, content}), ``values`` (one per reported quantity, as
printed, with its conformity statement: the columns of :class:`~rotacal.records.models.ReportedValue`).
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import getpass
import hashlib
import json
import socket
from collections.abc import Mapping
from typing import Any, cast

import sqlalchemy as sa
from sqlalchemy.dialects import postgresql, sqlite

from rotacal.certificate.content import CertificateContent

from . import models as m

__all__ = [
    "id_of",
    "insert_for",
    "insert_record",
    "read_record",
    "record_of",
    "station",
    "utc_text",
]

#: The columns of a reported value a record carries (all but the certificate's id).
VALUE_COLUMNS = tuple(
    c.name for c in m.ReportedValue.__table__.columns if c.name != "certificate_id"
)


def _table(model: type[m.Base]) -> sa.Table:
    return cast(sa.Table, model.__table__)


def station() -> str:
    """Who records: user@computer (the test station), as far as the system tells."""
    try:
        user = getpass.getuser()
    except (KeyError, OSError):  # no name for this user id (a container)
        user = "?"
    return f"{user}@{socket.gethostname()}"[:256]


def _contact(contact: Any) -> dict[str, Any]:
    return {k: v for k, v in dataclasses.asdict(contact).items() if v}


def utc_text(moment: dt.datetime) -> str:
    """A moment as ISO text in UTC (SQLite hands back naive datetimes: they were stored in UTC)."""
    if moment.tzinfo is None:
        moment = moment.replace(tzinfo=dt.timezone.utc)
    return moment.astimezone(dt.timezone.utc).isoformat()


def record_of(
    content: CertificateContent,
    files: Mapping[str, bytes],
    *,
    recorded_at: dt.datetime | None = None,
) -> dict[str, Any]:
    """The record of a certificate being issued: what it states (``content``, with its final
    number), every file of its folder (``files``: name → bytes) and when it is recorded
    (``recorded_at``, timezone-aware; default now)."""
    plan = content.plan
    values = []
    for mr in content.measurements:
        statements = {c.key: c for c in mr.conformity}
        for position, q in enumerate(mr.quantities):
            c = statements.get(q.key)
            values.append(
                {
                    "measurement": mr.index,
                    "position": position,
                    "measurement_name": mr.name,
                    "command": mr.command,
                    "quantity": q.key,
                    "name": q.name,
                    "unit": q.unit,
                    "value": q.value,
                    "expanded": q.U,
                    "coverage_factor": q.k,
                    "coverage_probability": q.p,
                    "interval_low": q.interval[0] if q.interval else None,
                    "interval_high": q.interval[1] if q.interval else None,
                    "limit_min": (c.limit_min or None) if c else None,
                    "limit_max": (c.limit_max or None) if c else None,
                    "decision_rule": c.decision_rule if c else None,
                    "verdict": c.verdict if c else None,
                }
            )
    item = plan.item
    return {
        "number": content.number,
        "title": plan.title,
        "laboratory": _contact(plan.laboratory),
        "customer": _contact(plan.customer),
        "start_date": plan.start_date.isoformat(),
        "end_date": plan.end_date.isoformat(),
        "issue_date": plan.issue_date.isoformat(),
        "item": {
            "kind": item.kind,
            "manufacturer": item.manufacturer,
            "model": item.model,
            "serial": item.serial,
        },
        "plan_name": plan.path.name,
        "plan": plan.text,
        "plan_sha256": content.plan_sha256,
        "results": files["results.json"].decode("utf-8"),
        "software_version": content.software_version,
        "supersedes": plan.supersedes,
        "recorded_at": utc_text(recorded_at or dt.datetime.now(dt.timezone.utc)),
        "recorded_by": station(),
        "persons": [{"name": p.name, "title": p.title, "role": p.role} for p in plan.persons],
        "standards": [
            {"id": s.id, "name": s.name, "certificate": s.certificate, "due": s.due.isoformat()}
            for s in plan.standards
        ],
        "inputs": [
            {"measurement": mr.index, "path": c.path, "sha256": c.sha256, "bytes": c.bytes}
            for mr in content.measurements
            for c in mr.captures
        ],
        "files": [
            {"name": name, "sha256": hashlib.sha256(data).hexdigest(), "content": data}
            for name, data in sorted(files.items())
        ],
        "values": values,
    }


def insert_for(connection: sa.Connection) -> Any:
    return postgresql.insert if connection.dialect.name == "postgresql" else sqlite.insert


def id_of(connection: sa.Connection, model: type[m.Base], values: Mapping[str, Any]) -> int:
    """The id of the row of ``model`` with ``values`` (all of its unique key), inserted when
    absent — safe when other writers insert the same row at the same time."""
    table = _table(model)
    connection.execute(insert_for(connection)(table).values(**values).on_conflict_do_nothing())
    where = [table.c[k] == v for k, v in values.items()]
    return int(connection.execute(sa.select(table.c.id).where(*where)).scalar_one())


def insert_record(connection: sa.Connection, record: Mapping[str, Any]) -> int:
    """Write ``record`` (the form of :func:`record_of`) in the caller's transaction; returns the
    certificate's id."""
    date = dt.date.fromisoformat
    people = [{"name": p["name"], "title": p["title"]} for p in record["persons"]]
    standards_used = [
        {"identifier": s["id"], "name": s["name"], "certificate": s["certificate"],
         "due": date(s["due"])}
        for s in record["standards"]
    ]  # fmt: skip
    # Shared rows are inserted in one global order (sorted by their key), whatever order the
    # plan names them in: two writers naming the same new persons in opposite orders would
    # otherwise each wait for the other's row (a deadlock on PostgreSQL).
    insert = insert_for(connection)
    shared: tuple[tuple[type[m.Base], list[dict[str, Any]]], ...] = (
        (m.Person, people),
        (m.Standard, standards_used),
    )
    for shared_model, shared_rows in shared:
        for row in sorted(shared_rows, key=lambda r: tuple(str(v) for v in r.values())):
            statement = insert(_table(shared_model)).values(**row)
            connection.execute(statement.on_conflict_do_nothing())
    item_id = id_of(connection, m.Item, record["item"])
    certificate_id = connection.execute(
        sa.insert(m.Certificate)
        .values(
            number=record["number"],
            item_id=item_id,
            title=record["title"],
            laboratory=json.dumps(record["laboratory"], ensure_ascii=False),
            customer=json.dumps(record["customer"], ensure_ascii=False),
            start_date=date(record["start_date"]),
            end_date=date(record["end_date"]),
            issue_date=date(record["issue_date"]),
            plan_name=record["plan_name"],
            plan=record["plan"],
            plan_sha256=record["plan_sha256"],
            results=record["results"],
            software_version=record["software_version"],
            supersedes=record["supersedes"],
            recorded_at=dt.datetime.fromisoformat(record["recorded_at"]),
            recorded_by=record["recorded_by"],
        )
        .returning(m.Certificate.id)
    ).scalar_one()
    persons = [
        {"position": i, "person_id": id_of(connection, m.Person, person), "role": p["role"]}
        for i, (p, person) in enumerate(zip(record["persons"], people, strict=True))
    ]
    standards = [
        {"position": i, "standard_id": id_of(connection, m.Standard, standard)}
        for i, standard in enumerate(standards_used)
    ]
    inputs = [
        {
            "position": i,
            "measurement": c["measurement"],
            "path": c["path"],
            "sha256": c["sha256"],
            "size_bytes": c["bytes"],
        }
        for i, c in enumerate(record["inputs"])
    ]
    files = [{k: f[k] for k in ("name", "sha256", "content")} for f in record["files"]]
    values = [{k: v[k] for k in VALUE_COLUMNS} for v in record["values"]]
    for model, rows in (
        (m.CertificatePerson, persons),
        (m.CertificateStandard, standards),
        (m.CertificateInput, inputs),
        (m.CertificateFile, files),
        (m.ReportedValue, values),
    ):
        if rows:
            connection.execute(
                sa.insert(model), [{"certificate_id": certificate_id, **r} for r in rows]
            )
    return int(certificate_id)


def _rows(connection: sa.Connection, model: type[m.Base], certificate_id: int) -> list[Any]:
    table = _table(model)
    order = [c for c in table.primary_key.columns if c.name != "certificate_id"]
    return list(
        connection.execute(
            sa.select(table).where(table.c.certificate_id == certificate_id).order_by(*order)
        ).mappings()
    )


def read_record(connection: sa.Connection, number: str) -> dict[str, Any] | None:
    """The record of certificate ``number`` as :func:`record_of` made it (None: no such
    certificate)."""
    c = (
        connection.execute(sa.select(_table(m.Certificate)).where(m.Certificate.number == number))
        .mappings()
        .first()
    )
    if c is None:
        return None
    item = connection.execute(
        sa.select(m.Item.kind, m.Item.manufacturer, m.Item.model, m.Item.serial).where(
            m.Item.id == c["item_id"]
        )
    ).one()
    persons = connection.execute(
        sa.select(m.Person.name, m.Person.title, m.CertificatePerson.role)
        .join(m.CertificatePerson, m.CertificatePerson.person_id == m.Person.id)
        .where(m.CertificatePerson.certificate_id == c["id"])
        .order_by(m.CertificatePerson.position)
    ).all()
    standards = connection.execute(
        sa.select(m.Standard.identifier, m.Standard.name, m.Standard.certificate, m.Standard.due)
        .join(m.CertificateStandard, m.CertificateStandard.standard_id == m.Standard.id)
        .where(m.CertificateStandard.certificate_id == c["id"])
        .order_by(m.CertificateStandard.position)
    ).all()
    return {
        "number": c["number"],
        "title": c["title"],
        "laboratory": json.loads(c["laboratory"]),
        "customer": json.loads(c["customer"]),
        "start_date": c["start_date"].isoformat(),
        "end_date": c["end_date"].isoformat(),
        "issue_date": c["issue_date"].isoformat(),
        "item": dict(item._mapping),
        "plan_name": c["plan_name"],
        "plan": bytes(c["plan"]),
        "plan_sha256": c["plan_sha256"],
        "results": c["results"],
        "software_version": c["software_version"],
        "supersedes": c["supersedes"],
        "recorded_at": utc_text(c["recorded_at"]),
        "recorded_by": c["recorded_by"],
        "persons": [{"name": n, "title": t, "role": r} for n, t, r in persons],
        "standards": [
            {"id": i, "name": n, "certificate": cert, "due": due.isoformat()}
            for i, n, cert, due in standards
        ],
        "inputs": [
            {
                "measurement": r["measurement"],
                "path": r["path"],
                "sha256": r["sha256"],
                "bytes": r["size_bytes"],
            }
            for r in _rows(connection, m.CertificateInput, c["id"])
        ],
        "files": [
            {"name": r["name"], "sha256": r["sha256"], "content": bytes(r["content"])}
            for r in _rows(connection, m.CertificateFile, c["id"])
        ],
        "values": [
            {k: r[k] for k in VALUE_COLUMNS} for r in _rows(connection, m.ReportedValue, c["id"])
        ],
    }
