"""Uncertainty budgets of the multiposition drift coefficients (seed 001): a hand-derived latitude
sensitivity, orientation-error sensitivities against an independent re-solve of eq. (11) with the
twin's exactly rotated inputs, and the honesty check (spread over twin runs against the stated u,
Type A alone and with the latitude and orientation error drawn per run)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from rotacal.errors import ConfigError
from rotacal.gyro.multiposition import (
    EARTH_RATE_DEG_H,
    calibrate_multiposition,
    coefficient_names,
    drift_sensitivities,
)
from rotacal.sim.multiposition import TABLE1_COEFFICIENTS, simulate_multiposition
from rotacal.uncertainty.gum import coverage_factor
from rotacal.uncertainty.specs import load_specs

LAT = 45.75


def _specs(lat_u: float | None = 0.02, orient_half: float | None = 20.0):
    data: dict = {}
    if lat_u is not None:
        data["site"] = {"latitude_deg": {"distribution": "normal", "value": LAT, "u": lat_u}}
    if orient_half is not None:
        data["table"] = {
            "orientation_error_arcsec": {"distribution": "rectangular", "half_width": orient_half}
        }
    return load_specs(data)


def _calibrate(cap, **kw):
    c = cap.columns
    kw.setdefault("latitude_deg", LAT)
    return calibrate_multiposition(
        c["phi1_deg"], c["phi2_deg"], c["output_deg_h"], axis=cap.truth["axis"], **kw
    )


def _chi2_bounds(n: int, level: float = 0.999) -> tuple[float, float]:
    tail = 0.5 * (1.0 - level)
    q = stats.chi2.ppf([tail, 1.0 - tail], n - 1)
    return float(np.sqrt(q[0] / (n - 1))), float(np.sqrt(q[1] / (n - 1)))


@pytest.mark.parametrize("axis", ["x", "y"])
def test_latitude_sensitivity_and_u_by_hand(axis):
    """ωx = Ωe·cos λ·cos φ1 cos φ2 + Ωe·sin λ·ax: on the full 45° grid cos φ1 cos φ2 is orthogonal
    to every column of A, so only Dx (x axis; Dy for y, by ωy = … + Ωe·sin λ·ay) moves with λ,
    by ∂D/∂λ = −Ωe·cos λ (per rad). Its budget: u² = u_A² + (Ωe cos λ·π/180·u_λ)², ν_eff by W–S."""
    u_lat = 0.05
    cap = simulate_multiposition(axis=axis, seed=4)
    r = _calibrate(cap, specs=_specs(lat_u=u_lat, orient_half=None))
    plain = _calibrate(cap)
    hit = "Dx" if axis == "x" else "Dy"
    c = -EARTH_RATE_DEG_H * math.cos(math.radians(LAT)) * math.pi / 180.0
    for name in coefficient_names(axis):
        b = r._budgets[f"drift_coefficients.{name}"]
        fit, lat = b.rows
        assert fit.sensitivity == 1.0 and fit.u == plain.drift_coefficients_u[name]
        assert lat.sensitivity == pytest.approx(c if name == hit else 0.0, abs=1e-12)
    b = r._budgets[f"drift_coefficients.{hit}"]
    u_a = plain.drift_coefficients_u[hit]
    u = math.hypot(u_a, c * u_lat)
    assert b.u == pytest.approx(u, rel=1e-12)
    assert r.drift_coefficients_u[hit] == b.u  # one truth
    nu = u**4 / (u_a**4 / plain.dof)
    assert b.dof_eff == pytest.approx(nu, rel=1e-9)
    assert b.k == pytest.approx(coverage_factor(nu), rel=1e-12)
    assert b.U == pytest.approx(b.k * u, rel=1e-12)
    # the coefficients themselves are unchanged by stating a spec with a zero-mean error
    assert r.drift_coefficients == plain.drift_coefficients


@pytest.mark.parametrize("axis", ["x", "y"])
def test_orientation_sensitivities_match_an_independent_re_solve(axis):
    """Eq. (11) solved with the gravity and Earth-rate components of the twin turned exactly
    (Rodrigues) by ±30″ about each axis; the central difference quotient equals ∂β/∂Δ to 1e-4 of
    the largest sensitivity."""
    cap = simulate_multiposition(axis=axis, seed=3)
    c = cap.columns
    beta, jac = drift_sensitivities(
        c["phi1_deg"], c["phi2_deg"], c["output_deg_h"], axis=axis, latitude_deg=LAT
    )
    k = 0 if axis == "x" else 1

    def resolve(err):
        t = simulate_multiposition(
            axis=axis, noise_deg_h=0.0, repeats=1, orientation_error_arcsec=err
        )
        g = np.tile(t.truth["gravity_components_g"], (4, 1))
        w = np.tile(t.truth["earth_rate_components_deg_h"][:, k], 4)
        gx, gy, gz = g.T
        sq = gx * gx if axis == "x" else gy * gy
        a = np.column_stack([np.ones_like(gx), gx, gy, gz, sq, gz * gz, gx * gy])
        return np.linalg.lstsq(a, c["output_deg_h"] - w, rcond=None)[0]

    step = 30.0
    for col in (1, 2, 3):
        err = np.zeros(3)
        err[col - 1] = step
        fd = (resolve(err) - resolve(-err)) / (2.0 * step)
        scale = np.max(np.abs(jac[:, col]))
        assert scale > 1e-6
        np.testing.assert_allclose(jac[:, col], fd, rtol=0, atol=1e-4 * scale)
    assert np.all(np.isfinite(beta))


def test_stated_mean_orientation_error_is_corrected():
    err = 40.0
    cap = simulate_multiposition(
        axis="y", noise_deg_h=0.0, repeats=1, orientation_error_arcsec=(err, err, err)
    )
    spec = load_specs(
        {
            "table": {
                "orientation_error_arcsec": {
                    "distribution": "rectangular",
                    "value": err,
                    "half_width": 5.0,
                }
            }
        }
    )
    plain = _calibrate(cap)
    r = _calibrate(cap, specs=spec)
    truth = TABLE1_COEFFICIENTS["y"]
    worst_plain = max(abs(plain.drift_coefficients[k] - v) for k, v in truth.items())
    worst = max(abs(r.drift_coefficients[k] - v) for k, v in truth.items())
    # eq. (7) is first order: what remains is O(Δ²·|β|) ≈ (2e-4 rad)²·100 °/h ≈ 4e-6 °/h
    assert worst_plain > 5e-3 and worst < 2e-5
    assert any("corrected" in n for n in r.notes)
    # Policy A: each budget says so in the standard text and its rows keep the stated value and u
    for b in r._budgets.values():
        assert any(
            "corrected for the stated mean of table.orientation_error_arcsec = 40" in n
            for n in b.notes
        )
        rows = [row for row in b.rows if "table.orientation_error_arcsec" in row.origin]
        assert len(rows) == 3
        assert all(row.value == err and row.u == pytest.approx(5 / 3**0.5) for row in rows)


def test_latitude_from_the_specs_and_contradictions():
    cap = simulate_multiposition(seed=1)
    c = cap.columns
    r = calibrate_multiposition(
        c["phi1_deg"], c["phi2_deg"], c["output_deg_h"], specs=_specs(orient_half=None)
    )
    assert r.latitude_deg == LAT
    with pytest.raises(ConfigError, match=r"contradicts site\.latitude_deg") as exc:
        calibrate_multiposition(
            c["phi1_deg"], c["phi2_deg"], c["output_deg_h"], latitude_deg=45.0, specs=_specs()
        )
    assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match="give the latitude"):
        calibrate_multiposition(c["phi1_deg"], c["phi2_deg"], c["output_deg_h"])


def test_bad_specification_is_one_line():
    for spec, msg in (
        ({"distribution": "normal", "value": LAT, "u": -0.01}, "≥ 0"),
        ({"distribution": "cauchy", "value": LAT, "u": 0.01}, "unknown distribution"),
    ):
        with pytest.raises(ConfigError, match=msg) as exc:
            load_specs({"site": {"latitude_deg": spec}})
        assert "\n" not in str(exc.value)


def test_json_keys_and_type_a_note():
    r = _calibrate(simulate_multiposition(axis="x", seed=2))
    d = json.loads(json.dumps(r.to_dict()))
    names = list(coefficient_names("x"))
    for key in ("drift_coefficients_u", "drift_coefficients_U"):
        assert list(d[key]) == names
    assert list(d["k"]["drift_coefficients"]) == names
    assert d["coverage_probability"] == 0.95
    for n in names:
        b = d["uncertainty_budgets"]["drift_coefficients"][n]
        assert b["u"] == d["drift_coefficients_u"][n]
        assert d["drift_coefficients_U"][n] == pytest.approx(
            d["k"]["drift_coefficients"][n] * d["drift_coefficients_u"][n]
        )
        assert any("Type A only" in note for note in b["notes"])
    # an exact fit (7 readings) has no uncertainty: the keys are there, null
    pos = np.array([[0, 0], [90, 0], [90, 90], [45, 0], [45, 45], [135, 30], [60, 120]], float)
    e = _calibrate(simulate_multiposition(positions=pos, noise_deg_h=0.0, repeats=1))
    de = json.loads(json.dumps(e.to_dict()))
    assert all(v is None for v in de["drift_coefficients_U"].values())
    assert de["coverage_probability"] is None


@pytest.mark.parametrize("axis", ["x", "y"])
@pytest.mark.parametrize("type_b", [False, True])
def test_honesty_spread_matches_u_on_the_twin(axis, type_b):
    """100 twin runs (64 positions × 4 readings, 0.005 °/h): std of every coefficient over mean u
    within the χ² bounds for 100 repeats at 99.9 %. With type_b the twin's latitude is drawn from
    N(45.75°, 0.02°) and its orientation error (Δψ, Δθ, Δγ) from U(−20″, 20″) per run, the same
    distributions the specs state; the analysis uses 45.75° and no orientation error. Type B is
    then 1.3…6.5 times Type A in u, so the check fails if either part is wrong."""
    n = 100
    rng = np.random.default_rng(2026 if type_b else 1)
    specs = _specs() if type_b else None
    est, us = [], []
    for i in range(n):
        kw = {}
        if type_b:
            kw = {
                "latitude_deg": LAT + 0.02 * float(rng.standard_normal()),
                "orientation_error_arcsec": rng.uniform(-20.0, 20.0, 3),
            }
        cap = simulate_multiposition(axis=axis, seed=500 + i, **kw)
        r = _calibrate(cap, specs=specs)
        est.append(list(r.drift_coefficients.values()))
        us.append(list(r.drift_coefficients_u.values()))
    ratio = np.std(est, axis=0, ddof=1) / np.mean(us, axis=0)
    lo, hi = _chi2_bounds(n)
    assert np.all((ratio > lo) & (ratio < hi)), dict(
        zip(coefficient_names(axis), ratio, strict=True)
    )


def test_twin_orientation_error_turns_the_inputs_and_checks_its_setting():
    # 1 arcmin about z (Δθ) at φ1 = φ2 = 0: gravity stays up, the Earth rate's north component
    # moves into the gyro's −y axis by Ωe·cos λ·Δθ (eq. 8: ωy′ = ωy − ωx·Δθ + ωz·Δγ)
    d = math.radians(1.0 / 60.0)
    cap = simulate_multiposition(
        positions=[(0.0, 0.0)], noise_deg_h=0.0, repeats=1, orientation_error_arcsec=(0, 60.0, 0)
    )
    w = cap.truth["earth_rate_components_deg_h"][0]
    g = cap.truth["gravity_components_g"][0]
    north = EARTH_RATE_DEG_H * math.cos(math.radians(LAT))
    assert w[1] == pytest.approx(-north * math.sin(d), rel=1e-12)
    assert w[0] == pytest.approx(north * math.cos(d), rel=1e-12)
    np.testing.assert_allclose(g, [0.0, 0.0, 1.0], atol=1e-15)
    assert cap.truth["orientation_error_arcsec"] == [0.0, 60.0, 0.0]
    for bad in ((1.0, 2.0), (1.0, float("nan"), 0.0), "abc"):
        with pytest.raises(ConfigError, match="orientation_error_arcsec"):
            simulate_multiposition(orientation_error_arcsec=bad)
