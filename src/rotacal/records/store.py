"""The records store: what a laboratory keeps of every certificate it issued, and the number series.

:func:`open_store` opens (and on first use creates) the store named by a URL
(:mod:`rotacal.records.engine`). A :class:`Store` draws certificate numbers, keeps an issued
certificate in ONE transaction (:meth:`Store.keep`), and reads records back. Every change of a
number's state — drawn (draft), issued, superseded, voided — appends an event to the audit trail
in the same transaction (:mod:`rotacal.records.audit`), stamped by the store's ``clock``. It
never changes or deletes an issued row: it has no method that would, an ORM session that tries
is stopped before the database is touched, and the schema's triggers refuse it for any other
program.

``rotacal certify`` uses a store through the small protocol that
:class:`rotacal.certificate.issue.Registry` names, so the certificate code knows nothing of
databases.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import string
from collections.abc import Callable, Iterator, Mapping
from typing import Any, cast

import sqlalchemy as sa
from sqlalchemy import event
from sqlalchemy.orm import Session

from rotacal.certificate.content import CertificateContent
from rotacal.errors import AlreadyCertifiedError, ConfigError, RecordImmutableError, StoreError
from rotacal.plan.approval import check_approval, performers
from rotacal.plan.model import Plan

from . import models as m
from .audit import append_event, record_issue
from .engine import (
    READ_ONLY,
    display_url,
    make_engine,
    resolve_url,
    store_errors,
    timeout_from_environment,
)
from .record import insert_for, insert_record, record_of, station
from .schema import ensure_schema

__all__ = ["DEFAULT_SETTINGS", "Store", "open_store"]

#: The laboratory's settings and their defaults: the number series (``{year}`` and ``{count}``,
#: Python format syntax) and the fixed calibration interval used when no drift sets one.
DEFAULT_SETTINGS = {"number_format": "RC-{year}-{count:04d}", "interval_months": "12"}


def check_number_format(fmt: str) -> str:
    """``fmt`` if it is a usable number format: ``{count}`` (with an optional format spec such
    as ``:04d``) and optionally ``{year}``, nothing else in braces."""
    try:
        fields = {name for _, name, _, _ in string.Formatter().parse(fmt) if name is not None}
        fmt.format(year="2026", count=1)
    except (ValueError, KeyError, IndexError) as e:
        raise ConfigError(f"number format {fmt!r}: not usable ({e})") from None
    if "count" not in fields or fields - {"year", "count"}:
        raise ConfigError(
            f"number format {fmt!r}: must contain {{count}} (e.g. {{count:04d}}) and may "
            "contain {year}, nothing else in braces"
        )
    return fmt


def _refuse_changes(session: Session, _context: Any, _instances: Any) -> None:
    """Stop an ORM session that would change or delete an issued row (before any SQL)."""
    for obj in (*session.dirty, *session.deleted):
        table = getattr(obj, "__tablename__", None)
        if table in m.IMMUTABLE_TABLES and (obj in session.deleted or session.is_modified(obj)):
            if table == "audit_events":
                raise RecordImmutableError("audit_events: the audit trail is append-only")
            raise RecordImmutableError(
                f"{table}: issued records are immutable; a correction is a new certificate "
                'whose plan says supersedes = "NUMBER"'
            )


event.listen(Session, "before_flush", _refuse_changes)


def utc_now() -> dt.datetime:
    """The present moment in UTC (the store's default clock)."""
    return dt.datetime.now(dt.timezone.utc)


def open_store(
    url: str | None = None,
    *,
    timeout_s: float | None = None,
    check_schema: bool = True,
    clock: Callable[[], dt.datetime] | None = None,
) -> Store:
    """Open the records store at ``url`` (``--db``; default ``ROTACAL_DB``, else the SQLite file
    in the user's data folder), making its schema when the database is empty.

    Parameters
    ----------
    url : str, optional
        SQLAlchemy URL of the store.
    timeout_s : float, optional
        How long to wait for a store locked by another writer, or for a server's answer [s]
        [default: ``ROTACAL_DB_TIMEOUT``, else 30 s].
    check_schema : bool
        Refuse a store whose schema is not this rotacal's (False only for ``records upgrade``).
    clock : callable, optional
        Gives the timezone-aware moment of each record and audit event [default: the system
        clock in UTC]; tests give a fixed one.

    Raises
    ------
    ConfigError
        The URL is not usable.
    StoreError
        The store cannot be reached or used; one line says why and what to do.
    """
    resolved = resolve_url(url)
    if timeout_s is None:
        timeout_s = timeout_from_environment()
    engine = make_engine(resolved, timeout_s=timeout_s)
    store = Store(engine, resolved, timeout_s, clock)
    if check_schema:
        with store.errors():
            ensure_schema(engine, store.shown)
    return store


class Store:
    """An open records store. Make one with :func:`open_store`."""

    def __init__(
        self,
        engine: sa.Engine,
        url: str,
        timeout_s: float,
        clock: Callable[[], dt.datetime] | None = None,
    ) -> None:
        self.engine = engine
        #: when a record is kept and an event happens (timezone-aware)
        self.clock = clock or utc_now
        self._reader = engine.execution_options(**{READ_ONLY: True})
        self.url = url
        self.shown = display_url(url)
        self.timeout_s = timeout_s

    # -- plumbing ----------------------------------------------------------------------------
    def close(self) -> None:
        """Close the store's pooled connections (the store opens new ones if used again)."""
        self.engine.dispose()

    def errors(self) -> contextlib.AbstractContextManager[None]:
        """Database faults as one-line :class:`StoreError` naming this store."""
        return store_errors(self.url, self.timeout_s)

    @contextlib.contextmanager
    def begin(self, *, read_only: bool = False) -> Iterator[sa.Connection]:
        """A transaction. On SQLite a writing one holds the write lock from its start; a
        ``read_only`` one reads a snapshot and neither waits for writers nor holds them up."""
        engine = self._reader if read_only else self.engine
        with self.errors(), engine.begin() as connection:
            yield connection

    @contextlib.contextmanager
    def read(self) -> Iterator[Session]:
        """A session for reading records (a snapshot, as ``begin(read_only=True)``)."""
        with self.errors(), Session(self._reader) as session:
            yield session

    # -- settings ----------------------------------------------------------------------------
    def settings(self) -> dict[str, str]:
        """The laboratory's settings (:data:`DEFAULT_SETTINGS` where none is set)."""
        with self.begin(read_only=True) as connection:
            rows = connection.execute(sa.select(m.Setting.key, m.Setting.value)).all()
        return {**DEFAULT_SETTINGS, **{k: v for k, v in rows}}

    def set_settings(self, **values: str) -> dict[str, str]:
        """Change settings (``number_format``, ``interval_months``); returns all of them."""
        for key, value in values.items():
            if key not in DEFAULT_SETTINGS:
                raise ConfigError(f"no setting {key!r}; settings: {', '.join(DEFAULT_SETTINGS)}")
            if key == "number_format":
                check_number_format(value)
            if key == "interval_months" and (not value.isdigit() or not 1 <= int(value) <= 240):
                raise ConfigError(
                    f"interval {value!r}: give a whole number of months from 1 to 240"
                )
        with self.begin() as connection:
            insert = insert_for(connection)
            for key, value in values.items():
                stmt = insert(m.Setting).values(key=key, value=value)
                connection.execute(
                    stmt.on_conflict_do_update(index_elements=["key"], set_={"value": value})
                )
        return self.settings()

    # -- numbers -----------------------------------------------------------------------------
    def _taken(self, connection: sa.Connection, number: str) -> bool:
        issued = sa.select(m.Certificate.id).where(m.Certificate.number == number)
        voided = sa.select(m.VoidedNumber.number).where(m.VoidedNumber.number == number)
        # a number with an audit event was drawn (perhaps by a process that never finished)
        drawn = sa.select(m.AuditEvent.seq).where(m.AuditEvent.number == number)
        exists = sa.exists(issued) | sa.exists(voided) | sa.exists(drawn)
        return bool(connection.execute(sa.select(exists)).scalar_one())

    def draw_number(self, issue_date: dt.date, *, plan: Plan | None = None) -> str:
        """The next number of the laboratory's series for a certificate issued on
        ``issue_date``; never one issued, voided or drawn before, whatever other writers do at
        the same time (the count is incremented in the database, row-locked). A number drawn and
        then not used must be given back with :meth:`void_number`, which keeps it out of the
        series with its reason. The draw is the number's ``draft`` event in the audit trail
        (``who``: the ``plan``'s performers when given, else this station)."""
        fmt = check_number_format(self.settings()["number_format"])
        year = f"{issue_date.year:04d}"
        scope = year if "year" in fmt else "*"
        counters = cast(sa.Table, m.Counter.__table__)
        with self.begin() as connection:
            insert = insert_for(connection)
            connection.execute(
                insert(counters).values(scope=scope, last=0).on_conflict_do_nothing()
            )
            while True:  # skip numbers that explicit plans took
                count = connection.execute(
                    sa.update(counters)
                    .where(counters.c.scope == scope)
                    .values(last=counters.c.last + 1)
                    .returning(counters.c.last)
                ).scalar_one()
                number = fmt.format(year=year, count=count)
                if not self._taken(connection, number):
                    here = station()
                    who = "; ".join(performers(plan)) if plan is not None else ""
                    append_event(
                        connection, number, "draft", who=who or here, station=here,
                        at=self.clock(), reason="measured; number drawn from the series",
                    )  # fmt: skip
                    return number

    def void_number(self, number: str, reason: str) -> None:
        """Keep a drawn number out of the series for good, with the reason it was not issued
        (and the ``voided`` event of its audit trail)."""
        at = self.clock()
        why = " ".join(reason.split())[:2000]
        with self.begin() as connection:
            insert = insert_for(connection)
            voided = connection.execute(
                insert(m.VoidedNumber)
                .values(number=number, voided_at=at, reason=why)
                .on_conflict_do_nothing()
                .returning(m.VoidedNumber.number)
            ).first()
            if voided is None:  # voided before: its event is there
                return
            here = station()
            if not self._drawn(connection, number):  # voided without being drawn here
                append_event(
                    connection, number, "draft", who=here, station=here, at=at,
                    reason="number given back without a draft in this store",
                )  # fmt: skip
            append_event(connection, number, "voided", who=here, station=here, at=at, reason=why)

    def _drawn(self, connection: sa.Connection, number: str) -> bool:
        drawn = sa.select(m.AuditEvent.seq).where(m.AuditEvent.number == number)
        return bool(connection.execute(sa.select(sa.exists(drawn))).scalar_one())

    # -- the Registry protocol of rotacal.certificate.issue ------------------------------------
    def check_plan(self, plan: Plan) -> None:
        """Refuse, before anything is measured, a plan whose explicit number is taken or whose
        ``supersedes`` names no issued certificate or one already superseded, or that names no
        approver (or the performer as approver: :func:`rotacal.plan.approval.check_approval`)."""
        check_approval(plan)
        with self.begin() as connection:
            if plan.number != "auto" and self._taken(connection, plan.number):
                raise ConfigError(
                    f"{plan.path}: certificate.number: {plan.number} is already in the records "
                    f"({self.shown}); a number is never issued twice — a correction is a new "
                    'certificate whose plan says supersedes = "' + plan.number + '"'
                )
            if plan.supersedes is None:
                return
            if not self._exists(connection, plan.supersedes):
                raise ConfigError(
                    f"{plan.path}: certificate.supersedes: no certificate {plan.supersedes} in "
                    f"the records ({self.shown}); name an issued certificate"
                )
            later = connection.execute(
                sa.select(m.Certificate.number).where(m.Certificate.supersedes == plan.supersedes)
            ).scalar()
            if later is not None:
                raise ConfigError(
                    f"{plan.path}: certificate.supersedes: {plan.supersedes} is already superseded "
                    f"by {later}; supersede {later} instead"
                )

    def _exists(self, connection: sa.Connection, number: str) -> bool:
        issued = sa.select(m.Certificate.id).where(m.Certificate.number == number)
        return bool(connection.execute(sa.select(sa.exists(issued))).scalar_one())

    def _conflict(self, content: CertificateContent, e: sa.exc.IntegrityError) -> StoreError:
        """What another writer did meanwhile, from the unique key the insert ran into."""
        if "plan_sha256" in str(e.orig):
            return StoreError(
                f"{content.plan.path}: this plan and its captures were certified meanwhile by "
                f"another writer ({self.shown}); `rotacal records list` shows it"
            )
        return StoreError(
            f"records store {self.shown}: certificate {content.number} was issued meanwhile by "
            "another writer; certify again"
        )

    def issued_with(self, plan_sha256: str) -> str | None:
        """The number of the certificate issued from exactly this plan and these captures."""
        with self.begin() as connection:
            return connection.execute(
                sa.select(m.Certificate.number)
                .where(m.Certificate.plan_sha256 == plan_sha256)
                .order_by(m.Certificate.id)
            ).scalar()

    def check_unissued(self, plan: Plan, plan_sha256: str) -> None:
        """Refuse a plan whose every byte, and every capture's, was certified before."""
        number = self.issued_with(plan_sha256)
        if number is not None:
            raise AlreadyCertifiedError(
                f"{plan.path}: this plan and its captures were certified already as {number} "
                f"(same plan_sha256, {self.shown}); a correction is a new plan with "
                f'supersedes = "{number}"',
                number,
            )

    @contextlib.contextmanager
    def keep(self, content: CertificateContent, files: Mapping[str, bytes]) -> Iterator[None]:
        """Keep an issued certificate: every row of it in ONE transaction, committed when the
        block ends without an exception (the caller publishes the certificate folder inside the
        block), rolled back otherwise. The same transaction appends the audit trail's events:
        the issue, approved by the plan's approvers at the store's ``clock`` (which is also the
        record's ``recorded_at``), and the supersession of the certificate it supersedes.

        Parameters
        ----------
        content : CertificateContent
            What the certificate states (with its final number).
        files : mapping of str to bytes
            Every file of the certificate folder by name (PDF, XML, results.json, figures).
        """
        with self.errors():
            connection = self.engine.connect()
            transaction = connection.begin()
        try:
            with self.errors():
                try:
                    check_approval(content.plan)
                    at = self.clock()
                    record = record_of(content, files, recorded_at=at)
                    insert_record(connection, record)
                    record_issue(connection, record, at)
                except sa.exc.IntegrityError as e:
                    raise self._conflict(content, e) from None
            yield
            with self.errors():
                transaction.commit()
        except BaseException:
            with contextlib.suppress(sa.exc.SQLAlchemyError):
                transaction.rollback()
            raise
        finally:
            connection.close()
