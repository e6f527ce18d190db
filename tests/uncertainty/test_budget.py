"""Tests of rotacal.uncertainty.budget: ILAC-P14 rounding, budget tables and statements.

Rounding cases are worked by hand from the stated rule (ILAC-P14:09/2020 §5.4: U to two
significant digits, the value to the same decimal place; ties to even; round_up for U only) and
from the examples of GUM §7.2.6.
"""

from __future__ import annotations

import json
import math
import re

import pytest

from rotacal.errors import ConfigError
from rotacal.uncertainty.budget import UncertaintyBudget, result_keys, round_ilac
from rotacal.uncertainty.gum import Input, coverage_factor, propagate


@pytest.mark.parametrize(
    ("value", "U", "kwargs", "expected"),
    [
        (12.34567, 0.0934, {}, ("12.346", "0.093")),
        (12.34567, 0.0934, {"round_up": True}, ("12.346", "0.094")),
        (5.0, 1.25, {}, ("5.0", "1.2")),  # a tie goes to the even digit
        (5.0, 1.35, {}, ("5.0", "1.4")),
        (1234.5, 96.0, {}, ("1234", "96")),  # tie → even
        (1235.5, 96.0, {}, ("1236", "96")),
        (-12.34567, 0.0934, {}, ("-12.346", "0.093")),
        (10.05762, 0.027, {}, ("10.058", "0.027")),  # GUM §7.2.6: y = 10.057 62 Ω, u = 27 mΩ
        (0.0, 10.47, {"round_up": True}, ("0", "11")),  # GUM §7.2.6: 10.47 mΩ rounded up → 11
        (0.0, 28.05, {}, ("0", "28")),  # GUM §7.2.6: 28.05 kHz → 28 kHz
        (1.0, 0.0996, {}, ("1.00", "0.10")),  # two significant digits, trailing zero kept
        (1.0, 0.0991, {"round_up": True}, ("1.00", "0.10")),
        (1.0, 0.093, {"round_up": True}, ("1.000", "0.093")),  # exact: nothing to round up
        (1234.5, 99.6, {}, ("1230", "100")),
        (56789.0, 1234.0, {}, ("56800", "1200")),
        (0.0012, 0.0196, {}, ("0.001", "0.020")),  # U ≥ value
        (-0.00004, 0.0196, {}, ("0.000", "0.020")),  # no "-0.000"
        (12.34567, 0.0934, {"digits": 1}, ("12.35", "0.09")),
        (50_000_838.6, 92.48, {}, ("50000839", "92")),
        (1.23456e-7, 2.34e-10, {}, ("0.00000012346", "0.00000000023")),
    ],
)
def test_round_ilac_cases(value, U, kwargs, expected):
    assert round_ilac(value, U, **kwargs) == expected


def test_round_ilac_keeps_two_significant_digits_and_aligns_the_value():
    for u in (0.0123456, 1.98765, 34.5678, 6.7e-5):
        value_str, u_str = round_ilac(3.14159265, u)
        digits = u_str.replace(".", "").lstrip("0")
        assert len(digits) == 2
        decimals = len(u_str.split(".")[1]) if "." in u_str else 0
        assert (len(value_str.split(".")[1]) if "." in value_str else 0) == decimals


@pytest.mark.parametrize(
    ("value", "U", "match"),
    [
        (1.0, 0.0, "is not positive"),
        (1.0, -0.1, "is not positive"),
        (1.0, math.nan, "is not finite"),
        (1.0, math.inf, "is not finite"),
        (math.nan, 0.1, "nothing to round"),
    ],
)
def test_round_ilac_rejects_unroundable_input(value, U, match):
    with pytest.raises(ConfigError, match=match) as exc:
        round_ilac(value, U)
    assert "\n" not in str(exc.value)


def test_round_ilac_rejects_bad_digits():
    with pytest.raises(ConfigError, match="digits must be an integer"):
        round_ilac(1.0, 0.1, digits=0)


# ------------------------------------------------------------------------------- budgets
def simple_result():
    """y = a + 2·b: a = 1 V (u 0.3 V, ν 9), b = 2 A (rectangular, u 0.2 A, ν ∞)."""
    ins = [
        Input("a", 1.0, 0.3, 9, unit="V", source="Type A"),
        Input(
            "b", 2.0, 0.2, distribution="rectangular", unit="A", description="rectangular ±0.346"
        ),
    ]
    return propagate(lambda a, b: a + 2.0 * b, ins, names_out=["y"], units_out=["V"])


