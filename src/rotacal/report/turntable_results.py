"""The results a lab signs from a turntable budget, for the report's summary.

What the Monte Carlo check and the calibration check state with a coverage interval
(:mod:`rotacal.turntable.draws`): the orientation error 99.9 % of tables built within the
tolerances stay within, the fraction of tables outside the requirement and — for a table of the
GyroWheel study's geometry — the rate-sensing error 95 % of drift calibrations stay within and the
fraction of calibrations above the required accuracy. Each is compared with its limit; the verdict
is "pass" only when the whole interval is within the limit, "fail" only when it is wholly outside,
and none (inconclusive) when it straddles the limit (guarded acceptance, ILAC-G8). The largest
error among the draws grows with their number and has no such interval: the report shows it as a
diagnostic, with the worst case of the allocation.

References
----------
Clopper & Pearson (1934); David & Nagaraja (2003) §7.1; ILAC-G8:09/2019 §4.2 (decision rules
with guard bands); the GyroWheel study (Int. J. Aerospace Eng., article 6524782), §4.3, Figure 9
and eqs. (7)–(14).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rotacal.numbers import fixed
from rotacal.report.html import ResultRow
from rotacal.report.turntable_common import COMP_SYMBOL
from rotacal.report.uncertainty import result_row, verdict, verdict_note
from rotacal.turntable.budget import TurntableBudget
from rotacal.turntable.model import COMPONENTS

__all__ = ["RESULT_REFERENCES", "monte_carlo_rows", "turntable_results"]

#: The references the results cite (the section lists them).
RESULT_REFERENCES = ["clopper1934", "david2003", "ilac_g8"]

#: A fraction whose interval ends below this is stated in ppm (easier to read than 0.00037 %).
_PPM_BELOW = 1e-3


def _interval_row(
    name: str, value: float, interval: Sequence[float], unit: str, limit: float, p: float
) -> ResultRow:
    low, high = float(interval[0]), float(interval[1])
    passed = verdict((low, high), limit)
    return result_row(
        name,
        value,
        unit,
        U=0.5 * (high - low),
        p=p,
        interval=(low, high),
        limit=f"≤ {fixed(limit, 4)} {unit}",
        passed=passed,
        note=verdict_note(passed),
    )


def _fraction_row(
    name: str, hits: int, n: int, interval: Sequence[float], what: str, p: float
) -> ResultRow:
    """A fraction of draws, in ppm or %, with its interval. No verdict: the limit is "none", which
    an interval from finitely many draws never lies wholly within (the worst case of the
    allocation is the guarantee); the count of the draws is the note."""
    scale, unit = (1e6, "ppm") if float(interval[1]) < _PPM_BELOW else (100.0, "%")
    low, high = (float(v) * scale for v in interval)
    return result_row(
        name,
        hits / n * scale,
        unit,
        U=0.5 * (high - low),
        p=p,
        interval=(low, high),
        note=f"{hits:,} of {n:,} {what}".replace(",", " "),
    )


def monte_carlo_rows(budget: TurntableBudget) -> list[ResultRow]:
    """The Monte Carlo check's summary rows: each |Δ|'s 99.9 % quantile with its order-statistic
    interval and verdict, then the fraction of tables outside the requirement (Clopper–Pearson)."""
    mc = budget.monte_carlo
    p = float(mc["coverage_probability"])
    rows = []
    if "quantile_abs_arcmin" in mc:
        for c in COMPONENTS:
            rows.append(
                _interval_row(
                    f"|{COMP_SYMBOL[c]}| not exceeded by 99.9 % of tables",
                    mc["quantile_abs_arcmin"][c],
                    mc["quantile_abs_interval_arcmin"][c],
                    "′",
                    budget.requirement_arcmin[c],
                    p,
                )
            )
    outside = int(mc["outside"])
    rows.append(
        _fraction_row(
            "tables outside the orientation requirement",
            outside,
            int(mc["runs"]),
            mc["fraction_outside_interval"],
            "tables drawn",
            p,
        )
    )
    return rows


def _calibration_rows(cal: Mapping[str, Any], p: float) -> list[ResultRow]:
    wm = float(cal["required_deg_h"])
    runs = int(cal["runs"])
    rows = []
    for axis in ("x", "y"):
        interval = cal["p95_rate_error_interval_deg_h"].get(axis)
        if interval is not None:
            rows.append(
                _interval_row(
                    f"Δω{axis} not exceeded by 95 % of calibrations",
                    cal["p95_rate_error_deg_h"][axis],
                    interval,
                    "°/h",
                    wm,
                    p,
                )
            )
    for axis in ("x", "y"):
        above = round(float(cal["fraction_above_required"][axis]) * runs)
        rows.append(
            _fraction_row(
                f"calibrations with Δω{axis} above ωm",
                above,
                runs,
                cal["fraction_above_required_interval"][axis],
                "tables drawn",
                p,
            )
        )
    return rows


def turntable_results(budget: TurntableBudget) -> list[ResultRow]:
    """The summary rows of a turntable budget (module docstring): the Monte Carlo check's, then the
    calibration check's where the budget has one."""
    mc = budget.monte_carlo
    rows = monte_carlo_rows(budget)
    cal = budget.calibration
    if cal is not None and "p95_rate_error_interval_deg_h" in cal:
        rows += _calibration_rows(cal, float(mc["coverage_probability"]))
    return rows
