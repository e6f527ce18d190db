"""rotacal._brentq gives SciPy's brentq roots bit for bit (the truth: scipy.optimize.brentq)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotacal._brentq import brentq


def _functions(rng):
    for _ in range(150):
        c = rng.normal(size=3)
        r = rng.uniform(0.1, 5.0)
        yield lambda x, r=r, c=c: c[0] * (x - r) + 0.1 * c[1] * (x - r) ** 3 * (c[0] * c[1] > 0)
        yield lambda x, r=r: math.exp(x) - math.exp(r)
        yield lambda x, r=r, c=c: math.tanh(abs(c[2]) * (x - r))
        yield lambda x, r=r: (x - r) ** 3
        yield lambda x, r=r: math.erf(x - r) + 1e-3 * (x - r)


def _outcome(solver, *args, **kwargs):
    try:
        return solver(*args, **kwargs)
    except (ValueError, RuntimeError) as e:  # no sign change / no convergence: both must fail
        return type(e)


def test_roots_equal_scipys_bit_for_bit():
    scipy_brentq = pytest.importorskip("scipy.optimize").brentq
    rng = np.random.default_rng(7)
    roots = 0
    for f in _functions(rng):
        b = 6.0 + rng.uniform(0.0, 10.0)
        tols = {"xtol": 10 ** rng.uniform(-14, -3) * b, "rtol": 10 ** rng.uniform(-15, -8)}
        ours = _outcome(brentq, f, 0.0, b, **tols)
        assert ours == _outcome(scipy_brentq, f, 0.0, b, **tols)
        roots += isinstance(ours, float)
    assert roots > 600  # most cases are roots, not failures


def test_known_root_and_faults():
    assert brentq(lambda x: x * x - 2.0, 0.0, 2.0, xtol=1e-15) == pytest.approx(
        math.sqrt(2), abs=2e-15
    )
    assert brentq(lambda x: x - 1.0, 1.0, 3.0) == 1.0  # a root at the bracket's end
    with pytest.raises(ValueError, match="different signs"):
        brentq(lambda x: x * x + 1.0, -1.0, 1.0)
    with pytest.raises(ValueError, match="rtol too small"):
        brentq(lambda x: x, -1.0, 1.0, rtol=1e-17)
    with pytest.raises(RuntimeError, match="no convergence"):
        brentq(lambda x: math.exp(x) - 2.0, 0.0, 1.0, xtol=1e-300, maxiter=3)
