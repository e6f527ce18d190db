"""3-axis gyro calibration (seed 003): least squares, robust rejection, plan check, bad input."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.triad import (
    SEED_RATES_DEG_S,
    apply_triad_calibration,
    calibrate_triad,
    calibrate_triad_columns,
    decompose_scale_misalignment,
    triad_plan,
    triad_plan_check,
)
from rotacal.sim.gyro_triad import simulate_gyro_triad

K_TRUE = np.array(
    [
        [1.0120, 0.0045, -0.0031],
        [-0.0052, 0.9930, 0.0022],
        [0.0036, -0.0017, 1.0050],
    ]
)
B_TRUE = np.array([0.42, -0.27, 0.15])


def _arrays(cap):
    c = cap.columns
    omega = np.column_stack([c["wx_deg_s"], c["wy_deg_s"], c["wz_deg_s"]])
    u = np.column_stack([c["ux"], c["uy"], c["uz"]])
    return omega, u


def _twin(**kw):
    opts = {"K": K_TRUE, "bias": B_TRUE}
    opts.update(kw)
    return simulate_gyro_triad(**opts)


# ------------------------------------------------------------------------------------ least squares
def test_noise_free_twin_gives_the_truth_and_eq7_inverts_it() -> None:
    cap = _twin(noise_std=0.0, samples_per_point=3)
    omega, u = _arrays(cap)
    r = calibrate_triad(omega, u)
    np.testing.assert_allclose(r.scale_misalignment, K_TRUE, atol=1e-12)
    np.testing.assert_allclose(r.bias, B_TRUE, atol=1e-12)
    np.testing.assert_allclose(r.calibrate(u), omega, atol=1e-10)
    assert r.outliers_rejected == 0
    assert np.all(r.residual_rms < 1e-10)


def test_least_squares_equals_the_closed_form_of_a_symmetric_plan() -> None:
    """For ± rates about each axis the columns of A are orthogonal: K's column j is
    Σ r·(u(+r) − u(−r)) / (2·Σ r²·m) over the points about j, and b is the mean of all outputs."""
    spp = 40
    cap = _twin(noise_std=0.3, samples_per_point=spp, seed=11)
    omega, u = _arrays(cap)
    r = calibrate_triad(omega, u, reject_k=math.inf)
    rates = np.asarray(SEED_RATES_DEG_S)
    pts = u.reshape(3, rates.size, 2, spp, 3).mean(axis=3)  # axis, rate, sign, output
    k_closed = np.einsum("r,jro->oj", rates, pts[:, :, 0] - pts[:, :, 1]) / (2 * rates @ rates)
    np.testing.assert_allclose(r.scale_misalignment, k_closed, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.bias, u.mean(axis=0), rtol=0, atol=1e-12)


def test_interface_keys_and_json() -> None:
    r = calibrate_triad_columns(_twin(samples_per_point=20).columns)
    d = r.to_dict()
    for key in ("scale_misalignment", "bias", "outliers_rejected", "residual_rms"):
        assert key in d
    assert np.shape(d["scale_misalignment"]) == (3, 3) and len(d["bias"]) == 3
    assert isinstance(d["outliers_rejected"], int) and len(d["residual_rms"]) == 3
    assert "_plot" not in d and d["plan"]["rank"] == 4
    json.dumps(d, allow_nan=False)


# ------------------------------------------------------------------------------------ outliers
@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("channels", ["one", "all"])
def test_two_percent_gross_outliers_meet_the_issue_bar(seed: int, channels: str) -> None:
    cap = _twin(outlier_fraction=0.02, outlier_size=20.0, outlier_channels=channels, seed=seed)
    r = calibrate_triad_columns(cap.columns)
    assert np.max(np.abs(r.scale_misalignment - K_TRUE)) < 2e-4
    assert np.max(np.abs(r.bias - B_TRUE)) < 5e-3
    # the rule finds every corrupted measurement (≥ 10 °/s = 100 σ) and few good ones (5 % rate)
    o = cap.truth["outliers"]
    truth = {(row, col) for row, col in zip(o["rows"], o["columns"], strict=True)}
    found = {(e["row"], e["column"]) for e in r.rejected}
    assert truth <= found
    assert len(found - truth) <= 2
    assert r.outliers_rejected >= len(o["row_set"])


def test_without_rejection_the_outliers_spoil_the_bias() -> None:
    """The rejection matters: plain least squares on the same capture misses the issue's bar."""
    cap = _twin(outlier_fraction=0.02, outlier_size=20.0, seed=5, outlier_channels="all")
    plain = calibrate_triad_columns(cap.columns, reject_k=math.inf)
    robust = calibrate_triad_columns(cap.columns)
    assert plain.outliers_rejected == 0
    err_plain = np.max(np.abs(plain.bias - B_TRUE))
    err_robust = np.max(np.abs(robust.bias - B_TRUE))
    assert err_plain > 5e-3 > err_robust


