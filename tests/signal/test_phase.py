"""The phase every deviation is computed from (rotacal.signal._phase), against long double."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.signal._phase import RUNNING_SUM_BLOCK, phase_record, running_sum

EPS = np.finfo(np.float64).eps


def ramp_rate(n: int) -> np.ndarray:
    """White noise on a steep rate ramp: a running sum of it is a parabola to ~10¹⁰."""
    rng = np.random.default_rng(3)
    return rng.standard_normal(n) + 1e-2 * np.arange(n, dtype=np.float64)


def test_running_sum_stays_at_its_rounding_where_one_running_sum_drifts():
    """Each value within 2ε·(block Σ|v| + |value|) of the long-double sum (the worst case is b
    times that; rounding errors mostly cancel), at a length that is not a multiple of the block
    and from a non-zero start. np.cumsum's drift along the parabola is over 30 times that (the
    reason the phase is summed in blocks)."""
    v = ramp_rate(1_000_003)
    exact = 7.25 + np.cumsum(v.astype(np.longdouble))
    got = running_sum(v.copy(), 7.25)
    whole = v[: v.size // RUNNING_SUM_BLOCK * RUNNING_SUM_BLOCK]
    block_abs = np.abs(whole).reshape(-1, RUNNING_SUM_BLOCK).sum(axis=1).max()
    scale = EPS * (block_abs + np.abs(got))
    assert np.max(np.abs((got - exact).astype(np.float64)) / scale) < 2.0
    drift = np.abs((7.25 + np.cumsum(v) - exact).astype(np.float64))
    assert np.max(drift / scale) > 30.0


def test_running_sum_refuses_a_strided_array():
    with pytest.raises(ValueError, match="contiguous"):
        running_sum(np.zeros(10)[::2])


@pytest.mark.parametrize("data_type", ["rate", "phase"])
def test_ramp_blind_phase_differs_by_a_parabola(data_type):
    """``ramp_blind`` removes a parabola (the rate's best line, integrated) and nothing else:
    the third differences of the two phases agree to rounding, the second do not."""
    y = ramp_rate(5000)
    if data_type == "phase":
        y = np.cumsum(y)
    plain = phase_record(y, 2.0, data_type)
    blind = phase_record(y, 2.0, data_type, ramp_blind=True)
    third = np.diff(plain - blind, 3)
    assert np.max(np.abs(third)) < 1e-9 * np.max(np.abs(np.diff(plain, 3)))
    assert np.max(np.abs(np.diff(plain - blind, 2))) > 1e-3
    assert abs(float(np.mean(blind))) < 1e-9 * float(np.max(np.abs(blind)))
