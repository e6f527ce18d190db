"""The tables of the records store (SQLAlchemy 2 declarative models).

What a laboratory must keep of every calibration (ISO/IEC 17025:2017 §7.5 technical records, §7.8
reports, §8.4 control of records): the item, the reference standards with their certificates and
due dates, the persons, and the certificate itself — its number, dates, the plan as given, the
hash that ties it to its plan and captures (``plan_sha256``), each capture's SHA-256, the results,
the conformity statements, every file of the certificate folder (PDF, DCC XML, results.json,
figures) with its SHA-256, the software version and the certificate it supersedes.

Every change of a certificate's state (draft → issued → superseded, or draft → voided) is an
:class:`AuditEvent`, appended in the transaction of the change and chained by SHA-256
(:mod:`rotacal.records.audit`); the audit trail is append-only like the issued rows.

Issued rows are never changed: the migrations put triggers on every table of an issued record that
refuse UPDATE and DELETE (``IMMUTABLE_TABLES``), and :mod:`rotacal.records.store` refuses such
changes before they reach the database. The schema is made and changed only by the Alembic
migrations in ``migrations/versions``; a test checks that they give exactly these models.
"""

from __future__ import annotations

import datetime as dt

import sqlalchemy as sa
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column, relationship

__all__ = [
    "IMMUTABLE_TABLES",
    "AuditEvent",
    "Base",
    "Certificate",
    "CertificateFile",
    "CertificateInput",
    "CertificatePerson",
    "CertificateStandard",
    "Counter",
    "Item",
    "Person",
    "ReportedValue",
    "Setting",
    "Standard",
    "VoidedNumber",
]


class Base(DeclarativeBase):
    # Named constraints, so that the migrations can name what they change on both engines.
    metadata = sa.MetaData(
        naming_convention={
            "ix": "ix_%(table_name)s_%(column_0_name)s",
            "uq": "uq_%(table_name)s_%(column_0_N_name)s",
            "fk": "fk_%(table_name)s_%(column_0_name)s",
            "pk": "pk_%(table_name)s",
        }
    )


#: Decimal text as printed on a certificate (ILAC-P14 rounded): kept as text, never as a float,
#: so that the record says exactly what the certificate said.
_DECIMAL = sa.String(64)


class Setting(Base):
    """A laboratory-wide setting (``number_format``, ``interval_months``)."""

    __tablename__ = "settings"
    key: Mapped[str] = mapped_column(sa.String(64), primary_key=True)
    value: Mapped[str] = mapped_column(sa.Text)


class Counter(Base):
    """The last count drawn in one scope of the number series: a year ("2026"), or "*" for a
    format without a year."""

    __tablename__ = "number_counters"
    scope: Mapped[str] = mapped_column(sa.String(16), primary_key=True)
    last: Mapped[int] = mapped_column(sa.Integer)


class VoidedNumber(Base):
    """A number drawn for a certificate that was then not issued (its rendering failed): never
    drawn again, and kept with the reason so that a gap in the series is explained."""

    __tablename__ = "voided_numbers"
    number: Mapped[str] = mapped_column(sa.String(128), primary_key=True)
    voided_at: Mapped[dt.datetime] = mapped_column(sa.DateTime(timezone=True))
    reason: Mapped[str] = mapped_column(sa.Text)


class Item(Base):
    """An item calibrated: its kind, manufacturer, model and serial number."""

    __tablename__ = "items"
    __table_args__ = (sa.UniqueConstraint("kind", "manufacturer", "model", "serial"),)
    id: Mapped[int] = mapped_column(primary_key=True)
    kind: Mapped[str] = mapped_column(sa.String(64))
    manufacturer: Mapped[str] = mapped_column(sa.String(256))
    model: Mapped[str] = mapped_column(sa.String(256))
    serial: Mapped[str] = mapped_column(sa.String(256), index=True)


class Person(Base):
    """A person named on certificates (who performed, who approved)."""

    __tablename__ = "persons"
    __table_args__ = (sa.UniqueConstraint("name", "title"),)
    id: Mapped[int] = mapped_column(primary_key=True)
    name: Mapped[str] = mapped_column(sa.String(256))
    title: Mapped[str] = mapped_column(sa.String(256))


