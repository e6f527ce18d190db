"""Ferraris calibration with gravity and the Earth rate: twins with known truth, imucal's two real
recordings, the accelerometer triad, quantised and clipped outputs, refusals."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.accel_triad import calibrate_accel_triad, normal_gravity
from rotacal.gyro.ferraris import calibrate_ferraris
from rotacal.gyro.rotation_sections import sections_from_labels
from rotacal.signal.clipping import ClippedSignalError
from rotacal.sim import simulate_ferraris

EARTH_DEG_S = math.degrees(7.2921150e-5)


def _cols(cap, names):
    return np.column_stack([cap.columns[c] for c in names])


def _fit(cap, **kw):
    t = cap.truth
    kw.setdefault("gravity_m_s2", t["gravity_m_s2"])
    return calibrate_ferraris(
        _cols(cap, ("ux", "uy", "uz")),
        _cols(cap, ("ax", "ay", "az")),
        t["sensor"]["fs_hz"],
        t["sections"],
        **kw,
    )


def _truth(t):
    return {
        k: np.asarray(t[k], dtype=float) for k in ("scale_misalignment", "bias", "g_sensitivity")
    }


# ------------------------------------------------------------------------------------ twins
def test_noise_free_twin_on_a_still_earth_gives_the_truth() -> None:
    cap = simulate_ferraris(noise_std=0.0, acc_noise_std=0.0, earth_rate=False)
    r = _fit(cap)
    t = _truth(cap.truth)
    np.testing.assert_allclose(r.scale_misalignment, t["scale_misalignment"], atol=1e-10)
    np.testing.assert_allclose(r.bias, t["bias"], atol=1e-10)
    np.testing.assert_allclose(r.g_sensitivity, t["g_sensitivity"], atol=1e-12)
    acc = r.accelerometer
    np.testing.assert_allclose(
        acc.scale_misalignment, cap.truth["acc_scale_misalignment"], atol=1e-12
    )
    np.testing.assert_allclose(acc.bias, cap.truth["acc_bias"], atol=1e-12)
    assert r.warnings == ()


def test_noise_free_twin_on_the_earth_vertical_rate_removed_horizontal_in_u() -> None:
    """The vertical Earth rate is removed exactly: K_ga's diagonal, which it would shift by
    3·10⁻⁴, is left with the horizontal rate through K's cross-axis terms (< 10⁻⁶); what the
    unknown heading leaves is within the stated uncertainty."""
    cap = simulate_ferraris(noise_std=0.0, acc_noise_std=0.0, latitude_deg=49.6)
    t = _truth(cap.truth)
    r = _fit(cap, latitude_deg=49.6)
    np.testing.assert_allclose(np.diag(r.g_sensitivity), np.diag(t["g_sensitivity"]), atol=1e-6)
    for key in ("scale_misalignment", "bias", "g_sensitivity"):
        err = np.abs(getattr(r, key) - t[key])
        assert np.all(err <= 2.0 * getattr(r, f"{key}_u") + 1e-12), key
    # without the latitude nothing is removed: K_ga's diagonal carries K·Ω_E·sin L/g, in its u
    r0 = _fit(cap)
    shift = np.diag(r0.g_sensitivity - t["g_sensitivity"])
    expected = np.diag(t["scale_misalignment"]) * EARTH_DEG_S * math.sin(math.radians(49.6))
    g = cap.truth["gravity_m_s2"]
    np.testing.assert_allclose(shift, expected / g, rtol=0, atol=1e-6)  # K cross-axis terms
    assert np.all(np.abs(shift) < 2.0 * np.diag(r0.g_sensitivity_u))


@pytest.mark.parametrize("seed", range(3))
def test_noisy_twin_each_parameter_within_its_uncertainty(seed: int) -> None:
    cap = simulate_ferraris(seed=seed, noise_std=0.05, acc_noise_std=0.01)
    t = _truth(cap.truth)
    r = _fit(cap, latitude_deg=cap.truth["latitude_deg"])
    for key in ("scale_misalignment", "bias", "g_sensitivity"):
        z = (getattr(r, key) - t[key]) / getattr(r, f"{key}_u")
        assert np.all(np.abs(z) < 4.0), (key, z)
    acc = r.accelerometer
    for key, truth in (
        ("scale_misalignment", cap.truth["acc_scale_misalignment"]),
        ("bias", cap.truth["acc_bias"]),
    ):
        z = (getattr(acc, key) - np.asarray(truth)) / getattr(acc, f"{key}_u")
        assert np.all(np.abs(z) < 4.0), (key, z)


def test_the_uncertainty_matches_the_scatter_over_twins() -> None:
    """z-scores over 12 twins on the rotating Earth, each quantity's elements pooled: rms near 1
    (measured 0.94 K, 1.0 K_ga, 1.25 b, 1.08 K_a·R_a, 0.95 b_a; a u half the true one would give
    about 2)."""
    zs: dict[str, list[np.ndarray]] = {}
    for seed in range(12):
        cap = simulate_ferraris(seed=100 + seed, noise_std=0.05, acc_noise_std=0.01)
        r = _fit(cap, latitude_deg=cap.truth["latitude_deg"])
        t = _truth(cap.truth)
        acc = r.accelerometer
        pairs = {
            "K": (r.scale_misalignment - t["scale_misalignment"]) / r.scale_misalignment_u,
            "K_ga": (r.g_sensitivity - t["g_sensitivity"]) / r.g_sensitivity_u,
            "b": (r.bias - t["bias"]) / r.bias_u,
            "M_a": (acc.scale_misalignment - cap.truth["acc_scale_misalignment"])
            / acc.scale_misalignment_u,
            "b_a": (acc.bias - cap.truth["acc_bias"]) / acc.bias_u,
        }
        for key, z in pairs.items():
            zs.setdefault(key, []).append(np.ravel(z))
    for key, z in zs.items():
        rms = float(np.sqrt(np.mean(np.concatenate(z) ** 2)))
        assert 0.6 < rms < 1.5, (key, rms)


def test_quantised_twin_is_no_clipping_and_a_clipped_one_is_refused() -> None:
    """Many repeated values everywhere (a 16-bit MEMS's steps) are quantisation, not a rail."""
    for noise, acc_noise in ((0.02, 0.002), (0.0, 0.0)):  # dithered by noise, and not at all
        quantised = simulate_ferraris(
            quantum=2000 / 32768, acc_quantum=0.00479, noise_std=noise, acc_noise_std=acc_noise
        )
        r = _fit(quantised, latitude_deg=49.6)
        assert r.warnings == ()
        # the rounding a noise-free output leaves in each mean is in the uncertainty
        t = _truth(quantised.truth)
        for key in ("scale_misalignment", "bias", "g_sensitivity"):
            assert np.all(np.abs(getattr(r, key) - t[key]) < 4 * getattr(r, f"{key}_u")), key
        acc, truth = r.accelerometer, quantised.truth["acc_scale_misalignment"]
        assert np.all(np.abs(acc.scale_misalignment - truth) < 4 * acc.scale_misalignment_u)
    # the gyro at a rail during the turns (peak 180 °/s, range 150 °/s)
    clipped = simulate_ferraris(output_limit=150.0, quantum=2000 / 32768)
    with pytest.raises(ClippedSignalError) as exc:
        _fit(clipped)
    assert "\n" not in str(exc.value) and "clipped" in str(exc.value)
    # the accelerometer at a rail in a static position (range ±9.7 m/s² below g)
    clipped_acc = simulate_ferraris(acc_output_limit=9.7, acc_quantum=0.00479)
    with pytest.raises(ClippedSignalError):
        _fit(clipped_acc)
    allowed = _fit(clipped_acc, allow_clipped=True)
    assert any("clipped" in w for w in allowed.warnings)


def test_refusals_in_one_line() -> None:
    cap = simulate_ferraris(noise_std=0.05)
    secs = cap.truth["sections"]
    no_pos = {k: v for k, v in secs.items() if k != "y_a"}
    with pytest.raises(ConfigError, match="lacks y_a"):
        _fit(cap.__class__(cap.kind, cap.columns, {**cap.truth, "sections": no_pos}))
    with pytest.raises(ConfigError, match="static position y_a is missing"):
        calibrate_accel_triad(_cols(cap, ("ax", "ay", "az")), {k: v for k, v in no_pos.items()})
    overlap = {**secs, "z_a": [secs["z_p"][0] + 10, secs["z_a"][1]]}
    with pytest.raises(ConfigError, match="overlap"):
        _fit(cap.__class__(cap.kind, cap.columns, {**cap.truth, "sections": overlap}))
    # a quarter turn short of 360°: with the nominal sensitivity (°/s) it cannot pass into K
    s, e = secs["y_rot"]
    short = {**secs, "y_rot": [s, s + (e - s) * 3 // 5]}
    with pytest.raises(CaptureError, match="not the set -360") as exc:
        _fit(
            cap.__class__(cap.kind, cap.columns, {**cap.truth, "sections": short}),
            nominal_scale=1.0,
        )
    assert "\n" not in str(exc.value)
    with pytest.raises(ConfigError, match="latitude"):
        _fit(cap, latitude_deg=95.0)
    assert sections_from_labels(["a", "a", "b", "b", "b"]) == {"a": (0, 2), "b": (2, 5)}
    with pytest.raises(ConfigError, match="section a is not one contiguous block"):
        sections_from_labels(["a", "b", "a"])


def test_normal_gravity_closed_form() -> None:
    """WGS 84 normal gravity: 9.7803253359 at the equator, 9.8321849378 at the poles (NIMA
    TR8350.2 Table 3.4); at 45° the 1980 International Gravity Formula's series,
    9.780327·(1 + 0.0053024·sin²φ − 0.0000058·sin²2φ), agrees to its few 10⁻⁶ m/s²."""
    assert normal_gravity(0.0) == pytest.approx(9.7803253359, abs=1e-10)
    assert normal_gravity(90.0) == pytest.approx(9.8321849378, abs=1e-9)
    series = 9.780327 * (1 + 0.0053024 * 0.5 - 0.0000058 * 1.0)
    assert normal_gravity(45.0) == pytest.approx(series, abs=3e-6)


# ------------------------------------------------------------------------------------ imucal
def _load_102(imucal: Path):
    d = np.loadtxt(
        imucal / "example_data" / "example_ferraris_session.csv", delimiter=",", skiprows=1
    )
    sec = json.loads((imucal / "example_data" / "example_ferraris_session_list.json").read_text())
    return d[:, 1:4], d[:, 4:7], sec


def _load_204(imucal: Path):
    with open(imucal / "example_data" / "annotated_session.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0][2:] == ["acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"]
    vals = np.array([r[2:] for r in rows[1:]], dtype=float)
    return vals[:, 3:6], vals[:, 0:3], sections_from_labels([r[0] for r in rows[1:]])


SESSIONS = [
    ("102.4 Hz", _load_102, 102.4, "example_ferraris_session_cal_computed_imucal2.6.0.json"),
    ("204.8 Hz counts", _load_204, 204.8, "tests/snapshots/example_cal.json"),
]


@pytest.mark.parametrize(("name", "load", "fs", "ref_file"), SESSIONS, ids=[s[0] for s in SESSIONS])
def test_imucal_recordings(name, load, fs, ref_file, shared_data) -> None:
    """imucal's K_g·R_g, K_ga, b_g and K_a, R_a, b_a on its own recordings, with its g = 9.81
    and, like imucal, no Earth rate removed."""
    imucal = shared_data("imucal")
    gyr, acc, sec = load(imucal)
    ref = {
        k: np.asarray(v, dtype=float)
        for k, v in json.loads((imucal / ref_file).read_text()).items()
        if k[:2] in ("K_", "R_", "b_")
    }
    r = calibrate_ferraris(gyr, acc, fs, sec, gravity_m_s2=9.81)
    k_ref = ref["K_g"] @ ref["R_g"]
    scale = np.abs(np.diag(ref["K_g"])).min()
    # K: before K_ga was removed the rotations differed from imucal by up to 2.1e-4 of K
    assert np.abs(r.scale_misalignment - k_ref).max() / scale < 3e-6
    np.testing.assert_allclose(r.g_sensitivity, ref["K_ga"], rtol=1e-10, atol=1e-15)
    # b: imucal's pooled static mean keeps the mean of K_ga·a over the static samples
    rows = np.concatenate(
        [
            np.arange(int(sec[k]["start"]), int(sec[k]["end"]))
            if isinstance(sec[k], dict)
            else np.arange(*sec[k])
            for k in ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")
        ]
    )
    a_cal = r.accelerometer.calibrate(acc[rows])
    np.testing.assert_allclose(
        r.bias + (a_cal @ r.g_sensitivity.T).mean(axis=0), ref["b_g"], atol=1e-9 * scale
    )
    acc_r = r.accelerometer
    np.testing.assert_allclose(acc_r.scale_factors, np.diag(ref["K_a"]), rtol=1e-12)
    np.testing.assert_allclose(acc_r.sensitive_axes, ref["R_a"], atol=1e-12)
    np.testing.assert_allclose(acc_r.bias, ref["b_a"], rtol=1e-12)
    # and imucal's K within rotacal's stated uncertainty
    assert np.all(np.abs(r.scale_misalignment - k_ref) < r.scale_misalignment_u)

    # at the lab's latitude (Erlangen, 49.6° N, assumed): K_ga's diagonal drops by the vertical
    # Earth rate, K_ii·Ω_E·sin L/g, which imucal leaves in it
    r_lat = calibrate_ferraris(gyr, acc, fs, sec, gravity_m_s2=9.81, latitude_deg=49.6)
    drop = np.diag(ref["K_ga"] - r_lat.g_sensitivity)
    expect = np.diag(r_lat.scale_misalignment) * EARTH_DEG_S * math.sin(math.radians(49.6)) / 9.81
    np.testing.assert_allclose(drop, expect, rtol=0.02)
