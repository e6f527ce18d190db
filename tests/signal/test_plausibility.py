"""The shared plausibility statistics against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal.signal.plausibility import (
    LACK_OF_FIT_P,
    chi_square_test,
    lack_of_fit_warning,
    mistaken_factor,
    replicate_lack_of_fit,
    set_value_warning,
)


@pytest.mark.parametrize(
    ("ratio", "name"),
    [(10.0, "×10"), (0.1, "1/10"), (1000.0, "×10^3"), (2.0, "×2"), (0.5, "1/2"), (1.05, None)],
)
def test_mistaken_factor_names_powers_of_ten_and_two(ratio, name) -> None:
    assert mistaken_factor(ratio) == name
    assert mistaken_factor(ratio * 1.08) == name  # within 10 %
    assert mistaken_factor(math.pi / 180.0) == "1/180/π (rad vs deg)"


def test_set_value_warning_fires_on_factors_and_large_errors_only() -> None:
    assert set_value_warning("amplitude", 0.5 * 1.03, 0.5, "deg", "--lines") is None
    line = set_value_warning("amplitude", 5.0, 0.5, "deg", "--lines")
    assert line is not None and "+900 %" in line and "×10" in line and "--lines" in line
    line = set_value_warning("amplitude", 0.35, 0.5, "deg", "--lines")  # −30 %: no factor
    assert line is not None and "-30 %" in line and "20 %" in line
    assert set_value_warning("amplitude", 0.35, 0.5, "deg", "x", limit_percent=40) is None


def test_chi_square_p_value_is_the_closed_form_for_two_dof() -> None:
    # χ² with ν = 2: P(χ² ≥ x) = exp(−x/2)
    test = chi_square_test([3.0, 4.0, 0.0], [1.0, 1.0, 2.0], 2)
    assert test is not None
    assert test.chi2 == pytest.approx(25.0)
    assert test.p_value == pytest.approx(math.exp(-12.5), rel=1e-12)
    assert test.birge_ratio == pytest.approx(math.sqrt(12.5))
    line = lack_of_fit_warning("the line", test, "check it")
    assert line is not None and "12.5" in line and "ν = 2" in line and "check it" in line
    # the same residuals with u = 5: χ² = 1, p = exp(−½) — no lack of fit
    calm = chi_square_test([3.0, 4.0, 0.0], 5.0, 2)
    assert calm is not None and calm.p_value == pytest.approx(math.exp(-0.5))
    assert lack_of_fit_warning("the line", calm, "check it") is None
    assert chi_square_test([1.0], 0.0, 1) is None and chi_square_test([1.0], 1.0, 0) is None


def test_replicate_lack_of_fit_is_the_handbook_f_statistic() -> None:
    # 3 points × 2 repeats, 1 parameter: SS_lof = Σ n_i·r̄_i², SS_pe = ΣΣ(r − r̄_i)²
    r = np.array([1.0, 1.02, -0.5, -0.52, 0.01, -0.01])
    g = np.array([0, 0, 1, 1, 2, 2])
    ss_lof = 2 * (1.01**2 + 0.51**2 + 0.0**2)
    ss_pe = 6 * 0.01**2
    f = (ss_lof / 2) / (ss_pe / 3)
    test = replicate_lack_of_fit(r, g, 1)
    assert test is not None and test.statistic == "F"
    assert test.reduced_chi2 == pytest.approx(f, rel=1e-12)
    # P(F(2, 3) ≥ f) in closed form: (1 + 2f/3)^(−3/2) for d1 = 2
    assert test.p_value == pytest.approx((1 + 2 * f / 3) ** -1.5, rel=1e-9)
    assert test.lack_of_fit and test.p_value < LACK_OF_FIT_P
    assert replicate_lack_of_fit(r, np.arange(6), 1) is None  # no repeats: no pure error
