"""Multiposition drift coefficients (seed 001, eqs. 1–6) against independent kinematics, the twin's
truth (Table 1 values) and the spread of repeated estimates."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.multiposition import (
    EARTH_RATE_DEG_H,
    calibrate_multiposition,
    check_multiposition_plan,
    coefficient_names,
    drift_design_matrix,
    earth_rate_and_gravity,
    multiposition_plan,
)
from rotacal.sim.multiposition import TABLE1_COEFFICIENTS, simulate_multiposition


def _calibrate(cap, **kw):
    c = cap.columns
    return calibrate_multiposition(
        c["phi1_deg"],
        c["phi2_deg"],
        c["output_deg_h"],
        axis=cap.truth["axis"],
        latitude_deg=cap.truth["latitude_deg"],
        **kw,
    )


def test_eq3_matches_the_turntable_rotations_built_by_scipy():
    # Frame NWU; the outer axis (west, y) turns the gyro by φ1, then the inner axis (its z) by φ2.
    # A world vector in the gyro frame is R⁻¹·v with R = Ry(φ1)·Rz(φ2) (intrinsic rotations).
    rng = np.random.default_rng(0)
    p1, p2 = rng.uniform(-360, 360, 50), rng.uniform(-360, 360, 50)
    lat = 37.3
    w, a = earth_rate_and_gravity(p1, p2, lat)
    rot = Rotation.from_euler("YZ", np.column_stack([p1, p2]), degrees=True)
    lam = math.radians(lat)
    earth = EARTH_RATE_DEG_H * np.array([math.cos(lam), 0.0, math.sin(lam)])
    np.testing.assert_allclose(a, rot.inv().apply([0.0, 0.0, 1.0]), atol=1e-14)
    np.testing.assert_allclose(w, rot.inv().apply(earth), atol=1e-12)
    # and by hand: at rest the gyro reads the north and up Earth rate and 1 g up
    w0, a0 = earth_rate_and_gravity([0.0], [0.0], 90.0)
    np.testing.assert_allclose(w0[0], [0.0, 0.0, EARTH_RATE_DEG_H], atol=1e-12)
    np.testing.assert_allclose(a0[0], [0.0, 0.0, 1.0])
    assert EARTH_RATE_DEG_H == pytest.approx(math.degrees(7.292115e-5) * 3600, rel=1e-7)


def test_design_matrix_columns():
    a = drift_design_matrix([90.0, 0.0], [0.0, 30.0], axis="x")
    np.testing.assert_allclose(a[0], [1, -1, 0, 0, 1, 0, 0], atol=1e-15)
    np.testing.assert_allclose(a[1], [1, 0, 0, 1, 0, 1, 0], atol=1e-15)
    ay = drift_design_matrix([90.0], [90.0], axis="y")
    np.testing.assert_allclose(ay[0], [1, 0, 1, 0, 1, 0, 0], atol=1e-15)
    assert coefficient_names("y") == ("DF", "Dx", "Dy", "Dz", "Dyy", "Dzz", "Dyx")


@pytest.mark.parametrize("axis", ["x", "y"])
def test_noise_free_twin_gives_table1_exactly(axis):
    cap = simulate_multiposition(axis=axis, noise_deg_h=0.0, repeats=1, latitude_deg=-33.9)
    r = _calibrate(cap)
    for k, v in TABLE1_COEFFICIENTS[axis].items():
        assert r.drift_coefficients[k] == pytest.approx(v, abs=1e-11)
    assert r.residual_rms_deg_h < 1e-11
    assert r.rank == 7 and r.positions == 64


@pytest.mark.parametrize("axis", ["x", "y"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_twin_coefficients_within_0p01_deg_h_of_table1(axis, seed):
    # 64 positions × 4 readings with 0.005 °/h noise each: u ≤ 0.0015 (deg/h, /g, /g²).
    cap = simulate_multiposition(axis=axis, seed=seed)
    r = _calibrate(cap)
    truth = cap.truth["drift_coefficients"]
    assert set(r.drift_coefficients) == set(truth)
    for k, v in truth.items():
        assert abs(r.drift_coefficients[k] - v) < 0.01, k
        assert abs(r.drift_coefficients[k] - v) < 5 * r.drift_coefficients_u[k], k
    assert r.residual_std_deg_h == pytest.approx(0.005, rel=0.15)
    assert r.condition_number == pytest.approx(6.91, abs=0.01)


def test_uncertainties_match_the_spread_of_repeated_calibrations():
    cap0 = simulate_multiposition(axis="x", noise_deg_h=0.02, repeats=1, seed=0)
    est, us = [], []
    for seed in range(300):
        r = _calibrate(simulate_multiposition(axis="x", noise_deg_h=0.02, repeats=1, seed=seed))
        est.append(list(r.drift_coefficients.values()))
        us.append(list(r.drift_coefficients_u.values()))
    spread = np.std(est, axis=0, ddof=1)
    u = np.mean(us, axis=0)
    np.testing.assert_allclose(u, spread, rtol=0.15)  # 300 draws: std known to ~4 %
    # and the expected value: σ·√diag((AᵀA)⁻¹) computed here directly
    c = cap0.columns
    a = drift_design_matrix(c["phi1_deg"], c["phi2_deg"])
    np.testing.assert_allclose(u, 0.02 * np.sqrt(np.diag(np.linalg.inv(a.T @ a))), rtol=0.05)


def test_json_keys_and_units():
    r = _calibrate(simulate_multiposition(axis="y", seed=4))
    d = json.loads(json.dumps(r.to_dict()))
    assert list(d["drift_coefficients"]) == ["DF", "Dx", "Dy", "Dz", "Dyy", "Dzz", "Dyx"]
    assert list(d["drift_coefficients_u"]) == list(d["drift_coefficients"])
    assert d["drift_coefficient_units"]["Dyx"] == "deg/h/g^2"
    assert d["earth_rate_deg_h"] == 15.041067
    assert "_plot" not in d and "_covariance" not in d


# ------------------------------------------------------------------ plans
def test_plan_generator_identifies_every_coefficient_of_both_axes():
    for axis in ("x", "y"):
        p = multiposition_plan(axis=axis)
        assert p.rank == 7 and p.identifiable and p.positions == 64
        assert p.condition_number < 10
        assert check_multiposition_plan(p.phi1_deg, p.phi2_deg, axis=axis).rank == 7
    # the twin's default positions are the generator's default plan
    p = multiposition_plan()
    cap = simulate_multiposition(repeats=1)
    np.testing.assert_array_equal(cap.columns["phi1_deg"], p.phi1_deg)
    np.testing.assert_array_equal(cap.columns["phi2_deg"], p.phi2_deg)


def test_obvious_plans_make_a_column_vanish():
    # Both axes on 90° multiples: ax·ay = −sin²φ1·sin φ2·cos φ2 = 0 at every position.
    g = np.arange(0.0, 360.0, 90.0)
    p1, p2 = (v.ravel() for v in np.meshgrid(g, g, indexing="ij"))
    assert np.all(np.abs(drift_design_matrix(p1, p2)[:, 6]) < 1e-15)
    with pytest.raises(ConfigError, match=r"leaves Dxy of the x axis unidentifiable.*zero"):
        check_multiposition_plan(p1, p2, axis="x")
    with pytest.raises(ConfigError, match=r"leaves Dyx of the y axis unidentifiable"):
        check_multiposition_plan(p1, p2, axis="y")
    # Inner angles only at 45° + k·90°: ax² = ay² = sin²φ1/2 and az² = 1 − 2ax² (collinear).
    with pytest.raises(ConfigError, match=r"DF, Dxx, Dzz of the x axis unidentifiable"):
        multiposition_plan(outer_steps=4, inner_steps=4, inner_offset_deg=45.0)
    # Only the inner axis turns: gravity never changes.
    with pytest.raises(ConfigError, match="rank 1 of 7"):
        multiposition_plan(outer_steps=1, inner_steps=12)
    with pytest.raises(ConfigError, match="6 distinct turntable position"):
        check_multiposition_plan([0, 45, 90, 0, 45, 90, 0], [0, 0, 0, 45, 45, 45, 360])


# ------------------------------------------------------------------ bad input
def test_bad_input_gives_one_clear_line():
    cap = simulate_multiposition(axis="x", repeats=1)
    c = cap.columns
    p1, p2, y = c["phi1_deg"], c["phi2_deg"], c["output_deg_h"]
    with pytest.raises(ConfigError, match="latitude_deg must be between"):
        calibrate_multiposition(p1, p2, y, latitude_deg=95.0)
    with pytest.raises(ConfigError, match="latitude_deg"):
        calibrate_multiposition(p1, p2, y, latitude_deg=float("nan"))
    with pytest.raises(ConfigError, match="axis must be 'x' or 'y'"):
        calibrate_multiposition(p1, p2, y, axis="z", latitude_deg=45.0)
    yy = y.copy()
    yy[[2, 9]] = np.nan
    with pytest.raises(CaptureError, match=r"column output_deg_h has 2 non-finite.*rows 2, 9"):
        calibrate_multiposition(p1, p2, yy, latitude_deg=45.0)
    pp = p2.copy()
    pp[4] = np.inf
    with pytest.raises(CaptureError, match=r"column phi2_deg has 1 non-finite.*rows 4"):
        calibrate_multiposition(p1, pp, y, latitude_deg=45.0)
    with pytest.raises(CaptureError, match="5 distinct turntable position"):
        calibrate_multiposition(p1[:5], p2[:5], y[:5], latitude_deg=45.0)
    on90 = (np.mod(p1, 90) == 0) & (np.mod(p2, 90) == 0)
    with pytest.raises(CaptureError, match="capture leaves Dxy of the x axis unidentifiable"):
        calibrate_multiposition(p1[on90], p2[on90], y[on90], latitude_deg=45.0)
    with pytest.raises(CaptureError, match="rows but phi1_deg"):
        calibrate_multiposition(p1, p2, y[:-1], latitude_deg=45.0)


def test_exact_fit_has_no_uncertainty_and_says_so():
    pos = np.array([[0, 0], [90, 0], [90, 90], [45, 0], [45, 45], [135, 30], [60, 120]], float)
    assert np.linalg.matrix_rank(drift_design_matrix(pos[:, 0], pos[:, 1])) == 7
    r = _calibrate(simulate_multiposition(positions=pos, noise_deg_h=0.0, repeats=1))
    assert r.dof == 0 and all(math.isnan(v) for v in r.drift_coefficients_u.values())
    assert any("exact" in n for n in r.notes)
    for k, v in TABLE1_COEFFICIENTS["x"].items():
        assert r.drift_coefficients[k] == pytest.approx(v, abs=1e-9)
