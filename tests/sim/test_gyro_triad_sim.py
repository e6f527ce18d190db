"""Twins of the 3-axis gyro test (seed 003) and of a Ferraris rotation recording."""

from __future__ import annotations

import json

import numpy as np
import pytest

import rotacal.sim.gyro_triad  # noqa: F401  (registers the kinds)
from rotacal.errors import ConfigError
from rotacal.sim import known_kinds, simulate
from rotacal.sim.gyro_triad import (
    DEFAULT_BIAS,
    DEFAULT_K,
    simulate_gyro_rotations,
    simulate_gyro_triad,
)

RATE_COLS = ("wx_deg_s", "wy_deg_s", "wz_deg_s")
OUT_COLS = ("ux", "uy", "uz")


def _omega_u(cap):
    c = cap.columns
    return np.column_stack([c[k] for k in RATE_COLS]), np.column_stack([c[k] for k in OUT_COLS])


# ------------------------------------------------------------------------------------ seed 003 twin
def test_plan_of_table_2_and_the_noise_free_model() -> None:
    spp = 4
    cap = simulate_gyro_triad(samples_per_point=spp, noise_std=0.0)
    assert cap.kind == "gyro-triad"
    assert list(cap.columns) == ["time_s", *RATE_COLS, *OUT_COLS]
    omega, u = _omega_u(cap)
    assert omega.shape == (3 * 10 * spp, 3) and cap.truth["points"] == 30
    # seed 003 Table 2: 6, 18, 30, 60, 90 °/s, each in both directions, about x then y then z
    rates = [6, -6, 18, -18, 30, -30, 60, -60, 90, -90]
    for j in range(3):
        block = omega[j * 10 * spp : (j + 1) * 10 * spp : spp]
        np.testing.assert_array_equal(block[:, j], rates)
        assert not np.delete(block, j, axis=1).any()
    k = np.array(DEFAULT_K)
    b = np.array(DEFAULT_BIAS)
    for i in range(omega.shape[0]):  # the model, row by row (test code: clarity over speed)
        np.testing.assert_allclose(u[i], k @ omega[i] + b, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.diff(cap.columns["time_s"]), 0.01)


def test_noise_level_and_reproducibility() -> None:
    a = simulate_gyro_triad(noise_std=0.2, seed=3)
    b = simulate_gyro_triad(noise_std=0.2, seed=3)
    c = simulate_gyro_triad(noise_std=0.2, seed=4)
    np.testing.assert_array_equal(a.columns["ux"], b.columns["ux"])
    assert not np.array_equal(a.columns["ux"], c.columns["ux"])
    omega, u = _omega_u(a)
    noise = u - (omega @ np.array(DEFAULT_K).T + np.array(DEFAULT_BIAS))
    np.testing.assert_allclose(noise.std(axis=0), 0.2, rtol=0.03)
    assert abs(float(noise.mean())) < 0.01


@pytest.mark.parametrize("channels", ["one", "all"])
def test_outliers_are_where_the_truth_says(channels: str) -> None:
    cap = simulate_gyro_triad(
        noise_std=0.0, outlier_fraction=0.02, outlier_size=20.0, outlier_channels=channels, seed=7
    )
    omega, u = _omega_u(cap)
    dev = u - (omega @ np.array(DEFAULT_K).T + np.array(DEFAULT_BIAS))
    o = cap.truth["outliers"]
    n = omega.shape[0]
    assert len(o["row_set"]) == round(0.02 * n)
    per_row = 1 if channels == "one" else 3
    assert len(o["rows"]) == per_row * len(o["row_set"])
    mask = np.zeros_like(dev, bool)
    mask[o["rows"], [OUT_COLS.index(c) for c in o["columns"]]] = True
    assert np.all(np.abs(dev[~mask]) < 1e-12)
    assert np.all((np.abs(dev[mask]) >= 10.0 - 1e-9) & (np.abs(dev[mask]) <= 20.0 + 1e-9))
    np.testing.assert_allclose(
        dev[o["rows"], [OUT_COLS.index(c) for c in o["columns"]]], o["errors"]
    )


