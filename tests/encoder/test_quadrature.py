"""Tests of rotacal.encoder.quadrature against closed-form truth of synthetic captures."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from rotacal.encoder import (
    PhaseState,
    QuadratureCorrection,
    angle_deg,
    correct_quadrature,
    demodulate,
    find_reversals,
    fit_quadrature_correction,
    intercept_periods,
    reversing_subintervals,
    rotation_direction,
    subintervals,
    unwrapped_phase,
)
from rotacal.errors import CaptureError, ConfigError

LINES = 36000
HARMONICS = ((0.03, 2, 0.4), (0.01, 3, 1.1))  # (relative amplitude, order, phase rad)


# ---------------------------------------------------------------------------------------------
# local generator: truth from closed forms
# ---------------------------------------------------------------------------------------------


def motion_deg(t, amp, freq, harmonics=HARMONICS):
    theta = amp * np.sin(2 * np.pi * freq * t)
    for g, h, ph in harmonics:
        theta = theta + g * amp * np.sin(2 * np.pi * h * freq * t + ph)
    return theta


def motion_rate(t, amp, freq, harmonics=HARMONICS):
    w = 2 * np.pi * freq
    rate = amp * w * np.cos(w * t)
    for g, h, ph in harmonics:
        rate = rate + g * amp * h * w * np.cos(h * w * t + ph)
    return rate


def true_reversals(t_end, amp, freq, harmonics=HARMONICS, t_start=0.0):
    """Zeros of the analytic rate, located with brentq (times s, kinds +1 max / -1 min)."""
    grid = np.linspace(t_start, t_end, int((t_end - t_start) * freq * 400) + 2)
    r = motion_rate(grid, amp, freq, harmonics)
    times, kinds = [], []
    for i in np.flatnonzero(np.sign(r[:-1]) * np.sign(r[1:]) < 0):
        z = brentq(lambda x: motion_rate(x, amp, freq, harmonics), grid[i], grid[i + 1])
        times.append(z)
        kinds.append(1 if r[i] > 0 else -1)
    return np.array(times), np.array(kinds)


def quadrature(theta_deg, *, p=0.0, q=0.0, r=1.0, alpha=0.0, noise=0.0, rng=None, lines=LINES):
    phi = 2 * np.pi * lines * theta_deg / 360.0
    a = p + np.cos(phi)
    b = q + r * np.sin(phi + alpha)
    if noise:
        rng = rng or np.random.default_rng(0)
        a = a + noise * rng.standard_normal(a.size)
        b = b + noise * rng.standard_normal(b.size)
    return a, b


def wrap(x):
    return (x + np.pi) % (2 * np.pi) - np.pi


# ---------------------------------------------------------------------------------------------
# Heydemann correction
# ---------------------------------------------------------------------------------------------

P, Q, R, ALPHA = 0.01, -0.012, 1.02, math.radians(1.0)


def test_heydemann_recovers_ellipse_on_full_circle():
    phi = np.linspace(0, 40 * np.pi, 200_001)
    a = P + 1.3 * np.cos(phi)  # amplitude_a 1.3 as well, to check the scaling back
    b = Q + 1.3 * R * np.sin(phi + ALPHA)
    c = fit_quadrature_correction(a, b)
    assert c.method == "heydemann"
    assert c.coverage_rad == pytest.approx(2 * np.pi)
    assert c.offset_a == pytest.approx(P, abs=1e-10)
    assert c.offset_b == pytest.approx(Q, abs=1e-10)
    assert c.amplitude_a == pytest.approx(1.3, rel=1e-10)
    assert c.amplitude_ratio == pytest.approx(R, rel=1e-10)
    assert c.phase_error_rad == pytest.approx(ALPHA, abs=1e-10)
    u, v = correct_quadrature(a, b, c)
    assert np.max(np.abs(wrap(np.arctan2(v, u) - phi))) < 1e-4
    # without the correction the same data are off by far more than that
    assert np.max(np.abs(wrap(np.arctan2(b, a) - phi))) > 1e-2


def test_heydemann_with_noise_quantisation_and_striding():
    rng = np.random.default_rng(1)
    phi = rng.uniform(0, 2 * np.pi, 400_000)
    a = P + np.cos(phi) + 0.003 * rng.standard_normal(phi.size)
    b = Q + R * np.sin(phi + ALPHA) + 0.003 * rng.standard_normal(phi.size)
    lsb = 2.0 / 2**12  # 12-bit ADC over ±1
    a, b = np.round(a / lsb) * lsb, np.round(b / lsb) * lsb
    c = fit_quadrature_correction(a, b, max_points=100_000)
    assert c.points_used <= 100_000
    assert c.offset_a == pytest.approx(P, abs=5e-4)
    assert c.offset_b == pytest.approx(Q, abs=5e-4)
    assert c.amplitude_ratio == pytest.approx(R, rel=1e-3)
    assert c.phase_error_rad == pytest.approx(ALPHA, abs=1e-3)


def test_partial_arc_falls_back_to_offsets_only():
    # motion covering a quarter of a signal period (back and forth)
    phi = 0.3 + (np.pi / 4) * (1 + np.sin(np.linspace(0, 6 * np.pi, 50_000)))
    a = 0.05 + np.cos(phi)
    b = -0.03 + R * np.sin(phi + ALPHA)
    c = fit_quadrature_correction(a, b)
    assert "partial" in c.method
    assert c.coverage_rad == pytest.approx(np.pi / 2, abs=0.1)
    assert c.phase_error_rad == 0.0
    assert c.amplitude_a == c.amplitude_b
    assert c.amplitude_a == pytest.approx(1.0, abs=0.1)
    assert c.offset_a == pytest.approx(0.05, abs=0.05)
    assert c.offset_b == pytest.approx(-0.03, abs=0.05)
    u, v = correct_quadrature(a, b, c)
    assert np.max(np.abs(wrap(np.arctan2(v, u) - phi))) < 0.05


def test_too_short_arc_is_refused():
    phi = 0.3 + 0.1 * np.sin(np.linspace(0, 6 * np.pi, 5_000))
    with pytest.raises(CaptureError, match="1/8 of a signal period"):
        fit_quadrature_correction(np.cos(phi), np.sin(phi))


# ---------------------------------------------------------------------------------------------
# phase, angle, subintervals
# ---------------------------------------------------------------------------------------------


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    cuts=st.lists(st.integers(0, 3000), min_size=0, max_size=8),
)
def test_chunked_unwrap_equals_one_piece(seed, cuts):
    rng = np.random.default_rng(seed)
    phi = np.cumsum(rng.uniform(-2.5, 2.5, 3000))  # steps below π: unwrapping is well defined
    u, v = np.cos(phi), np.sin(phi)
    whole, _ = unwrapped_phase(u, v)
    parts, state = [], None
    bounds = [0, *sorted(cuts), 3000]
    for s, e in itertools.pairwise(bounds):
        out, state = unwrapped_phase(u[s:e], v[s:e], state=state)
        parts.append(out)
    assert np.array_equal(np.concatenate(parts), whole)
    assert isinstance(state, PhaseState)
    # and the phase itself is the truth (up to the start's 2π multiple)
    np.testing.assert_allclose(whole - whole[0], phi - phi[0], atol=1e-9)
    np.testing.assert_allclose(whole, np.unwrap(np.arctan2(v, u)), atol=1e-12)


def test_angle_labels_and_direction():
    phi = np.array([0.1, 0.6, 1.1, 3.2, 6.4, 6.0, -0.1])
    np.testing.assert_allclose(angle_deg(phi, 36000), phi * 360 / (2 * np.pi * 36000))
    expected = [math.floor(x / (np.pi / 6)) % 12 + 1 for x in phi]
    assert subintervals(phi).tolist() == expected
    idx, d = rotation_direction(phi)
    assert idx.tolist() == [1, 2, 3, 4, 5, 6]
    assert d.tolist() == [1, 1, 1, 1, -1, -1]
    with pytest.raises(ConfigError):
        angle_deg(phi, 0)


# ---------------------------------------------------------------------------------------------
# reversals: the paper's examples
# ---------------------------------------------------------------------------------------------


def labels_to_signals(labels, per_visit=5):
    """Samples at the centre of each labelled subinterval (labels never wrap here: k = label-1)."""
    k = np.repeat(np.asarray(labels, dtype=float) - 1, per_visit)
    phi = (k + 0.5) * (np.pi / 6)
    t = np.arange(phi.size) * 1e-3
    return t, np.cos(phi), np.sin(phi), phi


def test_paper_eq5_has_no_reversal():
    t, u, v, phi = labels_to_signals([2, 3, 4, 5, 4, 5, 6, 7, 8])
    sub_minus, _, _ = reversing_subintervals(phi)
    assert sub_minus.size == 0
    assert len(find_reversals(t, u, v, phi, hysteresis_subintervals=1)) == 0


def test_paper_eq6_has_one_reversal_in_the_second_7():
    labels = [4, 5, 6, 7, 8, 7, 8, 7, 6, 5]
    t, u, v, phi = labels_to_signals(labels, per_visit=5)
    sub_minus, sub_plus, kinds = reversing_subintervals(phi)
    assert sub_minus.tolist() == [5 * 5] and sub_plus.tolist() == [5 * 6 - 1]  # second 7
    assert kinds.tolist() == [1]
    rev = find_reversals(t, u, v, phi, hysteresis_subintervals=1)
    assert len(rev) == 1 and rev.kinds.tolist() == [1] and rev.candidates == 1
    # the precise point lies in the turn 8-7-8 at the largest phase there
    assert 20 <= rev.indices[0] < 35
    assert phi[rev.indices[0]] == phi[20:35].max()


# ---------------------------------------------------------------------------------------------
# reversals on synthetic motions
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("amp", "freq", "duration"), [(0.1, 5.0, 1.0), (5.0, 0.5, 4.5)])
def test_reversal_times_clean(amp, freq, duration):
    fs = 50_000.0
    t = np.arange(0, duration, 1 / fs)
    theta = motion_deg(t, amp, freq)
    a, b = quadrature(theta, p=P, q=Q, r=R, alpha=ALPHA)
    d = demodulate(t, a, b, LINES)
    truth, kinds = true_reversals(t[-1], amp, freq)
    assert len(d.reversals) == truth.size
    assert d.reversals.kinds.tolist() == kinds.tolist()
    assert np.max(np.abs(d.reversals.times_s - truth)) < 2e-3
    # the angle itself: θ up to a constant
    err = d.angle_deg - theta
    assert np.ptp(err) < 1e-8
    assert d.correction.method == "heydemann"


@pytest.mark.parametrize("noise", [0.003, 0.02])
def test_reversal_count_with_noise(noise):
    fs = 50_000.0
    t = np.arange(0, 1.5, 1 / fs)
    theta = motion_deg(t, 0.1, 5.0)
    a, b = quadrature(theta, p=P, q=Q, r=R, alpha=ALPHA, noise=noise)
    d = demodulate(t, a, b, LINES)
    truth, kinds = true_reversals(t[-1], 0.1, 5.0)
    assert len(d.reversals) == truth.size
    assert d.reversals.kinds.tolist() == kinds.tolist()
    assert np.max(np.abs(d.reversals.times_s - truth)) < 3e-3


VIBRATIONS = [(0.0005, 40.0), (0.0005, 80.0), (0.001, 40.0), (0.001, 60.0), (0.002, 80.0)]


@pytest.mark.parametrize(("vib_amp", "vib_freq"), VIBRATIONS)
def test_vibration_near_reversals_gives_no_spurious_reversal(vib_amp, vib_freq):
    fs = 50_000.0
    t = np.arange(0, 1.5, 1 / fs)
    rng = np.random.default_rng(7)
    truth, kinds = true_reversals(t[-1], 0.1, 5.0)
    for phase in (0.0, 2.0, 4.0):
        theta = motion_deg(t, 0.1, 5.0) + vib_amp * np.sin(2 * np.pi * vib_freq * t + phase)
        a, b = quadrature(theta, noise=0.005, rng=rng)
        d = demodulate(t, a, b, LINES)
        assert len(d.reversals) == truth.size
        assert d.reversals.kinds.tolist() == kinds.tolist()
        # Where the vibration's rate A·ω can exceed the base motion's curvature over a quarter
        # vibration period (A·ω² > κ·π/2), even the true extreme of the total motion may lie
        # farther than a quarter period from the base reversal: only the count is checked there.
        kappa = 0.1 * (2 * np.pi * 5.0) ** 2
        if vib_amp * (2 * np.pi * vib_freq) ** 2 < kappa * np.pi / 2:
            assert np.max(np.abs(d.reversals.times_s - truth)) < 0.25 / vib_freq


def test_paper_rule_alone_sees_vibration_pairs_that_the_clusters_prune():
    fs = 50_000.0
    t = np.arange(0, 1.0, 1 / fs)
    theta = motion_deg(t, 0.1, 5.0) + 0.003 * np.sin(2 * np.pi * 60.0 * t)
    a, b = quadrature(theta)
    truth, _ = true_reversals(t[-1], 0.1, 5.0)
    d = demodulate(t, a, b, LINES)
    assert len(d.reversals) == truth.size
    assert d.reversals.candidates > truth.size
    raw = demodulate(t, a, b, LINES, hysteresis_subintervals=1)
    assert len(raw.reversals) > truth.size


# ---------------------------------------------------------------------------------------------
# interception of n periods
# ---------------------------------------------------------------------------------------------


def test_intercept_periods_spans_2n_plus_1_reversals():
    fs = 20_000.0
    t = np.arange(0, 1.33, 1 / fs)
    a, b = quadrature(motion_deg(t, 0.1, 5.0))
    d = demodulate(t, a, b, LINES)
    idx = d.reversals.indices
    first, last, n = intercept_periods(d.reversals)
    assert n == (idx.size - 1) // 2
    assert np.count_nonzero((idx >= first) & (idx <= last)) == 2 * n + 1
    first2, last2, n2 = intercept_periods(d.reversals, 2)
    assert n2 == 2 and np.count_nonzero((idx >= first2) & (idx <= last2)) == 5
    ts, th, n3 = d.segment(2)
    assert n3 == 2 and ts.size == last2 - first2 + 1 == th.size
    # 2 periods of 5 Hz
    assert t[last2] - t[first2] == pytest.approx(0.4, abs=2e-3)
    with pytest.raises(CaptureError, match="periods"):
        intercept_periods(d.reversals, n + 1)
    with pytest.raises(ConfigError):
        intercept_periods(d.reversals, 0)


def test_too_few_reversals_is_a_capture_error():
    t = np.arange(0, 0.12, 1 / 20_000.0)  # one reversal only
    a, b = quadrature(motion_deg(t, 0.1, 5.0))
    d = demodulate(t, a, b, LINES)
    assert len(d.reversals) == 1
    with pytest.raises(CaptureError, match="reversing moments"):
        intercept_periods(d.reversals)


# ---------------------------------------------------------------------------------------------
# errors and results
# ---------------------------------------------------------------------------------------------


def _circle(n=20_000, cycles=10):
    return np.linspace(0, 2 * np.pi * cycles, n)


@pytest.mark.parametrize("alpha_deg", [88.0, -89.0, 60.0])
def test_not_quadrature_is_refused(alpha_deg):
    phi = _circle()
    rng = np.random.default_rng(3)
    a = np.cos(phi) + 0.001 * rng.standard_normal(phi.size)
    b = np.sin(phi + math.radians(alpha_deg)) + 0.001 * rng.standard_normal(phi.size)
    with pytest.raises(CaptureError, match="quadrature"):
        fit_quadrature_correction(a, b)


def test_a_equal_b_is_refused():
    phi = _circle()
    rng = np.random.default_rng(4)
    a = np.cos(phi) + 0.01 * rng.standard_normal(phi.size)
    b = np.cos(phi) + 0.01 * rng.standard_normal(phi.size)
    with pytest.raises(CaptureError, match="quadrature"):
        fit_quadrature_correction(a, b)
    with pytest.raises(CaptureError, match="quadrature"):
        fit_quadrature_correction(np.cos(phi), np.cos(phi))


def test_clipped_signal_is_refused_naming_the_column():
    phi = _circle()
    a = np.cos(phi)
    b = np.clip(1.1 * np.sin(phi), -1.0, 1.0)
    with pytest.raises(CaptureError, match="'b' is clipped"):
        fit_quadrature_correction(a, b)
    t = np.arange(phi.size) / 1e4
    with pytest.raises(CaptureError, match="'a' is clipped"):
        demodulate(t, np.clip(1.1 * a, -1, 1.05), np.sin(phi), 1000)


def test_nan_and_length_mismatch_are_refused():
    phi = _circle()
    a, b = np.cos(phi), np.sin(phi)
    b_nan = b.copy()
    b_nan[123] = np.nan
    with pytest.raises(CaptureError, match="'b' has 1 non-finite"):
        fit_quadrature_correction(a, b_nan)
    with pytest.raises(CaptureError, match="differ in length"):
        fit_quadrature_correction(a, b[:-1])
    t = np.arange(phi.size) / 1e4
    with pytest.raises(CaptureError, match="time_s"):
        demodulate(t[::-1], a, b, 1000)
    with pytest.raises(ConfigError, match="lines"):
        demodulate(t, a, b, 0)
    with pytest.raises(ConfigError, match="hysteresis"):
        find_reversals(t, a, b, phi, hysteresis_subintervals=0)


def test_result_json_and_given_correction():
    fs = 20_000.0
    t = np.arange(0, 0.5, 1 / fs)
    a, b = quadrature(motion_deg(t, 0.1, 5.0), p=P, q=Q, r=R, alpha=ALPHA)
    given_c = QuadratureCorrection(P, Q, 1.0, R, ALPHA, "given", 2 * np.pi)
    d = demodulate(t, a, b, LINES, correction=given_c)
    assert d.correction is given_c
    out = d.to_dict()
    json.dumps(out)
    assert "_angle_deg" not in out and "_time_s" not in out
    assert out["reversals"]["times_s"] == pytest.approx(d.reversals.times_s.tolist())
    assert d.sample_rate_hz == pytest.approx(fs)
