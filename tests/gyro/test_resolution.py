"""The FMVSS 126 resolution check (seed 004 Table 1: resolution < 0.004 °/s) against the twin's truth:
the resolution is the smallest rate change the output resolves — the output quantum or the noise of
one reading at a bandwidth — and does not improve with the length of the record.

Truth used here: the twin's noise_std and quantum (output units) divided by its scale factor, the
white-noise law σ_B = σ·√(2B/fs) for a bandwidth B, and the standard errors of the raw samples
(numpy) that the old rule judged.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from rotacal.errors import ConfigError
from rotacal.gyro.scale_factor import calibrate_scale_factor
from rotacal.sim.gyro_rates import simulate_gyro_rates

S = 0.0125  # the twin's scale factor, V/(°/s)
LIMIT = 0.004  # FMVSS 126 (seed 004 Table 1), °/s


def fit(cap, **kw):
    return calibrate_scale_factor(
        cap.columns["rate_deg_s"],
        cap.columns["output"],
        requirement="fmvss126",
        output_unit="V",
        mc_trials=2000,
        **kw,
    )


def resolution_check(r):
    return next(c for c in r.requirement.checks if c.quantity == "resolution")


def largest_standard_error_deg_s(cap) -> float:
    """What the old rule judged: the largest standard error of a point mean / S (numpy here)."""
    rate, out = cap.columns["rate_deg_s"], cap.columns["output"]
    return (
        max(
            float(np.std(out[rate == v], ddof=1) / math.sqrt(np.count_nonzero(rate == v)))
            for v in np.unique(rate)
        )
        / S
    )


def rounded_std(clean: float, sigma: float, q: float) -> float:
    """Standard deviation of q·round((clean + N(0, σ²))/q), summed over the grid values."""
    k = np.arange(math.floor((clean - 8 * sigma) / q), math.ceil((clean + 8 * sigma) / q) + 1)
    p = stats.norm.cdf((k * q + q / 2 - clean) / sigma) - stats.norm.cdf(
        (k * q - q / 2 - clean) / sigma
    )
    v = k * q - clean  # centred: no cancellation of large squares
    mean = float(np.sum(v * p))
    return math.sqrt(float(np.sum((v - mean) ** 2 * p)))


@pytest.mark.parametrize("samples", [5000, 50_000])
def test_a_noisy_gyro_fails_whatever_the_record_length(samples) -> None:
    cap = simulate_gyro_rates(noise_std=6.25e-4, samples_per_point=samples, seed=3)  # 0.05 °/s
    r = fit(cap)
    check = resolution_check(r)
    assert check.passed is False and r.resolution.set_by == "noise"
    # the noise of one reading is the twin's: 0.05 °/s (the largest of 11 point estimates)
    assert r.resolution_deg_s == pytest.approx(6.25e-4 / S, rel=0.03)
    assert r.resolution.quantum_deg_s is None
    # the old rule (standard error of a point mean) would have passed it, and more so for longer
    # records; it is not what the verdict rests on
    assert largest_standard_error_deg_s(cap) < LIMIT
    assert "set by the noise" in check.line and "rms of one reading" in check.line


def test_ten_times_the_samples_gives_the_same_verdict_and_value() -> None:
    short = fit(simulate_gyro_rates(noise_std=6.25e-4, samples_per_point=2000, seed=4))
    long = fit(simulate_gyro_rates(noise_std=6.25e-4, samples_per_point=20_000, seed=4))
    assert resolution_check(short).passed is resolution_check(long).passed is False
    assert long.resolution_deg_s == pytest.approx(short.resolution_deg_s, rel=0.06)


def test_a_quiet_finely_quantised_gyro_passes() -> None:
    cap = simulate_gyro_rates(noise_std=1e-5, quantum=1e-5, seed=5)  # 0.0008 °/s each
    r = fit(cap)
    check = resolution_check(r)
    assert check.passed is True
    assert r.resolution.quantum_deg_s == pytest.approx(1e-5 / r.scale_factor, rel=1e-9)
    assert r.resolution.quantum_deg_s == pytest.approx(1e-5 / S, rel=1e-4)
    # noise after rounding to the grid: √(σ² + q²/12) ≈ 1.04·σ
    truth = math.sqrt(1e-10 + 1e-10 / 12) / S
    assert r.resolution.noise_deg_s == pytest.approx(truth, rel=0.05)
    assert r.resolution_deg_s == max(r.resolution.noise_deg_s, r.resolution.quantum_deg_s)
    assert r.resolution_deg_s < LIMIT


def test_a_coarsely_quantised_gyro_fails_on_the_quantum() -> None:
    cap = simulate_gyro_rates(noise_std=2.5e-5, quantum=1e-4, seed=6)  # 0.002 and 0.008 °/s
    r = fit(cap)
    check = resolution_check(r)
    assert check.passed is False and r.resolution.set_by == "quantum"
    assert r.resolution_deg_s == pytest.approx(1e-4 / S, rel=1e-4)
    # the noise of one reading is that of the rounded output: its exact std for Gaussian noise,
    # from the twin's clean output at each point, the largest over the points
    truth = max(rounded_std(c, 2.5e-5, 1e-4) for c in cap.truth["clean_output"]) / S
    assert r.resolution.noise_deg_s == pytest.approx(truth, rel=0.05)
    assert r.resolution.noise_deg_s < r.resolution.quantum_deg_s
    assert "set by the quantum" in check.line


def test_the_bandwidth_comes_from_the_sample_rate_or_is_stated() -> None:
    cap = simulate_gyro_rates(noise_std=6.25e-4, samples_per_point=8000, seed=7)
    plain = fit(cap)
    at_fs = fit(cap, sample_rate_hz=100.0)
    assert plain.resolution.bandwidth_hz is None
    assert "sample rate not given" in plain.resolution.basis
    assert at_fs.resolution.bandwidth_hz == 50.0 and at_fs.resolution.block_samples == 1
    assert at_fs.resolution_deg_s == plain.resolution_deg_s
    # 6 Hz at 100 Hz: means of round(100/12) = 8 samples, a noise bandwidth of 100/16 = 6.25 Hz;
    # white noise: σ·√(2B/fs) = σ/√8
    r = fit(cap, sample_rate_hz=100.0, bandwidth_hz=6.0)
    assert r.resolution.block_samples == 8 and r.resolution.bandwidth_hz == 6.25
    assert r.resolution.noise_deg_s == pytest.approx(6.25e-4 / S / math.sqrt(8), rel=0.06)
    assert "stated 6 Hz: means of 8 samples at 100 Hz" in r.resolution.basis
    d = json.loads(json.dumps(r.to_dict()))["resolution"]
    assert d["set_by"] == "noise" and d["bandwidth_hz"] == 6.25 and d["sample_rate_hz"] == 100.0
    assert d["resolution_deg_s"] == r.resolution_deg_s == d["noise_deg_s"]


def test_scale_factor_bias_and_nl_do_not_depend_on_the_resolution_options() -> None:
    cap = simulate_gyro_rates(seed=8, samples_per_point=1000)
    a, b = fit(cap), fit(cap, sample_rate_hz=100.0, bandwidth_hz=5.0)
    assert (a.scale_factor, a.bias, a.nonlinearity_percent_fs) == (
        b.scale_factor,
        b.bias,
        b.nonlinearity_percent_fs,
    )
    assert a.scale_factor_u == b.scale_factor_u and np.array_equal(a.residuals, b.residuals)


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        (
            {"bandwidth_hz": 5.0},
            r"^the bandwidth \(--bandwidth-hz\) 5 Hz needs .* --sample-rate-hz",
        ),
        (
            {"sample_rate_hz": 100.0, "bandwidth_hz": 60.0},
            r"^the bandwidth \(--bandwidth-hz\) 60 Hz is above .* fs/2 = 50 Hz",
        ),
        (
            {"sample_rate_hz": 100.0, "bandwidth_hz": 0.001},
            r"averages blocks of 50000 samples, but no rate point holds two of them",
        ),
        (
            {"sample_rate_hz": -1.0},
            r"^the sample rate \(--sample-rate-hz\) must be a finite number",
        ),
        ({"sample_rate_hz": 100.0, "bandwidth_hz": math.nan}, r"bandwidth .* finite number > 0"),
    ],
)
def test_bad_bandwidth_settings_are_one_line(kw, message) -> None:
    cap = simulate_gyro_rates(seed=9, samples_per_point=200)
    with pytest.raises(ConfigError, match=message) as info:
        fit(cap, **kw)
    assert "\n" not in str(info.value)


def test_nothing_visible_is_not_assessed() -> None:
    # noise-free and unquantised: every point constant, no grid, no noise (5 samples a point: the
    # rail check takes ≥ 10 identical samples for a flat rail)
    cap = simulate_gyro_rates(noise_std=0.0, seed=10, samples_per_point=5)
    r = fit(cap)
    assert r.resolution_deg_s is None and r.resolution.set_by is None
    assert resolution_check(r).passed is None
