"""The THD belt's root finder (table/motion_thd._bracketed_root) against closed-form roots."""

from __future__ import annotations

import math

import pytest

from rotacal.table.motion_thd import _bracketed_root

CASES = [
    (lambda x: x**3 - 2.0, 2.0 ** (1.0 / 3.0)),
    (lambda x: math.exp(x) - 5.0, math.log(5.0)),
    (lambda x: math.tanh(10.0 * (x - 1.3)), 1.3),  # steep: secants overshoot
    (lambda x: (x - 0.7) ** 5, 0.7),  # flat at the root: plain false position stalls
    (lambda x: math.floor(1000.0 * x) / 1000.0 - 0.4995 + 1e-4 * x, None),  # steps, like a quantile
    (lambda x: math.atan(x - 3.1), 3.1),
]


@pytest.mark.parametrize("case", range(len(CASES)))
def test_bracketed_root_finds_the_root_within_tol_in_few_steps(case):
    f, root = CASES[case]
    calls = []

    def counted(x):
        calls.append(x)
        return f(x)

    b, tol = 10.0, 1e-9 * 10.0
    x = _bracketed_root(counted, 0.0, f(0.0), b, tol=tol)
    if root is not None:
        assert abs(x - root) <= tol
    else:  # a sign change of f lies within tol of x
        assert f(x - tol) * f(x + tol) <= 0.0
    # bisection alone needs log2(b/tol) = 34 steps; the safeguard keeps it within ~3x that
    assert len(calls) <= 3 * math.ceil(math.log2(b / tol))


def test_bracketed_root_returns_an_end_that_is_a_root():
    assert _bracketed_root(lambda x: x - 1.0, 1.0, 0.0, 3.0, tol=1e-12) == 1.0
    assert _bracketed_root(lambda x: x - 3.0, 0.0, -3.0, 3.0, tol=1e-12) == 3.0
