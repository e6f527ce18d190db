"""Reading a calibration plan file and checking every key before anything runs.

A plan is TOML (INTERFACE.md, "Calibration plans and certificates"). Every fault a user can make
ends in one :class:`~rotacal.errors.ConfigError` line that names the plan file, the key
(``measurement[2].capture``) and, where the file shows it, the line: the TOML parser's own line for
a syntax error, the line of the key for everything else. Unknown keys are refused (a misspelt
``limts`` must not silently drop the conformity statement), paths are taken relative to the plan,
and a reference standard past its due date on the calibration date is refused.
"""

from __future__ import annotations

import datetime as dt
import math
import re
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from rotacal.certificate.stated import window_limit_problem
from rotacal.errors import ConfigError

from .approval import approval_problem
from .model import (
    DECISION_RULES,
    ITEM_KINDS,
    PERSON_ROLES,
    Conditions,
    Contact,
    Item,
    Limit,
    Measurement,
    Person,
    Plan,
    Standard,
)

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["MEASUREMENT_COMMANDS", "read_plan"]

#: The analysis commands a plan's measurement may run: those that read a capture and state their
#: results with uncertainties.
MEASUREMENT_COMMANDS = (
    "motion encoder",
    "motion lts",
    "motion fog",
    "motion angle",
    "selfcal",
    "rate",
    "gyro scale-factor",
    "gyro triad",
    "gyro rotations",
    "gyro multiposition",
    "allan",
    "position",
    "turntable identify",
    "gyro frequency-response",
    "gyro resolution",
    "gyro accelerometer",
)

_TABLES = {
    "certificate": (
        "number",
        "date",
        "start_date",
        "end_date",
        "issued",
        "supersedes",
        "language",
        "title",
        "location",
    ),
    "laboratory": ("name", "address", "email", "phone", "country"),
    "customer": ("name", "address", "email", "phone", "country"),
    "person": ("name", "role", "title"),
    "item": ("kind", "manufacturer", "model", "serial", "description", "condition", "received"),
    "standard": ("name", "id", "certificate", "due", "traceability"),
    "measurement": ("name", "command", "capture", "options", "limits", "decision_rule"),
}
_ARRAYS = ("person", "standard", "measurement")
_REQUIRED_TABLES = (
    "certificate",
    "laboratory",
    "customer",
    "person",
    "item",
    "standard",
    "measurement",
)
#: A limit that takes its bounds from the turntable's error allocation (turntable identify).
ALLOCATION = "allocation"
#: Options a plan may not give a command: ``certify`` decides where results go.
_OUTPUT_OPTIONS = ("json", "report", "overwrite")
_NUMBER = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")


