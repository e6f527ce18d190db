"""The quantiles that spare the gyro commands ``scipy.stats`` equal SciPy's own, to the bit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from rotacal.uncertainty.quantiles import (
    chi2_ppf,
    chi2_sf,
    f_sf,
    norm_isf,
    norm_pdf,
    norm_ppf,
    t_ppf,
)

PROBABILITIES = [1e-12, 1e-6, 0.0005, 0.0125, 0.025, 0.05, 0.1587, 0.5, 0.8413, 0.95, 0.975,
                 0.999, 1 - 1e-9]  # fmt: skip
DOFS = [0.7, 1, 2, 3, 4.5, 7, 13, 30, 121, 1e4, 1.8e7]


@pytest.mark.parametrize("p", PROBABILITIES)
def test_normal_quantiles_and_density_are_scipys(p: float) -> None:
    assert norm_ppf(p) == float(stats.norm.ppf(p))
    assert norm_isf(p) == float(stats.norm.isf(p))
    z = float(stats.norm.ppf(p))
    assert norm_pdf(z) == float(stats.norm.pdf(z))


@pytest.mark.parametrize("dof", DOFS)
def test_t_and_chi2_quantiles_are_scipys(dof: float) -> None:
    for p in PROBABILITIES:
        assert t_ppf(p, dof) == float(stats.t.ppf(p, dof)), p
        assert chi2_ppf(p, dof) == float(stats.chi2.ppf(p, dof)), p
    for n in (3, 10, 57):  # integer ν, as the lack-of-fit tests pass them
        assert chi2_ppf(0.999, n) == float(stats.chi2.ppf(0.999, n))


@pytest.mark.parametrize("x", [1e-3, 0.5, 1.0, 3.7, 12.0, 80.0, 400.0])
def test_chi2_and_f_tail_probabilities_are_scipys(x: float) -> None:
    for dof in DOFS:
        assert chi2_sf(x, dof) == float(stats.chi2.sf(x, dof)), dof
        for dfd in (1, 4, 17, 250):
            assert f_sf(x / 10.0, dof, dfd) == float(stats.f.sf(x / 10.0, dof, dfd)), (dof, dfd)


def test_a_wrong_formula_would_be_seen() -> None:
    # the comparison above can fail: the one-sided 0.975 quantile is not the two-sided one
    assert t_ppf(0.975, 5) != pytest.approx(float(stats.t.ppf(0.95, 5)), rel=1e-3)
    assert np.isclose(t_ppf(0.975, 5), 2.5705818366147395)
