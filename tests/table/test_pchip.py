"""The PCHIP of the arg-max table (table/_argmax_table.py) against SciPy's PchipInterpolator,
an independent implementation of the same method (Fritsch & Butland slopes, three-point ends)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator

from rotacal.table._argmax_table import LOG_F, LOG_G, pchip_eval, pchip_slopes


@pytest.mark.parametrize("kind", ["random", "increasing", "plateaus"])
def test_pchip_equals_scipy(kind):
    rng = np.random.default_rng(["random", "increasing", "plateaus"].index(kind))
    for _ in range(40):
        n = int(rng.integers(3, 30))
        x = np.cumsum(rng.uniform(0.05, 1.0, n))
        y = {
            "random": rng.normal(size=n),
            "increasing": np.cumsum(rng.uniform(0.0, 1.0, n)),
            "plateaus": np.round(rng.normal(size=n), 1),  # equal neighbours: zero slopes
        }[kind]
        ref = PchipInterpolator(x, y)
        d = pchip_slopes(x, y)
        scale = np.max(np.abs(np.diff(y) / np.diff(x)))
        assert np.abs(d - ref.derivative()(x)).max() <= 1e-14 * scale
        at = np.concatenate([rng.uniform(x[0], x[-1], 200), x])
        assert np.abs(pchip_eval(x, y, d, at) - ref(at)).max() <= 1e-14 * np.abs(y).max()
        beyond = x[-1] + rng.uniform(0.0, 0.3, 20)  # the end cubic continued, as SciPy does
        assert pchip_eval(x, y, d, beyond) == pytest.approx(ref(beyond), rel=1e-12, abs=1e-12)


def test_the_table_interpolant_equals_scipy():
    at = np.linspace(LOG_G[0], LOG_G[-1] + 0.2, 2001)
    mine = pchip_eval(LOG_G, LOG_F, pchip_slopes(LOG_G, LOG_F), at)
    assert np.abs(mine - PchipInterpolator(LOG_G, LOG_F)(at)).max() <= 1e-14