def test_clipping_and_quantisation() -> None:
    cap = simulate_gyro_triad(noise_std=0.0, output_limit=60.0, quantum=0.25)
    _, u = _omega_u(cap)
    assert np.abs(u).max() <= 60.0
    np.testing.assert_allclose(u / 0.25, np.round(u / 0.25), atol=1e-9)
    # which set rates exceed ±60 in some channel, from K and b by hand: x +60 (60.8), ±90;
    # y −60 (−60.12), ±90; z +60 (60.32), ±90: 9 points of 500 samples, one channel each
    assert cap.truth["clipped_samples"] == 9 * 500
    static = simulate_gyro_triad(include_static=True, noise_std=0.0, samples_per_point=2)
    omega, _ = _omega_u(static)
    assert not omega[:2].any() and static.truth["points"] == 31


def test_bad_settings_are_config_errors() -> None:
    for kw in (
        {"K": np.zeros((3, 3))},
        {"K": np.eye(2)},
        {"bias": (1.0, 2.0)},
        {"rates_deg_s": (0.0, 6.0)},
        {"outlier_fraction": 0.7},
        {"outlier_channels": "two"},
        {"samples_per_point": 0},
        {"noise_std": -1.0},
        {"output_limit": 0.0},
    ):
        with pytest.raises(ConfigError):
            simulate_gyro_triad(**kw)


def test_dispatcher_and_writing(tmp_path) -> None:
    assert {"gyro-triad", "gyro-rotations"} <= set(known_kinds())
    cap = simulate("gyro-triad", samples_per_point=2, seed=1)
    assert cap.kind == "gyro-triad"
    with pytest.raises(ConfigError, match="unknown option"):
        simulate("gyro-triad", amplitude=3)
    path = cap.write(tmp_path / "triad.csv")
    truth = json.loads((tmp_path / "triad.csv.truth.json").read_text())
    np.testing.assert_allclose(truth["scale_misalignment"], DEFAULT_K)
    import rotacal.io

    back = rotacal.io.read_capture(path, columns=list(RATE_COLS + OUT_COLS))
    np.testing.assert_allclose(back["uy"], cap.columns["uy"], rtol=1e-12)


# ------------------------------------------------------------------------------------ rotations twin
def test_rotation_profile_integrates_to_the_set_angle() -> None:
    """Σ sin²(πk/N) = N/2: the sampled rate of each turn sums to exactly angle·fs."""
    fs = 100.0
    cap = simulate_gyro_rotations(
        K=np.eye(3), bias=(0.0, 0.0, 0.0), noise_std=0.0, angle_deg=-360.0, fs_hz=fs
    )
    u = np.column_stack([cap.columns[c] for c in OUT_COLS])
    t = cap.truth
    for j, a in enumerate("xyz"):
        s, e = t["motion"][a]
        expected = np.zeros(3)
        expected[j] = -360.0
        np.testing.assert_allclose(u[s:e].sum(axis=0) / fs, expected, atol=1e-9)
        # the marked section holds the motion plus rest on both sides
        rs, re = t["rotations"][a]
        assert rs < s and e < re
        np.testing.assert_allclose(u[rs:re].sum(axis=0) / fs, expected, atol=1e-9)
        assert np.abs(u[s:e, j]).max() == pytest.approx(2 * 360 / 4.0, rel=1e-3)
    # static sections are at rest and overlap no rotation
    for s, e in t["static"]:
        assert not u[s:e].any()
        for rs, re in t["rotations"].values():
            assert e <= rs or re <= s


def test_rotation_twin_model_and_settings() -> None:
    k = np.array(DEFAULT_K)
    cap = simulate_gyro_rotations(noise_std=0.0, fs_hz=50.0, rotation_s=2.0, static_s=3.0)
    u = np.column_stack([cap.columns[c] for c in OUT_COLS])
    s, e = cap.truth["motion"]["y"]
    mid = (s + e) // 2
    assert cap.truth["angle_deg"] == -360.0  # the Ferraris protocol's clockwise turn
    rate_y = 2 * -360.0 / 2.0 * np.sin(np.pi * (mid - s) / (e - s)) ** 2
    np.testing.assert_allclose(u[mid], k @ np.array([0.0, rate_y, 0.0]) + np.array(DEFAULT_BIAS))
    assert len(cap) == 4 * 150 + 3 * 100
    for kw in ({"angle_deg": 0.0}, {"rotation_s": 0.01}, {"static_s": 0.5, "margin_s": 0.5}):
        with pytest.raises(ConfigError):
            simulate_gyro_rotations(**kw)
