"""The encoder's direction convention and the reversal rule's hysteresis, as the docstrings state.

Direction (INTERFACE.md): θ increases when ``a = cos φ`` leads ``b = sin φ`` by a quarter signal
period. The lead is read here from the times of the signals' own peaks on the twin, without
arctan2, and the demodulated angle must then rise with the twin's true angle.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal.encoder import (
    demodulate,
    find_reversals,
    plan_reversals,
    reversing_subintervals,
    unwrapped_phase,
)
from rotacal.encoder.quadrature import _transitions
from rotacal.sim import SineMotion, simulate_encoder
from rotacal.table.motion_drift import drift_free_hysteresis

LINES = 36000


def peak_times(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Times of the local maxima of x above 0.9 (parabola through each peak's three samples)."""
    i = np.flatnonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:]) & (x[1:-1] > 0.9)) + 1
    y0, y1, y2 = x[i - 1], x[i], x[i + 1]
    return t[i] + 0.5 * (y0 - y2) / (y0 - 2 * y1 + y2) * (t[1] - t[0])


def lag_of_b_behind_a(t: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """For each peak of a, the time to the next peak of b, in units of the local signal period."""
    pa, pb = peak_times(t, a), peak_times(t, b)
    period = np.diff(pa)
    nxt = np.searchsorted(pb, pa[:-1])
    ok = nxt < pb.size
    return (pb[nxt[ok]] - pa[:-1][ok]) / period[ok]


@pytest.mark.parametrize("rising", [True, False])
def test_theta_increases_when_a_leads_b_on_the_twin(rising: bool) -> None:
    m = SineMotion(0.1, 5.0, harmonics={3: (0.02, 0.4)})
    cap = simulate_encoder(m, lines=LINES, fs_hz=400_000.0, duration_s=0.2)
    t, a, b = cap.columns["time_s"], cap.columns["a"], cap.columns["b"]
    # a stretch around the fastest motion: rising near t = 0, falling near half a period
    centre = 0.0 if rising else 0.1
    s = np.abs(t - centre) < 0.03
    truth_rate = m.rate_deg_s(t[s])
    assert np.all(truth_rate > 0) if rising else np.all(truth_rate < 0)
    lag = lag_of_b_behind_a(t[s], a[s], b[s])
    assert lag.size > 5
    if rising:  # b peaks a quarter period after a: a leads b
        np.testing.assert_allclose(lag, 0.25, atol=0.05)
    else:  # b peaks three quarters after a, i.e. a quarter before it: b leads a
        np.testing.assert_allclose(lag, 0.75, atol=0.05)
    d = demodulate(t, a, b, LINES)
    rise = np.diff(d.angle_deg[s])
    assert np.all(rise > 0) if rising else np.all(rise < 0)
    np.testing.assert_allclose(
        d.angle_deg - d.angle_deg[0], m.angle_deg(t) - m.angle_deg(t[0]), atol=1e-9
    )


def test_hand_made_quadrature_sets_the_sign() -> None:
    t = np.arange(2000) * 1e-4
    w = 2 * math.pi * 50.0
    up = demodulate(t, np.cos(w * t), np.sin(w * t), LINES)  # a leads b
    down = demodulate(t, np.sin(w * t), np.cos(w * t), LINES)  # b leads a
    assert np.all(np.diff(up.angle_deg) > 0)
    assert np.all(np.diff(down.angle_deg) < 0)


def _random_walk_capture(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A slow motion with a vibration faster than it and noise (many trend changes)."""
    rng = np.random.default_rng(seed)
    t = np.arange(20_000) * 1e-4
    theta = 0.02 * np.sin(2 * math.pi * 2.5 * t) + 0.0015 * np.sin(2 * math.pi * 60 * t + seed)
    phi = 2 * math.pi * LINES * theta / 360 + rng.normal(0, 0.05, t.size)
    u, v = np.cos(phi), np.sin(phi)
    phase, _ = unwrapped_phase(u, v)
    return t, u, v, phase


@pytest.mark.parametrize("seed", range(6))
def test_hysteresis_one_or_two_is_the_paper_odd_even_rule(seed: int) -> None:
    t, u, v, phase = _random_walk_capture(seed)
    one = find_reversals(t, u, v, phase, hysteresis_subintervals=1)
    two = find_reversals(t, u, v, phase, hysteresis_subintervals=2)
    three = find_reversals(t, u, v, phase, hysteresis_subintervals=3)
    sub_minus, sub_plus, kinds = reversing_subintervals(phase)  # the paper's middle visits
    # no candidate is pruned: every odd run of trend changes is a reversal, as in eqs. (5)-(6)
    assert np.array_equal(one.indices, two.indices)
    assert len(one) == one.candidates == sub_minus.size
    assert np.array_equal(one.kinds, kinds)
    assert len(three) < len(one)  # a wider hysteresis does prune (vibration pairs) ...
    default = find_reversals(t, u, v, phase)  # ... and 10 % of the span leaves the motion's
    assert default.hysteresis_subintervals == round(0.1 * np.ptp(np.floor(phase * 6 / math.pi)))
    assert len(default) in (10, 11) and len(default) < len(three)
    # ... but the reversing point is searched in the visits at the run's extreme level (one
    # sample wider each side), not in the paper's middle visit: where a run of three or more
    # changes dips between two visits of the extreme level, it lies outside the paper's visit
    idx, ka, _, k0 = _transitions(phase)
    plan = plan_reversals(idx, ka, k0, hysteresis_subintervals=1)
    k = np.floor(phase * 6 / math.pi)
    outside = 0
    for rev, (first, last), lo, hi, kind in zip(
        one.indices, plan.windows.tolist(), sub_minus, sub_plus, kinds, strict=True
    ):
        assert first - 1 <= rev <= last + 1
        extreme = k[first : last + 1].max() if kind > 0 else k[first : last + 1].min()
        assert k[first] == extreme and k[last] == extreme
        outside += not lo <= rev <= hi
    assert outside > 0


def test_drift_free_hysteresis_keeps_the_reversals_of_a_drifting_table() -> None:
    """The drift spans 2° while the table swings 0.2°: the default hysteresis, 10 % of the span
    (0.22°), swallows the swings; with --drift it is 10 % of the span without the drift."""
    m = SineMotion(0.1, 5.0, harmonics={3: (0.03, 0.5)}, drift_deg_s=2.0 / 1.225)
    cap = simulate_encoder(m, lines=LINES, fs_hz=50_000.0, duration_s=1.225, noise_rms=0.003)
    t, a, b = cap.columns["time_s"], cap.columns["a"], cap.columns["b"]
    truth = np.asarray(cap.truth["reversal_times_s"])
    assert truth.size == 12
    assert len(demodulate(t, a, b, LINES).reversals) < truth.size
    rule = drift_free_hysteresis()
    d = demodulate(t, a, b, LINES, hysteresis_from=rule)
    assert len(d.reversals) == truth.size
    assert np.max(np.abs(d.reversals.times_s - truth)) < 2e-3
    # the rule's value: about 10 % of the stroke (the twin's peak-to-peak without the drift, in
    # subintervals; the straight line that takes the drift off leaves a part of a stroke), far
    # below 10 % of the span
    stroke = np.ptp(m.angle_no_vibration_deg(np.linspace(0, 0.2, 20001))) * LINES / 30
    assert 0.08 * stroke <= d.reversals.hysteresis_subintervals <= 0.15 * stroke