class Standard(Base):
    """A reference standard as used: its identifier, the certificate that makes it traceable and
    that certificate's due date (a standard recalibrated is a new row)."""

    __tablename__ = "standards"
    __table_args__ = (sa.UniqueConstraint("identifier", "name", "certificate", "due"),)
    id: Mapped[int] = mapped_column(primary_key=True)
    identifier: Mapped[str] = mapped_column(sa.String(256), index=True)
    name: Mapped[str] = mapped_column(sa.String(256))
    certificate: Mapped[str] = mapped_column(sa.String(256))
    due: Mapped[dt.date] = mapped_column(sa.Date)


class Certificate(Base):
    """An issued certificate: what it says, what it was made from, and its files."""

    __tablename__ = "certificates"
    id: Mapped[int] = mapped_column(primary_key=True)
    number: Mapped[str] = mapped_column(sa.String(128), unique=True)
    item_id: Mapped[int] = mapped_column(sa.ForeignKey("items.id"), index=True)
    title: Mapped[str] = mapped_column(sa.Text)
    laboratory: Mapped[str] = mapped_column(sa.Text)
    customer: Mapped[str] = mapped_column(sa.Text)
    start_date: Mapped[dt.date] = mapped_column(sa.Date)
    end_date: Mapped[dt.date] = mapped_column(sa.Date)
    issue_date: Mapped[dt.date] = mapped_column(sa.Date, index=True)
    #: the plan file's name and its bytes as given
    plan_name: Mapped[str] = mapped_column(sa.Text)
    plan: Mapped[bytes] = mapped_column(sa.LargeBinary)
    #: one certificate per plan and captures: the same calibration is never certified twice
    plan_sha256: Mapped[str] = mapped_column(sa.String(64), index=True, unique=True)
    #: results.json as issued (UTF-8 text)
    results: Mapped[str] = mapped_column(sa.Text)
    software_version: Mapped[str] = mapped_column(sa.String(64))
    supersedes: Mapped[str | None] = mapped_column(
        sa.ForeignKey("certificates.number"), unique=True
    )
    recorded_at: Mapped[dt.datetime] = mapped_column(sa.DateTime(timezone=True))
    #: the computer and user that recorded it (the test station)
    recorded_by: Mapped[str] = mapped_column(sa.String(256))

    item: Mapped[Item] = relationship()
    inputs: Mapped[list[CertificateInput]] = relationship(order_by="CertificateInput.position")
    files: Mapped[list[CertificateFile]] = relationship(order_by="CertificateFile.name")
    persons: Mapped[list[CertificatePerson]] = relationship(order_by="CertificatePerson.position")
    standards: Mapped[list[CertificateStandard]] = relationship(
        order_by="CertificateStandard.position"
    )
    values: Mapped[list[ReportedValue]] = relationship(
        order_by="(ReportedValue.measurement, ReportedValue.position)"
    )


class CertificateInput(Base):
    """A file the measurements read (a capture or an option file): its path as the plan names it,
    its SHA-256 and its size."""

    __tablename__ = "certificate_inputs"
    certificate_id: Mapped[int] = mapped_column(sa.ForeignKey("certificates.id"), primary_key=True)
    position: Mapped[int] = mapped_column(primary_key=True)
    measurement: Mapped[int] = mapped_column(sa.Integer)
    path: Mapped[str] = mapped_column(sa.Text)
    sha256: Mapped[str] = mapped_column(sa.String(64), index=True)
    size_bytes: Mapped[int] = mapped_column(sa.BigInteger)


class CertificateFile(Base):
    """A file of the certificate folder as issued, with its SHA-256."""

    __tablename__ = "certificate_files"
    certificate_id: Mapped[int] = mapped_column(sa.ForeignKey("certificates.id"), primary_key=True)
    name: Mapped[str] = mapped_column(sa.String(256), primary_key=True)
    sha256: Mapped[str] = mapped_column(sa.String(64))
    content: Mapped[bytes] = mapped_column(sa.LargeBinary)


