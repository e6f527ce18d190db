"""Results and uncertainty budgets in reports, rounded as ILAC-P14 asks, named by the glossary.

Every calibration's report section puts :func:`budget_results` — each budget's quantity as
value ± U with k and p — into its ``results`` (the report's summary at the top) and
:func:`budget_details` — one GUM budget table per measurand — into its folded ``details``.
:func:`result_row` states any other result the same way.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from rotacal.errors import ConfigError
from rotacal.glossary import GLOSSARY
from rotacal.numbers import coverage, fixed, format_quantity
from rotacal.report.html import ResultRow, Table
from rotacal.report.wording import readable
from rotacal.uncertainty.budget import UncertaintyBudget

__all__ = [
    "budget_details",
    "budget_results",
    "budget_table",
    "budget_tables",
    "plain_name",
    "result_row",
    "results_table",
    "verdict",
    "verdict_note",
]


def plain_name(key: str) -> str:
    """The glossary's name of a JSON key (:mod:`rotacal.glossary`); the key itself if it has none
    (the report tests fail on any key that reaches a reader)."""
    term = GLOSSARY.get(key)
    return term.name if term is not None else key


def result_row(
    quantity: str,
    value: Any,
    unit: str = "",
    *,
    U: Any = None,
    k: Any = None,
    p: float | None = None,
    interval: Any = None,
    limit: str = "",
    passed: bool | None = None,
    note: str = "",
) -> ResultRow:
    """One result for a report's summary: value ± U unit (ILAC-P14 rounding, SI prefixes), k, p.

    ``quantity`` is the plain name (or a glossary key); ``U`` the expanded uncertainty in ``unit``
    (None: a value without uncertainty, e.g. a count); ``interval`` a coverage interval that is
    not centred on the value (a THD near zero).
    """
    has_u = U is not None and isinstance(U, (int, float)) and U == U and U > 0
    return ResultRow(
        quantity=plain_name(quantity),
        value=readable(format_quantity(value, unit, U=U, p=p, interval=interval, si_prefix=True)),
        coverage=coverage(float(k), p).strip("()") if has_u and k is not None else "",
        limit=limit,
        passed=passed,
        note=note,
    )


def budget_results(
    budgets: Mapping[str, UncertaintyBudget],
    *,
    names: Mapping[str, str] | None = None,
    notes: Mapping[str, str] | None = None,
) -> list[ResultRow]:
    """The summary rows of a result's budgets: each quantity as value ± U (k, p) in its unit.

    ``names`` overrides the glossary's name of a key (e.g. to add an axis); ``notes`` adds a
    remark under a name. A biased, bounded quantity (a THD) states its coverage interval.

    References
    ----------
    JCGM 100:2008 (GUM) §7.2.4; ILAC-P14:09/2020 §5.2–5.4.
    """
    rows = []
    for key, b in budgets.items():
        name = (names or {}).get(key) or plain_name(b.quantity if b.quantity in GLOSSARY else key)
        rows.append(
            result_row(
                name,
                b.value,
                b.unit,
                U=b.U,
                k=b.k,
                p=b.p,
                interval=b.interval,
                note=(notes or {}).get(key, ""),
            )
        )
    return rows


def budget_details(budgets: Mapping[str, UncertaintyBudget]) -> list[Table]:
    """One folded GUM budget table per measurand (:func:`budget_table`), for a section's details."""
    return [budget_table(b) for b in budgets.values()]


#: ν_eff at or above this is shown as ∞ (a t-factor no longer differs from the normal one).
NU_INFINITE = 1e6


def _nu_text(nu: float) -> str:
    """ν_eff to three significant digits in fixed notation (67 967 → 68000); ∞ from 10⁶ on."""
    return "∞" if not nu < NU_INFINITE else fixed(nu, 3)


def _is_monte_carlo(b: UncertaintyBudget) -> bool:
    return b.method == "Monte Carlo"


def _rounded(b: UncertaintyBudget) -> tuple[str, str]:
    try:
        return b.rounded()
    except ConfigError:  # U = 0 or not finite: state the plain value, no ±
        return fixed(b.value), "—"


