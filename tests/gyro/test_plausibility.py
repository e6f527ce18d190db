"""Plausibility warnings of the gyro calibrations: valid twins say nothing, known faults are named."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal import sim
from rotacal.gyro import calibrate_multiposition, calibrate_scale_factor, gyro_noise
from rotacal.gyro.plausibility import scale_factor_warnings
from rotacal.gyro.triad import calibrate_triad_columns

TRIAD_OUT = ("ux", "uy", "uz")


# ------------------------------------------------------------------------------- scale factor
@pytest.fixture(scope="module")
def rates():
    return sim.simulate_gyro_rates(seed=5)


def _sf(cap, **kw):
    return calibrate_scale_factor(cap.columns["rate_deg_s"], cap.columns["output"], **kw)


def test_valid_rate_test_gives_no_warning(rates) -> None:
    assert _sf(rates).warnings == ()


def test_a_gyro_mounted_upside_down_has_a_negative_scale_factor(rates) -> None:
    r = calibrate_scale_factor(rates.columns["rate_deg_s"], -rates.columns["output"])
    (line,) = r.warnings
    assert "negative" in line and "upside down" in line


def test_a_rate_point_the_table_missed_is_a_lack_of_fit(rates) -> None:
    """The +40 °/s point really ran at 40.4 °/s: a step a smooth cubic cannot follow."""
    set_rate = rates.columns["rate_deg_s"]
    out = rates.columns["output"].copy()
    at = set_rate == 40.0
    assert at.any()
    out[at] += 0.0125 * 0.4  # S·0.4 °/s
    (line,) = _sf(
        rates.__class__(rates.kind, {**rates.columns, "output": out}, rates.truth)
    ).warnings
    assert line.startswith("lack of fit: a smooth cubic") and "40 °/s" in line and "p " in line


def test_a_nonlinearity_beyond_ten_percent_fs_is_named() -> None:
    lines = scale_factor_warnings(
        scale_factor=1.0,
        nonlinearity_percent_fs=12.0,
        rates_deg_s=np.array([-100.0, 0.0, 100.0]),
        residuals=np.zeros(3),
        point_u=None,
        full_scale_deg_s=100.0,
        output_unit="",
    )
    assert len(lines) == 1 and "12 %FS" in lines[0] and "10 %FS" in lines[0]


# ------------------------------------------------------------------------------- triad
@pytest.fixture(scope="module")
def triad():
    return sim.simulate_gyro_triad(seed=7)


def test_valid_triad_gives_no_warning(triad) -> None:
    assert calibrate_triad_columns(triad.columns).warnings == ()


def test_triad_with_a_reversed_reference_axis_names_the_diagonal(triad) -> None:
    cols = {**triad.columns, "wy_deg_s": -triad.columns["wy_deg_s"]}
    warnings = calibrate_triad_columns(cols).warnings
    assert len(warnings) == 1 and "K_yy = -" in warnings[0]


def test_triad_with_a_nonlinear_axis_is_a_lack_of_fit(triad) -> None:
    """uz grows with ωz² (a 2 % square-law term at 90 °/s): the plane u = K·ω + b misses it."""
    wz = triad.columns["wz_deg_s"]
    cols = {**triad.columns, "uz": triad.columns["uz"] + 0.02 * wz**2 / 90.0}
    warnings = calibrate_triad_columns(cols).warnings
    assert len(warnings) == 1 and warnings[0].startswith("lack of fit: u = K·ω + b for uz")


# ------------------------------------------------------------------------------- Allan
def test_a_record_too_short_for_the_bias_instability_says_so() -> None:
    default = sim.simulate_gyro_noise(duration_s=3600.0, seed=1)
    c = default.columns
    assert gyro_noise(c["rate_deg_s"], time_s=c["time_s"]).warnings == ()
    white = sim.simulate_gyro_noise(duration_s=600.0, bias_instability_deg_h=0.0, seed=1)
    c = white.columns
    r = gyro_noise(c["rate_deg_s"], time_s=c["time_s"])
    assert r.noise_terms["bias_instability_deg_h_interval"][0] == 0.0  # not resolved
    (line,) = r.warnings
    assert line.startswith("no bias instability") and "too short" in line


# ------------------------------------------------------------------------------- multiposition
@pytest.mark.parametrize(("axis", "fires"), [("x", False), ("y", True)])
def test_multiposition_of_the_wrong_axis_is_a_lack_of_fit(axis, fires) -> None:
    """An x-axis capture analysed as the y axis: the model's terms do not fit the readings."""
    cap = sim.simulate_multiposition(axis="x", seed=1)
    c = cap.columns
    r = calibrate_multiposition(
        c["phi1_deg"],
        c["phi2_deg"],
        c["output_deg_h"],
        axis=axis,
        latitude_deg=cap.truth["latitude_deg"],
    )
    assert bool(r.warnings) is fires
    if fires:
        (line,) = r.warnings
        assert line.startswith("lack of fit: the drift model") and "--axis" in line