class CertificatePerson(Base):
    """A person named on a certificate, in the plan's order, with the role there."""

    __tablename__ = "certificate_persons"
    certificate_id: Mapped[int] = mapped_column(sa.ForeignKey("certificates.id"), primary_key=True)
    position: Mapped[int] = mapped_column(primary_key=True)
    person_id: Mapped[int] = mapped_column(sa.ForeignKey("persons.id"), index=True)
    role: Mapped[str] = mapped_column(sa.String(32))
    person: Mapped[Person] = relationship()


class CertificateStandard(Base):
    """A reference standard a certificate used, in the plan's order."""

    __tablename__ = "certificate_standards"
    certificate_id: Mapped[int] = mapped_column(sa.ForeignKey("certificates.id"), primary_key=True)
    position: Mapped[int] = mapped_column(primary_key=True)
    standard_id: Mapped[int] = mapped_column(sa.ForeignKey("standards.id"), index=True)
    standard: Mapped[Standard] = relationship()


class ReportedValue(Base):
    """One reported quantity of a certificate as printed (decimal text), with its conformity
    statement when the plan set a limit: the rows that ``records history`` reads."""

    __tablename__ = "reported_values"
    certificate_id: Mapped[int] = mapped_column(sa.ForeignKey("certificates.id"), primary_key=True)
    measurement: Mapped[int] = mapped_column(primary_key=True)
    position: Mapped[int] = mapped_column(primary_key=True)
    measurement_name: Mapped[str] = mapped_column(sa.Text)
    command: Mapped[str] = mapped_column(sa.String(64))
    quantity: Mapped[str] = mapped_column(sa.String(128))
    name: Mapped[str] = mapped_column(sa.Text)
    unit: Mapped[str] = mapped_column(sa.String(64))
    value: Mapped[str] = mapped_column(_DECIMAL)
    expanded: Mapped[str] = mapped_column(_DECIMAL)
    coverage_factor: Mapped[str] = mapped_column(_DECIMAL)
    coverage_probability: Mapped[str] = mapped_column(_DECIMAL)
    interval_low: Mapped[str | None] = mapped_column(_DECIMAL)
    interval_high: Mapped[str | None] = mapped_column(_DECIMAL)
    limit_min: Mapped[str | None] = mapped_column(_DECIMAL)
    limit_max: Mapped[str | None] = mapped_column(_DECIMAL)
    decision_rule: Mapped[str | None] = mapped_column(sa.String(16))
    verdict: Mapped[str | None] = mapped_column(sa.String(16))


class AuditEvent(Base):
    """One change of a certificate number's state, in the order of its number's chain (``seq``
    from 1): ``from_state`` → ``to_state`` (None → draft → issued → superseded, draft → voided),
    ``who`` (the persons responsible: performers for a draft, approvers for an issue or a
    supersession), ``station`` (user@computer that wrote it), ``at`` (UTC), ``reason``, and the
    chain: ``prev_hash`` (the number's previous event's ``hash``; 64 zeros for the first) and
    ``hash`` (SHA-256 of this event's content and ``prev_hash``:
    :func:`rotacal.records.audit.event_hash`).
    No foreign key to ``certificates``: a drawn or voided number has no certificate."""

    __tablename__ = "audit_events"
    number: Mapped[str] = mapped_column(sa.String(128), primary_key=True)
    seq: Mapped[int] = mapped_column(primary_key=True, autoincrement=False)
    from_state: Mapped[str | None] = mapped_column(sa.String(16))
    to_state: Mapped[str] = mapped_column(sa.String(16))
    who: Mapped[str] = mapped_column(sa.Text)
    station: Mapped[str] = mapped_column(sa.String(256))
    at: Mapped[dt.datetime] = mapped_column(sa.DateTime(timezone=True), index=True)
    reason: Mapped[str] = mapped_column(sa.Text)
    prev_hash: Mapped[str] = mapped_column(sa.String(64))
    hash: Mapped[str] = mapped_column(sa.String(64), unique=True)


#: The tables whose rows are part of an issued record: no UPDATE, no DELETE (the triggers of
#: migrations 0002 and 0003 and the store's own check).
IMMUTABLE_TABLES = (
    "items",
    "persons",
    "standards",
    "certificates",
    "certificate_inputs",
    "certificate_files",
    "certificate_persons",
    "certificate_standards",
    "reported_values",
    "voided_numbers",
    "audit_events",
)
