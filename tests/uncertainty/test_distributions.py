"""Distributions of JCGM 101 §6.4 against closed forms, scipy.stats and 10⁶ samples.

The expected moments are written here from the textbook formulas (GUM §4.3, JCGM 101 §6.4) or
taken from scipy.stats — never from the code under test. The curvilinear trapezoid, which scipy
does not have, is checked against a variance and a CDF derived below from its definition.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from rotacal.errors import ConfigError
from rotacal.uncertainty.distributions import (
    Arcsine,
    Constant,
    CurvilinearTrapezoid,
    Distribution,
    MultivariateNormal,
    Normal,
    Rectangular,
    StudentT,
    Trapezoidal,
    Triangular,
    distribution_from_spec,
)

N = 1_000_000


def _rng(tag: int) -> np.random.Generator:
    return np.random.default_rng(20260 + tag)


# --------------------------------------------------------------------------- closed-form moments
CASES: list[tuple[str, Distribution, float, float]] = [
    # (label, distribution, expected mean, expected std) — std from the GUM/JCGM 101 formula
    ("normal", Normal(3.0, 0.7), 3.0, 0.7),
    ("rectangular", Rectangular(1.10, 1.30), 1.20, 0.20 / math.sqrt(12.0)),  # GUM eq. (7)
    ("rectangular.centered", Rectangular.centered(11.5e-6, 2e-6), 11.5e-6, 2e-6 / math.sqrt(3)),
    ("triangular", Triangular(-2.0, 4.0), 1.0, 6.0 / math.sqrt(24.0)),  # GUM §4.3.9
    # general triangular: var = (a² + b² + c² − ab − ac − bc)/18 with a=0, b=3, c=1 → 7/18
    ("triangular mode", Triangular(0.0, 3.0, 1.0), 4.0 / 3.0, math.sqrt(7.0 / 18.0)),
    # trapezoid: u² = (b − a)²(1 + β²)/24 (GUM §4.3.9, JCGM 101 §6.4.4.3)
    ("trapezoidal", Trapezoidal(-1.0, 1.0, 0.4), 0.0, 2.0 * math.sqrt(1.16 / 24.0)),
    # half-width W ~ R(a − d, a + d), X | W ~ R(−W, W): Var X = E[W²]/3 = (a² + d²/3)/3 = a²/3 + d²/9
    (
        "curvilinear trapezoid",
        CurvilinearTrapezoid(0.5, 0.05, 0.025),
        0.5,
        math.sqrt(0.05**2 / 3 + 0.025**2 / 9),
    ),
    ("arcsine", Arcsine(-0.1, 0.5), -0.1, 0.5 / math.sqrt(2.0)),  # JCGM 101 §6.4.6.3
    ("t", StudentT(215.0, 5.8, 24), 215.0, 5.8 * math.sqrt(24.0 / 22.0)),  # JCGM 101 §6.4.9.3
    ("t nu=10", StudentT(0.0, 2.0, 10), 0.0, 2.0 * math.sqrt(10.0 / 8.0)),
    ("constant", Constant(42.0), 42.0, 0.0),
]


@pytest.mark.parametrize(("label", "dist", "mean", "std"), CASES, ids=[c[0] for c in CASES])
def test_moments_closed_form(label: str, dist: Distribution, mean: float, std: float) -> None:
    assert dist.mean == pytest.approx(mean, rel=1e-12, abs=1e-15)
    assert dist.std == pytest.approx(std, rel=1e-12, abs=1e-15)


@pytest.mark.parametrize(("label", "dist", "mean", "std"), CASES, ids=[c[0] for c in CASES])
def test_moments_of_one_million_samples(
    label: str, dist: Distribution, mean: float, std: float
) -> None:
    x = dist.sample(_rng(1), N)
    assert x.shape == (N,)
    assert x.dtype == np.float64
    if std == 0.0:
        assert np.all(x == mean)
        return
    # sampling errors: SE(mean) = σ/√N; SE(s) ≈ √((m₄ − s⁴)/N)/(2s) from the sample's 4th moment
    se_mean = std / math.sqrt(N)
    c = x - x.mean()
    s = float(np.sqrt(np.mean(c**2)))
    se_std = math.sqrt((float(np.mean(c**4)) - s**4) / N) / (2.0 * s)
    assert abs(float(x.mean()) - mean) < 5.0 * se_mean
    assert abs(float(x.std(ddof=1)) - std) < 5.0 * se_std


SCIPY_CASES: list[tuple[str, Distribution, stats.rv_continuous]] = [
    ("rectangular", Rectangular(1.10, 1.30), stats.uniform(1.10, 0.20)),
    ("triangular", Triangular(-2.0, 4.0), stats.triang(0.5, loc=-2.0, scale=6.0)),
    ("triangular mode", Triangular(0.0, 3.0, 1.0), stats.triang(1.0 / 3.0, loc=0.0, scale=3.0)),
    ("normal", Normal(3.0, 0.7), stats.norm(3.0, 0.7)),
    ("t", StudentT(215.0, 5.8, 24), stats.t(24, loc=215.0, scale=5.8)),
    ("t nu=3", StudentT(0.0, 1.0, 3), stats.t(3)),
    # arcsine = beta(½, ½) on [m − a, m + a]
    ("arcsine", Arcsine(-0.1, 0.5), stats.beta(0.5, 0.5, loc=-0.6, scale=1.0)),
    ("trapezoidal", Trapezoidal(-1.0, 1.0, 0.4), stats.trapezoid(0.3, 0.7, loc=-1.0, scale=2.0)),
]


@pytest.mark.parametrize(("label", "dist", "ref"), SCIPY_CASES, ids=[c[0] for c in SCIPY_CASES])
def test_against_scipy(label: str, dist: Distribution, ref: stats.rv_continuous) -> None:
    assert dist.mean == pytest.approx(float(ref.mean()), rel=1e-9, abs=1e-12)
    assert dist.std == pytest.approx(float(ref.std()), rel=1e-9)
    x = dist.sample(_rng(2), 200_000)
    # Kolmogorov–Smirnov: a wrong shape or scale gives p ≪ 1e-6 at this sample size
    assert stats.kstest(x, ref.cdf).pvalue > 1e-4


def _ctrap_cdf(x: np.ndarray, m: float, a: float, d: float) -> np.ndarray:
    """CDF of the curvilinear trapezoid, derived from its definition (not from the sampler).

    W ~ R(lo, hi), lo = a − d, hi = a + d; X | W ~ R(m − W, m + W). For t = |x − m| and
    c = clip(t, lo, hi): P(|X − m| ≤ t) = [(c − lo) + ∫_c^hi t/w dw]/(2d) = [(c − lo) + t·ln(hi/c)]/(2d),
    and F(x) = ½ ± ½·P(|X − m| ≤ |x − m|) by symmetry.
    """
    lo, hi = a - d, a + d
    t = np.minimum(np.abs(x - m), hi)
    c = np.clip(t, lo, hi)
    inside = ((c - lo) + t * np.log(hi / c)) / (2.0 * d)
    return 0.5 + 0.5 * np.sign(x - m) * np.minimum(inside, 1.0)


def test_curvilinear_trapezoid_distribution() -> None:
    dist = CurvilinearTrapezoid(0.0, 1.0, 0.3)
    x = dist.sample(_rng(3), 200_000)
    assert np.all(np.abs(x) <= 1.3)
    assert np.any(np.abs(x) > 1.2)  # the limits really move beyond a
    assert stats.kstest(x, lambda v: _ctrap_cdf(v, 0.0, 1.0, 0.3)).pvalue > 1e-4
    # the KS test can fail: a plain rectangular ±1 is rejected
    wrong = Rectangular.centered(0.0, 1.0).sample(_rng(4), 200_000)
    assert stats.kstest(wrong, lambda v: _ctrap_cdf(v, 0.0, 1.0, 0.3)).pvalue < 1e-6
    # the CDF derived above integrates back to the closed-form variance a²/3 + d²/9
    grid = np.linspace(0.0, 1.3, 200_001)
    second_moment = 2.0 * np.trapezoid(2.0 * grid * (1.0 - _ctrap_cdf(grid, 0.0, 1.0, 0.3)), grid)
    assert second_moment == pytest.approx(1.0 / 3.0 + 0.09 / 9.0, rel=1e-6)
    assert dist.std**2 == pytest.approx(1.0 / 3.0 + 0.09 / 9.0, rel=1e-12)


def test_student_t_std_is_infinite_for_nu_at_most_two() -> None:
    assert math.isinf(StudentT(0.0, 1.0, 2).std)
    assert StudentT(0.0, 1.0, math.inf).std == 1.0


def test_multivariate_normal() -> None:
    cov = np.array([[4.0, -1.2, 0.0], [-1.2, 1.0, 0.3], [0.0, 0.3, 0.25]])
    dist = MultivariateNormal([1.0, 2.0, 3.0], cov)
    x = dist.sample(_rng(5), N)
    assert x.shape == (N, 3)
    np.testing.assert_allclose(dist.std, [2.0, 1.0, 0.5])
    np.testing.assert_allclose(x.mean(axis=0), [1.0, 2.0, 3.0], atol=5 * 2.0 / math.sqrt(N))
    np.testing.assert_allclose(np.cov(x.T), cov, atol=0.02)
    # a perfectly correlated (singular, semi-definite) covariance still samples
    y = MultivariateNormal([0.0, 0.0], [[1.0, 1.0], [1.0, 1.0]]).sample(_rng(6), 1000)
    np.testing.assert_allclose(y[:, 0], y[:, 1], atol=1e-12)
    with pytest.raises(ConfigError, match="positive semi-definite"):
        MultivariateNormal([0.0, 0.0], [[1.0, 2.0], [2.0, 1.0]])
    with pytest.raises(ConfigError, match="square"):
        MultivariateNormal([0.0, 0.0], np.eye(3))


def test_describe_and_name() -> None:
    assert Rectangular.centered(11.5e-6, 2e-6).describe() == "rectangular ±2e-06"
    assert Rectangular(0, 1).name == "rectangular"
    assert Normal(0, 1).name == "normal"
    assert StudentT(0, 1, 5).name == "t"
    assert "arcsine" in Arcsine(0, 0.5).describe()
    assert "curvilinear trapezoid" in CurvilinearTrapezoid(0, 1, 0.1).describe()
    assert Normal(0, 1, 9).dof == 9.0
    assert math.isinf(Rectangular(0, 1).dof)
    assert math.isinf(Constant(1.0).dof)


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: Normal(0.0, -1.0), "std must be ≥ 0"),
        (lambda: Rectangular(2.0, 1.0), "lower"),
        (lambda: Triangular(0.0, 1.0, 2.0), "mode"),
        (lambda: Trapezoidal(0.0, 1.0, 1.5), "beta"),
        (lambda: CurvilinearTrapezoid(0.0, 1.0, 2.0), "exceeds"),
        (lambda: StudentT(0.0, 1.0, 0.0), "dof"),
        (lambda: Normal(math.nan, 1.0), "finite"),
    ],
)
def test_invalid_parameters(make: object, match: str) -> None:
    with pytest.raises(ConfigError, match=match):
        make()  # type: ignore[operator]


# ------------------------------------------------------------------------------ from the spec
@pytest.mark.parametrize(
    ("spec", "cls", "mean", "std"),
    [
        ({"distribution": "normal", "value": 1.0, "u": 0.2}, Normal, 1.0, 0.2),
        ({"distribution": "Gaussian", "value": 1.0, "U": 0.4, "k": 2}, Normal, 1.0, 0.2),
        (
            {"distribution": "rectangular", "value": 0.0, "half_width": 1.0},
            Rectangular,
            0.0,
            1 / math.sqrt(3),
        ),
        (
            {"distribution": "uniform", "lower": 1.1, "upper": 1.3},
            Rectangular,
            1.2,
            0.1 / math.sqrt(3),
        ),
        ({"distribution": "rectangular", "value": 5.0, "u": 0.5}, Rectangular, 5.0, 0.5),
        (
            {"distribution": "triangular", "value": 0.0, "half_width": 2.0},
            Triangular,
            0.0,
            2 / math.sqrt(6),
        ),
        (
            {"distribution": "triangular", "lower": 0.0, "upper": 3.0, "mode": 1.0},
            Triangular,
            4 / 3,
            math.sqrt(7 / 18),
        ),
        (
            {"distribution": "trapezoidal", "value": 0.0, "half_width": 1.0, "beta": 0.4},
            Trapezoidal,
            0.0,
            math.sqrt(4 * 1.16 / 24),
        ),
        (
            {
                "distribution": "curvilinear_trapezoid",
                "value": 0.0,
                "half_width": 0.05,
                "half_width_uncertainty": 0.025,
            },
            CurvilinearTrapezoid,
            0.0,
            math.sqrt(0.05**2 / 3 + 0.025**2 / 9),
        ),
        (
            {"distribution": "arcsine", "value": -0.1, "half_width": 0.5},
            Arcsine,
            -0.1,
            0.5 / math.sqrt(2),
        ),
        ({"distribution": "u-shaped", "value": 0.0, "u": 0.3}, Arcsine, 0.0, 0.3),
        (
            {"distribution": "t", "value": 215.0, "u": 5.8, "dof": 24},
            StudentT,
            215.0,
            5.8 * math.sqrt(24 / 22),
        ),
        ({"distribution": "constant", "value": 7.0}, Constant, 7.0, 0.0),
    ],
)
def test_from_spec_forms(spec: dict[str, object], cls: type, mean: float, std: float) -> None:
    dist = distribution_from_spec(spec, where="[inputs.x]")
    assert isinstance(dist, cls)
    assert dist.mean == pytest.approx(mean, abs=1e-12)
    assert dist.std == pytest.approx(std, rel=1e-12)


def test_from_spec_dof() -> None:
    d = distribution_from_spec(
        {"distribution": "normal", "value": 0.0, "u": 1.0, "dof": 4}, where="w"
    )
    assert d.dof == 4.0
    r = distribution_from_spec(
        {"distribution": "rectangular", "value": 0.0, "half_width": 1.0, "dof": 50}, where="w"
    )
    assert r.dof == 50.0


@pytest.mark.parametrize(
    ("spec", "fragment"),
    [
        ({"distribution": "lognormal", "value": 1.0, "u": 0.1}, "unknown distribution 'lognormal'"),
        ({"distribution": "normal", "value": 1.0, "u": -0.1}, "'u' must be ≥ 0"),
        (
            {"distribution": "rectangular", "value": 0.0, "half_width": -1.0},
            "'half_width' must be ≥ 0",
        ),
        (
            {"distribution": "rectangular", "lower": 2.0, "upper": 1.0},
            "'lower' (2) is above 'upper' (1)",
        ),
        ({"distribution": "normal", "value": 1.0, "sigma": 0.1}, "unknown key 'sigma'"),
        ({"distribution": "normal", "value": 1.0}, "missing key 'u'"),
        ({"distribution": "t", "value": 1.0, "u": 0.1}, "missing key 'dof'"),
        ({"distribution": "t", "value": 1.0, "u": 0.1, "dof": 2}, "needs dof > 2"),
        ({"distribution": "rectangular", "value": 0.0, "half_width": 1e300}, "u² overflows"),
        ({"value": 1.0, "u": 0.1}, "missing key 'distribution'"),
        ({"distribution": "normal", "value": 1.0, "U": 0.2}, "missing key 'k'"),
        ({"distribution": "normal", "value": "one", "u": 0.1}, "'value' must be a number"),
        ({"distribution": "normal", "value": 1.0, "u": True}, "'u' must be a number"),
        ({"distribution": "normal", "value": 1.0, "u": 0.1, "beta": 0.5}, "does not apply"),
        ({"distribution": "rectangular", "value": 0.0, "lower": -1.0, "upper": 1.0}, "either"),
        ({"distribution": "trapezoidal", "value": 0.0, "half_width": 1.0}, "missing key 'beta'"),
        ({"distribution": "trapezoidal", "value": 0.0, "half_width": 1.0, "beta": 2.0}, "beta"),
    ],
)
def test_from_spec_faults(spec: dict[str, object], fragment: str) -> None:
    with pytest.raises(ConfigError) as err:
        distribution_from_spec(spec, where="[inputs.l_s] in budget.toml")
    msg = str(err.value)
    assert msg.startswith("[inputs.l_s] in budget.toml: ")
    assert fragment in msg
    assert "\n" not in msg
