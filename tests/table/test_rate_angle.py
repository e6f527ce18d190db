"""rate on angle/count readings: mark crossings against the twin's true angle, rates against truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.sim.angle import constant_rate_angle_deg, simulate_angle
from rotacal.table.rate_angle import (
    MarkCrossings,
    calibrate_rate_from_angle,
    calibrate_rate_from_counts,
    crossing_error_bound_s,
)

W, A, FW = 300.0, 1e-3, 5.0  # rate (deg/s), relative fluctuation, its frequency (Hz)


@pytest.fixture(scope="module")
def spin():
    return simulate_angle(
        rate_deg_s=W, fluctuation=A, fluctuation_hz=FW, reading="angle", fs_hz=20_000, duration_s=2
    )


def _true_crossings(marks_deg: np.ndarray) -> np.ndarray:
    """Newton on the twin's closed-form θ(t) = mark (independent of the interpolation)."""
    t = marks_deg / W
    for _ in range(6):
        t -= (constant_rate_angle_deg(t, W, A, FW) - marks_deg) / (
            W * (1 + A * np.cos(2 * np.pi * FW * t))
        )
    return t


def test_crossings_within_the_stated_bound(spin):
    t, a = spin.columns["time_s"], spin.columns["angle_deg"]
    marks = MarkCrossings(3600)
    for s in range(0, t.size, 7_001):  # streamed: the last sample carried over
        marks.feed(t[s : s + 7_001], a[s : s + 7_001])
    times, direction = marks.result()
    assert direction == 1 and times.size == 5_999
    err = np.max(np.abs(times - _true_crossings(0.1 * np.arange(1, times.size + 1))))
    bound = crossing_error_bound_s(W * A * 2 * np.pi * FW, 1 / 20_000, W * (1 - A))
    assert err <= bound and err > 0.2 * bound  # the bound is tight, and the test can fail


def test_rates_against_the_true_rate(spin):
    t, a = spin.columns["time_s"], spin.columns["angle_deg"]
    r = calibrate_rate_from_angle(t, a, pulses_per_rev=3600, set_rate_deg_s=W)
    assert abs(r.mean_rate_deg_s - W) <= 1e-9 * W  # 10 whole fluctuation periods
    # the 10-mark rate points sample the true rate: their rms deviation is a/√2 (in %)
    assert r.rate_deviation_rms_percent == pytest.approx(100 * A / math.sqrt(2), rel=2e-3)
    backwards = calibrate_rate_from_angle(t[:4_000], -a[:4_000], pulses_per_rev=3600)
    assert backwards.mean_rate_deg_s == pytest.approx(W, rel=2 * A)  # not whole periods
    assert "turns backwards" in backwards.notes[-1]


def test_wrapping_counter_within_the_resolution_bound():
    cap = simulate_angle(
        rate_deg_s=W, fluctuation=A, fluctuation_hz=FW, counts_per_rev=144_000, fs_hz=20_000,
        duration_s=2, counter_bits=16, drop_rows=3, repeat_rows=2,
    )  # fmt: skip
    assert cap.truth["sensor"]["wraps"] >= 3
    t, c = cap.columns["time_s"], cap.columns["count"]
    r = calibrate_rate_from_counts(t, c, counts_per_rev=144_000, pulses_per_rev=360, average=10)
    q = 360 / 144_000  # one count: each crossing within q/ω, the mean rate within 2q/(ω·T)
    assert abs(r.mean_rate_deg_s - W) <= 2 * q / (r.duration_s * W) * W
    assert "16-bit unsigned register" in " ".join(r.notes) and "resolution 0.0025°" in r.notes[-1]
    assert any("3 gap(s)" in w for w in r.warnings) and any("2 repeated" in w for w in r.warnings)


def test_a_table_that_turns_back_is_refused():
    t = np.arange(20_000) / 1_000
    with pytest.raises(CaptureError, match="turns back by"):
        calibrate_rate_from_angle(t, 10 * np.sin(t), pulses_per_rev=360)
    with pytest.raises(CaptureError, match="crosses only 0 mark"):
        calibrate_rate_from_angle(t, 1e-4 * t, pulses_per_rev=360)
