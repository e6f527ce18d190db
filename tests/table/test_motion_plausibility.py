"""Plausibility warnings of the motion calibration: twins whose fault is known."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal import sim
from rotacal.table import (
    calibrate_encoder_motion,
    calibrate_encoder_motion_chunked,
    calibrate_fog_motion,
    calibrate_lts_motion,
)
from rotacal.table.motion_plausibility import residual_to_noise_ratio

MOTION = sim.SineMotion(amplitude_deg=0.5, frequency_hz=2.0)
SET = {"set_amplitude_deg": 0.5, "set_frequency_hz": 2.0}


@pytest.fixture(scope="module")
def encoder():
    return sim.simulate_encoder(MOTION, lines=36_000, noise_rms=0.002, seed=1).columns


def _chunks(columns, rows=50_000):
    def chunks():
        for i in range(0, columns["a"].size, rows):
            yield {k: columns[k][i : i + rows] for k in ("time_s", "a", "b")}

    return chunks


def test_residual_to_noise_ratio_is_one_for_white_noise_and_large_for_a_slow_wave() -> None:
    rng = np.random.default_rng(0)
    white = rng.normal(0.0, 1.0, 20_000)
    assert residual_to_noise_ratio(white) == pytest.approx(1.0, abs=0.03)
    slow = np.sin(2 * np.pi * np.arange(20_000) / 2_000)  # 2000 samples per period
    # rms 1/√2 over successive differences 2π/2000/√2 · √2 … ratio = 2000/(2π)·… closed form:
    expected = math.sqrt(0.5 / ((2 * math.sin(math.pi / 2_000)) ** 2 * 0.5 / 2))
    assert residual_to_noise_ratio(slow) == pytest.approx(expected, rel=1e-3)


def test_valid_encoder_capture_gives_no_warning(encoder) -> None:
    c = encoder
    assert calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36_000, **SET).warnings == ()
    assert calibrate_encoder_motion_chunked(_chunks(c), lines=36_000, **SET).warnings == ()


@pytest.mark.parametrize("chunked", [False, True], ids=["in-memory", "chunked"])
def test_a_line_count_ten_times_too_small_names_lines(encoder, chunked) -> None:
    c = encoder
    if chunked:
        r = calibrate_encoder_motion_chunked(_chunks(c), lines=3_600, **SET)
    else:
        r = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=3_600, **SET)
    assert r.amplitude_error_percent == pytest.approx(900.0, rel=1e-3)  # what the issue saw
    (line,) = r.warnings
    assert "+900 %" in line and "×10" in line and "--lines" in line


def test_a_frequency_set_in_the_wrong_unit_and_a_large_error(encoder) -> None:
    c = encoder
    r = calibrate_encoder_motion(
        c["time_s"], c["a"], c["b"], lines=36_000, set_amplitude_deg=0.5, set_frequency_hz=20.0
    )
    assert len(r.warnings) == 1
    assert "frequency" in r.warnings[0] and "1/10" in r.warnings[0]
    r = calibrate_encoder_motion(
        c["time_s"], c["a"], c["b"], lines=36_000, set_amplitude_deg=0.7, set_frequency_hz=2.0
    )
    assert len(r.warnings) == 1 and "-28.57 %" in r.warnings[0] and "20 %" in r.warnings[0]


def test_lts_radius_in_cm_names_radius() -> None:
    m = sim.SineMotion(amplitude_deg=0.025, frequency_hz=10.0)
    c = sim.simulate_lts(m, radius_mm=100.0, noise_mm=3e-5, seed=4).columns
    kw = {"set_amplitude_deg": 0.025, "set_frequency_hz": 10.0}
    assert (
        calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0, **kw).warnings
        == ()
    )
    r = calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=10.0, **kw)
    (line,) = r.warnings
    assert "×10" in line and "--radius-mm" in line


def test_fog_rate_in_rad_per_s_names_the_unit() -> None:
    m = sim.SineMotion(amplitude_deg=0.5, frequency_hz=2.0)
    c = sim.simulate_fog(m, noise_deg_s=0.01, seed=2).columns
    ok = calibrate_fog_motion(c["time_s"], c["rate_deg_s"], **SET)
    assert ok.warnings == ()
    r = calibrate_fog_motion(c["time_s"], np.radians(c["rate_deg_s"]), **SET)
    (line,) = r.warnings
    assert "180/π" in line and "unit" in line


def test_a_vibration_the_harmonics_do_not_explain_is_a_lack_of_fit() -> None:
    shaky = sim.SineMotion(
        amplitude_deg=0.5, frequency_hz=2.0, vibration_deg=0.005, vibration_hz=37.0
    )
    c = sim.simulate_encoder(shaky, lines=36_000, noise_rms=0.002, seed=1).columns
    r = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36_000)
    (line,) = r.warnings
    assert line.startswith("lack of fit: the residual of the 10-harmonic fit")


def test_harmonics_beyond_the_fit_are_a_lack_of_fit() -> None:
    distorted = sim.SineMotion(amplitude_deg=0.5, frequency_hz=2.0, harmonics={3: (0.02, 0.0)})
    c = sim.simulate_encoder(distorted, lines=36_000, noise_rms=0.002, seed=1).columns
    full = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36_000)
    assert full.warnings == ()
    one = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36_000, harmonics=1)
    (line,) = one.warnings
    assert "1-harmonic fit" in line and "--harmonics" in line
