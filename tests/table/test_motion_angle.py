"""motion angle: the seed-000 calibration on angle and counter readings against the twin's truth."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.sim import SineMotion, simulate_angle
from rotacal.table.motion_angle import (
    angle_quantum,
    calibrate_angle_motion,
    calibrate_count_motion,
    quantisation_u,
)
from rotacal.table.motion_angle_stream import calibrate_angle_motion_chunked

MOTION = SineMotion(
    amplitude_deg=0.5, frequency_hz=2.0, harmonics={2: (0.005, 1.0), 3: (0.01, 0.3)}
)


def _within(d: dict, truth: dict) -> None:
    """Amplitude, frequency and acceleration within U of the truth; the THD's interval holds it."""
    for key in ("amplitude_deg", "frequency_hz", "angular_acceleration_amplitude_deg_s2"):
        assert abs(d[key] - truth[key]) <= d[f"{key}_U"], key
    lo, hi = d["thd_percent_interval"]
    assert lo <= truth["thd_percent"] <= hi


def test_wrapping_signed_counter_against_truth():
    cap = simulate_angle(MOTION, counter_bits=16, signed=True, noise_deg=0.002, seed=3)
    assert cap.truth["sensor"]["wraps"] > 0
    r = calibrate_count_motion(
        cap.columns["time_s"],
        cap.columns["count"],
        counts_per_rev=144_000,
        set_amplitude_deg=0.5,
        set_frequency_hz=2.0,
    )
    d = r.to_dict()
    assert r.scheme == "angle" and d["periods_used"] == 5 and d["warnings"] == []
    assert "16-bit signed register (inferred" in r.notes[-1]
    _within(d, cap.truth)
    assert {"amplitude_error_percent", "position_error_max_deg", "reversal_times_s"} <= set(d)
    rows = [row.source for row in r._budgets["amplitude_error_percent"].rows]
    assert any("quantisation of A₁ (1 count of 144000/rev)" in s for s in rows)


def test_undithered_readout_quantisation_is_in_the_budget():
    """No noise: the quantisation error repeats with the motion and is the largest error; the
    Type B row makes u hold it (without it the fit's u alone is about a third of the error)."""
    cap = simulate_angle(MOTION, reading="angle", resolution_deg=0.002, fs_hz=1000.0, seed=0)
    r = calibrate_angle_motion(cap.columns["time_s"], cap.columns["angle_deg"])
    d = r.to_dict()
    assert "quantum of the readings" in r.notes[-1]
    _within(d, cap.truth)
    rows = {row.source: row.u for row in r._budgets["amplitude_deg"].rows}
    assert (
        rows["readout quantisation of A₁ (quantum of the readings)"] > rows["A (fundamental, fit)"]
    )


@pytest.mark.parametrize("per", [2857.0, 2857.14])  # commensurate sampling, and not
def test_quantisation_u_against_a_monte_carlo_of_the_offset(per):
    """Independent: quantise A·sin φ + c for random c, fit the harmonics by least squares; the
    rms error of each A_h lies between half the stated u and u."""
    q, a = 0.002, 0.5
    phi = 2 * np.pi * np.arange(20_000) / per
    x = np.column_stack([f(h * phi) for h in (1, 2, 3) for f in (np.cos, np.sin)])
    th = a * np.sin(phi) + np.random.default_rng(0).uniform(0, q, (150, 1))
    co = (np.round(th / q) * q - th) @ np.linalg.pinv(x).T  # least squares, every offset at once
    mc = np.sqrt(np.mean(co[:, 0::2] ** 2 + co[:, 1::2] ** 2, axis=0))
    u = quantisation_u(q, a, 3, per)
    assert np.all(mc <= 1.1 * u) and np.all(u <= 2 * mc), (u, mc)
    assert quantisation_u(q, a, 1, per, noise_deg=q)[0] < 1e-3 * mc[0]  # dithered: averaged


