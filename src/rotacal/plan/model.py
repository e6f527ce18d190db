"""A calibration plan as rotacal holds it once read: who, what, with which standards, and which
measurements with which limits (INTERFACE.md, "Calibration plans and certificates").

:func:`rotacal.plan.read_plan` makes these from a plan file; everything downstream (running the
measurements, the certificate, the records) reads them and never the TOML again.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = [
    "DECISION_RULES",
    "ITEM_KINDS",
    "PERSON_ROLES",
    "Conditions",
    "Contact",
    "Item",
    "Limit",
    "Measurement",
    "Person",
    "Plan",
    "Standard",
]

#: Kinds of item a plan may calibrate (INTERFACE.md).
ITEM_KINDS = ("gyroscope", "rate-table", "angular-acceleration-table", "encoder", "turntable")
#: Roles of the persons a certificate names (ISO/IEC 17025 §7.8.2.1 p): who performed the
#: calibration and who approved (authorised) the certificate.
PERSON_ROLES = ("performed", "approved")
#: Decision rules of a conformity statement (ILAC-G8:09/2019 §4.2): simple acceptance (w = 0) or
#: guarded acceptance with the guard band w = U.
DECISION_RULES = ("simple", "guarded")


@dataclasses.dataclass(frozen=True)
class Contact:
    """A laboratory or a customer: name, postal address, e-mail (and a phone, if given);
    ``country`` as an ISO 3166-1 alpha-2 code ("DE"), "" when not given."""

    name: str
    address: str = ""
    email: str = ""
    phone: str = ""
    country: str = ""


@dataclasses.dataclass(frozen=True)
class Person:
    """A person responsible for the certificate: ``role`` is ``performed`` or ``approved``."""

    name: str
    role: str
    title: str = ""


@dataclasses.dataclass(frozen=True)
class Item:
    """The item calibrated; ``serial`` identifies it (and its records' history). ``condition`` is
    its condition on receipt and ``received`` the date it was received (ISO/IEC 17025:2017
    §7.8.2.1 g, h), when the plan states them."""

    kind: str
    manufacturer: str
    model: str
    serial: str
    description: str = ""
    condition: str = ""
    received: dt.date | None = None


@dataclasses.dataclass(frozen=True)
class Standard:
    """A reference standard used, with the certificate that makes it traceable and its due date."""

    name: str
    id: str
    certificate: str
    due: dt.date
    traceability: str = ""


@dataclasses.dataclass(frozen=True)
class Conditions:
    """Environmental conditions of the calibration (ISO/IEC 17025 §7.8.4.1 a).

    ``temperature_c`` and its standard uncertainty ``temperature_u_c`` in °C,
    ``humidity_percent`` relative humidity in %; ``others`` keeps any further key of the plan's
    ``[conditions]`` as given (name → value), in the plan's order.
    """

    temperature_c: float | None = None
    temperature_u_c: float | None = None
    humidity_percent: float | None = None
    others: tuple[tuple[str, Any], ...] = ()


@dataclasses.dataclass(frozen=True)
class Limit:
    """An acceptance limit on one reported quantity (a JSON key of the command's results), in the
    quantity's own unit: ``min`` and/or ``max`` (None: no limit on that side). ``allocation``:
    the limits are the bounds of the turntable's error allocation that ``turntable identify``
    reports (``errors_arcsec = "allocation"``), one per identified error or sum."""

    key: str
    min: float | None = None
    max: float | None = None
    allocation: bool = False


@dataclasses.dataclass(frozen=True)
class Measurement:
    """One ``[[measurement]]`` of a plan.

    ``index`` counts from 1 in the plan's order; ``captures`` are absolute paths (the plan gives
    them relative to itself); ``options`` the command's options as on the CLI without ``--``
    (name → value, in the plan's order); ``decision_rule`` one of :data:`DECISION_RULES`.
    """

    index: int
    name: str
    command: str
    captures: tuple[Path, ...]
    options: tuple[tuple[str, Any], ...] = ()
    limits: tuple[Limit, ...] = ()
    decision_rule: str = "guarded"

    @property
    def key(self) -> str:
        """How error messages name this measurement in the plan: ``measurement[2]``."""
        return f"measurement[{self.index}]"

    def option_map(self) -> dict[str, Any]:
        return dict(self.options)


@dataclasses.dataclass(frozen=True)
class Plan:
    """A calibration plan, read and checked.

    ``number`` is the certificate number or ``"auto"``; ``start_date``/``end_date`` the dates of
    calibration (equal for a one-day calibration) and ``issue_date`` the certificate's date of issue
    (``[certificate] issued``; default ``end_date``) — all from the plan, never the clock, so that
    the same plan gives the same certificate. ``location`` is where the calibration was performed
    when not at the laboratory (ISO/IEC 17025 §7.8.2.1 c). ``text`` is the plan file's bytes as
    given, ``data`` the TOML as parsed.
    """

    path: Path
    text: bytes
    data: Mapping[str, Any]
    number: str
    start_date: dt.date
    end_date: dt.date
    issue_date: dt.date
    laboratory: Contact
    customer: Contact
    persons: tuple[Person, ...]
    item: Item
    standards: tuple[Standard, ...]
    conditions: Conditions
    measurements: tuple[Measurement, ...]
    supersedes: str | None = None
    language: str = "en"
    title: str = "Calibration certificate"
    location: str = ""
