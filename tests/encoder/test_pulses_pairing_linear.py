"""The linear-time search and mode of the head pairing against NumPy's own."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.encoder.pulses import _mode, _sorted_search, pair_heads
from rotacal.sim.pulses import simulate_pulses


@pytest.mark.parametrize("case", ["paired", "drifting", "gaps", "outside", "ties"])
def test_sorted_search_is_searchsorted(case):
    rng = np.random.default_rng(4)
    times = np.cumsum(rng.uniform(0.5, 1.5, 5000))
    if case == "paired":  # the usual: another head's pulses, slightly delayed
        queries = times[100:4000] + 0.3
    elif case == "drifting":  # a different pulse rate: the guess fails more and more
        queries = np.linspace(times[10], times[-10], 6000)
    elif case == "gaps":  # lost pulses in the searched train
        queries = times[200:3000] - 0.2
        times = np.delete(times, [500, 501, 2000])
    elif case == "outside":  # queries before the first and after the last time
        queries = np.concatenate(([-5.0, -1.0], times[:50] + 0.1, [times[-1] + 1, times[-1] + 9]))
    else:  # queries equal to times: the left insertion point
        queries = times[5:300].copy()
    np.testing.assert_array_equal(_sorted_search(times, queries), np.searchsorted(times, queries))


@pytest.mark.parametrize("spread", [0, 3, 10**9])
def test_mode_is_uniques_most_frequent(spread):
    rng = np.random.default_rng(9)
    values = rng.integers(-spread, spread + 1, 1000) if spread else np.full(1000, 7)
    values[:400] = 5 if spread != 10**9 else values[0]  # one clear mode (or none: the first)
    found, counts = np.unique(values, return_counts=True)
    assert _mode(values) == int(found[np.argmax(counts)])
    tie = np.array([4, 4, 2, 2, 9])  # equally frequent: the smallest, as np.unique gives it
    assert _mode(tie) == 2


def test_pairing_offsets_are_the_twins_lines():
    """On a twin whose heads run at one rate, every pair is less than half a pulse apart."""
    cap = simulate_pulses(heads=4, pulses_per_rev=720, revolutions=3.0, seed=3)
    heads = [cap.columns[f"head_{i}"] for i in range(4)]
    pairing = pair_heads(heads)
    t0 = heads[0]
    for i in range(1, 4):
        k = pairing.index_offsets[i] + np.arange(pairing.first, pairing.stop)
        period = float(np.median(np.diff(t0)))
        assert np.max(np.abs(heads[i][k] - t0[pairing.first : pairing.stop])) < 0.5 * period
