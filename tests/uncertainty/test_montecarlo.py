"""The Monte Carlo method (JCGM 101) against the published examples and closed forms.

Inputs come from /work/shared/UNCERTAINTY-EXAMPLES.md; the published results are the JCGM 101
§9 / JCGM 102 numbers. Where a closed form exists (additive models, the mass-calibration variance,
the gauge-block variance, the Rice distribution, E|Z|²) the Monte Carlo values are also checked
against it within their own sampling error, estimated from sub-blocks of the kept samples.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from scipy import integrate, optimize, stats

from rotacal.errors import CaptureError, ConfigError
from rotacal.uncertainty.distributions import (
    Arcsine,
    CurvilinearTrapezoid,
    MultivariateNormal,
    Normal,
    Rectangular,
    StudentT,
)
from rotacal.uncertainty.gum import Input, propagate
from rotacal.uncertainty.montecarlo import (
    MonteCarloResult,
    coverage_interval,
    monte_carlo,
    numerical_tolerance,
    validate_gum,
)

SQ3 = math.sqrt(3.0)


def _one(r: MonteCarloResult | dict[str, MonteCarloResult]) -> MonteCarloResult:
    assert isinstance(r, MonteCarloResult)
    return r


def _se(samples: np.ndarray, stat: Callable[[np.ndarray], float], blocks: int = 20) -> float:
    """Standard error of ``stat`` over all samples, from the spread over sub-blocks."""
    vals = [stat(b) for b in np.array_split(samples, blocks)]
    return float(np.std(vals, ddof=1) / math.sqrt(blocks))


def _short(p: float, side: int) -> Callable[[np.ndarray], float]:
    return lambda y: coverage_interval(y, p, shortest=True)[side]


# ------------------------------------------------------------------------------ JCGM 101 §9.2
def _additive(x1: np.ndarray, x2: np.ndarray, x3: np.ndarray, x4: np.ndarray) -> np.ndarray:
    return x1 + x2 + x3 + x4


def _irwin_hall_cdf(s: float, n: int) -> float:
    """CDF of the sum of n U(0, 1) (Irwin–Hall), closed form."""
    k = np.arange(0, math.floor(s) + 1)
    terms = (-1.0) ** k * np.array([math.comb(n, int(i)) for i in k]) * (s - k) ** n
    return float(np.clip(terms.sum() / math.factorial(n), 0.0, 1.0))


def _irwin_hall_pdf(s: float, n: int) -> float:
    if s <= 0.0 or s >= n:
        return 0.0
    k = np.arange(0, math.floor(s) + 1)
    terms = (-1.0) ** k * np.array([math.comb(n, int(i)) for i in k]) * (s - k) ** (n - 1)
    return float(terms.sum() / math.factorial(n - 1))


def _quantile_four_unit_rect(prob: float) -> float:
    """Quantile of the sum of four R(−√3, √3) = 2√3·(S₄ − 2), S₄ Irwin–Hall."""
    s = optimize.brentq(lambda v: _irwin_hall_cdf(v, 4) - prob, 0.0, 4.0, xtol=1e-14)
    return 2.0 * SQ3 * (s - 2.0)


def _quantile_924(prob: float) -> float:
    """Quantile of X₁ + X₂ + X₃ + X₄, X₁..₃ ~ R(−√3, √3), X₄ ~ R(−10√3, 10√3), by quadrature.

    The sum of the first three is 2√3·(S₃ − 3/2), S₃ Irwin–Hall; P(Y ≤ y) = E[F₄(y − that sum)].
    """
    a4 = 10.0 * SQ3

    def cdf(y: float) -> float:
        def integrand(s: float) -> float:
            z = y - 2.0 * SQ3 * (s - 1.5)
            return _irwin_hall_pdf(s, 3) * min(max((z + a4) / (2.0 * a4), 0.0), 1.0)

        return integrate.quad(integrand, 0.0, 3.0, points=[1.0, 2.0], epsabs=1e-13)[0]

    return optimize.brentq(lambda y: cdf(y) - prob, -40.0, 40.0, xtol=1e-12)


ADDITIVE = {
    # case: (inputs, published u, published ± endpoint, unit of the last digit,
    #        exact u, exact endpoint of the (symmetric = shortest) 95 % interval)
    "9.2.2": (
        {f"x{i}": Normal(0.0, 1.0) for i in range(1, 5)},
        2.00,
        3.92,
        0.01,
        2.0,
        2.0 * stats.norm.ppf(0.975),
    ),
    "9.2.3": (
        {f"x{i}": Rectangular.centered(0.0, SQ3) for i in range(1, 5)},
        2.00,
        3.88,
        0.01,
        2.0,
        _quantile_four_unit_rect(0.975),
    ),
    "9.2.4": (
        {
            "x1": Rectangular.centered(0.0, SQ3),
            "x2": Rectangular.centered(0.0, SQ3),
            "x3": Rectangular.centered(0.0, SQ3),
            "x4": Rectangular.centered(0.0, 10.0 * SQ3),
        },
        10.2,  # published; the exact value √103 = 10.149 rounds to 10.1 — see the test
        17.0,
        0.1,
        math.sqrt(103.0),
        _quantile_924(0.975),
    ),
}


@pytest.mark.parametrize("case", sorted(ADDITIVE))
def test_additive_model_fixed_one_million(case: str) -> None:
    inputs, u_pub, e_pub, unit, u_exact, e_exact = ADDITIVE[case]
    r = _one(monte_carlo(_additive, inputs, trials=1_000_000))
    y = r.samples
    assert r.trials == 1_000_000 and y.size == 1_000_000
    se_u = _se(y, lambda b: float(np.std(b, ddof=1)))
    # u(y): the exact value within the Monte Carlo error, and the published digits
    assert abs(r.u - u_exact) < 4.0 * se_u
    assert abs(r.u - u_pub) <= unit + 4.0 * se_u
    assert abs(r.value) < 4.0 * u_exact / 1000.0
    # shortest 95 % interval: published ± half a unit of its last digit, plus 4 standard errors
    for side, sign in ((0, -1.0), (1, 1.0)):
        end = r.interval_shortest[side]
        se_e = _se(y, _short(0.95, side))
        assert abs(end - sign * e_exact) < 4.0 * se_e, (case, side, end, e_exact, se_e)
        assert abs(end - sign * e_pub) <= 0.5 * unit + 4.0 * se_e, (case, side, end)
    # the exact endpoints reproduce the published digits (the check above is meaningful)
    assert round(e_exact / unit) * unit == pytest.approx(e_pub)


@pytest.mark.parametrize("case", sorted(ADDITIVE))
def test_additive_model_adaptive(case: str) -> None:
    inputs, u_pub, e_pub, unit, u_exact, e_exact = ADDITIVE[case]
    r = _one(monte_carlo(_additive, inputs, ndigits=2))
    assert r.converged
    assert r.trials % 10_000 == 0 and r.trials >= 20_000
    delta = numerical_tolerance(r.u, 2)
    assert delta == r.tolerance
    # the adaptive procedure aims at u and the endpoints within δ (2·s ≤ δ)
    assert abs(r.u - u_exact) <= delta
    assert abs(r.interval_shortest[0] + e_exact) <= delta
    assert abs(r.interval_shortest[1] - e_exact) <= delta
    assert abs(r.u - u_pub) <= delta + unit
    assert abs(r.interval_shortest[1] - e_pub) <= delta + 0.5 * unit


def test_published_924_gum_column_and_its_failed_validation() -> None:
    # JCGM 101 §9.2.4, Table 4: the GUM column gives u(y) = 10.2 (the exact √(3·1 + 10²) = 10.149
    # rounded up) and the interval ±19.9; the Monte Carlo interval is ±17.0, so the GUM framework
    # is NOT validated there (§9.2.4: one rectangular input dominates).
    inputs = ADDITIVE["9.2.4"][0]
    gum = propagate(
        lambda a, b, c, d: a + b + c + d,
        [Input.from_distribution(name, dist) for name, dist in inputs.items()],
    )
    assert float(gum.u[0]) == pytest.approx(math.sqrt(103.0), rel=1e-12)
    assert math.isinf(float(gum.dof_eff[0]))
    assert float(gum.U[0]) == pytest.approx(19.9, abs=0.05)  # published GUM interval
    mc = _one(monte_carlo(_additive, inputs, trials=200_000, seed=7))
    check = validate_gum(gum, mc, ndigits=2)
    assert check["passed"] is False
    # the ends differ by ≈ 19.9 − 17.0 (published) on both sides
    assert check["d_low"] == pytest.approx(19.9 - 17.0, abs=0.2)
    assert check["d_high"] == pytest.approx(19.9 - 17.0, abs=0.2)


# ------------------------------------------------------------------------------ JCGM 101 §9.3
RHO_A0 = 1.2  # kg/m³
M_NOM = 100_000.0  # mg
MASS_INPUTS = {
    "m_rc": Normal(100_000.000, 0.050),  # mg
    "dm_rc": Normal(1.234, 0.020),  # mg
    "rho_a": Rectangular(1.10, 1.30),  # kg/m³
    "rho_w": Rectangular(7000.0, 9000.0),  # kg/m³
    "rho_r": Rectangular(7950.0, 8050.0),  # kg/m³
}


def _mass(m_rc, dm_rc, rho_a, rho_w, rho_r):  # type: ignore[no-untyped-def]
    return (m_rc + dm_rc) * (1.0 + (rho_a - RHO_A0) * (1.0 / rho_w - 1.0 / rho_r)) - M_NOM


def _mass_exact() -> tuple[float, float]:
    """Exact mean and std of δm: with A = m + δm, B = ρ_a − ρ_a0, C = 1/ρ_W − 1/ρ_R independent,
    E[B] = 0 → E[δm] = E[A] − m_nom and Var = Var A + E[A²]·Var B·E[C²]."""
    ea, va = 100_001.234, 0.05**2 + 0.02**2
    vb = 0.2**2 / 12.0

    def m1(a: float, b: float) -> float:  # E[1/ρ], ρ ~ R(a, b)
        return math.log(b / a) / (b - a)

    def m2(a: float, b: float) -> float:  # E[1/ρ²]
        return (1.0 / a - 1.0 / b) / (b - a)

    ec2 = m2(7000, 9000) - 2.0 * m1(7000, 9000) * m1(7950, 8050) + m2(7950, 8050)
    return ea - M_NOM, math.sqrt(va + (ea**2 + va) * vb * ec2)


def test_mass_calibration_fixed() -> None:
    r = _one(monte_carlo(_mass, MASS_INPUTS, trials=1_000_000))
    mean_x, u_x = _mass_exact()
    se_u = _se(r.samples, lambda b: float(np.std(b, ddof=1)))
    # published Monte Carlo: 1.2341 mg, u = 0.0754 mg (±1 in the last digit of the rounded value)
    assert abs(round(r.value, 4) - 1.2341) <= 1e-4 + 1e-12
    assert abs(round(r.u, 4) - 0.0754) <= 1e-4 + 1e-12
    # and the exact values (1.2340 mg, 0.07548 mg) within the Monte Carlo error
    assert abs(r.value - mean_x) < 4.0 * u_x / 1000.0
    assert abs(r.u - u_x) < 4.0 * se_u
    # shortest 95 % interval about [1.083, 1.383] mg
    assert r.interval_shortest[0] == pytest.approx(1.083, abs=0.002)
    assert r.interval_shortest[1] == pytest.approx(1.383, abs=0.002)


def test_mass_calibration_adaptive_and_gum_not_validated() -> None:
    r = _one(monte_carlo(_mass, MASS_INPUTS, ndigits=2))
    mean_x, u_x = _mass_exact()
    assert r.converged and r.trials > 100_000
    assert abs(r.u - u_x) <= r.tolerance
    assert abs(r.value - mean_x) <= r.tolerance
    gum = propagate(
        lambda m, dm, ra, rw, rr: _mass(m, dm, ra, rw, rr),
        [Input.from_distribution(name, d) for name, d in MASS_INPUTS.items()],
    )
    # first-order GUM: 1.2340 mg, u = 0.0539 mg, [1.1285, 1.3395] mg (JCGM 101 §9.3)
    assert float(gum.u[0]) == pytest.approx(0.0539, abs=1e-4)
    check = validate_gum(gum, r, ndigits=2)
    assert check["passed"] is False
    assert check["delta"] == pytest.approx(0.0005)
    assert check["d_low"] > 0.02 and check["d_high"] > 0.02
    assert check["gum_interval"][0] == pytest.approx(1.1285, abs=2e-4)


def test_validate_gum_passes_for_the_normal_additive_model() -> None:
    inputs = ADDITIVE["9.2.2"][0]
    gum = propagate(
        lambda a, b, c, d: a + b + c + d,
        [Input.from_distribution(name, dist) for name, dist in inputs.items()],
    )
    mc = _one(monte_carlo(_additive, inputs, trials=1_000_000))
    check = validate_gum(gum, mc, ndigits=2)
    assert check["passed"] is True
    assert check["delta"] == pytest.approx(0.05)
    assert max(check["d_low"], check["d_high"]) < 0.05
    # the symmetric Monte Carlo interval validates it too
    assert validate_gum(gum, mc, shortest=False)["passed"] is True
    # a Monte Carlo result at another p is refused
    mc99 = _one(monte_carlo(_additive, inputs, trials=100_000, p=0.99))
    with pytest.raises(ConfigError, match=r"p = 0\.95"):
        validate_gum(gum, mc99)


# ------------------------------------------------------------------------------ JCGM 101 §9.5
L_S = 50_000_623.6  # nm
GAUGE_INPUTS = {
    "l_s": StudentT(L_S, 25.0, 18),  # nm
    "d": StudentT(215.0, 5.8, 24),  # nm
    "d1": StudentT(0.0, 3.9, 5),  # nm
    "d2": StudentT(0.0, 6.7, 8),  # nm
    "alpha_s": Rectangular(9.5e-6, 13.5e-6),  # 1/°C
    "theta_bar": Normal(-0.1, 0.2),  # °C
    "delta": Arcsine(0.0, 0.5),  # °C
    "d_alpha": CurvilinearTrapezoid(0.0, 1e-6, 0.1e-6),  # 1/°C
    "d_theta": CurvilinearTrapezoid(0.0, 0.050, 0.025),  # °C
}


def _gauge_nonlinear(l_s, d, d1, d2, alpha_s, theta_bar, delta, d_alpha, d_theta):  # type: ignore[no-untyped-def]
    """Deviation from 50 mm (nm) of L = [l_s(1 + α_s θ_s) + D]/(1 + α θ), θ_s = θ − δθ,
    α = α_s + δα (from D = L(1 + αθ) − l_s(1 + α_s θ_s), GUM H.1.1)."""
    theta = theta_bar + delta
    big_d = d + d1 + d2
    length = (l_s * (1.0 + alpha_s * (theta - d_theta)) + big_d) / (
        1.0 + (alpha_s + d_alpha) * theta
    )
    return length - 50_000_000.0


def _gauge_linear(l_s, d, d1, d2, alpha_s, theta_bar, delta, d_alpha, d_theta):  # type: ignore[no-untyped-def]
    """GUM H.1 first-order model l = l_s + d − l_s(δα·θ + α_s·δθ), as a deviation from 50 mm."""
    theta = theta_bar + delta
    return l_s - 50_000_000.0 + d + d1 + d2 - l_s * (d_alpha * theta + alpha_s * d_theta)


def _gauge_linear_exact_u() -> float:
    """Exact u of the linear model: l = A(1 − B) + D with A, B, D independent, E[B] = 0:
    Var = Var A + E[A²]·E[B²] + Var D, E[B²] = Var δα·E[θ²] + E[α_s²]·Var δθ."""
    var_a = 25.0**2 * 18 / 16
    var_d = 5.8**2 * 24 / 22 + 3.9**2 * 5 / 3 + 6.7**2 * 8 / 6
    e_theta2 = 0.1**2 + 0.2**2 + 0.5**2 / 2
    var_dalpha = (1e-6) ** 2 / 3 + (0.1e-6) ** 2 / 9
    var_dtheta = 0.05**2 / 3 + 0.025**2 / 9
    e_alpha2 = 11.5e-6**2 + (2e-6) ** 2 / 3
    e_b2 = var_dalpha * e_theta2 + e_alpha2 * var_dtheta
    return math.sqrt(var_a + (L_S**2 + var_a) * e_b2 + var_d)


def test_gauge_block_full_distributions() -> None:
    r = _one(monte_carlo(_gauge_nonlinear, GAUGE_INPUTS, p=0.99, ndigits=2))
    assert r.converged
    # published Monte Carlo: 838 nm, u = 36 nm, shortest 99 % interval [745, 932] nm (±1 nm)
    assert r.value == pytest.approx(838.0, abs=1.0)
    assert r.u == pytest.approx(36.0, abs=1.0)
    assert r.interval_shortest[0] == pytest.approx(745.0, abs=1.0)
    assert r.interval_shortest[1] == pytest.approx(932.0, abs=1.0)
    # exact expectation 838.6 nm (E[δα·θ] = E[α_s·δθ] = 0) and exact u of the linearised model
    assert abs(r.value - 838.6) <= r.tolerance
    assert abs(r.u - _gauge_linear_exact_u()) <= r.tolerance
    # the first-order (GUM H.1) model gives the same numbers to well below 1 nm
    lin = _one(monte_carlo(_gauge_linear, GAUGE_INPUTS, p=0.99, trials=r.trials))
    assert lin.value == pytest.approx(r.value, abs=0.05)
    assert lin.u == pytest.approx(r.u, abs=0.05)
    assert lin.interval_shortest[0] == pytest.approx(r.interval_shortest[0], abs=0.2)


# ------------------------------------------------------------------------------------ JCGM 102
def _magnitude(re: np.ndarray, im: np.ndarray) -> np.ndarray:
    return np.hypot(re, im)


MAG_INPUTS = {"re": Normal(0.001, 0.01), "im": Normal(0.0, 0.01)}


def test_magnitude_near_zero_independent() -> None:
    r = _one(monte_carlo(_magnitude, MAG_INPUTS, trials=1_000_000))
    # published: |Z| = 0.013, u = 0.007
    assert round(r.value, 3) == pytest.approx(0.013)
    assert round(r.u, 3) == pytest.approx(0.007)
    # exact: |Z| is Rice-distributed, b = 0.001/0.01, scale 0.01
    rice = stats.rice(0.1, scale=0.01)
    assert abs(r.value - rice.mean()) < 4.0 * rice.std() / 1000.0
    assert r.u == pytest.approx(rice.std(), rel=0.005)


def test_magnitude_near_zero_correlated() -> None:
    corr = [[1.0, 0.9], [0.9, 1.0]]
    r = _one(monte_carlo(_magnitude, MAG_INPUTS, trials=1_000_000, correlation=corr))
    # published with r(Re, Im) = 0.9: 0.012, 0.008
    assert round(r.value, 3) == pytest.approx(0.012)
    assert round(r.u, 3) == pytest.approx(0.008)
    # exact: E|Z|² = μ² + 2σ² whatever the correlation; E|Z| by quadrature of the bivariate normal
    assert r.value**2 + r.u**2 == pytest.approx(0.001**2 + 2 * 0.01**2, rel=0.01)
    cov = 1e-4 * np.array(corr)
    # the bivariate normal density written out (scipy's multivariate_normal.pdf, called once per
    # point by dblquad, took a second for the same integral)
    (a, b), (_, d) = np.linalg.inv(cov)
    norm = 1.0 / (2.0 * math.pi * math.sqrt(np.linalg.det(cov)))

    def integrand(y: float, x: float) -> float:
        dx = x - 0.001
        return math.hypot(x, y) * norm * math.exp(-0.5 * (a * dx * dx + 2 * b * dx * y + d * y * y))

    e_abs = integrate.dblquad(integrand, -0.08, 0.08, -0.08, 0.08, epsabs=1e-10)[0]
    assert r.value == pytest.approx(e_abs, rel=0.003)
    # the correlation matters: the uncorrelated answer is different
    r0 = _one(monte_carlo(_magnitude, MAG_INPUTS, trials=1_000_000))
    assert abs(r0.value - r.value) > 5e-4
    # a mapping of named pairs works as well
    r_named = _one(
        monte_carlo(_magnitude, MAG_INPUTS, trials=1_000_000, correlation={("re", "im"): 0.9})
    )
    assert r_named.value == r.value


# --------------------------------------------------------------------------- faults and settings
def test_non_psd_correlation_is_one_line() -> None:
    inputs = {"a": Normal(0, 1), "b": Normal(0, 1), "c": Normal(0, 1)}
    corr = [[1.0, 0.9, 0.9], [0.9, 1.0, -0.9], [0.9, -0.9, 1.0]]
    with pytest.raises(ConfigError) as err:
        monte_carlo(lambda a, b, c: a + b + c, inputs, correlation=corr, trials=10_000)
    assert "positive semi-definite" in str(err.value)
    assert "\n" not in str(err.value)


def test_correlation_with_a_non_normal_input() -> None:
    inputs = {"a": Normal(0, 1), "b": Rectangular(0, 1)}
    with pytest.raises(ConfigError) as err:
        monte_carlo(lambda a, b: a + b, inputs, correlation=[[1, 0.5], [0.5, 1]], trials=10_000)
    msg = str(err.value)
    assert "'b' (rectangular)" in msg and "only among Normal inputs" in msg
    assert "MultivariateNormal" in msg and "\n" not in msg


def test_multivariate_normal_input() -> None:
    cov = [[1.0, 0.5], [0.5, 4.0]]
    r = _one(
        monte_carlo(
            lambda v: v[:, 0] + v[:, 1],
            {"v": MultivariateNormal([0.0, 1.0], cov)},
            trials=1_000_000,
        )
    )
    # Var(v₀ + v₁) = 1 + 4 + 2·0.5 = 6
    assert r.u == pytest.approx(math.sqrt(6.0), rel=0.005)
    assert r.value == pytest.approx(1.0, abs=0.01)


@pytest.mark.parametrize("trials", [200_000, None])
def test_same_seed_same_result_for_any_batch(trials: int | None) -> None:
    a = _one(monte_carlo(_mass, MASS_INPUTS, trials=trials, batch=10_000, ndigits=1))
    b = _one(monte_carlo(_mass, MASS_INPUTS, trials=trials, batch=100_000, ndigits=1))
    assert a.trials == b.trials
    assert a.to_dict() == b.to_dict()
    np.testing.assert_array_equal(a.samples, b.samples)
    c = _one(monte_carlo(_mass, MASS_INPUTS, trials=trials, seed=7, ndigits=1))
    assert c.value != a.value


def test_correlated_inputs_are_reproducible_across_batches() -> None:
    corr = [[1.0, 0.9], [0.9, 1.0]]
    a = _one(monte_carlo(_magnitude, MAG_INPUTS, trials=50_000, correlation=corr, batch=10_000))
    b = _one(monte_carlo(_magnitude, MAG_INPUTS, trials=50_000, correlation=corr, batch=30_000))
    np.testing.assert_array_equal(a.samples, b.samples)


def test_model_returning_nan_names_the_output() -> None:
    with pytest.raises(ConfigError) as err:
        monte_carlo(
            lambda a, b: {"ratio": a / b, "sqrt_a": np.sqrt(a)},
            {"a": Normal(0.0, 1.0), "b": Rectangular(1.0, 2.0)},
            trials=10_000,
        )
    msg = str(err.value)
    assert "'sqrt_a'" in msg and "NaN or infinite" in msg and "a=" in msg
    assert "\n" not in msg


def test_model_with_wrong_shape() -> None:
    with pytest.raises(ConfigError, match=r"shape \(\), expected \(10000,\)"):
        monte_carlo(lambda a: float(np.mean(a)), {"a": Normal(0.0, 1.0)}, trials=10_000)
    with pytest.raises(ConfigError, match="shape"):
        monte_carlo(lambda a: np.stack([a, a]), {"a": Normal(0.0, 1.0)}, trials=10_000)


def test_several_outputs() -> None:
    res = monte_carlo(
        lambda a, b: {"sum": a + b, "diff": a - b},
        {"a": Normal(1.0, 0.3), "b": Normal(2.0, 0.4)},
        trials=1_000_000,
    )
    assert isinstance(res, dict) and set(res) == {"sum", "diff"}
    assert res["sum"].output == "sum"
    assert res["sum"].value == pytest.approx(3.0, abs=0.002)
    assert res["diff"].u == pytest.approx(0.5, rel=0.005)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"p": 1.0}, "strictly between 0 and 1"),
        ({"trials": 100}, "too few"),
        ({"ndigits": 0}, "ndigits"),
        ({"seed": -1}, "seed"),
        ({"max_trials": 10_000}, "max_trials"),
    ],
)
def test_bad_settings(kwargs: dict[str, object], match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        monte_carlo(lambda a: a, {"a": Normal(0.0, 1.0)}, **kwargs)  # type: ignore[arg-type]


def test_bad_inputs() -> None:
    with pytest.raises(ConfigError, match="not a Distribution"):
        monte_carlo(lambda a: a, {"a": 1.0}, trials=10_000)  # type: ignore[dict-item]
    with pytest.raises(ConfigError, match="identifier"):
        monte_carlo(lambda a: a, {"a b": Normal(0, 1)}, trials=10_000)


def test_adaptive_stops_at_max_trials_without_converging() -> None:
    r = _one(monte_carlo(_mass, MASS_INPUTS, ndigits=4, max_trials=50_000))
    assert r.converged is False
    assert r.trials == 50_000


def test_progress_is_reported() -> None:
    seen: list[tuple[int, int]] = []
    monte_carlo(
        lambda a: a,
        {"a": Normal(0.0, 1.0)},
        trials=250_000,
        progress=lambda d, t: seen.append((d, t)),
    )
    assert seen == [(100_000, 250_000), (200_000, 250_000), (250_000, 250_000)]


# --------------------------------------------------------------------------- coverage intervals
def test_coverage_interval_index_rules() -> None:
    # JCGM 101 §7.7.1 by hand. M = 100, p = 0.9: q = 90, r = (100 − 90)/2 = 5 → [y₍₅₎, y₍₉₅₎]
    y = np.random.default_rng(1).permutation(np.arange(1.0, 101.0))
    assert coverage_interval(y, 0.9) == (5.0, 95.0)
    # equally spaced values: every interval has the same width, the first (r = 1) is taken
    assert coverage_interval(y, 0.9, shortest=True) == (1.0, 91.0)
    # M = 101, p = 0.95: pM = 95.95 → q = 96; M − q = 5 → r = int((5 + 1)/2) = 3 → [y₍₃₎, y₍₉₉₎]
    assert coverage_interval(np.arange(1.0, 102.0), 0.95) == (3.0, 99.0)
    with pytest.raises(CaptureError, match="too few"):
        coverage_interval(np.arange(10.0), 0.95)
    with pytest.raises(CaptureError, match="NaN"):
        coverage_interval(np.array([1.0, math.nan] * 100), 0.5)


def test_shortest_interval_of_a_skewed_sample() -> None:
    y = np.random.default_rng(2).exponential(1.0, 1_000_000)
    lo, hi = coverage_interval(y, 0.95, shortest=True)
    # exponential: the shortest 95 % interval is [0, −ln 0.05]
    assert lo < 1e-3
    assert hi == pytest.approx(-math.log(0.05), abs=0.02)
    slo, shi = coverage_interval(y, 0.95)
    # probabilistically symmetric: [−ln 0.975, −ln 0.025]
    assert slo == pytest.approx(-math.log(0.975), abs=0.002)
    assert shi == pytest.approx(-math.log(0.025), abs=0.03)
    assert (hi - lo) < (shi - slo) - 0.6


def test_numerical_tolerance() -> None:
    # JCGM 101 §7.9.2: u = 0.0754 at two digits is 75·10⁻³ → δ = 0.0005
    assert numerical_tolerance(0.0754, 2) == pytest.approx(0.0005)
    assert numerical_tolerance(2.0, 2) == pytest.approx(0.05)
    assert numerical_tolerance(35.7, 2) == pytest.approx(0.5)
    assert numerical_tolerance(35.7, 1) == pytest.approx(5.0)
    assert numerical_tolerance(0.0996, 2) == pytest.approx(0.005)  # rounds to 0.10
    assert numerical_tolerance(0.0, 2) == 0.0


def test_result_json_leaves_the_samples_out() -> None:
    r = _one(monte_carlo(lambda a: a, {"a": Normal(0.0, 1.0)}, trials=10_000))
    d = r.to_dict()
    assert "_samples" not in d and d["trials"] == 10_000
    assert set(d) >= {
        "value",
        "u",
        "p",
        "trials",
        "seed",
        "interval_symmetric",
        "interval_shortest",
        "converged",
    }
