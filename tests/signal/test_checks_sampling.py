"""check_sampling's one-pass check of long records finds the same faults, with the same messages,
as its full passes (the truth: faults put at known samples)."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.signal import _checks
from rotacal.signal._checks import check_sampling

N = 1000


@pytest.fixture
def long_record(monkeypatch):
    # a "long" record of 1000 samples: the one-pass path runs, over blocks of 64 steps
    monkeypatch.setattr(_checks, "TYPICAL_STEPS", 100)
    monkeypatch.setattr(_checks, "_GRID_CHUNK", 64)
    return np.arange(N) * 0.01 + 3.0


def _nan(t, i):
    t[i] = np.nan


def _inf(t, i):
    t[i] = np.inf


def _repeat(t, i):
    t[i] = t[i - 1]


def _back(t, i):
    t[i] = t[i - 1] - 0.005


def _gap(t, i):
    t[i:] += 0.5


@pytest.mark.parametrize(
    ("fault", "message"),
    [
        (_nan, "has a NaN or inf at sample {i}"),
        (_inf, "has a NaN or inf at sample {i}"),
        (_repeat, "not strictly increasing at sample {i} "),
        (_back, "not strictly increasing at sample {i} "),
        (_gap, "has a gap of 0.51 s before sample {i} "),
    ],
)
@pytest.mark.parametrize("i", [1, 63, 64, 65, 500, N - 1])
def test_faults_of_long_records_are_named_at_their_sample(long_record, fault, message, i):
    assert _checks._typical_if_steps_in_bounds(long_record, 3.0) == pytest.approx(0.01)
    fault(long_record, i)
    assert _checks._typical_if_steps_in_bounds(long_record, 3.0) is None  # → the full passes
    with pytest.raises(CaptureError, match=message.format(i=i).replace("(", r"\(")):
        check_sampling(long_record)


def test_first_fault_wins_and_jitter_passes(long_record):
    rng = np.random.default_rng(1)
    check_sampling(long_record + rng.uniform(-1e-4, 1e-4, N))  # jitter is no fault
    t = long_record.copy()
    _gap(t, 700)
    _repeat(t, 800)
    with pytest.raises(CaptureError, match="not strictly increasing at sample 800"):
        check_sampling(t)  # order faults are searched before gaps, as in the full passes
    t = long_record.copy()
    t[-1] = 1e300  # a step of 1e300 s: a gap, not an overflow
    with pytest.raises(CaptureError, match=f"gap of 1e\\+300 s before sample {N - 1}"):
        check_sampling(t)
