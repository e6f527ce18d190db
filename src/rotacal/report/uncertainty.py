"""Uncertainty budgets in reports: one table per measurand, results rounded as ILAC-P14 asks.

Every calibration's report section calls :func:`budget_tables` with the budgets of its result and
adds :func:`results_table` — the certificate's lines (value ± U, k, p) — above them.
"""

from __future__ import annotations

from collections.abc import Mapping

from rotacal.errors import ConfigError
from rotacal.report.html import Table
from rotacal.uncertainty.budget import UncertaintyBudget

__all__ = ["budget_table", "budget_tables", "results_table"]


#: ν_eff at or above this is shown as ∞ (a t-factor no longer differs from the normal one).
NU_INFINITE = 1e6


def _nu_text(nu: float) -> str:
    return "∞" if not nu < NU_INFINITE else f"{nu:.3g}"


def _is_monte_carlo(b: UncertaintyBudget) -> bool:
    return b.method == "Monte Carlo"


def _rounded(b: UncertaintyBudget) -> tuple[str, str]:
    try:
        return b.rounded()
    except ConfigError:  # U = 0 or not finite: state the plain value, no ±
        return f"{b.value:.6g}", "—"


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
                b.quantity,
                f"{value}{unit}",
                cell_u,
                f"{b.k:.3g}",
                f"{100 * b.p:g} %",
                nu,
                f"{b.u:.3g}{unit}",
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
    for row in rows:  # the dof column: ν ≥ 10⁶ is ∞ for a reader
        try:
            row[-1] = _nu_text(float(row[-1]))
        except ValueError:
            pass
    orientation = ""
    if _is_monte_carlo(budget) and "share" in header:
        # the rows' c·u are first-order estimates beside a Monte Carlo interval: need not add up
        header = list(header)
        header[header.index("share")] = "share (first order, for orientation)"
        orientation = (
            " Monte Carlo budget: the contributions and shares are first-order estimates shown "
            "for orientation; they need not add up to u, and a share may exceed 100 %."
        )
    try:
        statement = budget.statement()
    except ConfigError:
        statement = f"{budget.quantity} = {budget.value:.6g} {budget.unit}".strip()
    notes = f" {' '.join(budget.notes)}" if budget.notes else ""
    return Table(
        header,
        rows,
        caption=(
            f"Uncertainty budget of {budget.quantity} ({budget.method}): {statement}."
            f"{orientation}{notes}"
        ),
    )


def budget_tables(budgets: Mapping[str, UncertaintyBudget]) -> list[Table]:
    """:func:`results_table` of all the budgets, then one :func:`budget_table` per measurand."""
    if not budgets:
        return []
    return [results_table(budgets), *(budget_table(b) for b in budgets.values())]
