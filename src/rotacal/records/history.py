"""An item's calibrations over time: each reported quantity with its U, its drift per year, and
the date the item is next due (``rotacal records history SERIAL``).

:func:`item_history` reads every certificate of one item in one query (items, certificates, the
certificate that supersedes each one, and the reported values as printed), fits each quantity's
drift by weighted least squares (:mod:`rotacal.records.trend`) and sets ``next_due``:

- for every quantity whose drift is significant (|b| > 2 u(b)) and whose latest certificate
  states an acceptance limit on the side it drifts towards: the date at which the predicted value
  plus (minus, for a lower limit) its expanded uncertainty (k = 2) reaches that limit — the
  earliest such date (ILAC-G24:2022 / OIML D 10 §6.3, method 2; NCSLI RP-1, variables data);
- otherwise the laboratory's fixed interval (``interval_months``, default 12) after the last
  calibration.

Drift may only SHORTEN the fixed interval, never lengthen it: a drift date later than the fixed
interval leaves the fixed date (the method then says when the drift would reach its limit).
Lengthening an interval is a decision of the laboratory's interval review on more evidence than a
fitted line (ILAC-G24 §6.1), so rotacal does not take it. A superseded certificate is listed, but
its values do not enter the fits: the certificate that superseded it replaces it.

Quantity keys: a quantity is named by its key (``scale_factor``). When one certificate of the item
reports a key in more than one measurement, every value of that key (in every certificate of the
item) is named ``key@measurement name`` — so that each series follows one measurement by its name
through time, whatever order the plans listed them in. Messages quote a key as the plan names
it: “scale_factor”.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import functools
from collections import Counter
from collections.abc import Mapping, Sequence
from decimal import Decimal, InvalidOperation
from typing import Any, NamedTuple, cast

import numpy as np
import sqlalchemy as sa

from rotacal.errors import ConfigError
from rotacal.numbers import fixed
from rotacal.results import Result
from rotacal.uncertainty import round_ilac

from . import models as m
from .store import Store
from .trend import (
    DriftLine,
    add_months,
    date_after,
    fit_drift,
    limit_crossing,
    years_since,
)

__all__ = [
    "Calibration",
    "Drift",
    "ItemHistory",
    "NextDue",
    "ReportedResult",
    "item_history",
    "per_year",
]


def per_year(unit: str) -> str:
    """The unit of a drift: ``ppm`` → ``ppm/year``, ``°/s`` → ``(°/s)/year``, none → ``1/year``."""
    if not unit:
        return "1/year"
    return f"({unit})/year" if any(c in unit for c in "/ ·*") else f"{unit}/year"


@dataclasses.dataclass(frozen=True, slots=True)
class ReportedResult:
    """One reported quantity of one certificate, as printed and as numbers.

    ``value``, ``U`` and ``k`` are the printed decimal text converted to numbers (None where the
    text is not a number), ``u = U/k`` [unit]. ``interval`` is the coverage interval a certificate
    states instead of ± U for a bounded quantity near zero. ``limit_min``/``limit_max`` and
    ``verdict`` are the conformity statement, where the plan set a limit.
    """

    value: float | None
    u: float | None
    U: float | None
    k: float | None
    unit: str
    name: str
    measurement: str
    printed: tuple[str, str]
    interval: tuple[float, float] | None = None
    limit_min: float | None = None
    limit_max: float | None = None
    verdict: str | None = None

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "value": self.value,
            "u": self.u,
            "U": self.U,
            "k": self.k,
            "unit": self.unit,
        }
        if self.interval is not None:
            out["interval"] = list(self.interval)
        if self.verdict is not None or self.limit_min is not None or self.limit_max is not None:
            out.update(limit_min=self.limit_min, limit_max=self.limit_max, verdict=self.verdict)
        return out


@dataclasses.dataclass(frozen=True)
class Calibration:
    """One certificate of the item: its number, calibration (end) date, issue date, the
    certificate it supersedes and the one that superseded it, and its reported quantities."""

    number: str
    date: dt.date
    issue_date: dt.date
    supersedes: str | None
    superseded_by: str | None
    results: Mapping[str, ReportedResult]

    def to_dict(self) -> dict[str, Any]:
        return {
            "number": self.number,
            "date": self.date.isoformat(),
            "issue_date": self.issue_date.isoformat(),
            "supersedes": self.supersedes,
            "superseded_by": self.superseded_by,
            "results": {key: r.to_dict() for key, r in self.results.items()},
        }


@dataclasses.dataclass(frozen=True)
class Drift:
    """One quantity's drift: ``value`` ± ``u`` in ``unit`` (the quantity's unit per year),
    ``significant`` when |value| > 2u, fitted over ``n`` calibrations, with the Birge ratio (None
    for two). ``line`` is the fit (its time axis: years after ``origin``, the last calibration);
    ``limits`` the acceptance limits (min, max) of the latest certificate reporting the quantity,
    in ``quantity_unit``. ``reaches`` is the date at which the prediction ± its expanded
    uncertainty reaches the limit it drifts towards (``reaches_limit`` names it; None when it
    does not drift significantly towards a limit; 9999-12-31 when beyond the calendar)."""

    value: float
    u: float
    unit: str
    significant: bool
    n: int
    birge_ratio: float | None
    line: DriftLine
    origin: dt.date
    quantity_unit: str
    limits: tuple[float | None, float | None] = (None, None)
    reaches: dt.date | None = None
    reaches_limit: str = ""

    def rounded(self) -> tuple[str, str]:
        """The drift and its u as a person reads them: u to two significant digits, the drift to
        the same decimal place (ILAC-P14 §5.4)."""
        return round_ilac(self.value, self.u)

    def to_dict(self) -> dict[str, Any]:
        return {
            "value": self.value,
            "u": self.u,
            "unit": self.unit,
            "significant": self.significant,
            "n": self.n,
            "birge_ratio": self.birge_ratio,
        }


@dataclasses.dataclass(frozen=True)
class NextDue:
    """When the item is next due: ``date``, the sentence that says what set it (``method``), and
    the quantity whose drift set it (None: the fixed interval)."""

    date: dt.date
    method: str
    quantity: str | None = None

    def to_dict(self) -> dict[str, Any]:
        return {"date": self.date.isoformat(), "method": self.method, "quantity": self.quantity}


@dataclasses.dataclass(frozen=True)
class ItemHistory(Result):
    """An item's calibrations (oldest first), each quantity's drift per year and its next due date.

    ``item`` is ``{kind, manufacturer, model, serial}``. ``_fixed_due`` is the date the fixed
    interval alone gives, ``_interval_months`` that interval (for the report).
    """

    serial: str
    item: Mapping[str, str]
    calibrations: tuple[Calibration, ...]
    drift_per_year: Mapping[str, Drift]
    next_due: NextDue
    _fixed_due: dt.date
    _interval_months: int


# -- reading -----------------------------------------------------------------------------------


@functools.lru_cache(maxsize=16384)  # U, k and limits repeat from certificate to certificate
def _number(text: str | None) -> float | None:
    """Printed decimal text as a float (Decimal first: the text is exactly what was printed)."""
    if text is None or not str(text).strip():
        return None
    try:
        value = Decimal(str(text).strip().replace("−", "-"))
    except InvalidOperation:
        return None
    return float(value) if value.is_finite() else None


def _pick_item(store: Store, serial: str, model: str | None) -> tuple[list[int], dict[str, str]]:
    """The ids of the item(s) with ``serial`` that the history covers, and the item's names.

    Items that differ only in their kind are one item (the same manufacturer, model and serial)."""
    items = _table(m.Item)
    with store.read() as session:
        rows = session.execute(
            sa.select(items.c.id, items.c.kind, items.c.manufacturer, items.c.model)
            .where(items.c.serial == serial)
            .order_by(items.c.id)
        ).all()
        if not rows:
            near = session.execute(
                sa.select(items.c.serial)
                .where(sa.func.lower(sa.func.trim(items.c.serial)) == serial.strip().lower())
                .distinct()
                .limit(5)
            ).scalars()
            near_text = ", ".join(repr(s) for s in near)
    if not rows:
        hint = f"; serials differing only in case or spaces: {near_text}" if near_text else ""
        raise ConfigError(
            f"records store {store.shown}: no certificate of an item with serial {serial!r}"
            f"{hint}; `rotacal records list` shows the certificates and their serials"
        )
    groups: dict[tuple[str, str], list[Any]] = {}
    for row in rows:
        groups.setdefault((row.manufacturer, row.model), []).append(row)
    if model is not None:
        groups_all = list(groups)
        groups = {
            key: group for key, group in groups.items() if model in (key[1], f"{key[0]} {key[1]}")
        }
        if not groups:
            found = "; ".join(f"{mf} {md}" for mf, md in sorted(groups_all))
            raise ConfigError(
                f"records store {store.shown}: serial {serial!r} has no item of model {model!r}; "
                f"its items: {found}"
            )
    if len(groups) > 1:
        models = Counter(md for _, md in groups)
        choices = "; ".join(
            f"{mf} {md} (--model {_shell(md if models[md] == 1 else f'{mf} {md}')})"
            for mf, md in sorted(groups)
        )
        raise ConfigError(
            f"records store {store.shown}: serial {serial!r} belongs to {len(groups)} items: "
            f"{choices}; say which with --model"
        )
    (manufacturer, model_name), group = next(iter(groups.items()))
    kinds = list(dict.fromkeys(r.kind for r in group))
    item = {
        "kind": " / ".join(kinds),
        "manufacturer": manufacturer,
        "model": model_name,
        "serial": serial,
    }
    return [r.id for r in group], item


def _table(model: type[m.Base]) -> sa.Table:
    return cast(sa.Table, model.__table__)


def _shell(text: str) -> str:
    """``text`` as it is typed on a command line (quoted when it has a space)."""
    return f'"{text}"' if any(c.isspace() for c in text) else text


class _Row(NamedTuple):
    """One row of :func:`_rows` (a plain tuple: its fields read fast)."""

    id: int
    number: str
    end_date: dt.date
    issue_date: dt.date
    supersedes: str | None
    superseded_by: str | None
    measurement: int | None
    measurement_name: str | None
    quantity: str | None
    name: str
    unit: str
    value: str
    expanded: str
    coverage_factor: str
    interval_low: str | None
    interval_high: str | None
    limit_min: str | None
    limit_max: str | None
    verdict: str | None


def _rows(store: Store, item_ids: Sequence[int]) -> list[_Row]:
    """Every reported value of the items' certificates, with the certificate's dates and the
    number of the certificate that superseded it: one query, oldest calibration first (a
    certificate without values gives one row whose value columns are None)."""
    cert = _table(m.Certificate).alias("c")
    later = _table(m.Certificate).alias("later")
    rv = _table(m.ReportedValue).alias("v")
    stmt = (
        sa.select(
            cert.c.id,
            cert.c.number,
            cert.c.end_date,
            cert.c.issue_date,
            cert.c.supersedes,
            later.c.number,
            *(rv.c[name] for name in _Row._fields[6:]),
        )
        .select_from(cert)
        .outerjoin(later, later.c.supersedes == cert.c.number)
        .outerjoin(rv, rv.c.certificate_id == cert.c.id)
        .where(cert.c.item_id.in_(item_ids))
        .order_by(cert.c.end_date, cert.c.issue_date, cert.c.id, rv.c.measurement, rv.c.position)
    )
    with store.begin(read_only=True) as connection:
        return [_Row._make(r) for r in connection.execute(stmt).all()]


def _series_keys(rows: Sequence[_Row]) -> list[str | None]:
    """The series name of each row: its key, or ``key@measurement name`` for a key that some
    certificate reports more than once (see the module's docstring); None for a certificate
    without values."""
    keys: list[str | None] = [r.quantity for r in rows]
    counts = Counter(zip((r.id for r in rows), keys, strict=True))
    repeated = {key for (_, key), n in counts.items() if n > 1 and key is not None}
    if not repeated:
        return keys
    seen: Counter[tuple[int, str]] = Counter()
    for i, r in enumerate(rows):
        if r.quantity not in repeated:
            continue
        name = f"{r.quantity}@{r.measurement_name}"
        seen[(r.id, name)] += 1
        if seen[(r.id, name)] > 1:  # two measurements of one certificate with the same name
            name = f"{name} (measurement {r.measurement})"
        keys[i] = name
    return keys


def _result(r: _Row, warnings: list[str], key: str) -> ReportedResult:
    value, U, k = _number(r.value), _number(r.expanded), _number(r.coverage_factor)
    u = U / k if U is not None and k is not None and k > 0 else None
    if value is None or u is None or not u > 0:
        warnings.append(
            f"{r.number}: “{key}” = {r.value} ± {r.expanded} (k = {r.coverage_factor}) is not a "
            "value with a positive uncertainty; it is listed but left out of the drift"
        )
    low, high = _number(r.interval_low), _number(r.interval_high)
    return ReportedResult(
        value=value,
        u=u,
        U=U,
        k=k,
        unit=r.unit,
        name=r.name,
        measurement=r.measurement_name or "",
        printed=(r.value, r.expanded),
        interval=(low, high) if low is not None and high is not None else None,
        limit_min=_number(r.limit_min),
        limit_max=_number(r.limit_max),
        verdict=r.verdict,
    )


def _calibrations(rows: Sequence[_Row], warnings: list[str]) -> list[Calibration]:
    """The rows grouped into certificates (in the query's order)."""
    keys = _series_keys(rows)
    calibrations: list[Calibration] = []
    current: dict[str, ReportedResult] = {}
    last_id = None
    for r, key in zip(rows, keys, strict=True):
        if r.id != last_id:
            last_id = r.id
            current = {}
            calibrations.append(
                Calibration(
                    number=r.number,
                    date=r.end_date,
                    issue_date=r.issue_date,
                    supersedes=r.supersedes,
                    superseded_by=r.superseded_by,
                    results=current,
                )
            )
        if key is not None:
            current[key] = _result(r, warnings, key)
    return calibrations


# -- drift and next due ------------------------------------------------------------------------


def _drift(
    key: str, calibrations: Sequence[Calibration], origin: dt.date, warnings: list[str]
) -> Drift | None:
    """The drift of ``key`` over the certificates that were not superseded (None: fewer than two
    usable values on distinct dates)."""
    points = [
        (c.date, c.results[key])
        for c in calibrations
        if c.superseded_by is None and key in c.results
    ]
    if not points:
        return None
    unit = points[-1][1].unit
    other_units = sorted({r.unit for _, r in points if r.unit != unit})
    if other_units:
        warnings.append(
            f"“{key}”: some certificates state it in {', '.join(other_units)}, the latest in "
            f"{unit}; the drift uses only the values in {unit}"
        )
    usable = [(d, r) for d, r in points if r.unit == unit and r.value is not None and r.u]
    if len(usable) < 2 or len({d for d, _ in usable}) < 2:
        return None
    t = years_since([d for d, _ in usable], origin)
    line = fit_drift(t, np.array([r.value for _, r in usable]), np.array([r.u for _, r in usable]))
    if line.scaled:
        warnings.append(
            f"“{key}”: the values scatter more than their uncertainties allow (Birge ratio "
            f"{line.birge_ratio:.2f} over {line.n} calibrations); the drift's uncertainty is "
            "multiplied by it"
        )
    if any(r.interval is not None for _, r in usable):
        warnings.append(
            f"“{key}”: its certificates state a coverage interval rather than ± U (a bounded "
            "quantity near zero); the drift treats each value as ± U/k"
        )
    latest = usable[-1][1]
    drift = Drift(
        value=line.slope,
        u=line.u_slope,
        unit=per_year(unit),
        significant=line.significant,
        n=line.n,
        birge_ratio=line.birge_ratio,
        line=line,
        origin=origin,
        quantity_unit=unit,
        limits=(latest.limit_min, latest.limit_max),
    )
    found = _crossing(drift)
    if found is None:
        return drift
    return dataclasses.replace(drift, reaches=found[0], reaches_limit=found[1])


def _crossing(drift: Drift) -> tuple[dt.date, str] | None:
    """When a drift takes its prediction's band to the limit it runs towards: the date
    (9999-12-31 beyond the calendar) and which limit; None when no limit lies that way."""
    low, high = drift.limits
    upper = drift.value > 0
    limit = high if upper else low
    if limit is None:
        return None
    t = limit_crossing(drift.line, limit, upper)
    if t is None:
        return None
    side = "upper" if upper else "lower"
    day = date_after(drift.origin, t) or (dt.date.min if t < 0 else dt.date.max)
    unit = f" {drift.quantity_unit}" if drift.quantity_unit else ""
    return day, f"its {side} limit {fixed(limit)}{unit}"


def _next_due(
    drifts: Mapping[str, Drift],
    last: dt.date,
    months: int,
    today: dt.date,
    warnings: list[str],
) -> NextDue:
    fixed_due = add_months(last, months)
    fixed_text = (
        f"the laboratory's fixed interval of {months} month{'s' if months != 1 else ''} after "
        f"the last calibration on {last}"
    )
    crossings = [(d.reaches, key) for key, d in drifts.items() if d.reaches is not None]
    for day, key in sorted(crossings):
        if day < today:
            warnings.append(
                f"“{key}” is predicted out of tolerance since {day}: its predicted value "
                f"{'plus' if drifts[key].value > 0 else 'minus'} its expanded uncertainty "
                f"(k = 2) reaches {drifts[key].reaches_limit} then; recalibrate the item before "
                "further use"
            )
    method_ref = (
        "straight-line drift by weighted least squares, k = 2; ILAC-G24:2022 / OIML D 10 §6.3, "
        "method 2; NCSLI RP-1, variables data"
    )
    if crossings:
        day, key = min(crossings)
        drift = drifts[key]
        limit_text = drift.reaches_limit
        value, u = drift.rounded()
        what = (
            f"the drift of “{key}” ({value} {drift.unit}, u = {u} {drift.unit}) "
            f"takes its predicted value {'plus' if drift.value > 0 else 'minus'} its expanded "
            f"uncertainty to {limit_text}"
        )
        if day < fixed_due:
            method = (
                f"{what} on {day} ({method_ref}); earlier than the end of {fixed_text}, {fixed_due}"
            )
            return NextDue(day, _sentence(method), key)
        when = "beyond the year 9999" if day == dt.date.max else f"on {day}"
        method = (
            f"{fixed_text}; {what} only {when}, and drift may shorten the interval, "
            "never lengthen it"
        )
    elif any(d.significant for d in drifts.values()):
        method = (
            f"{fixed_text}; the quantities that drift significantly have no limit on the side "
            "they drift towards"
        )
    else:
        method = f"{fixed_text}; no quantity with a limit drifts significantly (|b| > 2 u(b))"
    if fixed_due < today:
        warnings.append(f"the item is overdue for calibration since {fixed_due}")
    return NextDue(fixed_due, _sentence(method), None)


def _sentence(text: str) -> str:
    return text[:1].upper() + text[1:] + "."


def _interval_months(store: Store) -> int:
    text = store.settings()["interval_months"]
    if not text.strip().isdigit() or not 1 <= int(text) <= 240:
        raise ConfigError(
            f"records store {store.shown}: the setting interval_months = {text!r} is not a whole "
            "number of months from 1 to 240; correct it in the store's settings table (it was "
            "changed outside rotacal)"
        )
    return int(text)


def item_history(
    store: Store, serial: str, *, model: str | None = None, today: dt.date | None = None
) -> ItemHistory:
    """Every calibration of the item with ``serial``, each quantity's drift per year and the
    date it is next due (the module's docstring gives the method).

    Parameters
    ----------
    store : Store
        The records store.
    serial : str
        The item's serial number, exactly as its certificates state it.
    model : str, optional
        The item's model (or "manufacturer model"), when the serial belongs to several items.
    today : date, optional
        The date against which "overdue" is judged [default: today's date].

    Raises
    ------
    ConfigError
        No certificate of that serial; the serial belongs to several items and ``model`` does not
        pick one; the store's ``interval_months`` setting is not usable.
    """
    item_ids, item = _pick_item(store, serial, model)
    months = _interval_months(store)
    warnings: list[str] = []
    calibrations = _calibrations(_rows(store, item_ids), warnings)
    current = [c for c in calibrations if c.superseded_by is None] or calibrations
    last = max(c.date for c in current)
    keys = list(dict.fromkeys(key for c in current for key in c.results))
    drifts = {}
    for key in keys:
        drift = _drift(key, calibrations, last, warnings)
        if drift is not None:
            drifts[key] = drift
    latest = current[-1]
    for key, r in latest.results.items():
        if r.verdict == "fail":
            warnings.append(
                f"the latest calibration ({latest.number}) found “{key}” outside its limit"
            )
    next_due = _next_due(drifts, last, months, today or dt.date.today(), warnings)
    return ItemHistory(
        serial=serial,
        item=item,
        calibrations=tuple(calibrations),
        drift_per_year=drifts,
        next_due=next_due,
        _fixed_due=add_months(last, months),
        _interval_months=months,
        warnings=tuple(dict.fromkeys(warnings)),
    )
