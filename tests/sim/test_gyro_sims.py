"""The gyro rate-table and multiposition twins: their truth against closed forms and hand values."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import rotacal.io
from rotacal.errors import ConfigError
from rotacal.results import to_jsonable
from rotacal.sim import known_kinds, simulate
from rotacal.sim.gyro_rates import DEFAULT_RATES_DEG_S, simulate_gyro_rates
from rotacal.sim.multiposition import (
    DEFAULT_POSITIONS_DEG,
    EARTH_RATE_DEG_H,
    TABLE1_COEFFICIENTS,
    simulate_multiposition,
)


# ------------------------------------------------------------------ gyro-rates
def test_rates_capture_layout_and_determinism():
    a = simulate_gyro_rates(seed=7, samples_per_point=10)
    b = simulate_gyro_rates(seed=7, samples_per_point=10)
    assert a.kind == "gyro-rates" and list(a.columns) == ["rate_deg_s", "output"]
    assert len(a) == 110 and len(DEFAULT_RATES_DEG_S) == 11
    np.testing.assert_array_equal(a.columns["output"], b.columns["output"])
    np.testing.assert_array_equal(a.columns["rate_deg_s"], np.repeat(DEFAULT_RATES_DEG_S, 10))
    json.dumps(to_jsonable(a.truth))


def test_both_twins_write_a_capture_and_its_truth(tmp_path):
    for cap in (simulate_gyro_rates(samples_per_point=4), simulate_multiposition(repeats=1)):
        path = cap.write(tmp_path / f"{cap.kind}.csv")
        back = rotacal.io.read_capture(path)
        for name, col in cap.columns.items():
            np.testing.assert_allclose(np.asarray(back[name]), col, rtol=1e-12)
        truth = json.loads((tmp_path / f"{cap.kind}.csv.truth.json").read_text())
        assert truth["kind"] == cap.kind


def test_rates_truth_line_has_the_closed_form():
    # V = V0 + S·Ω + c2·Ω² + c3·Ω³ over points symmetric about 0: the LS line has slope
    # S + c3·ΣΩ⁴/ΣΩ² and intercept V0 + c2·mean(Ω²).
    s, v0, c2, c3 = 0.0125, 2.5, 4e-8, -1.5e-11
    cap = simulate_gyro_rates(scale_factor=s, bias=v0, nonlinearity=(c2, c3), noise_std=0.0)
    w = np.asarray(DEFAULT_RATES_DEG_S)
    t = cap.truth
    assert t["scale_factor"] == s and t["bias"] == v0
    assert t["ls_scale_factor"] == pytest.approx(s + c3 * np.sum(w**4) / np.sum(w**2), rel=1e-13)
    assert t["ls_bias"] == pytest.approx(v0 + c2 * np.mean(w**2), rel=1e-13)
    clean = v0 + s * w + c2 * w**2 + c3 * w**3
    resid = clean - (t["ls_scale_factor"] * w + t["ls_bias"])
    np.testing.assert_allclose(t["ls_residuals"], resid, atol=1e-15)
    nl = 100 * np.max(np.abs(resid)) / (abs(t["ls_scale_factor"]) * 100.0)
    assert t["nonlinearity_percent_fs"] == pytest.approx(nl, rel=1e-12)
    # noise-free: every sample is the clean response of its rate
    np.testing.assert_allclose(cap.columns["output"], np.repeat(clean, 5000), rtol=1e-15)


def test_rates_noise_quantum_and_rails():
    cap = simulate_gyro_rates(noise_std=1e-3, samples_per_point=20000, seed=1)
    out = cap.columns["output"].reshape(11, -1)
    assert np.std(out, axis=1, ddof=1) == pytest.approx(np.full(11, 1e-3), rel=0.03)
    q = 0.002
    cq = simulate_gyro_rates(quantum=q, seed=1)
    k = cq.columns["output"] / q
    assert np.max(np.abs(k - np.round(k))) < 1e-9
    cs = simulate_gyro_rates(saturation=(1.4, 3.6), seed=1)
    assert cs.columns["output"].max() == 3.6 and cs.columns["output"].min() == 1.4
    assert cs.truth["saturated_rates_deg_s"] == [-100.0, 100.0]
    # the truth is of the analog response, untouched by the rails
    assert cs.truth["ls_scale_factor"] == simulate_gyro_rates().truth["ls_scale_factor"]


def test_rates_dispatcher_and_bad_settings():
    assert {"gyro-rates", "multiposition"} <= set(known_kinds())  # registered on import
    cap = simulate("gyro-rates", samples_per_point=3, noise_std=0.0)
    assert cap.kind == "gyro-rates" and len(cap) == 33
    for kw, msg in (
        ({"rates_deg_s": [10.0]}, "at least 2 distinct"),
        ({"scale_factor": 0.0}, "nonzero"),
        ({"noise_std": -1.0}, "noise_std"),
        ({"samples_per_point": 0}, "samples_per_point"),
        ({"quantum": 0.0}, "quantum"),
        ({"saturation": (3.0, 1.0)}, "low < high"),
        ({"nonlinearity": {1: 0.1}}, "powers"),
    ):
        with pytest.raises(ConfigError, match=msg):
            simulate_gyro_rates(**kw)


# ------------------------------------------------------------------ multiposition
def test_multiposition_hand_values():
    lat = 40.0
    lam = math.radians(lat)
    we = EARTH_RATE_DEG_H
    x = TABLE1_COEFFICIENTS["x"]
    y = TABLE1_COEFFICIENTS["y"]
    pos = [(0.0, 0.0), (90.0, 0.0), (90.0, 90.0), (180.0, 0.0)]
    cx = simulate_multiposition(positions=pos, axis="x", latitude_deg=lat, noise_deg_h=0.0)
    cy = simulate_multiposition(positions=pos, axis="y", latitude_deg=lat, noise_deg_h=0.0)
    ox, oy = cx.truth["clean_output_deg_h"], cy.truth["clean_output_deg_h"]
    # level, north-west-up: ωx = Ωe cos λ, ωy = 0, a = (0, 0, 1)
    assert ox[0] == pytest.approx(we * math.cos(lam) + x["DF"] + x["Dz"] + x["Dzz"], abs=1e-12)
    assert oy[0] == pytest.approx(y["DF"] + y["Dz"] + y["Dzz"], abs=1e-12)
    # outer axis at 90° about west: the gyro x axis points down: a = (−1, 0, 0), ωx = −Ωe sin λ
    assert ox[1] == pytest.approx(-we * math.sin(lam) + x["DF"] - x["Dx"] + x["Dxx"], abs=1e-12)
    # then the inner axis at 90°: a = (0, 1, 0), ωy = Ωe sin λ
    assert oy[2] == pytest.approx(we * math.sin(lam) + y["DF"] + y["Dy"] + y["Dyy"], abs=1e-12)
    # upside down: a = (0, 0, −1), ωx = −Ωe cos λ
    assert ox[3] == pytest.approx(-we * math.cos(lam) + x["DF"] - x["Dz"] + x["Dzz"], abs=1e-12)
    g = cx.truth["gravity_components_g"]
    np.testing.assert_allclose(np.linalg.norm(g, axis=1), 1.0, rtol=1e-15)
    w = cx.truth["earth_rate_components_deg_h"]
    np.testing.assert_allclose(np.linalg.norm(w, axis=1), we, rtol=1e-15)
    # the angle between Earth rate and up is the colatitude at every position
    np.testing.assert_allclose(np.sum(w * g, axis=1) / we, math.sin(lam), atol=1e-15)


def test_multiposition_capture_layout_noise_and_settings():
    cap = simulate_multiposition(repeats=3, noise_deg_h=0.01, seed=2)
    assert cap.kind == "multiposition"
    assert list(cap.columns) == ["phi1_deg", "phi2_deg", "output_deg_h"]
    assert len(cap) == 3 * len(DEFAULT_POSITIONS_DEG) == 192
    noise = cap.columns["output_deg_h"] - np.tile(cap.truth["clean_output_deg_h"], 3)
    assert np.std(noise) == pytest.approx(0.01, rel=0.15)
    assert cap.truth["drift_coefficients"] == TABLE1_COEFFICIENTS["x"]
    c = simulate_multiposition(axis="y", coefficients={"Dyx": 1.0})
    assert c.truth["drift_coefficients"]["Dyx"] == 1.0
    assert c.truth["drift_coefficients"]["DF"] == TABLE1_COEFFICIENTS["y"]["DF"]
    assert simulate("multiposition", repeats=1).kind == "multiposition"
    for kw, msg in (
        ({"axis": "z"}, "axis"),
        ({"latitude_deg": 91.0}, "latitude_deg"),
        ({"coefficients": {"Dxy": 1.0}, "axis": "y"}, "unknown drift coefficient 'Dxy'"),
        ({"repeats": 0}, "repeats"),
        ({"noise_deg_h": -0.1}, "noise_deg_h"),
        ({"positions": [(0.0, 1.0, 2.0)]}, "pairs"),
    ):
        with pytest.raises(ConfigError, match=msg):
            simulate_multiposition(**kw)
