"""The reported quantities of a measurement: each result that carries an uncertainty budget, with
value, U, k and p rounded as ILAC-P14 asks, in a unit a certificate can state.

Every analysis command's JSON holds ``uncertainty_budgets``: key → a GUM budget (value, U, k, p,
unit, and for a biased, bounded quantity its coverage interval), or states results as a value and
its u (:mod:`rotacal.certificate.stated`: the rate's windows, position, turntable identify).
Those are the calibration results; what a budget stands for only as an example of many (one
reversing moment of the table, one line of the self-calibrated scale) is not a result of the item
and is left out.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from decimal import ROUND_HALF_EVEN, Decimal
from typing import Any

from rotacal.errors import CaptureError, ConfigError
from rotacal.glossary import GLOSSARY
from rotacal.uncertainty.budget import round_ilac

from .content import ReportedQuantity
from .stated import stated_budgets
from .units import CONVERTED_UNITS, dsi_unit, factor_to_printed, printed_unit

__all__ = ["REPRESENTATIVE_BUDGETS", "reported_quantities", "standard_uncertainty"]

#: Budgets that stand for one of many values (not a result of the item), by command.
REPRESENTATIVE_BUDGETS: dict[str, frozenset[str]] = {
    "motion encoder": frozenset({"reversal_times_s"}),
    "motion lts": frozenset({"reversal_times_s"}),
    "motion fog": frozenset({"reversal_times_s"}),
    "motion angle": frozenset({"reversal_times_s"}),
    "selfcal": frozenset({"deviation_arcsec"}),
}


def _budgets(budgets: Mapping[str, Any], prefix: str = "") -> Iterator[tuple[str, Mapping]]:
    """(key, budget) of every budget; nested groups (drift coefficients) as ``group.name``."""
    for key, b in budgets.items():
        if isinstance(b, Mapping) and "value" in b and "U" in b:
            yield prefix + key, b
        elif isinstance(b, Mapping):
            yield from _budgets(b, f"{prefix}{key}.")


def _three_digits(k: float) -> str:
    """k with three significant digits in fixed notation (the DCC's k admits no exponent)."""
    d = Decimal(repr(float(k)))
    exponent = d.adjusted() - 2
    return str(d.quantize(Decimal(1).scaleb(exponent), rounding=ROUND_HALF_EVEN))


def _p_text(p: float) -> str:
    text = repr(float(p))
    return text[:-2] if text.endswith(".0") else text


def _name(key: str, budget: Mapping[str, Any]) -> str:
    """The reader's name: the glossary's for the key, else the budget's own quantity name."""
    term = GLOSSARY.get(key)
    if term is not None:
        return term.name + (f" {term.symbol}" if term.symbol else "")
    return str(budget.get("quantity") or key)


def _interval(interval: Any, value: float, decimals: int) -> tuple[str, str]:
    low, high = (float(x) for x in interval)
    # a bounded quantity (THD, nonlinearity ≥ 0): the interval does not reach below zero
    low = max(low, 0.0) if low <= 0.0 <= value else low
    return f"{low:.{decimals}f}", f"{high:.{decimals}f}"


def reported_quantities(
    command: str, results: Mapping[str, Any], *, output_unit: str = ""
) -> tuple[ReportedQuantity, ...]:
    """The quantities a certificate reports of one command's ``results`` (its JSON).

    Parameters
    ----------
    command : str
        The analysis command ("gyro scale-factor").
    results : mapping
        The command's JSON; its ``uncertainty_budgets`` are read.
    output_unit : str
        The gyro's output unit, put in for "output unit" (``--output-unit``).

    Raises
    ------
    ConfigError
        When a result's unit cannot be stated (the output unit not given) or a budget has no
        positive, finite U (a certificate states no result without its uncertainty).

    References
    ----------
    ILAC-P14:09/2020 §5.4 (U to two significant digits, the value to the same decimal place);
    JCGM 100:2008 (GUM) §7.2.4.
    """
    skip = REPRESENTATIVE_BUDGETS.get(command, frozenset())
    quantities = []
    budgets = {**(results.get("uncertainty_budgets") or {}), **stated_budgets(command, results)}
    for key, b in _budgets(budgets):
        if key in skip:
            continue
        unit = printed_unit(str(b.get("unit", "")), output_unit)
        factor = factor_to_printed(str(b.get("unit", "")), output_unit)
        if not float(b["U"]) > 0.0:
            raise CaptureError(
                f"the {_name(key, b)} has no uncertainty (U = {b['U']}): a certificate states no "
                "result without one; is the capture noise-free (a simulation without noise)?"
            )
        value, big_u = round_ilac(factor * float(b["value"]), factor * float(b["U"]))
        decimals = len(big_u.split(".")[1]) if "." in big_u else 0
        interval = b.get("interval")
        quantities.append(
            ReportedQuantity(
                key=key,
                name=_name(key, b),
                unit=unit,
                dsi_unit=dsi_unit(str(b.get("unit", "")), output_unit),
                value=value,
                U=big_u,
                k=_three_digits(float(b["k"])),
                p=_p_text(float(b["p"])),
                interval=_interval(
                    [factor * float(x) for x in interval], factor * float(b["value"]), decimals
                )
                if interval is not None
                else None,
                note=_note(key, results, str(b.get("unit", ""))),
            )
        )
    if not quantities:
        raise ConfigError(
            f"'{command}' gave no result with an uncertainty: there is nothing to certify"
        )
    return tuple(quantities)


def _note(key: str, results: Mapping[str, Any], unit: str) -> str:
    if unit in CONVERTED_UNITS:
        return "stated per m/s² (1 g = 9.806 65 m/s²)"
    if key.endswith("_percent_fs") and results.get("full_scale_deg_s") is not None:
        return f"of the full scale {float(results['full_scale_deg_s']):g} °/s"
    return ""


def standard_uncertainty(q: ReportedQuantity) -> str:
    """u = U/k of the printed U and k, to two significant digits: the standard uncertainty the
    DCC's ``si:coverageInterval`` of a biased, bounded quantity needs; the PDF prints it beside
    that interval, so both state the same number."""
    u = Decimal(q.U) / Decimal(q.k)
    return round_ilac(0.0, float(u))[1]
