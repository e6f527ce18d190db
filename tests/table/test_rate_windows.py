"""Rate accuracy and stability over angle windows against the twin's closed-form angle.

The truth of every window is computed from the twin's own motion: its angle θ(t) in closed form
(:func:`rotacal.sim.pulses.table_angle_deg`, the integral of the true rate) at the window's end
times, never from the pulse count or the deviation the method uses.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.sim.pulses import simulate_pulses, table_angle_deg
from rotacal.table.rate_windows import (
    WindowSums,
    rate_windows,
    rate_windows_stream,
    window_pitches,
    window_rates,
)

M = 3600
RATE = 300.0
WINDOWS = (1.0, 10.0, 360.0)


def _twin(jitter_s: float, rate: float = RATE, revolutions: float = 12.0, seed: int = 3):
    """One head on a table with a once-per-revolution and a 10-per-revolution rate ripple and a
    slow wander (0.05 % rms in all), a scale with an eccentricity and a strong 50th order."""
    return simulate_pulses(
        heads=2,
        pulses_per_rev=M,
        rate_deg_s=rate,
        revolutions=revolutions,
        harmonics=((1, 3.0, 0.3), (50, 2.0, 0.7)),
        graduation_noise_arcsec=0.0,
        rate_fluctuation_percent=0.05,
        fluctuation_hz=[rate / 360.0, 10.0 * rate / 360.0, rate / 3000.0],
        jitter_s=jitter_s,
        seed=seed,
    )


def _truth_rates(cap, window_deg: float) -> np.ndarray:
    """The true mean rate over each window's time span: Δθ/Δt of the closed-form angle."""
    t = np.asarray(cap.columns["head_0"])
    k = round(window_deg * M / 360.0)
    edges = t[::k][: (t.size - 1) // k + 1]
    return np.diff(table_angle_deg(cap.truth, edges)) / np.diff(edges)


@pytest.fixture(scope="module")
def noisy():
    """The twin with 0.2 µs timing jitter (σ_w ≈ 0.009 % of rate over 1°)."""
    cap = _twin(2e-7)
    return cap, np.asarray(cap.columns["head_0"]), np.asarray(cap.truth["deviation_arcsec"])


def test_each_window_rate_is_the_true_mean_rate_without_noise():
    cap = _twin(0.0)
    t, dev = np.asarray(cap.columns["head_0"]), np.asarray(cap.truth["deviation_arcsec"])
    for w in WINDOWS:
        truth = _truth_rates(cap, w)
        _, comp = window_rates(t, pulses_per_rev=M, window_deg=w, deviation_arcsec=dev)
        _, nominal = window_rates(t, pulses_per_rev=M, window_deg=w)
        assert comp.size == truth.size == (t.size - 1) // round(w * M / 360)
        np.testing.assert_allclose(comp, truth, rtol=1e-10)
        if w == 360.0:  # whole revolutions: the graduation cancels without compensation
            np.testing.assert_allclose(nominal, truth, rtol=1e-12)
        else:  # the 50th order moves the 1° and 10° windows: the check can see it
            assert np.max(np.abs(nominal / truth - 1)) > 1e-4


def test_accuracy_stability_and_peak_against_the_closed_form(noisy):
    cap, t, dev = noisy
    comp = rate_windows(
        t, pulses_per_rev=M, windows_deg=WINDOWS, deviation_arcsec=dev, set_rate_deg_s=RATE
    )
    nominal = rate_windows(t, pulses_per_rev=M, windows_deg=WINDOWS, set_rate_deg_s=RATE)
    for w in WINDOWS:
        key = f"{w:g}"
        truth = _truth_rates(cap, w)
        mean = truth.mean()
        s_true = 100 * truth.std(ddof=1) / mean
        peak_true = 100 * np.max(np.abs(truth - mean)) / mean
        acc_true = 100 * (mean - RATE) / RATE
        assert (
            abs(comp.rate_stability_percent[key] - s_true) <= 2 * comp.rate_stability_percent_u[key]
        )
        assert (
            abs(comp.rate_stability_peak_percent[key] - peak_true)
            <= 2 * comp.rate_stability_peak_percent_u[key]
        )
        assert (
            abs(comp.rate_accuracy_percent[key] - acc_true) <= 2 * comp.rate_accuracy_percent_u[key]
        )
        if w == 360.0:
            assert nominal.rate_stability_percent[key] == pytest.approx(
                comp.rate_stability_percent[key], rel=1e-12
            )
        elif w == 1.0:  # uncompensated, the scale's 50th order is read as rate: far outside u
            off = abs(nominal.rate_stability_percent[key] - s_true)
            assert off > 5 * nominal.rate_stability_percent_u[key]
    # the stated noise of one window rate is the spread of (measured − true) over the windows
    for w in (1.0, 10.0):
        _, r = window_rates(t, pulses_per_rev=M, window_deg=w, deviation_arcsec=dev)
        spread = 100 * np.std(r / _truth_rates(cap, w) - 1)
        assert spread == pytest.approx(comp.window_noise_percent[f"{w:g}"], rel=0.1)
    # the ripple's window average in closed form: a 1° window keeps almost all of it, and a
    # 10° window divides the 10-per-revolution part by sinc(π·10·10/360)
    assert comp.rate_stability_percent["1"] > comp.rate_stability_percent["10"]
    assert all(
        comp.window_count[k] == (t.size - 1) // comp.window_pulses[k] for k in comp.window_count
    )


def test_streamed_equals_in_memory_to_1e9(noisy):
    _, t, dev = noisy
    kw = dict(pulses_per_rev=M, windows_deg=WINDOWS, deviation_arcsec=dev, set_rate_deg_s=RATE)
    whole = rate_windows(t, **kw).to_dict()
    for size in (97, 3599, 3601, 40_000):
        parts = [t[i : i + size] for i in range(0, t.size, size)]
        streamed = rate_windows_stream(parts, pulses=t.size, check=False, **kw).to_dict()
        for name, per_window in whole.items():
            if isinstance(per_window, dict):
                for key, value in per_window.items():
                    assert streamed[name][key] == pytest.approx(value, rel=1e-9, abs=0), (name, key)
    # and the sums against a plain computation over the whole array of window rates
    for w in WINDOWS:
        _, r = window_rates(t, pulses_per_rev=M, window_deg=w, deviation_arcsec=dev)
        key = f"{w:g}"
        assert whole["rate_stability_percent"][key] == pytest.approx(
            100 * r.std(ddof=1) / r.mean(), rel=1e-9
        )
        assert whole["window_mean_rate_deg_s"][key] == pytest.approx(r.mean(), rel=1e-12)


def test_trace_keeps_the_least_and_largest_of_each_block(noisy):
    _, t, _ = noisy
    ws = WindowSums(1.0, M, trace_points=100)
    for i in range(0, t.size, 1000):
        ws.update(t[i : i + 1000])
    _, r = window_rates(t, pulses_per_rev=M, window_deg=1.0)
    b = ws.trace.block
    assert ws.trace.index.size <= 100 and b == 64  # 4319 windows in blocks of 2^j
    blocks = [r[i : i + b] for i in range(0, r.size, b)]
    np.testing.assert_array_equal(ws.trace.lo, [x.min() for x in blocks])
    np.testing.assert_array_equal(ws.trace.hi, [x.max() for x in blocks])


@pytest.mark.parametrize("rate", [0.001, 1000.0])
def test_slow_and_fast_tables(rate):
    """0.001 °/s (a 360° window lasts 100 h) and 1000 °/s: every window rate is the true one."""
    cap = _twin(0.0, rate=rate, revolutions=2.2, seed=5)
    t = np.asarray(cap.columns["head_0"])
    dev = np.asarray(cap.truth["deviation_arcsec"])
    res = rate_windows(
        t, pulses_per_rev=M, windows_deg=WINDOWS, deviation_arcsec=dev, set_rate_deg_s=rate
    )
    for w in WINDOWS:
        truth = _truth_rates(cap, w)
        _, comp = window_rates(t, pulses_per_rev=M, window_deg=w, deviation_arcsec=dev)
        np.testing.assert_allclose(comp, truth, rtol=1e-9)
        key = f"{w:g}"
        s_true = 100 * truth.std(ddof=1) / truth.mean()
        assert res.rate_stability_percent[key] == pytest.approx(s_true, rel=1e-6, abs=1e-9)
    assert not res.warnings
    # the same record stamped from a clock started 30 years ago: float64 cannot resolve a
    # 1° window at 1000 °/s (1 ms) finely there, and the result says so
    if rate == 1000.0:
        late = rate_windows(t + 1e9, pulses_per_rev=M, windows_deg=[1.0], set_rate_deg_s=rate)
        assert any("resolved to" in w and "1° window" in w for w in late.warnings)


def test_refusals_name_the_window(noisy):
    _, t, _ = noisy
    with pytest.raises(ConfigError, match=r"--window-deg 0.1: .* fewer than 2"):
        window_pitches(0.1, M)
    with pytest.raises(ConfigError, match="positive"):
        window_pitches(-1, M)
    with pytest.raises(CaptureError, match=r"--window-deg 7200: .* 0 whole window"):
        rate_windows(t, pulses_per_rev=M, windows_deg=[1, 7200])
    with pytest.raises(CaptureError, match=r"--window-deg 2880: .* 1 whole window"):
        rate_windows(t, pulses_per_rev=M, windows_deg=[2880])
    with pytest.raises(ConfigError, match="twice"):
        rate_windows(t, pulses_per_rev=M, windows_deg=[10, 10.0])
    assert math.isclose(window_pitches(360, M), M)
    bad = t.copy()
    bad[5000] = np.nan
    with pytest.raises(CaptureError, match="NaN or inf at pulse 5000"):
        rate_windows_stream(
            [bad[:4999], bad[4999:]], pulses_per_rev=M, windows_deg=[1], pulses=t.size
        )
    bad[5000] = bad[4998]
    with pytest.raises(CaptureError, match="not strictly increasing at pulse 5000"):
        rate_windows(bad, pulses_per_rev=M, windows_deg=[1])


def test_specifications_enter_the_budget(noisy):
    """A stated timebase error widens the accuracy by its u (rectangular: a/√3); a stated
    graduation error widens the uncompensated window noise by √2·u/(3600·W), not over 360°."""
    from rotacal.uncertainty import load_specs

    _, t, _ = noisy
    specs = load_specs(
        '[timebase]\nrelative_error = { distribution = "rectangular", half_width = 2e-6 }\n'
        '[encoder]\ngraduation_error_arcsec = { distribution = "normal", u = 0.5 }\n'
    )
    kw = dict(pulses_per_rev=M, windows_deg=WINDOWS, set_rate_deg_s=RATE, timing_jitter_s=2e-7)
    plain = rate_windows(t, **kw)
    stated = rate_windows(t, specs=specs, **kw)
    for w in WINDOWS:
        key = f"{w:g}"
        scale = stated.window_mean_rate_deg_s[key] / RATE
        tb = 100 * 2e-6 / math.sqrt(3) * scale
        line = 0.0 if w == 360 else 100 * math.sqrt(2) * 0.5 / 3600 / w
        ends = line / stated.window_count[key] * scale  # the mean's two far ends
        assert stated.rate_accuracy_percent_u[key] ** 2 == pytest.approx(
            plain.rate_accuracy_percent_u[key] ** 2 + tb**2 + ends**2, rel=1e-9
        )
        assert stated.window_noise_percent[key] ** 2 == pytest.approx(
            plain.window_noise_percent[key] ** 2 + line**2, rel=1e-9
        )
    assert not any("graduation_error_arcsec stated" in n for n in stated.notes)
    assert any("graduation_error_arcsec stated" in n for n in plain.notes)
