"""The report tables of the budgets: ν_eff shown as ∞ when huge, Monte Carlo shares labelled,
intervals of biased quantities stated instead of ± U."""

from __future__ import annotations

import math

from rotacal.report.uncertainty import budget_table, budget_tables, results_table
from rotacal.uncertainty.budget import BudgetRow, UncertaintyBudget
from rotacal.uncertainty.gum import Input, propagate


def _row(contribution: float, share: float, dof: float) -> BudgetRow:
    return BudgetRow("x", 1.0, "V", "normal", 0.1, 1.0, contribution, share, dof, "Type A")


def _budget(**kw) -> UncertaintyBudget:
    base = dict(
        quantity="y",
        unit="V",
        value=1.234,
        u=0.01,
        dof_eff=9.47e29,
        k=1.96,
        p=0.95,
        U=0.0196,
        rows=(_row(0.01, 1.0, 9.47e29),),
    )
    base.update(kw)
    return UncertaintyBudget(**base)


def test_huge_nu_eff_shows_as_infinity():
    # Welch–Satterthwaite of a huge-ν input and a tiny finite-ν one: ν_eff ≈ 1e29, not ∞
    gum = propagate(
        lambda a, b: a + b,
        [Input("a", 0.0, 1.0, dof=1e30), Input("b", 0.0, 1e-9, dof=3)],
    )
    b = gum.budget(0)
    assert math.isfinite(b.dof_eff) and b.dof_eff > 1e6
    res = results_table({"y": b})
    assert res.rows[0][res.columns.index("ν_eff")] == "∞"
    tab = budget_table(b)
    assert tab.rows[0][-1] == "∞" and tab.rows[1][-1] == "3"
    # below the threshold the number stays
    small = results_table({"y": _budget(dof_eff=12.4)})
    assert small.rows[0][small.columns.index("ν_eff")] == "12.4"


def test_monte_carlo_shares_are_labelled_first_order():
    mc = _budget(method="Monte Carlo", dof_eff=math.inf, rows=(_row(0.0103, 1.03, math.inf),))
    tab = budget_table(mc)
    assert "share (first order, for orientation)" in tab.columns
    assert "share" not in tab.columns
    assert "may exceed 100 %" in tab.note
    assert tab.rows[0][tab.columns.index("share (first order, for orientation)")] == "103.0 %"
    gum = budget_table(_budget(method="GUM"))
    assert "share" in gum.columns and "for orientation" not in gum.note


def test_an_interval_is_stated_instead_of_plus_minus_u():
    b = _budget(
        value=0.0154,
        u=0.0046,
        U=0.0088,
        k=1.91,
        dof_eff=math.inf,
        method="Monte Carlo",
        interval=(-0.002, 0.0176),
    )
    res = results_table({"thd_percent": b})
    cell = res.rows[0][res.columns.index("U (or interval)")]
    assert cell == "[0.0000, 0.0176] V"  # clipped at the bound 0, decimals of U (0.0088)
    assert "true value in [0.0000, 0.0176] V" in budget_table(b).note
    plain = results_table({"y": _budget(dof_eff=math.inf)})
    assert plain.rows[0][plain.columns.index("U (or interval)")] == "0.020 V"
    assert len(budget_tables({"a": b, "b": _budget()})) == 3
    assert budget_tables({}) == []