def test_daq_faults_are_named_and_refused_above_one_percent():
    cap = simulate_angle(MOTION, noise_deg=0.002, drop_rows=4, repeat_rows=2, seed=5)
    r = calibrate_count_motion(cap.columns["time_s"], cap.columns["count"], counts_per_rev=144_000)
    dropped = np.array(cap.truth["sensor"]["dropped_samples"])
    after = dropped - np.arange(dropped.size)  # the record's sample after each gap
    repeated = cap.truth["sensor"]["repeated_rows"]
    after += np.searchsorted(np.array(repeated) - np.arange(len(repeated)), after, side="right")
    assert any(f"before sample(s) {', '.join(map(str, after))}" in w for w in r.warnings)
    assert any(f"at sample(s) {', '.join(map(str, repeated))}, dropped" in w for w in r.warnings)
    _within(r.to_dict(), cap.truth)
    many = simulate_angle(MOTION, noise_deg=0.002, drop_rows=200, seed=5)
    t, c = many.columns["time_s"], many.columns["count"]
    with pytest.raises(CaptureError, match="--allow-gaps"):
        calibrate_count_motion(t, c, counts_per_rev=144_000)
    assert calibrate_count_motion(t, c, counts_per_rev=144_000, allow_gaps=True).periods_used == 5


def test_drift_is_fitted():
    motion = SineMotion(amplitude_deg=0.5, frequency_hz=2.0, drift_deg_s=0.05)
    cap = simulate_angle(motion, counter_bits=32, noise_deg=0.002, seed=1)
    r = calibrate_count_motion(
        cap.columns["time_s"], cap.columns["count"], counts_per_rev=144_000, drift=True
    )
    d = r.to_dict()
    assert abs(d["drift_deg_s"] - 0.05) <= 2 * d["drift_deg_s_u"]
    assert abs(d["amplitude_deg"] - cap.truth["amplitude_deg"]) <= d["amplitude_deg_U"]


def test_quantum_rule_and_refusals():
    assert angle_quantum(np.array([0.1, 0.3, 0.2, 0.7]) * 3) == pytest.approx(0.3)
    assert angle_quantum(np.sin(np.arange(1000.0))) is None
    t = np.arange(100) * 0.01
    with pytest.raises(CaptureError, match="constant"):
        calibrate_angle_motion(t, np.zeros(100))
    with pytest.raises(CaptureError, match="NaN or inf at sample 4"):
        calibrate_angle_motion(t, np.where(np.arange(100) == 4, np.nan, t))
    with pytest.raises(ConfigError, match="--counts-per-rev"):
        calibrate_count_motion(t, np.arange(100), counts_per_rev=0)
    with pytest.raises(ConfigError, match="--resolution-deg"):
        calibrate_angle_motion(t, np.sin(t), resolution_deg=-1.0)


@pytest.mark.parametrize("drift", [False, True])
def test_chunked_equals_in_memory(drift):
    """The streamed passes give the in-memory result: uneven chunks, DAQ faults, a wrapping
    counter whose register is inferred from the whole range, a drift."""
    motion = SineMotion(
        amplitude_deg=0.5, frequency_hz=2.0, harmonics={3: (0.01, 0.3)}, drift_deg_s=0.02
    )
    cap = simulate_angle(motion, noise_deg=0.002, drop_rows=5, repeat_rows=3, seed=1)
    t, c = cap.columns["time_s"], cap.columns["count"].astype(float)

    def chunks():
        for s in range(0, t.size, 997):
            yield t[s : s + 997], c[s : s + 997]

    kw = {"set_amplitude_deg": 0.5, "set_frequency_hz": 2.0, "drift": drift}
    whole = calibrate_count_motion(t, c, counts_per_rev=144_000, **kw).to_dict()
    streamed = calibrate_angle_motion_chunked(chunks, counts_per_rev=144_000, **kw).to_dict()
    assert whole.keys() == streamed.keys()
    for key, value in whole.items():
        if isinstance(value, float) or key in ("reversal_times_s", "harmonic_amplitudes_deg"):
            np.testing.assert_allclose(streamed[key], value, rtol=1e-9, atol=1e-13, err_msg=key)
        elif key != "uncertainty_budgets":
            assert streamed[key] == value, key
