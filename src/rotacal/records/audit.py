"""The audit trail of the records store: every change of a certificate number's state, appended
in the transaction of the change and never rewritten (ISO/IEC 17025:2017 §7.5.2 amendments to
technical records traceable to previous versions, §8.4.2 records retained; §7.8.1.1 results
reviewed and authorised before release).

States and the changes the store makes::

    (none) → draft       measured and numbered (``Store.draw_number``; with an explicit number,
                          in the transaction that issues it)
    draft → issued        approved and issued (``Store.keep``; ``who`` = the plan's approvers)
    issued → superseded   a new certificate says ``supersedes = "NUMBER"`` (same transaction)
    draft → voided        a drawn number that was not issued (``Store.void_number``)

Tamper evidence: each number's events form a hash chain. An event's ``hash`` is the SHA-256 of
the canonical JSON of its content (``number``, ``seq``, states, ``who``, ``station``, ``at`` as
ISO-8601 UTC text, ``reason``) together with ``prev_hash``, the hash of the number's previous
event (64 zeros for its first), so a change of any event after it was written — by someone who
bypassed the database's append-only triggers — no longer matches its hash or breaks the link
of the event after it. :func:`check_trail` recomputes every chain and also checks that the
chains agree with the records: every certificate has its ``issued`` event, every superseded one
its ``superseded`` event, every voided number its ``voided`` event (so a whole chain cannot be
removed unnoticed either).

An event is a plain dict with the keys of :data:`EVENT_KEYS` (``at`` as ISO text), the form
``records audit``, ``records show`` and the export carry.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
from collections.abc import Iterable, Mapping, Sequence
from typing import Any, cast

import sqlalchemy as sa

from rotacal.errors import StoreError

from . import models as m
from .record import utc_text

__all__ = [
    "EVENT_KEYS",
    "GENESIS",
    "TRANSITIONS",
    "append_event",
    "approval_of",
    "chain_problems",
    "check_trail",
    "event_hash",
    "events_of",
    "insert_events",
    "names",
    "reconstruct",
    "record_issue",
]

#: The ``prev_hash`` of a number's first event.
GENESIS = "0" * 64
#: The state changes the store makes (from, to); None: a number not yet drawn.
TRANSITIONS = frozenset(
    {(None, "draft"), ("draft", "issued"), ("issued", "superseded"), ("draft", "voided")}
)
#: The keys of an event, in the order of the table's columns.
EVENT_KEYS = (
    "number", "seq", "from_state", "to_state", "who", "station", "at", "reason", "prev_hash",
    "hash",
)  # fmt: skip
#: The version of the hashed form; part of every hash, so a future form cannot be confused.
_HASH_FORM = 1


def _table() -> sa.Table:
    return cast(sa.Table, m.AuditEvent.__table__)


def event_hash(event: Mapping[str, Any]) -> str:
    """SHA-256 (hex) of an event's content and ``prev_hash``: the canonical JSON (sorted keys, no
    spaces, UTF-8) of every key of :data:`EVENT_KEYS` but ``hash``, with the form's version."""
    content = {k: event[k] for k in EVENT_KEYS if k != "hash"}
    content["form"] = _HASH_FORM
    text = json.dumps(content, ensure_ascii=False, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def names(persons: Iterable[Mapping[str, Any]], role: str) -> str:
    """The names of the persons with ``role`` (``performed``, ``approved``), joined by "; "."""
    return "; ".join(str(p["name"]) for p in persons if p["role"] == role)


def _utc(moment: dt.datetime) -> dt.datetime:
    if moment.tzinfo is None:
        raise StoreError(f"audit trail: the time {moment.isoformat()} has no time zone")
    # microseconds as the databases keep them, so that the hash is of what is stored
    return moment.astimezone(dt.timezone.utc)


def _row_event(row: sa.RowMapping) -> dict[str, Any]:
    return {k: (utc_text(row[k]) if k == "at" else row[k]) for k in EVENT_KEYS}


def events_of(connection: sa.Connection, number: str | None = None) -> list[dict[str, Any]]:
    """The events of ``number`` (all numbers when None), by number and then in chain order."""
    t = _table()
    query = sa.select(t).order_by(t.c.number, t.c.seq)
    if number is not None:
        query = query.where(t.c.number == number)
    return [_row_event(r) for r in connection.execute(query).mappings()]


def _last(connection: sa.Connection, number: str) -> dict[str, Any] | None:
    """The number's last event's ``seq``, ``to_state`` and ``hash`` (None: no event)."""
    t = _table()
    row = (
        connection.execute(
            sa.select(t.c.seq, t.c.to_state, t.c.hash)
            .where(t.c.number == number)
            .order_by(t.c.seq.desc())
            .limit(1)
        )
        .mappings()
        .first()
    )
    return dict(row) if row is not None else None


def append_event(
    connection: sa.Connection,
    number: str,
    to_state: str,
    *,
    who: str,
    station: str,
    at: dt.datetime,
    reason: str,
) -> dict[str, Any]:
    """Append the change of ``number`` to ``to_state`` to its chain, in the caller's transaction
    (the one that makes the change). Returns the event.

    Parameters
    ----------
    who : str
        The persons responsible (names; "; " between several).
    station : str
        user@computer that makes the change.
    at : datetime
        When, timezone-aware (stored and hashed in UTC).
    reason : str
        Why (one line; whitespace is collapsed).

    Raises
    ------
    StoreError
        The change is not one the store makes from the number's present state.
    """
    event = _next(_last(connection, number), number, to_state, who, station, at, reason)
    _insert(connection, [event])
    return event


def _next(
    last: Mapping[str, Any] | None,
    number: str,
    to_state: str,
    who: str,
    station: str,
    at: dt.datetime,
    reason: str,
) -> dict[str, Any]:
    """The event that follows ``last`` (the number's last event, None for its first)."""
    from_state = last["to_state"] if last is not None else None
    if (from_state, to_state) not in TRANSITIONS:
        raise StoreError(
            f"audit trail: {number} is {from_state or 'not drawn'}; it cannot become {to_state}"
        )
    event = {
        "number": number,
        "seq": (last["seq"] if last is not None else 0) + 1,
        "from_state": from_state,
        "to_state": to_state,
        "who": who,
        "station": station[:256],
        "at": utc_text(_utc(at)),
        "reason": " ".join(reason.split())[:2000],
        "prev_hash": last["hash"] if last is not None else GENESIS,
    }
    event["hash"] = event_hash(event)
    return event


def _insert(connection: sa.Connection, events: Sequence[Mapping[str, Any]]) -> None:
    """Insert events as they are (``at`` from its ISO text), in one statement."""
    rows = [{**e, "at": dt.datetime.fromisoformat(str(e["at"]))} for e in events]
    if rows:
        connection.execute(sa.insert(_table()), rows)


def record_issue(connection: sa.Connection, record: Mapping[str, Any], at: dt.datetime) -> None:
    """The events of keeping ``record`` (the form of :func:`rotacal.records.record.record_of`):
    its draft when its number was not drawn from the series, its issue (``who``: the approvers),
    and the supersession of the certificate it supersedes — in the caller's transaction."""
    number, station = record["number"], record["recorded_by"]
    approvers = names(record["persons"], "approved")
    if not approvers:
        raise StoreError(
            f'{record["plan_name"]}: no [[person]] with role = "approved"; a certificate is '
            "issued only when the plan names who approves it"
        )
    last: Mapping[str, Any] | None = _last(connection, number)
    events = []
    if last is None:  # an explicit number: drafted and issued in this one transaction
        last = _next(
            None, number, "draft", names(record["persons"], "performed") or station, station,
            at, "measured; number given by the plan",
        )  # fmt: skip
        events.append(last)
    issued = _next(
        last, number, "issued", approvers, station, at,
        f"approved and issued; plan_sha256 {record['plan_sha256']}",
    )  # fmt: skip
    events.append(issued)
    _insert(connection, events)
    if record["supersedes"]:
        append_event(
            connection, record["supersedes"], "superseded", who=approvers, station=station,
            at=at, reason=f"superseded by {number}",
        )  # fmt: skip


def approval_of(events: Sequence[Mapping[str, Any]]) -> tuple[str | None, str | None]:
    """Who approved the certificate and when (UTC ISO text): its ``issued`` event's ``who`` and
    ``at``; (None, None) when it has none."""
    for event in events:
        if event["to_state"] == "issued":
            return event["who"], event["at"]
    return None, None


def _label(event: Mapping[str, Any]) -> str:
    return (
        f"{event['number']} event {event['seq']} ({event['from_state'] or 'none'} → "
        f"{event['to_state']}, {event['at']})"
    )


def chain_problems(events: Sequence[Mapping[str, Any]]) -> list[str]:
    """What is wrong with the chains of ``events`` (grouped by number, each in ``seq`` order):
    a gap in ``seq``, a ``prev_hash`` that is not the previous event's hash, a hash that does not
    match the event's content, a state change the store does not make. Each problem names the
    event."""
    problems: list[str] = []
    by_number: dict[str, list[Mapping[str, Any]]] = {}
    for event in events:
        by_number.setdefault(str(event["number"]), []).append(event)
    for chain in by_number.values():
        chain.sort(key=lambda e: int(e["seq"]))
        prev_hash, state = GENESIS, None
        for expected_seq, event in enumerate(chain, start=1):
            label = _label(event)
            if event["seq"] != expected_seq:
                problems.append(f"{label}: the chain jumps to it from event {expected_seq - 1}")
            elif event["prev_hash"] != prev_hash:
                problems.append(
                    f"{label}: prev_hash is not the hash of the event before it (an event was "
                    "changed or removed)"
                )
            elif event_hash(event) != event["hash"]:
                problems.append(f"{label}: its content does not match its hash (changed)")
            elif (event["from_state"], event["to_state"]) not in TRANSITIONS or (
                event["from_state"] != state
            ):
                problems.append(f"{label}: not a state change the store makes after {state}")
            else:
                prev_hash, state = event["hash"], event["to_state"]
                continue
            break  # the rest of this chain cannot be trusted; name the first break only
    return problems


def _expected_states(connection: sa.Connection, number: str | None) -> dict[str, set[str]]:
    """The states the records say each number must have reached."""
    c, v = m.Certificate, m.VoidedNumber
    issued = sa.select(c.number, c.supersedes)
    voided = sa.select(v.number)
    if number is not None:
        issued = issued.where((c.number == number) | (c.supersedes == number))
        voided = voided.where(v.number == number)
    expected: dict[str, set[str]] = {}
    for n, supersedes in connection.execute(issued):
        expected.setdefault(n, set()).add("issued")
        if supersedes is not None:
            expected.setdefault(supersedes, set()).add("superseded")
    for (n,) in connection.execute(voided):
        expected.setdefault(n, set()).add("voided")
    if number is not None:
        return {number: expected.get(number, set())}
    return expected


def check_trail(connection: sa.Connection, number: str | None = None) -> dict[str, Any]:
    """Check the audit trail of ``number`` (of the whole store when None): its hash chains
    (:func:`chain_problems`) and their agreement with the records (every certificate issued,
    superseded or voided has that event; an event of issue or voiding has its record).

    Returns ``events`` (as :func:`events_of`), ``intact`` (bool) and ``problems`` (each naming
    the number or event, first break of each chain only).
    """
    events = events_of(connection, number)
    problems = chain_problems(events)
    reached: dict[str, set[str]] = {}
    for event in events:
        reached.setdefault(str(event["number"]), set()).add(str(event["to_state"]))
    expected = _expected_states(connection, number)
    for n in sorted(expected.keys() | reached.keys()):
        want, have = expected.get(n, set()), reached.get(n, set())
        for state in sorted(want - have):
            problems.append(f"{n}: the records say {state}, but its trail has no {state} event")
        for state in sorted((have & {"issued", "superseded", "voided"}) - want):
            problems.append(f"{n}: its trail says {state}, but the records do not")
    return {"events": events, "intact": not problems, "problems": problems}


def insert_events(
    connection: sa.Connection, events: Sequence[Mapping[str, Any]], where: str
) -> int:
    """Put a number's chain as exported (``events``, all of one number) into the store, events
    and hashes unchanged: the part the store lacks when the store's chain is a beginning of it.
    Returns how many events were added.

    Raises
    ------
    StoreError
        The chain is broken, or differs from the store's chain of that number.
    """
    chain = sorted(events, key=lambda e: int(e["seq"]))
    number = str(chain[0]["number"])
    broken = chain_problems(chain)
    if broken:
        raise StoreError(f"{where}: audit trail: {broken[0]}; nothing was imported")
    held = [e["hash"] for e in events_of(connection, number)]
    given = [e["hash"] for e in chain]
    if given[: len(held)] != held and held[: len(given)] != given:
        raise StoreError(
            f"{where}: the audit trail of {number} differs from the one the store holds; "
            "nothing was imported"
        )
    new = chain[len(held) :]
    _insert(connection, new)
    return len(new)


def reconstruct(connection: sa.Connection, reason: str) -> int:
    """Write the events the records imply but the trail lacks — for certificates recorded before
    the audit trail existed (migration 0003, an export without a trail): draft and issue at the
    certificate's ``recorded_at`` (``who``: its performers, then its approvers), supersession at
    the superseding certificate's, draft and voiding at the voided number's ``voided_at``. Each
    event's ``reason`` says it was reconstructed. Returns how many events were written."""
    c, p, cp, v = m.Certificate, m.Person, m.CertificatePerson, m.VoidedNumber
    persons: dict[int, list[dict[str, str]]] = {}
    for certificate_id, name, role in connection.execute(
        sa.select(cp.certificate_id, p.name, cp.role)
        .join(p, p.id == cp.person_id)
        .order_by(cp.certificate_id, cp.position)
    ):
        persons.setdefault(certificate_id, []).append({"name": name, "role": role})
    written = 0

    def add(number: str, state: str, who: str, station: str, at: dt.datetime, why: str) -> None:
        nonlocal written
        if at.tzinfo is None:  # SQLite hands back naive datetimes: they were stored in UTC
            at = at.replace(tzinfo=dt.timezone.utc)
        append_event(
            connection, number, state, who=who, station=station, at=at,
            reason=f"{why} ({reason})",
        )  # fmt: skip
        written += 1

    rows = connection.execute(
        sa.select(c.id, c.number, c.supersedes, c.recorded_at, c.recorded_by).order_by(c.id)
    ).all()
    for certificate_id, number, supersedes, at, station in rows:
        people = persons.get(certificate_id, [])
        states = {e["to_state"] for e in events_of(connection, number)}
        if not states:
            add(number, "draft", names(people, "performed") or station, station, at, "measured")
        if "issued" not in states:
            add(number, "issued", names(people, "approved") or station, station, at, "issued")
        if supersedes is not None:
            last = _last(connection, supersedes)
            if last is not None and last["to_state"] == "issued":
                add(supersedes, "superseded", names(people, "approved") or station, station, at,
                    f"superseded by {number}")  # fmt: skip
    for number, at, why in connection.execute(
        sa.select(v.number, v.voided_at, v.reason).order_by(v.voided_at, v.number)
    ):
        last = _last(connection, number)
        if last is None:
            add(number, "draft", "unknown", "unknown", at, "number drawn")
        if last is None or last["to_state"] == "draft":
            add(number, "voided", "unknown", "unknown", at, why)
    return written
