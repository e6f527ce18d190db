"""The fused encoder pass (NumPy and Numba twins) against the separate steps and the twin's truth."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from rotacal import _jit, sim
from rotacal.encoder import (
    QuadratureCorrection,
    correct_quadrature,
    demodulate,
    fit_quadrature_correction,
    subinterval_transitions,
    unwrapped_phase,
)
from rotacal.encoder._kernel import BLOCK, phase_pass

LINES = 36000


@pytest.fixture(scope="module")
def twin():
    motion = sim.SineMotion(amplitude_deg=0.05, frequency_hz=5.0, harmonics={2: (0.02, 0.3)})
    cap = sim.simulate_encoder(
        motion,
        fs_hz=100_000.0,
        duration_s=1.225,
        offset_a=0.03,
        offset_b=-0.02,
        amplitude_b=0.97,
        phase_error_rad=0.02,
        noise_rms=0.004,
        seed=3,
    )
    t, a, b = (cap.columns[k] for k in ("time_s", "a", "b"))
    return motion, t, a, b


def _steps(a, b, corr):
    """The separate steps on the whole capture: the reference of the fused pass."""
    u, v = correct_quadrature(a, b, corr)
    phase, state = unwrapped_phase(u, v)
    idx, k_after, k_first, k_last = subinterval_transitions(phase)
    return phase, state, idx, k_after, k_first, k_last


@pytest.mark.parametrize("jit", [False, True])
def test_phase_pass_equals_the_separate_steps(twin, jit):
    assert _jit.use_numba(1, jit) == jit  # Numba is a dependency: the twin under test runs
    _, _, a, b = twin
    corr = fit_quadrature_correction(a, b)
    phase, state, idx, k_after, k_first, k_last = _steps(a, b, corr)
    assert a.size > 3 * BLOCK  # several blocks, a partial last one
    run = phase_pass(a, b, corr, jit=jit)
    # both twins take NumPy's arctan2 and the same operations after it: bit for bit
    np.testing.assert_array_equal(run.phase_rad, phase)
    np.testing.assert_array_equal(run.indices, idx)
    np.testing.assert_array_equal(run.k_after, k_after)
    assert (run.k_first, run.k_last) == (k_first, k_last)
    assert run.state.cycles == state.cycles
    assert run.state.last_wrapped_rad == state.last_wrapped_rad
    assert (run.phase_min_rad, run.phase_max_rad) == (phase.min(), phase.max())


@pytest.mark.parametrize("jit", [False, True])
def test_a_scale_in_the_pass_equals_scaling_afterwards(twin, jit):
    _, _, a, b = twin
    corr = fit_quadrature_correction(a, b)
    scale = 360.0 / (2 * math.pi * LINES)
    plain = phase_pass(a, b, corr, jit=jit)
    scaled = phase_pass(a, b, corr, jit=jit, scale=scale)
    np.testing.assert_array_equal(scaled.phase_rad, plain.phase_rad * scale)
    assert (scaled.k_first, scaled.k_last) == (plain.k_first, plain.k_last)
    assert (scaled.phase_min_rad, scaled.phase_max_rad) == (
        plain.phase_min_rad,
        plain.phase_max_rad,
    )
    np.testing.assert_array_equal(scaled.indices, plain.indices)


@pytest.mark.parametrize("jit", [False, True])
def test_phase_pass_carries_its_state_across_chunks(twin, jit):
    _, _, a, b = twin
    corr = fit_quadrature_correction(a, b)
    whole = phase_pass(a, b, corr, jit=False)
    cuts = [0, 17, BLOCK + 5, 2 * BLOCK + 999, a.size]
    state = k_prev = None
    pieces, idx = [], []
    for s, e in itertools.pairwise(cuts):
        run = phase_pass(a[s:e], b[s:e], corr, state=state, previous_k=k_prev, offset=s, jit=jit)
        state, k_prev = run.state, run.k_last
        pieces.append(run.phase_rad)
        idx.append(run.indices)
    np.testing.assert_array_equal(np.concatenate(pieces), whole.phase_rad)
    np.testing.assert_array_equal(np.concatenate(idx), whole.indices)


@pytest.mark.parametrize("jit", [False, True])
def test_a_transition_at_almost_every_sample(jit):
    """A fast motion (0.6 rad a sample, reversing): more transitions than the Numba twin first
    makes room for (it grows its output); both equal the separate steps."""
    n = 5 * BLOCK + 123
    phi = np.cumsum(np.where(np.arange(n) % 70_000 < 35_000, 0.6, -0.6))
    a, b = np.cos(phi), np.sin(phi)
    corr = QuadratureCorrection(0.0, 0.0, 1.0, 1.0, 0.0, "given", 2 * math.pi, n)
    phase, _, idx, k_after, _, _ = _steps(a, b, corr)
    run = phase_pass(a, b, corr, jit=jit)
    assert idx.size > n // 2
    np.testing.assert_array_equal(run.phase_rad, phase)
    np.testing.assert_array_equal(run.indices, idx)
    np.testing.assert_array_equal(run.k_after, k_after)


def test_demodulate_numba_and_numpy_agree_and_match_the_truth(twin, monkeypatch):
    motion, t, a, b = twin
    monkeypatch.setenv("ROTACAL_NUMBA", "0")
    plain = demodulate(t, a, b, LINES)
    monkeypatch.delenv("ROTACAL_NUMBA")
    monkeypatch.setattr(_jit, "MIN_SAMPLES", 0)
    assert _jit.use_numba(t.size)
    fast = demodulate(t, a, b, LINES)
    np.testing.assert_array_equal(fast.angle_deg, plain.angle_deg)
    np.testing.assert_array_equal(fast.reversals.indices, plain.reversals.indices)
    assert fast.angle_min_deg == pytest.approx(plain.angle_min_deg, rel=1e-12)
    assert fast.angle_max_deg == pytest.approx(plain.angle_max_deg, rel=1e-12)
    # truth: the twin's angle (its origin is the phase zero at the start of the capture)
    truth = motion.angle_deg(t)
    err = fast.angle_deg - truth
    err -= err.mean()
    assert np.abs(err).max() < 5e-5  # deg: 0.004 noise on a 0.01°/signal-period encoder
    true_rev = motion.reversal_times_s(float(t[0]), float(t[-1]))
    assert fast.reversals.times_s.size == true_rev.size
    np.testing.assert_allclose(fast.reversals.times_s, true_rev, atol=1e-3)


def test_the_angle_extremes_are_those_of_the_angle(twin):
    _, t, a, b = twin
    d = demodulate(t, a, b, LINES)
    assert d.angle_min_deg == d.angle_deg.min()
    assert d.angle_max_deg == d.angle_deg.max()
    assert math.isfinite(d.angle_min_deg)


@pytest.mark.parametrize("jit", [False, True])
def test_an_untilted_correction_equals_the_separate_steps(twin, jit):
    """A phase error of exactly 0 skips the tilt term in both correction paths alike."""
    _, _, a, b = twin
    corr = dataclasses.replace(fit_quadrature_correction(a, b), phase_error_rad=0.0)
    phase, _, idx, _, _, _ = _steps(a, b, corr)
    run = phase_pass(a, b, corr, jit=jit)
    np.testing.assert_array_equal(run.phase_rad, phase)
    np.testing.assert_array_equal(run.indices, idx)
