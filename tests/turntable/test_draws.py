"""The Monte Carlo statistics a turntable budget states (rotacal.turntable.draws, the 99.9 %
quantile of the Monte Carlo check) against truth that does not come from the code under test.

Truth: the binomial tail equations that define the Clopper–Pearson limits (evaluated with the
binomial distribution, not the beta quantiles the code uses), the closed forms of the all/none
cases, the known quantiles of a uniform distribution, and a table with one error source whose
orientation error is that source itself (|Δθ| = |e_z|, uniform between its bounds: the q-quantile
is LB + q·(UB − LB)). Coverage is checked over repeats with different seeds.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom

from rotacal.turntable.allocation import monte_carlo_check
from rotacal.turntable.budget import turntable_budget
from rotacal.turntable.draws import (
    TopValues,
    fraction_interval,
    quantile_interval,
    top_values_needed,
)
from rotacal.turntable.model import load_turntable

ONE_ERROR = """
name = "one error source"
units = "arcsec"
[requirement]
psi = 20.0
theta = 30.0
gamma = 20.0
[[chain]]
axis = "z"
angle = "phi"
rotations = { e_z = "z" }
[errors]
e_z = { lower = 3.0, label = "Position error" }
"""


@pytest.mark.parametrize(("hits", "n"), [(3, 50), (17, 1000), (1, 10_000), (9_990, 10_000)])
def test_fraction_interval_solves_the_binomial_tail_equations(hits: int, n: int) -> None:
    fraction, low, high = fraction_interval(hits, n)
    assert fraction == hits / n
    # Clopper & Pearson: P(X ≥ hits | low) = 2.5 % and P(X ≤ hits | high) = 2.5 %
    assert binom.sf(hits - 1, n, low) == pytest.approx(0.025, rel=1e-6)
    assert binom.cdf(hits, n, high) == pytest.approx(0.025, rel=1e-6)


def test_fraction_interval_all_and_none_have_closed_forms() -> None:
    n = 1_000_000
    assert fraction_interval(n, n) == (1.0, pytest.approx(0.025 ** (1 / n), rel=1e-12), 1.0)
    assert fraction_interval(0, n) == (0.0, 0.0, pytest.approx(1 - 0.025 ** (1 / n), rel=1e-9))
    # the "rule of three" for 95 % one-sided is 3/n; the two-sided 97.5 % end is ln(40)/n
    assert fraction_interval(0, n)[2] == pytest.approx(np.log(40.0) / n, rel=1e-5)


def test_quantile_interval_covers_the_uniform_quantile_95_percent_of_repeats() -> None:
    q, n, repeats = 0.999, 20_000, 400
    rng = np.random.default_rng(7)
    covered = 0
    for _ in range(repeats):
        x = rng.random(n)
        stated = quantile_interval(np.sort(x)[-top_values_needed(n, q) :], n, q)
        assert stated is not None
        value, low, high = stated
        assert low <= value <= high
        covered += low <= q <= high  # the q-quantile of U(0, 1) is q
    # coverage ≥ 95 % by construction (discrete ranks); 400 repeats: ±2.2 % at one σ…3 σ
    assert 0.93 <= covered / repeats <= 0.995


def test_quantile_interval_needs_enough_draws() -> None:
    assert quantile_interval(np.arange(100.0), 100, 0.999) is None
    assert top_values_needed(100, 0.999) == 0


def test_top_values_do_not_depend_on_the_chunks() -> None:
    rng = np.random.default_rng(3)
    x = rng.random((10_000, 3))
    for chunk in (1, 7, 999, 10_000):
        top = TopValues(50, 3)
        for start in range(0, len(x), chunk):
            top.add(x[start : start + chunk])
        np.testing.assert_array_equal(np.sort(top.values, axis=0), np.sort(x, axis=0)[-50:])


def test_monte_carlo_quantile_covers_the_closed_form_over_seeds() -> None:
    table = load_turntable(text=ONE_ERROR)
    budget = turntable_budget(table, runs=1_000)
    alloc = budget._allocation
    lb, ub = alloc.lower_bounds_rad["e_z"], alloc.upper_bounds_rad["e_z"]
    truth = lb + 0.999 * (ub - lb)  # |Δθ| = |e_z| = LB + (UB − LB)·U(0, 1)
    covered, estimates, intervals = 0, [], []
    for seed in range(200):
        mc = monte_carlo_check(table, alloc, runs=20_000, seed=seed, chunk=7_000)
        assert mc.quantile_abs_rad is not None
        value, low, high = mc.quantile_abs_rad["theta"]
        covered += low <= truth <= high
        estimates.append(value)
        intervals.append((low, high))
    assert 0.92 <= covered / 200 <= 0.995
    # the stated U (half the interval) is the spread of the estimates over seeds: U ≈ 1.96·s
    half = np.mean([0.5 * (high - low) for low, high in intervals])
    assert half / 1.96 == pytest.approx(np.std(estimates, ddof=1), rel=0.2)


def test_monte_carlo_statistics_reach_the_budgets_json() -> None:
    budget = turntable_budget(load_turntable(text=ONE_ERROR), runs=20_000)
    mc = budget.to_dict()["monte_carlo"]
    assert mc["outside"] == 0 and mc["fraction_outside"] == 0.0
    assert mc["fraction_outside_interval"][1] == pytest.approx(np.log(40.0) / 20_000, rel=1e-3)
    low, high = mc["quantile_abs_interval_arcmin"]["theta"]
    assert low <= mc["quantile_abs_arcmin"]["theta"] <= high


def test_verdict_passes_only_a_whole_interval_within_the_limit() -> None:
    from rotacal.report.uncertainty import verdict

    assert verdict((0.8, 0.99), 1.0) is True
    assert verdict((0.8, 1.0), 1.0) is True  # at the limit is within
    assert verdict((0.99, 1.01), 1.0) is None  # straddles: inconclusive (ILAC-G8 guarded)
    assert verdict((1.01, 1.2), 1.0) is False
