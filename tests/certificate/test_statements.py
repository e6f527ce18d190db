"""What a certificate states of a result: ILAC-P14 rounding, D-SI units and ILAC-G8 conformity,
against worked examples and hand-made cases (not against the code's own output)."""

from __future__ import annotations

import pytest

from rotacal.certificate.conformity import judge
from rotacal.certificate.content import ReportedQuantity
from rotacal.certificate.quantities import reported_quantities
from rotacal.certificate.units import dsi_unit, printed_unit
from rotacal.errors import CaptureError, ConfigError
from rotacal.plan.model import Limit


def _budget(
    value: float, U: float, k: float = 2.0, p: float = 0.95, unit: str = "°", interval=None
):
    return {
        "value": value,
        "U": U,
        "u": U / k,
        "k": k,
        "p": p,
        "unit": unit,
        "interval": interval,
        "quantity": "q",
    }


@pytest.mark.parametrize(
    ("value", "U", "shown_value", "shown_U"),
    [
        # GUM §7.2.6: y = 10.057 62 Ω with U = 27 mΩ is reported as 10.058 Ω
        (10.05762, 0.027, "10.058", "0.027"),
        # ILAC-P14 §5.4: U to two significant digits, trailing zeros that count are kept
        (1.234567, 0.0996, "1.23", "0.10"),
        (100.0049, 0.0123, "100.005", "0.012"),
        # ties go to the even digit (ISO 80000-1 Annex B, rule B)
        (0.1245, 0.011, "0.124", "0.011"),
        (2.00235, 0.0011, "2.0024", "0.0011"),
        (1234.5, 96.0, "1234", "96"),
    ],
)
def test_values_and_U_are_rounded_as_ilac_p14_asks(value, U, shown_value, shown_U) -> None:
    (q,) = reported_quantities(
        "allan", {"uncertainty_budgets": {"amplitude_deg": _budget(value, U)}}
    )
    assert (q.value, q.U) == (shown_value, shown_U)


@pytest.mark.parametrize(
    ("k", "text"),
    [(2.0, "2.00"), (1.959964, "1.96"), (12.7062, "12.7"), (1.0, "1.00"), (3.0877, "3.09")],
)
def test_k_has_three_significant_digits_without_an_exponent(k: float, text: str) -> None:
    (q,) = reported_quantities("allan", {"uncertainty_budgets": {"a": _budget(1.0, 0.1, k=k)}})
    assert q.k == text and q.p == "0.95"


def test_a_biased_bounded_quantity_states_its_interval_rounded_to_U() -> None:
    b = _budget(0.0189, 0.00156, unit="%FS", interval=[-0.0003, 0.02034])
    (q,) = reported_quantities(
        "gyro scale-factor",
        {"uncertainty_budgets": {"nonlinearity_percent_fs": b}, "full_scale_deg_s": 300.0},
    )
    assert q.interval == ("0.0000", "0.0203")  # not below zero; the decimal place of U = 0.0016
    assert q.note == "of the full scale 300 °/s"


def test_a_result_without_uncertainty_is_refused() -> None:
    with pytest.raises(CaptureError, match="no uncertainty"):
        reported_quantities("allan", {"uncertainty_budgets": {"a": _budget(1.0, 0.0)}})


def test_g_sensitivities_are_stated_per_metre_per_second_squared() -> None:
    b = {"drift_coefficients": {"Dx": _budget(9.80665, 0.980665, unit="deg/h/g")}}
    (q,) = reported_quantities("gyro multiposition", {"uncertainty_budgets": b})
    assert (q.key, q.value, q.U, q.unit) == ("drift_coefficients.Dx", "1.00", "0.10", "°/h/(m/s²)")
    assert "9.806 65" in q.note


@pytest.mark.parametrize(
    ("unit", "output_unit", "printed", "dsi"),
    [
        ("output unit/(°/s)", "V", "V/(°/s)", r"\volt\second\per\degree"),
        ("output unit/(°/s)", "LSB", "LSB/(°/s)", r"\second\per\degree"),
        ("output unit/(°/s)", "deg/s", "", r"\one"),
        ("output unit", "mV", "mV", r"\milli\volt"),
        ("°/√h", "", "°/√h", r"\degree\per\hour\tothe{0.5}"),
        ("%FS", "", "%FS", r"\percent"),
        ("arcsec", "", "arcsec", r"\arcsecond"),
    ],
)
def test_units_in_print_and_in_d_si(unit, output_unit, printed, dsi) -> None:
    assert printed_unit(unit, output_unit) == printed
    assert dsi_unit(unit, output_unit) == dsi


def test_an_unstated_or_unknown_output_unit_is_refused() -> None:
    with pytest.raises(ConfigError, match="output-unit"):
        dsi_unit("output unit/(°/s)")
    with pytest.raises(ConfigError, match="'furlong'"):
        dsi_unit("output unit", "furlong")


def _q(value: str, U: str, interval=None) -> ReportedQuantity:
    return ReportedQuantity("x", "x", "°", r"\degree", value, U, "2.00", "0.95", interval)


@pytest.mark.parametrize(
    ("value", "U", "limit", "simple", "guarded"),
    [
        ("0.40", "0.05", Limit("x", max=0.5), "pass", "pass"),
        ("0.46", "0.05", Limit("x", max=0.5), "pass", "indeterminate"),
        ("0.45", "0.05", Limit("x", max=0.5), "pass", "pass"),  # value + U on the limit: within
        ("0.50", "0.05", Limit("x", max=0.5), "pass", "indeterminate"),
        ("0.54", "0.05", Limit("x", max=0.5), "fail", "indeterminate"),
        ("0.56", "0.05", Limit("x", max=0.5), "fail", "fail"),
        ("-1.10", "0.05", Limit("x", min=-1.0, max=1.0), "fail", "fail"),
        ("-0.96", "0.05", Limit("x", min=-1.0, max=1.0), "pass", "indeterminate"),
        ("0.1", "0.3", Limit("x", min=0.3), "fail", "indeterminate"),
    ],
)
def test_simple_and_guarded_acceptance_follow_ilac_g8(value, U, limit, simple, guarded) -> None:
    assert judge(_q(value, U), limit, "simple").verdict == simple
    assert judge(_q(value, U), limit, "guarded").verdict == guarded


def test_decimals_decide_not_binary_floats() -> None:
    # 0.1 + 0.2 > 0.3 in binary floating point; on the certificate 0.1 ± 0.2 reaches 0.3 exactly
    assert judge(_q("0.1", "0.2"), Limit("x", max=0.3), "guarded").verdict == "pass"


def test_guarded_acceptance_uses_the_coverage_interval_of_a_biased_quantity() -> None:
    q = _q("0.0189", "0.0016", interval=("0.0171", "0.0502"))
    c = judge(q, Limit("x", max=0.05), "guarded")
    assert c.verdict == "indeterminate"  # 0.0189 + 0.0016 < 0.05, but the interval reaches 0.0502
    assert "[0.0171, 0.0502]" in c.statement and "guarded acceptance" in c.statement
