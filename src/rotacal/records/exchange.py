"""Export and import of a whole store as JSON lines: a backup, or the move from SQLite to PostgreSQL,
with nothing lost.

The file's first line says what it is (``{"type": "rotacal-records", "version": 2, …}``); then the
laboratory's settings, the number counters, the voided numbers, every certificate's record
(:mod:`rotacal.records.record`; bytes as base64), in the order they were recorded, and the audit
trail's events (``"type": "audit"``, :mod:`rotacal.records.audit`; by number, in chain order), one
JSON object per line. The same store always exports to the same bytes, so an export, an import
elsewhere and a second export can be compared byte for byte.

An import is one transaction: all of the file or nothing. A certificate already in the store is
skipped when its record is identical and refused when it differs; every file is checked against its
SHA-256 and every ``plan_sha256`` against the plan and its inputs before anything is written. Audit
events are imported as they were, hashes and all: a number's chain is added where the store has
none or only its beginning, and refused when it differs or is broken; the trail of the whole store
is checked before the import commits. A version-1 export (made before the audit trail) gets the
events its records imply, marked as reconstructed.
"""

from __future__ import annotations

import base64
import datetime as dt
import hashlib
import json
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import IO, Any

import sqlalchemy as sa

from rotacal.certificate.issue import plan_sha256
from rotacal.errors import ConfigError, StoreError

from . import models as m
from .audit import EVENT_KEYS, check_trail, events_of, insert_events, reconstruct
from .record import VALUE_COLUMNS, insert_for, insert_record, read_record, utc_text
from .schema import head_revision
from .store import Store

__all__ = ["FORMAT", "export_lines", "import_lines"]

#: What the first line names, and the version of the file's layout.
FORMAT, VERSION = "rotacal-records", 2
#: The versions this rotacal imports (1: before the audit trail).
_READABLE = (1, 2)

_CERTIFICATE_KEYS = {
    "number", "title", "laboratory", "customer", "start_date", "end_date", "issue_date", "item",
    "plan_name", "plan", "plan_sha256", "results", "software_version", "supersedes",
    "recorded_at", "recorded_by", "persons", "standards", "inputs", "files", "values",
}  # fmt: skip


def _line(obj: Mapping[str, Any]) -> str:
    return json.dumps(obj, ensure_ascii=False, sort_keys=True, separators=(",", ":")) + "\n"


def _encode(record: dict[str, Any]) -> dict[str, Any]:
    out = dict(record)
    out["plan"] = base64.b64encode(record["plan"]).decode("ascii")
    out["files"] = [
        {**f, "content": base64.b64encode(f["content"]).decode("ascii")} for f in record["files"]
    ]
    return {"type": "certificate", **out}


def export_lines(store: Store) -> Iterator[str]:
    """Every record of the store as JSON lines (see the module's description), from one
    snapshot of the store."""
    with store.begin(read_only=True) as connection:
        numbers = list(
            connection.execute(sa.select(m.Certificate.number).order_by(m.Certificate.id)).scalars()
        )
        yield _line(
            {
                "type": FORMAT,
                "version": VERSION,
                "schema_revision": head_revision(),
                "certificates": len(numbers),
            }
        )
        for key, value in connection.execute(
            sa.select(m.Setting.key, m.Setting.value).order_by(m.Setting.key)
        ):
            yield _line({"type": "setting", "key": key, "value": value})
        for scope, last in connection.execute(
            sa.select(m.Counter.scope, m.Counter.last).order_by(m.Counter.scope)
        ):
            yield _line({"type": "counter", "scope": scope, "last": last})
        for number, voided_at, reason in connection.execute(
            sa.select(
                m.VoidedNumber.number, m.VoidedNumber.voided_at, m.VoidedNumber.reason
            ).order_by(m.VoidedNumber.voided_at, m.VoidedNumber.number)
        ):
            yield _line(
                {"type": "voided", "number": number, "voided_at": utc_text(voided_at),
                 "reason": reason}
            )  # fmt: skip
        for number in numbers:
            record = read_record(connection, number)
            assert record is not None
            yield _line(_encode(record))
        for event in events_of(connection):
            yield _line({"type": "audit", **event})


def _decode(record: dict[str, Any], where: str) -> dict[str, Any]:
    """A certificate line back to a record, checked: keys, base64, each file's SHA-256 and the
    ``plan_sha256`` of the plan and its inputs."""
    missing = _CERTIFICATE_KEYS - record.keys()
    if missing:
        raise ConfigError(f"{where}: a certificate without {', '.join(sorted(missing))}")
    out = {k: record[k] for k in _CERTIFICATE_KEYS}
    try:
        out["plan"] = base64.b64decode(record["plan"], validate=True)
        out["files"] = [
            {**f, "content": base64.b64decode(f["content"], validate=True)} for f in record["files"]
        ]
        out["values"] = [{k: v[k] for k in VALUE_COLUMNS} for v in record["values"]]
    except (ValueError, TypeError, KeyError) as e:
        raise ConfigError(f"{where}: certificate {record['number']}: damaged ({e})") from None
    for f in out["files"]:
        if hashlib.sha256(f["content"]).hexdigest() != f.get("sha256"):
            raise ConfigError(
                f"{where}: certificate {record['number']}: {f.get('name')} does not match its "
                "SHA-256; the file is damaged"
            )
    digests = [str(i.get("sha256")) for i in out["inputs"]]
    if plan_sha256(out["plan"], digests) != out["plan_sha256"]:
        raise ConfigError(
            f"{where}: certificate {record['number']}: plan_sha256 does not match its plan and "
            "inputs; the file is damaged"
        )
    return out