class _Reader:
    """Checks one parsed plan; every error names the file, the key and the key's line."""

    def __init__(self, path: Path, text: str) -> None:
        self.path = path  # as the user gave it: messages name it so
        self.folder = path.resolve().parent  # every path in the plan is relative to it
        self.lines = text.splitlines()

    # --- errors -----------------------------------------------------------------------------
    def fail(self, key: str, message: str) -> ConfigError:
        line = self.line_of(key)
        where = f" (line {line})" if line else ""
        return ConfigError(f"{self.path}: {key}{where}: {message}")

    def line_of(self, key: str) -> int | None:
        """The line of ``key`` (``measurement[2].options.lines``) in the file, or None: the header
        of its table (the n-th ``[[measurement]]``), then the first line after it that sets the
        key's first name."""
        parts = re.findall(r"[^.\[\]]+|\[\d+\]", key)
        if not parts:
            return None
        table, rest = parts[0], parts[1:]
        index = 1
        if rest and rest[0].startswith("["):
            index, rest = int(rest[0][1:-1]), rest[1:]
        header = re.compile(rf"^\s*\[\[?\s*{re.escape(table)}\s*\]\]?\s*(#.*)?$")
        seen, start = 0, None
        for n, line in enumerate(self.lines):
            if header.match(line):
                seen += 1
                if seen == index:
                    start = n
                    break
        if start is None:
            return None
        if not rest:
            return start + 1
        setting = re.compile(rf"^\s*[\"']?{re.escape(rest[0])}[\"']?\s*[=.]")
        for n in range(start + 1, len(self.lines)):
            if self.lines[n].lstrip().startswith("["):
                break
            if setting.match(self.lines[n]):
                return n + 1
        return start + 1

    # --- values -----------------------------------------------------------------------------
    def table(self, data: Mapping[str, Any], key: str, name: str) -> Mapping[str, Any]:
        value = data.get(name)
        if not isinstance(value, Mapping):
            raise self.fail(key, "must be a table ([" + name + "])")
        return value

    def only_known(self, table: Mapping[str, Any], key: str, known: Sequence[str]) -> None:
        for name in table:
            if name not in known:
                raise self.fail(
                    f"{key}.{name}",
                    f"unknown key; the keys of [{key.split('[')[0]}] are " + ", ".join(known),
                )

    def text(self, table: Mapping[str, Any], key: str, name: str, *, required: bool = True) -> str:
        value = table.get(name)
        if value is None and not required:
            return ""
        if not isinstance(value, str) or (required and not value.strip()):
            what = "is missing" if value is None else f"must be a non-empty text, not {value!r}"
            raise self.fail(f"{key}.{name}", what)
        return value.strip()

    def number(self, table: Mapping[str, Any], key: str, name: str) -> float | None:
        value = table.get(name)
        if value is None:
            return None
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not math.isfinite(value)
        ):
            raise self.fail(f"{key}.{name}", f"must be a finite number, not {value!r}")
        return float(value)

    def date(self, table: Mapping[str, Any], key: str, name: str) -> dt.date | None:
        value = table.get(name)
        if value is None:
            return None
        if isinstance(value, dt.datetime):
            return value.date()
        if isinstance(value, dt.date):
            return value
        if isinstance(value, str):
            try:
                return dt.date.fromisoformat(value.strip())
            except ValueError:
                pass
        raise self.fail(f"{key}.{name}", f"must be a date like 2026-11-25, not {value!r}")

    # --- tables -----------------------------------------------------------------------------
    def contact(self, data: Mapping[str, Any], name: str) -> Contact:
        table = self.table(data, name, name)
        self.only_known(table, name, _TABLES[name])
        country = self.text(table, name, "country", required=False).upper()
        if country and not re.fullmatch(r"[A-Z]{2}", country):
            raise self.fail(
                f"{name}.country", f"must be a two-letter ISO 3166-1 code like DE, not {country!r}"
            )
        return Contact(
            name=self.text(table, name, "name"),
            address=self.text(table, name, "address", required=False),
            email=self.text(table, name, "email", required=False),
            phone=self.text(table, name, "phone", required=False),
            country=country,
        )

    def array(self, data: Mapping[str, Any], name: str) -> list[Mapping[str, Any]]:
        value = data.get(name)
        if not isinstance(value, list) or not value:
            raise self.fail(name, f"needs at least one [[{name}]] table")
        for i, entry in enumerate(value, start=1):
            if not isinstance(entry, Mapping):
                raise self.fail(f"{name}[{i}]", f"must be a table ([[{name}]])")
            self.only_known(entry, f"{name}[{i}]", _TABLES[name])
        return value

    def persons(self, data: Mapping[str, Any]) -> tuple[Person, ...]:
        persons = []
        for i, entry in enumerate(self.array(data, "person"), start=1):
            key = f"person[{i}]"
            role = self.text(entry, key, "role")
            if role not in PERSON_ROLES:
                raise self.fail(
                    f"{key}.role", f"must be one of {', '.join(PERSON_ROLES)}, not {role!r}"
                )
            persons.append(
                Person(
                    self.text(entry, key, "name"),
                    role,
                    self.text(entry, key, "title", required=False),
                )
            )
        problem = approval_problem(persons)
        if problem is not None:
            raise self.fail(*problem)
        return tuple(persons)

    def item(self, data: Mapping[str, Any]) -> Item:
        table = self.table(data, "item", "item")
        self.only_known(table, "item", _TABLES["item"])
        kind = self.text(table, "item", "kind")
        if kind not in ITEM_KINDS:
            raise self.fail("item.kind", f"must be one of {', '.join(ITEM_KINDS)}, not {kind!r}")
        return Item(
            kind=kind,
            manufacturer=self.text(table, "item", "manufacturer"),
            model=self.text(table, "item", "model"),
            serial=self.text(table, "item", "serial"),
            description=self.text(table, "item", "description", required=False),
            condition=self.text(table, "item", "condition", required=False),
            received=self.date(table, "item", "received"),
        )

    def standards(self, data: Mapping[str, Any], end: dt.date) -> tuple[Standard, ...]:
        standards = []
        for i, entry in enumerate(self.array(data, "standard"), start=1):
            key = f"standard[{i}]"
            due = self.date(entry, key, "due")
            if due is None:
                raise self.fail(
                    f"{key}.due", "is missing (the date the standard's calibration is due)"
                )
            standard = Standard(
                name=self.text(entry, key, "name"),
                id=self.text(entry, key, "id"),
                certificate=self.text(entry, key, "certificate"),
                due=due,
                traceability=self.text(entry, key, "traceability", required=False),
            )
            if due < end:
                raise self.fail(
                    f"{key}.due",
                    f"the standard {standard.id} was due on {due.isoformat()}, before the "
                    f"calibration ({end.isoformat()}): recalibrate it or use another standard",
                )
            standards.append(standard)
        return tuple(standards)

    def conditions(self, data: Mapping[str, Any]) -> Conditions:
        table = data.get("conditions", {})
        if not isinstance(table, Mapping):
            raise self.fail("conditions", "must be a table ([conditions])")
        known = {"temperature_c", "temperature_u_c", "humidity_percent"}
        values = {name: self.number(table, "conditions", name) for name in known}
        for name in ("temperature_u_c",):
            if values[name] is not None and values[name] < 0:  # type: ignore[operator]
                raise self.fail(f"conditions.{name}", "an uncertainty cannot be negative")
        humidity = values["humidity_percent"]
        if humidity is not None and not 0 <= humidity <= 100:
            raise self.fail("conditions.humidity_percent", f"must lie in 0…100 %, not {humidity:g}")
        others = []
        for name, value in table.items():
            if name in known:
                continue
            if isinstance(value, (Mapping, list)):
                raise self.fail(f"conditions.{name}", "must be a single value (a number or a text)")
            others.append((name, value))
        return Conditions(
            values["temperature_c"], values["temperature_u_c"], humidity, tuple(others)
        )

    def limits(self, table: Any, key: str, command: str = "") -> tuple[Limit, ...]:
        if table is None:
            return ()
        if not isinstance(table, Mapping):
            raise self.fail(key, "must be a table: quantity = { min = …, max = … }")
        limits: list[Limit] = []

        def walk(entries: Mapping[str, Any], prefix: str) -> None:
            for name, value in entries.items():
                full = prefix + name
                where = f"{key}.{full}"
                if value == ALLOCATION:
                    if command != "turntable identify" or full != "errors_arcsec":
                        raise self.fail(
                            where,
                            "only a turntable identify measurement takes errors_arcsec = "
                            '"allocation" (the bounds of its --config or --budget)',
                        )
                    limits.append(Limit(full, allocation=True))
                    continue
                if not isinstance(value, Mapping) or not value:
                    raise self.fail(where, "must be a table { min = …, max = … }")
                if set(value) <= {"min", "max"}:
                    low, high = self.number(value, where, "min"), self.number(value, where, "max")
                    if low is not None and high is not None and low > high:
                        raise self.fail(where, f"min {low:g} is above max {high:g}")
                    limits.append(Limit(full, low, high))
                elif any(isinstance(v, Mapping) for v in value.values()):
                    walk(value, full + ".")  # a group of results: drift_coefficients.DF
                else:
                    extra = sorted(set(value) - {"min", "max"})
                    raise self.fail(f"{where}.{extra[0]}", "unknown key; a limit has min and max")

        walk(table, "")
        return tuple(limits)

    def captures(self, entry: Mapping[str, Any], key: str) -> tuple[Path, ...]:
        value = entry.get("capture")
        names = [value] if isinstance(value, str) else value
        if (
            not isinstance(names, list)
            or not names
            or not all(isinstance(n, str) and n.strip() for n in names)
        ):
            raise self.fail(
                f"{key}.capture",
                "is missing: the capture file (or a list of them), relative to the plan",
            )
        paths = []
        for name in names:
            path = (self.folder / name).resolve()
            if not path.is_file():
                raise self.fail(
                    f"{key}.capture",
                    f"no such file: {name} (paths are relative to the plan's folder {self.folder})",
                )
            paths.append(path)
        return tuple(paths)

    def options(self, entry: Mapping[str, Any], key: str) -> tuple[tuple[str, Any], ...]:
        table = entry.get("options", {})
        if not isinstance(table, Mapping):
            raise self.fail(
                f"{key}.options", "must be a table of the command's options, e.g. { lines = 36000 }"
            )
        for name, value in table.items():
            if name in _OUTPUT_OPTIONS:
                raise self.fail(
                    f"{key}.options.{name}",
                    "certify writes every result into the certificate's folder: leave this option out",
                )
            if isinstance(value, Mapping) or (
                isinstance(value, list) and any(isinstance(v, (Mapping, list)) for v in value)
            ):
                raise self.fail(f"{key}.options.{name}", "must be a value or a list of values")
        return tuple(table.items())

    def measurements(self, data: Mapping[str, Any]) -> tuple[Measurement, ...]:
        measurements = []
        for i, entry in enumerate(self.array(data, "measurement"), start=1):
            key = f"measurement[{i}]"
            command = " ".join(self.text(entry, key, "command").split())
            if command not in MEASUREMENT_COMMANDS:
                raise self.fail(
                    f"{key}.command",
                    f"{command!r} is not a measurement command; use one of "
                    + ", ".join(MEASUREMENT_COMMANDS),
                )
            rule = entry.get("decision_rule", "guarded")
            if rule not in DECISION_RULES:
                raise self.fail(
                    f"{key}.decision_rule", f"must be simple or guarded (ILAC-G8), not {rule!r}"
                )
            options = self.options(entry, key)
            limits = self.limits(entry.get("limits"), f"{key}.limits", command)
            for limit in limits:
                problem = window_limit_problem(command, dict(options), limit.key)
                if limit.allocation and not {"config", "budget"} & dict(options).keys():
                    problem = (
                        "the allocation's bounds come from the table's allocation: give "
                        'options.config (e.g. config = "table.toml") or options.budget'
                    )
                if problem is not None:
                    raise self.fail(f"{key}.limits.{limit.key}", problem)
            measurements.append(
                Measurement(
                    index=i,
                    name=self.text(entry, key, "name"),
                    command=command,
                    captures=self.captures(entry, key),
                    options=options,
                    limits=limits,
                    decision_rule=rule,
                )
            )
        return tuple(measurements)

    def certificate(self, data: Mapping[str, Any]) -> dict[str, Any]:
        table = self.table(data, "certificate", "certificate")
        self.only_known(table, "certificate", _TABLES["certificate"])
        number = self.text(table, "certificate", "number")
        if number != "auto" and not _NUMBER.fullmatch(number):
            raise self.fail(
                "certificate.number",
                f"{number!r} cannot name the certificate's folder: use letters, digits, '.', '_' "
                'and \'-\' (e.g. "RC-2026-0001"), or "auto"',
            )
        day = self.date(table, "certificate", "date")
        start = self.date(table, "certificate", "start_date") or day
        end = self.date(table, "certificate", "end_date") or day or start
        if start is None or end is None:
            raise self.fail(
                "certificate.date",
                "is missing: the date of calibration (or start_date and end_date)",
            )
        if day is not None and ("start_date" in table or "end_date" in table):
            raise self.fail("certificate.date", "give either date or start_date/end_date, not both")
        if end < start:
            raise self.fail(
                "certificate.end_date",
                f"{end.isoformat()} is before start_date {start.isoformat()}",
            )
        issued = self.date(table, "certificate", "issued") or end
        if issued < end:
            raise self.fail(
                "certificate.issued",
                f"{issued.isoformat()} is before the calibration ended ({end.isoformat()})",
            )
        language = self.text(table, "certificate", "language", required=False) or "en"
        if not re.fullmatch(r"[a-z]{2}", language):
            raise self.fail(
                "certificate.language",
                f"must be a two-letter ISO 639-1 code like en, not {language!r}",
            )
        supersedes = self.text(table, "certificate", "supersedes", required=False) or None
        title = (
            self.text(table, "certificate", "title", required=False) or "Calibration certificate"
        )
        location = self.text(table, "certificate", "location", required=False)
        return {
            "number": number,
            "start_date": start,
            "end_date": end,
            "issue_date": issued,
            "language": language,
            "supersedes": supersedes,
            "title": title,
            "location": location,
        }