def results_table(budgets: Mapping[str, UncertaintyBudget], caption: str = "") -> Table:
    """The results with their expanded uncertainties (ILAC-P14 rounding), k, p, ν_eff, method.

    References
    ----------
    JCGM 100:2008 (GUM) §7.2.4; ILAC-P14:09/2020 §5.4 (U to at most two significant digits, the
    value to the same decimal place).
    """
    rows = []
    for b in budgets.values():
        value, big_u = _rounded(b)
        unit = f" {b.unit}" if b.unit else ""
        nu = _nu_text(b.dof_eff)
        cell_u = f"{big_u}{unit}" if big_u != "—" else "—"
        if b.interval is not None and big_u != "—":
            # a biased, bounded quantity: the interval for the true value, not ± U
            decimals = len(big_u.split(".")[1]) if "." in big_u else 0
            lo, hi = (float(v) for v in b.interval)
            lo = max(lo, 0.0) if lo <= 0.0 <= b.value else lo  # as UncertaintyBudget.statement
            cell_u = f"[{lo:.{decimals}f}, {hi:.{decimals}f}]{unit}"
        rows.append(
            [
                plain_name(b.quantity),
                f"{value}{unit}",
                cell_u,
                fixed(b.k, 3),
                f"{100 * b.p:g} %",
                nu,
                f"{fixed(b.u, 3)}{unit}",
                b.method,
            ]
        )
    return Table(
        ["quantity", "value", "U (or interval)", "k", "p", "ν_eff", "u", "method"],
        rows,
        caption=caption
        or "Results with their expanded uncertainty U = k·u (value rounded to the last digit of U, "
        "U to two significant digits: ILAC-P14); where the value is biased and bounded (near "
        "zero) the coverage interval for the true value is given instead of U; ν_eff ≥ 10⁶ "
        "shows as ∞",
    )


def budget_table(budget: UncertaintyBudget) -> Table:
    """The budget of one measurand: source, value, distribution, u, sensitivity, contribution,
    share, ν (GUM Table H.1 style), with the combined result in the caption.

    References
    ----------
    JCGM 100:2008 (GUM) §7.2.7 and Table H.1.
    """
    header, rows = budget.table()
    name = plain_name(budget.quantity)
    for row in rows:  # the dof column: ν ≥ 10⁶ is ∞ for a reader
        try:
            row[-1] = _nu_text(float(row[-1]))
        except ValueError:
            pass
    rows = [[readable(cell) for cell in row] for row in rows]
    orientation = ""
    if _is_monte_carlo(budget) and "share" in header:
        # the rows' c·u are first-order estimates beside a Monte Carlo interval: need not add up
        header = list(header)
        header[header.index("share")] = "share (first order, for orientation)"
        orientation = (
            " Monte Carlo budget: the contributions and shares are first-order estimates shown "
            "for orientation; they need not add up to u, and a share may exceed 100 %."
        )
    statement = format_quantity(
        budget.value,
        budget.unit,
        U=budget.U,
        k=budget.k,
        p=budget.p,
        interval=budget.interval,
        si_prefix=True,
    )
    statement = readable(f"{name[:1].upper()}{name[1:]}: {statement}")
    notes = readable(f" {' '.join(budget.notes)}") if budget.notes else ""
    return Table(
        header,
        rows,
        caption=f"Uncertainty budget of the {name} ({budget.method})",
        note=f"{statement}.{orientation}{notes}",
    )


def budget_tables(budgets: Mapping[str, UncertaintyBudget]) -> list[Table]:
    """:func:`results_table` of all the budgets, then one :func:`budget_table` per measurand."""
    if not budgets:
        return []
    return [results_table(budgets), *(budget_table(b) for b in budgets.values())]


def verdict(interval: Sequence[float], limit: float) -> bool | None:
    """Guarded acceptance of a result against an upper limit (ILAC-G8:09/2019 §4.2.2, guard band
    w = U): pass (True) when the whole coverage interval is at or below ``limit``, fail (False)
    when it lies wholly above, None (inconclusive) when it straddles the limit. ``interval`` and
    ``limit`` in the same unit."""
    low, high = float(interval[0]), float(interval[1])
    if high <= limit:
        return True
    if low > limit:
        return False
    return None


def verdict_note(passed: bool | None) -> str:
    """The note of a summary row judged by :func:`verdict`: empty unless inconclusive."""
    return "" if passed is not None else "inconclusive: the interval straddles the limit"