def test_quantised_output_is_not_mistaken_for_outliers() -> None:
    # analog noise a quarter of a code: residuals are whole codes, not anomalies
    cap = _twin(noise_std=0.025, quantum=0.1, seed=4)
    r = calibrate_triad_columns(cap.columns)
    assert r.outliers_rejected <= 2
    assert np.max(np.abs(r.scale_misalignment - K_TRUE)) < 1e-3


# ------------------------------------------------------------------------------------ uncertainty
def test_standard_uncertainties_match_the_scatter_over_many_twins() -> None:
    z_k, z_b = [], []
    for seed in range(150):
        r = calibrate_triad_columns(_twin(samples_per_point=10, noise_std=0.2, seed=seed).columns)
        z_k.append((r.scale_misalignment - K_TRUE) / r.scale_misalignment_u)
        z_b.append((r.bias - B_TRUE) / r.bias_u)
    for z in (np.array(z_k), np.array(z_b)):
        s = float(np.std(z))
        assert 0.88 < s < 1.12, s  # 150×9 or 150×3 normalised errors: std 1 within sampling
        assert abs(float(np.mean(z))) < 0.2


def test_residuals_before_and_after_follow_the_truth() -> None:
    sigma = 0.1
    cap = _twin(noise_std=sigma, seed=8)
    omega, u = _arrays(cap)
    r = calibrate_triad(omega, u)
    # before: (K − I)ω + b plus noise, from the twin's truth
    clean = omega @ (K_TRUE - np.eye(3)).T + B_TRUE
    expected_before = np.sqrt(np.mean(clean**2, axis=0) + sigma**2)
    np.testing.assert_allclose(r.residual_rms_before, expected_before, rtol=0.02)
    # after: the noise carried through K⁻¹ (rows of K⁻¹ have norm ≈ 1/scale)
    expected_after = sigma * np.linalg.norm(np.linalg.inv(K_TRUE), axis=1)
    np.testing.assert_allclose(r.residual_rms, expected_after, rtol=0.03)
    np.testing.assert_allclose(r.fit_residual_rms, sigma, rtol=0.03)


def test_nominal_scale_states_raw_counts_at_face_value() -> None:
    gain = 16.4  # counts per °/s
    cap = _twin(K=K_TRUE * gain, bias=B_TRUE * gain, noise_std=0.0, samples_per_point=2)
    omega, u = _arrays(cap)
    r = calibrate_triad(omega, u, nominal_scale=gain)
    np.testing.assert_allclose(r.scale_misalignment, K_TRUE * gain, rtol=1e-12)
    clean = omega @ (K_TRUE - np.eye(3)).T + B_TRUE
    np.testing.assert_allclose(r.residual_rms_before, np.sqrt(np.mean(clean**2, 0)), rtol=1e-9)


# ------------------------------------------------------------------------------------ decomposition
def test_decomposition_rebuilds_k() -> None:
    s, rmat, mis = decompose_scale_misalignment(K_TRUE)
    np.testing.assert_allclose(np.diag(s) @ rmat, K_TRUE, rtol=1e-14)
    np.testing.assert_allclose(np.linalg.norm(rmat, axis=1), 1.0, rtol=1e-14)
    # axis x of K_TRUE leans by atan(|(0.0045, −0.0031)|/1.012) from nominal
    assert mis[0] == pytest.approx(math.degrees(math.atan(math.hypot(0.0045, 0.0031) / 1.012)))


def test_apply_calibration_eq7_against_an_explicit_inverse() -> None:
    u = np.random.default_rng(0).normal(size=(50, 3)) * 30
    np.testing.assert_allclose(
        apply_triad_calibration(u, K_TRUE, B_TRUE), (np.linalg.inv(K_TRUE) @ (u - B_TRUE).T).T
    )
    assert apply_triad_calibration(u[0], K_TRUE, B_TRUE).shape == (3,)


# ------------------------------------------------------------------------------------ plans
def test_seed_plan_layout_and_its_conditioning_in_closed_form() -> None:
    spp = 7
    plan = triad_plan(samples_per_point=spp)
    rates = np.asarray(SEED_RATES_DEG_S)
    assert plan.shape == (3 * 2 * rates.size * spp, 3)
    first = plan[::spp][:10]
    np.testing.assert_array_equal(first[:, 0], np.ravel(np.column_stack([rates, -rates])))
    assert not first[:, 1:].any()
    chk = triad_plan_check(plan)
    assert chk.identifiable and chk.rank == 4 and chk.points == 30
    # columns of A are orthogonal: singular values are the column norms
    norms2 = np.array([2 * spp * rates @ rates] * 3 + [plan.shape[0]])
    assert chk.condition_number == pytest.approx(math.sqrt(norms2.max() / norms2.min()))
    assert chk.condition_number_scaled == pytest.approx(1.0)
    assert chk.noise_gain["wx"] == pytest.approx(1 / math.sqrt(norms2[0]))
    assert chk.noise_gain["bias"] == pytest.approx(1 / math.sqrt(norms2[3]))