def test_budget_table_statement_and_shares():
    res = simple_result()
    b = res.budget()
    assert isinstance(b, UncertaintyBudget)
    assert b.method == "GUM" and b.quantity == "y" and b.unit == "V"
    assert b.u == pytest.approx(0.5, rel=1e-12)  # √(0.3² + (2·0.2)²)
    nu = 0.5**4 / (0.3**4 / 9)
    assert b.dof_eff == pytest.approx(nu, rel=1e-9)
    assert b.k == pytest.approx(coverage_factor(math.floor(nu), 0.95), rel=1e-15)
    assert sum(row.share for row in b.rows) == pytest.approx(1.0, rel=1e-12)
    assert [round(row.share, 6) for row in b.rows] == [0.36, 0.64]

    header, rows = b.table()
    assert header == [
        "source",
        "value",
        "distribution",
        "u",
        "sensitivity",
        "contribution",
        "share",
        "dof",
    ]
    assert rows[0] == ["a (Type A)", "1 V", "normal", "0.3 V", "1", "0.3 V", "36.0 %", "9"]
    assert rows[1] == ["b", "2 A", "rectangular ±0.346", "0.2 A", "2 V/A", "0.4 V", "64.0 %", "∞"]

    # U = t_95(69)·0.5 = 0.997 V → two significant digits "1.0", the value to 0.1 V
    assert b.rounded() == ("5.0", "1.0")
    assert b.statement() == "y = 5.0 V ± 1.0 V (k = 1.99, p ≈ 95 %)"
    assert result_keys("y", b) == {"y_u": b.u, "y_U": b.U, "k": b.k}


def test_budget_statement_pattern_for_h1_style_numbers():
    b = UncertaintyBudget(
        quantity="l",
        unit="mm",
        value=50.0008386,
        u=31.66e-6,
        dof_eff=16.75,
        k=2.920781622,
        p=0.99,
        U=92.48e-6,
        rows=(),
    )
    assert b.statement() == "l = 50.000839 mm ± 0.000092 mm (k = 2.92, p ≈ 99 %)"
    assert b.statement(round_up=True).endswith("± 0.000093 mm (k = 2.92, p ≈ 99 %)")
    assert re.fullmatch(r"l = [\d.]+ mm ± [\d.]+ mm \(k = [\d.]+, p ≈ \d+ %\)", b.statement())


def test_budget_with_correlated_inputs_notes_that_shares_do_not_sum_to_one():
    ins = [Input("a", 1.0, 0.3, 4), Input("b", 2.0, 0.4, 4)]
    res = propagate(lambda a, b: a + b, ins, correlation={("a", "b"): 0.5})
    b = res.budget()
    total = sum(row.share for row in b.rows)
    # u² = 0.09 + 0.16 + 2·0.5·0.12 = 0.37; shares (0.09 + 0.16)/0.37
    assert total == pytest.approx(0.25 / 0.37, rel=1e-9)
    assert any(f"sum to {total:.3f}, not 1" in n for n in b.notes)
    assert b.dof_eff == pytest.approx(4.0, rel=1e-12)


def test_budget_second_order_row_completes_the_shares():
    ins = [Input("a", 0.0, 1.0), Input("b", 0.0, 2.0)]
    res = propagate(lambda a, b: 3.0 + a * b, ins, second_order=True)
    b = res.budget()
    # first order: c = (b, a) = (0, 0); GUM §5.1.2 note: (∂²y/∂a∂b)²·u_a²·u_b² = 4 → u = 2
    assert b.u == pytest.approx(2.0, rel=1e-9)
    assert b.rows[-1].source.startswith("second-order terms")
    assert sum(row.share for row in b.rows) == pytest.approx(1.0, rel=1e-9)
    _, rows = b.table()
    assert rows[-1][1] == "—" and rows[-1][6] == "100.0 %"


def test_budget_of_an_exact_result_and_bad_index():
    res = propagate(lambda a: 2.0 * a, [Input("a", 1.5, 0.0)], names_out=["q"])
    b = res.budget()
    assert b.u == 0.0 and b.U == 0.0
    assert b.statement().startswith("q = 3.0 (exact")
    assert b.rows[0].share == 0.0
    with pytest.raises(ConfigError, match="is not positive"):
        b.rounded()
    with pytest.raises(ConfigError, match="output index j = 1 is out of range"):
        res.budget(1)


def test_budget_json_and_multi_output_notes():
    ins = [Input("a", 1.0, 0.3, 9), Input("b", 2.0, 0.2, 9)]
    res = propagate(
        lambda a, b: [a + b, a - b], ins, correlation={("a", "b"): 0.2}, names_out=["s", "d"]
    )
    b = res.budget(1)
    assert b.quantity == "d"
    assert b.u == pytest.approx(math.sqrt(0.09 + 0.04 - 2 * 0.2 * 0.06), rel=1e-10)
    data = json.loads(json.dumps(b.to_dict()))
    assert data["quantity"] == "d" and len(data["rows"]) == 2
    assert data["rows"][0]["source"] == "a"
    assert all(not n.startswith("s:") for n in b.notes)  # only this output's notes
    assert any(n.startswith("d:") for n in res.notes)


def test_monte_carlo_style_budget_statement():
    b = UncertaintyBudget(
        quantity="δm",
        unit="mg",
        value=1.2341,
        u=0.0754,
        dof_eff=math.inf,
        k=0.150 / 0.0754,
        p=0.95,
        U=0.150,
        rows=(),
        method="Monte Carlo",
    )
    assert b.statement() == "δm = 1.23 mg ± 0.15 mg (k = 1.99, p ≈ 95 %)"
    assert json.loads(json.dumps(b.to_dict()))["dof_eff"] is None
