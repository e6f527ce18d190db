"""The chunked encoder's reversal candidates, found chunk by chunk, give the whole list's plan."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from rotacal.encoder import plan_reversals
from rotacal.table._stream_encoder import CandidateState


def _transitions(seed: int, noise: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Sample index and count k after each transition of a noisy sinusoidal count (dithering at
    the subinterval edges, runs of changes of every length, a few skipped subintervals)."""
    rng = np.random.default_rng(seed)
    n = 60_000
    k = np.round(40 * np.sin(np.linspace(0, 14 * np.pi, n)) + rng.normal(0, noise, n))
    at = np.flatnonzero(np.diff(k) != 0) + 1
    return at.astype(np.int64), k[at], float(k[0])


@pytest.mark.parametrize("noise", [0.05, 0.3])
@pytest.mark.parametrize("chunk", [1, 2, 5, 977, 10**9])
def test_candidates_by_chunk_give_the_plan_of_every_transition(noise, chunk):
    # truth: plan_reversals on the whole transition list (the in-memory path)
    idx, k, k0 = _transitions(3, noise)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        want = plan_reversals(idx, k, k0)
        found = CandidateState(k0)
        for s in range(0, idx.size, chunk):
            found.add(idx[s : s + chunk], k[s : s + chunk])
        got = found.plan(None, stacklevel=2)
    assert want.pairs.shape[0] >= 13
    np.testing.assert_array_equal(got.windows, want.windows)
    np.testing.assert_array_equal(got.pairs, want.pairs)
    np.testing.assert_array_equal(got.kinds, want.kinds)
    for name in (
        "candidates",
        "hysteresis_subintervals",
        "transitions",
        "skipped_transitions",
        "max_step_subintervals",
    ):
        assert getattr(got, name) == getattr(want, name), name