def read_plan(path: str | Path) -> Plan:
    """Read and check a calibration plan file (TOML; INTERFACE.md, "Calibration plans and
    certificates").

    Parameters
    ----------
    path : str or Path
        The plan file. Every path in it is relative to its folder.

    Returns
    -------
    Plan
        The plan with captures resolved to absolute paths and dates checked.

    Raises
    ------
    ConfigError
        One line naming the plan file, the key (``measurement[2].capture``) and its line: a TOML
        syntax error, a missing or unknown key, a value of the wrong kind, a capture that does not
        exist, a reference standard past its due date on the calibration date.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such plan file") from None
    except IsADirectoryError:
        raise ConfigError(f"{path}: is a folder, not a plan file") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ConfigError(
            f"{path}: not UTF-8 text (byte {e.start}): save the plan as UTF-8"
        ) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"{path}: not valid TOML: {e}") from None
    reader = _Reader(path, text)
    for name in data:
        if name not in (*_TABLES, "conditions"):
            raise reader.fail(
                name, "unknown table; a plan has " + ", ".join((*_REQUIRED_TABLES, "conditions"))
            )
    for name in _REQUIRED_TABLES:
        if name not in data:
            brackets = f"[[{name}]]" if name in _ARRAYS else f"[{name}]"
            raise reader.fail(
                name, f"is missing: a plan needs a {brackets} table (rotacal certify --example)"
            )
    head = reader.certificate(data)
    return Plan(
        path=path.resolve(),
        text=raw,
        data=data,
        laboratory=reader.contact(data, "laboratory"),
        customer=reader.contact(data, "customer"),
        persons=reader.persons(data),
        item=reader.item(data),
        standards=reader.standards(data, head["end_date"]),
        conditions=reader.conditions(data),
        measurements=reader.measurements(data),
        **head,
    )
