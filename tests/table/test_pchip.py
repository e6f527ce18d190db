"""rotacal.table._pchip equals SciPy's PchipInterpolator bit for bit (the truth: SciPy)."""

from __future__ import annotations

import numpy as np
import pytest

from rotacal.table._argmax_table import LOG_F, LOG_G
from rotacal.table._pchip import pchip


def test_pchip_equals_scipy_bit_for_bit():
    interpolate = pytest.importorskip("scipy.interpolate")
    rng = np.random.default_rng(0)
    cases = [(LOG_G, LOG_F)]
    for k in range(60):
        x = np.sort(rng.choice(np.linspace(-5.0, 5.0, 1001), rng.integers(3, 40), replace=False))
        y = rng.normal(size=x.size) if k % 3 else np.cumsum(rng.uniform(0.0, 1.0, x.size))
        if k % 4 == 0:
            y[rng.integers(0, x.size)] = y[rng.integers(0, x.size)]  # flat pieces, sign changes
        cases.append((x, y))
    for x, y in cases:
        points = np.concatenate([x, rng.uniform(x[0], x[-1], 400)])
        np.testing.assert_array_equal(
            pchip(x, y)(points), interpolate.PchipInterpolator(x, y)(points)
        )


def test_pchip_reproduces_a_cubic_shape_and_the_nodes():
    x = np.linspace(0.0, 2.0, 9)
    y = x**3  # monotone: PCHIP passes through the nodes and stays monotone between them
    f = pchip(x, y)
    np.testing.assert_array_equal(f(x), y)
    fine = f(np.linspace(0.0, 2.0, 401))
    assert np.all(np.diff(fine) >= 0)
    assert np.max(np.abs(fine - np.linspace(0.0, 2.0, 401) ** 3)) < 0.02