def _text_lines(lines: IO[str], name: str) -> Iterator[str]:
    """The lines of ``lines`` one at a time (an export may be larger than memory)."""
    iterator = iter(lines)
    while True:
        try:
            yield next(iterator)
        except StopIteration:
            return
        except UnicodeDecodeError:
            raise ConfigError(
                f"{name}: not text (UTF-8), so not a rotacal records export; make one with "
                "`rotacal records export`"
            ) from None


def _read(lines: IO[str], name: str) -> Iterator[tuple[str, dict[str, Any]]]:
    """(where, object) of each line, the first checked to be a rotacal records export."""
    for index, text in enumerate(_text_lines(lines, name), start=1):
        where = f"{name} line {index}"
        if not text.strip():
            continue
        try:
            obj = json.loads(text)
        except ValueError as e:
            raise ConfigError(f"{where}: not JSON ({e})") from None
        if not isinstance(obj, dict) or "type" not in obj:
            raise ConfigError(f"{where}: not a line of a rotacal records export")
        if index == 1 and (obj["type"] != FORMAT or obj.get("version") not in _READABLE):
            raise ConfigError(
                f"{where}: not a rotacal records export (version {VERSION}); make one with "
                "`rotacal records export`"
            )
        yield where, obj


def import_lines(store: Store, lines: IO[str], name: str) -> dict[str, Any]:
    """Import an export (``lines``, read from the file ``name``) into ``store`` in one
    transaction. Returns ``imported`` and ``unchanged`` (certificate counts) and ``warnings``.

    Raises
    ------
    ConfigError
        A line is not a record of an export, or is damaged (named by file and line).
    StoreError
        A certificate of the file differs from the one with its number in the store.
    """
    imported = unchanged = 0
    warnings: list[str] = []
    header_seen = False
    version = VERSION
    trails: dict[str, list[dict[str, Any]]] = {}
    with store.begin() as connection:
        insert = insert_for(connection)
        settings = dict(connection.execute(sa.select(m.Setting.key, m.Setting.value)).all())
        for where, obj in _read(lines, name):
            kind = obj["type"]
            if kind == FORMAT:
                header_seen, version = True, int(obj["version"])
            elif kind == "setting":
                key, value = str(obj["key"]), str(obj["value"])
                if key not in settings:
                    connection.execute(insert(m.Setting).values(key=key, value=value))
                elif settings[key] != value:
                    warnings.append(
                        f"setting {key}: the store keeps {settings[key]!r}; the file's {value!r} "
                        "was not taken"
                    )
            elif kind == "counter":
                stmt = insert(m.Counter).values(scope=str(obj["scope"]), last=int(obj["last"]))
                connection.execute(
                    stmt.on_conflict_do_update(
                        index_elements=["scope"],
                        set_={"last": sa.func.max(m.Counter.last, stmt.excluded.last)}
                        if connection.dialect.name == "sqlite"
                        else {"last": sa.func.greatest(m.Counter.last, stmt.excluded.last)},
                    )
                )
            elif kind == "voided":
                connection.execute(
                    insert(m.VoidedNumber)
                    .values(
                        number=obj["number"],
                        voided_at=_moment(obj["voided_at"]),
                        reason=obj["reason"],
                    )
                    .on_conflict_do_nothing()
                )
            elif kind == "certificate":
                record = _decode(obj, where)
                existing = read_record(connection, record["number"])
                if existing is None:
                    insert_record(connection, record)
                    imported += 1
                elif existing == record:
                    unchanged += 1
                else:
                    raise StoreError(
                        f"{where}: certificate {record['number']} differs from the one the store "
                        f"({store.shown}) already holds; nothing was imported"
                    )
            elif kind == "audit":
                trails.setdefault(str(obj.get("number")), []).append(_event(obj, where))
            else:
                raise ConfigError(f"{where}: unknown record type {kind!r}")
        if not header_seen:
            raise ConfigError(f"{name}: empty; not a rotacal records export")
        for chain in trails.values():
            insert_events(connection, chain, name)
        if version == 1:
            reconstruct(connection, f"reconstructed on import of {Path(name).name}")
        trail = check_trail(connection)
        if not trail["intact"]:
            raise StoreError(
                f"{name}: after the import the audit trail would not hold: "
                f"{trail['problems'][0]}; nothing was imported"
            )
    return {"imported": imported, "unchanged": unchanged, "warnings": warnings}


def _event(obj: Mapping[str, Any], where: str) -> dict[str, Any]:
    """An audit line back to an event (its chain is checked with the number's other events)."""
    missing = set(EVENT_KEYS) - obj.keys()
    if missing:
        raise ConfigError(f"{where}: an audit event without {', '.join(sorted(missing))}")
    try:
        _moment(str(obj["at"]))
        int(obj["seq"])
    except (TypeError, ValueError) as e:
        raise ConfigError(f"{where}: audit event of {obj['number']}: damaged ({e})") from None
    return {k: obj[k] for k in EVENT_KEYS}


def _moment(text: str) -> dt.datetime:
    return dt.datetime.fromisoformat(text)


def export_to(store: Store, path: Path) -> None:
    """Write the export to ``path``, whole or not at all (never over an existing file)."""
    from rotacal.io.outputs import write_output

    def fill(temporary: Path) -> None:
        with open(temporary, "w", encoding="utf-8", newline="\n") as out:
            out.writelines(export_lines(store))

    write_output(path, fill, label=f"--out {path}", make_folders=True)
