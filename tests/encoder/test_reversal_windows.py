"""The reversal windows and their Chp (eqs. (7)–(8)), found for all windows at once, equal a
literal loop over the windows written from the rule in the docstrings."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from rotacal.encoder import plan_reversals, reversal_point_in_window
from rotacal.encoder.reversals import ReversalPlan, _candidates, _direction, _pinned


def _transitions(seed: int, noise: float) -> tuple[np.ndarray, np.ndarray, float]:
    """A noisy sinusoidal subinterval count: runs of trend changes of every length, clusters."""
    rng = np.random.default_rng(seed)
    k = np.round(40 * np.sin(np.linspace(0, 14 * np.pi, 60_000)) + rng.normal(0, noise, 60_000))
    at = np.flatnonzero(np.diff(k) != 0) + 1
    return at.astype(np.int64), k[at], float(k[0])


def _chp(u: np.ndarray, v: np.ndarray) -> int:
    """Eqs. (7)–(8) for one window, literally: q of each signal against its endpoints."""
    qu = sum(u) - len(u) * (u[0] + u[-1]) / 2
    qv = sum(v) - len(v) * (v[0] + v[-1]) / 2
    x, q = (u, qu) if abs(qu) >= abs(qv) else (v, qv)
    if q == 0:
        return (len(u) - 1) // 2
    return int(np.argmax(x) if q > 0 else np.argmin(x))


@pytest.mark.parametrize("noise", [0.05, 0.3])
def test_windows_and_pairs_equal_a_loop_over_the_candidates(noise):
    idx, ka, k0 = _transitions(5, noise)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plan = plan_reversals(idx, ka, k0)
    dk = np.diff(ka, prepend=k0)
    assert plan.skipped_transitions == sum(abs(d) > 1 for d in dk)
    assert plan.skipped_transitions > 0 or noise < 0.1  # the noisy count skips subintervals
    assert plan.max_step_subintervals == int(max(abs(d) for d in dk))
    first, run, kinds, level = _candidates(ka, _direction(dk))
    assert list(kinds) == [int(np.sign(dk[j - 1])) for j in first]  # the trend before the run
    cand = []
    for j0, n, lv in zip(first, run, level, strict=True):
        at = [r for r in range(n) if ka[j0 - 1 + r] == lv]
        cand.append((idx[j0 - 1 + at[0]], idx[j0 + at[-1]] - 1))
    windows, pairs = [], []
    c = 0
    while c < len(cand):  # clusters: neighbours whose levels differ by less than the hysteresis
        end = c
        while (
            end + 1 < len(cand) and abs(level[end + 1] - level[end]) < plan.hysteresis_subintervals
        ):
            end += 1
        size = end - c + 1
        if size % 2:
            windows.append(cand[c])
            if size > 1:
                windows.append(cand[end])
            pairs.append((len(windows) - 1 - (size > 1), len(windows) - 1))
        c = end + 1
    assert any(p[0] != p[1] for p in pairs) or noise < 0.1  # the noisy case has clusters
    np.testing.assert_array_equal(plan.windows, np.array(windows).reshape(-1, 2))
    np.testing.assert_array_equal(plan.pairs, np.array(pairs).reshape(-1, 2))


def test_chp_of_all_windows_at_once_equals_each_window_alone():
    rng = np.random.default_rng(2)
    n = 50_000
    u = np.cos(np.cumsum(rng.normal(0, 0.05, n)))
    v = np.sin(np.cumsum(rng.normal(0, 0.05, n)))
    u[:5000] = np.round(u[:5000], 1)  # ties: the first extreme counts
    t = np.arange(n) * 1e-3
    firsts = np.sort(rng.choice(n - 600, 300, replace=False))
    lasts = firsts + rng.integers(0, 500, 300)  # some one-sample visits
    windows = np.column_stack((firsts, lasts))
    one_each = np.column_stack((np.arange(300),) * 2)
    plan = ReversalPlan(windows, one_each, np.ones(300), 300, 2, 0, 0, 0)
    got = _pinned(plan, t, lambda rows: (u[rows], v[rows])).indices
    for (f, last), g in zip(windows, got, strict=True):
        lo, hi = (f, f) if last <= f else (f - 1, last + 1)
        want = f if last <= f else lo + _chp(u[lo : hi + 1], v[lo : hi + 1])
        assert g == want
        if last > f:
            assert reversal_point_in_window(u[lo : hi + 1], v[lo : hi + 1]) == want - lo


@pytest.mark.parametrize("chunk", [1, 7, 1 << 16])
def test_the_steps_of_k_by_chunks_are_those_of_the_whole_list(monkeypatch, chunk):
    """The plan's summary of the steps of k, chunk by chunk, against np.diff of the whole list."""
    from rotacal.encoder import reversals

    rng = np.random.default_rng(7)
    k0 = 3.0
    ka = k0 + np.cumsum(rng.choice([-3, -1, 1, 2], size=1000, p=[0.01, 0.5, 0.48, 0.01]))
    ka = ka.astype(np.float64)
    dk = np.diff(ka, prepend=k0)
    monkeypatch.setattr(reversals, "_STEP_CHUNK", chunk)
    direction, skipped, max_step, (lo, hi) = reversals._steps(ka, k0)
    np.testing.assert_array_equal(direction, np.sign(dk).astype(np.int8))
    assert skipped == np.count_nonzero(np.abs(dk) > 1) > 0
    assert max_step == int(np.abs(dk).max()) == 3
    assert (lo, hi) == (min(k0, ka.min()), max(k0, ka.max()))
