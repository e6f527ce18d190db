"""rotacal._jit: when the Numba twins run (the numbers are the same either way: the twins'
own tests compare them)."""

from __future__ import annotations

import sys

from rotacal import _jit


def test_single_call_raises_the_default_threshold_until_numba_is_loaded(monkeypatch):
    monkeypatch.delenv("ROTACAL_NUMBA", raising=False)
    monkeypatch.setattr(_jit, "MIN_SAMPLES", 100)
    monkeypatch.setattr(_jit, "_available", True)
    monkeypatch.delitem(sys.modules, "numba", raising=False)
    assert _jit.use_numba(1_000)
    with _jit.single_call(10_000):
        assert not _jit.use_numba(1_000)  # one call does not repay the load
        assert _jit.use_numba(10_000)
        assert _jit.use_numba(1_000, threshold=500)  # an explicit threshold is the caller's
        assert _jit.use_numba(10, True)  # and force is
        monkeypatch.setitem(sys.modules, "numba", object())
        assert _jit.use_numba(1_000)  # loaded already: nothing left to repay
        monkeypatch.delitem(sys.modules, "numba")
        monkeypatch.setenv("ROTACAL_NUMBA", "1")
        assert _jit.use_numba(10)
        monkeypatch.delenv("ROTACAL_NUMBA")
    assert _jit.use_numba(1_000)  # the threshold is back after the block