def test_plan_about_one_axis_names_the_unidentifiable_columns() -> None:
    with pytest.raises(ConfigError, match=r"K_xy.*K_zz") as e:
        triad_plan_check(triad_plan(axes="x"))
    assert "no rotation about y" in str(e.value) and "\n" not in str(e.value)
    chk = triad_plan_check(triad_plan(axes="xy"), strict=False)
    assert not chk.identifiable
    assert set(chk.unidentifiable) == {"K_xz", "K_yz", "K_zz"}


def test_one_direction_one_rate_confounds_bias_and_scale() -> None:
    chk = triad_plan_check(triad_plan((90.0,), both_directions=False), strict=False)
    assert chk.rank == 3 and "b_x" in chk.unidentifiable
    # one direction but two rates, or a point at rest, fixes it
    assert triad_plan_check(triad_plan((30.0, 90.0), both_directions=False)).identifiable
    assert triad_plan_check(
        triad_plan((90.0,), both_directions=False, include_static=True)
    ).identifiable


def test_plan_generator_refuses_bad_settings() -> None:
    for kw in (
        {"rates_deg_s": ()},
        {"rates_deg_s": (-5.0,)},
        {"axes": "xq"},
        {"samples_per_point": 0},
    ):
        with pytest.raises(ConfigError):
            triad_plan(**kw)  # type: ignore[arg-type]
    with pytest.raises(ConfigError):
        triad_plan_check(np.zeros((0, 3)))


# ------------------------------------------------------------------------------------ bad input
def _one_line(e: pytest.ExceptionInfo[BaseException]) -> str:
    msg = str(e.value)
    assert "\n" not in msg and len(msg) < 400
    return msg


def test_nan_names_column_and_row() -> None:
    omega, u = _arrays(_twin(samples_per_point=5))
    u[17, 1] = np.nan
    with pytest.raises(CaptureError) as e:
        calibrate_triad(omega, u)
    assert "uy" in _one_line(e) and "row 17" in str(e.value)
    omega[3, 2] = np.inf
    with pytest.raises(CaptureError, match="wz_deg_s"):
        calibrate_triad(omega, u)


def test_too_few_rows_and_mismatched_lengths() -> None:
    omega, u = _arrays(_twin(samples_per_point=1))
    with pytest.raises(CaptureError, match="only 6 rows") as e:
        calibrate_triad(omega[:6], u[:6])
    _one_line(e)
    with pytest.raises(CaptureError, match="rows"):
        calibrate_triad(omega, u[:-1])
    with pytest.raises(CaptureError, match=r"\(n, 3\)"):
        calibrate_triad(omega[:, :2], u)


def test_capture_about_one_axis_is_refused() -> None:
    cap = _twin(samples_per_point=5)
    omega, u = _arrays(cap)
    sel = omega[:, 0] != 0
    with pytest.raises(CaptureError, match="K_xy") as e:
        calibrate_triad(omega[sel], u[sel])
    assert "wx_deg_s" in _one_line(e)


@pytest.mark.parametrize("quantum", [None, 0.05])
def test_saturated_output_is_detected_from_the_data(quantum: float | None) -> None:
    # true output at +90 °/s about x is 1.012·90 + 0.42 = 91.5: a ±91 range clips it
    cap = _twin(output_limit=91.0, quantum=quantum)
    assert cap.truth["clipped_samples"] > 0
    with pytest.raises(CaptureError, match=r"ux.*saturated") as e:
        calibrate_triad_columns(cap.columns)
    _one_line(e)
    # … and by the limits the user gives
    omega, u = _arrays(cap)
    with pytest.raises(CaptureError, match="ux reaches its limit"):
        calibrate_triad(omega, u, output_limits=(-91.0, 91.0))


def test_unsaturated_quantised_twin_is_not_called_saturated() -> None:
    r = calibrate_triad_columns(_twin(quantum=0.05, output_limit=200.0).columns)
    assert np.max(np.abs(r.scale_misalignment - K_TRUE)) < 2e-4


def test_wrong_columns_are_refused_not_fitted() -> None:
    cap = _twin(samples_per_point=50)
    omega, u = _arrays(cap)
    rng = np.random.default_rng(0)
    u[:, 2] = rng.permutation(u[:, 2])  # uz no longer follows the rates
    with pytest.raises(CaptureError, match="uz"):
        calibrate_triad(omega, u)


def test_missing_column_and_bad_settings() -> None:
    cols = dict(_twin(samples_per_point=3).columns)
    cols.pop("uy")
    with pytest.raises(CaptureError, match="'uy'"):
        calibrate_triad_columns(cols)
    omega, u = _arrays(_twin(samples_per_point=3))
    with pytest.raises(ConfigError, match="reject_k"):
        calibrate_triad(omega, u, reject_k=1.0)
    with pytest.raises(ConfigError, match="nominal_scale"):
        calibrate_triad(omega, u, nominal_scale=0.0)
    with pytest.raises(ConfigError, match="output_limits"):
        calibrate_triad(omega, u, output_limits=(5.0, -5.0))
