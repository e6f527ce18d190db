"""Tests of rotacal.uncertainty.gum against the GUM's worked examples and closed forms.

Inputs and published results: ../shared/UNCERTAINTY-EXAMPLES.md (JCGM 100:2008 Annex H,
JCGM 101:2008 §9.3). Every published number is recomputed from the inputs; the closed forms of the
linear / bilinear models are written out here independently of the code under test.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.uncertainty.budget import round_ilac
from rotacal.uncertainty.coverage import LARGE_DOF
from rotacal.uncertainty.gum import (
    GUMResult,
    Input,
    correlation_matrix,
    coverage_factor,
    linear_fit_uncertainty,
    propagate,
    welch_satterthwaite,
)

SQ3 = math.sqrt(3.0)


def published(x: float, digits: float, decimals: int) -> None:
    """x rounds to the published ``digits`` at ``decimals`` decimals (half an ulp of the print)."""
    assert abs(x - digits) <= 0.5 * 10.0**-decimals + 1e-12, (x, digits)


# ================================================================================ GUM H.1
# Model (first order): l = l_s + d − l_s·(δα·θ + α_s·δθ), in nm.
L_S = 50_000_623.6
U_D_PARTS = (5.8, 3.9, 6.7)
NU_D_PARTS = (24, 5, 8)
U_THETA = math.sqrt(0.2**2 + (0.5 / math.sqrt(2.0)) ** 2)  # θ̄ normal 0.2, Δ arcsine ±0.5


def h1_d() -> tuple[float, float]:
    u = math.sqrt(sum(v * v for v in U_D_PARTS))
    return u, welch_satterthwaite(U_D_PARTS, NU_D_PARTS)


def h1_inputs(l_s: float = L_S) -> list[Input]:
    u_d, nu_d = h1_d()
    return [
        Input("l_s", l_s, 25.0, 18, unit="nm", source="certificate"),
        Input("d", 215.0, u_d, nu_d, unit="nm", source="comparator, 3 parts"),
        Input("alpha_s", 11.5e-6, 2e-6 / SQ3, distribution="rectangular", unit="/°C"),
        Input("theta", -0.1, U_THETA, unit="°C"),
        Input("dalpha", 0.0, 1e-6 / SQ3, 50, "rectangular", unit="/°C"),
        Input("dtheta", 0.0, 0.05 / SQ3, 2, "rectangular", unit="°C"),
    ]


def h1_model(l_s, d, alpha_s, theta, dalpha, dtheta):
    return l_s + d - l_s * (dalpha * theta + alpha_s * dtheta)


def h1_closed_form(l_s: float = L_S) -> tuple[float, float]:
    """u_c and ν_eff written out by hand: c(δα) = −l_s·θ, c(δθ) = −l_s·α_s, c(l_s) = c(d) = 1."""
    u_d, nu_d = h1_d()
    c_da = l_s * 0.1 * (1e-6 / SQ3)
    c_dt = l_s * 11.5e-6 * (0.05 / SQ3)
    comps = [(25.0, 18.0), (u_d, nu_d), (c_da, 50.0), (c_dt, 2.0)]
    uc2 = sum(c * c for c, _ in comps)
    nu = uc2**2 / sum(c**4 / v for c, v in comps)
    return math.sqrt(uc2), nu


def test_h1_uncertainty_of_d_from_its_three_parts():
    u_d, nu_d = h1_d()
    assert abs(u_d - 9.68194195397) < 1e-10
    assert abs(nu_d - 25.4472507774) < 1e-9
    published(u_d, 9.7, 1)  # GUM H.1.3.2: u(d) = 9.7 nm
    published(nu_d, 25.4, 1)  # ν(d) = 25.6 in GUM (rounded intermediates); 25.4 exactly


def test_h1_gauge_block_first_order_matches_gum_and_closed_form():
    r = propagate(h1_model, h1_inputs(), p=0.99, names_out=["l"], units_out=["nm"])
    uc_ref, nu_ref = h1_closed_form()
    assert r.value[0] == pytest.approx(L_S + 215.0, abs=1e-6)
    # central differences at |y| = 5·10⁷ nm: round-off ~1e3·ε·|y| on each c_i·u_i
    assert r.u[0] == pytest.approx(uc_ref, rel=1e-7)
    assert r.dof_eff[0] == pytest.approx(nu_ref, rel=1e-6)
    # published: l = 50.000 838 mm (GUM quotes l_s to the nm), u_c = 32 nm, ν_eff = 16,
    # k = t_99(16) = 2.92, U_99 = 93 nm (= 2.92 × 32 nm from the rounded u_c)
    assert abs(r.value[0] - 50_000_838.0) < 1.0
    assert round(r.u[0]) == 32
    assert math.floor(r.dof_eff[0]) == 16
    assert round(r.k[0], 2) == 2.92
    assert r.k[0] == pytest.approx(coverage_factor(16, 0.99), rel=1e-15)
    assert abs(r.U[0] - 93.0) < 1.0  # 92.48 nm from the unrounded u_c
    assert any("truncated to 16" in note for note in r.notes)
    # sensitivities: c(l_s) = 1 − (δα·θ + α_s·δθ) = 1, c(δα) = −l_s·θ, c(δθ) = −l_s·α_s
    c = r.sensitivities[0]
    assert c[0] == pytest.approx(1.0, rel=1e-9)
    assert c[4] == pytest.approx(L_S * 0.1, rel=1e-6)
    assert c[5] == pytest.approx(-L_S * 11.5e-6, rel=1e-6)  # ulp(5e7 nm)/step ≈ 1e-7 relative
    assert abs(c[2]) < 1e-3 and abs(c[3]) < 1e-3  # zero: δθ = 0 and δα = 0


def test_h1_full_precision_with_nominal_length_in_the_products():
    """The full-precision figures evaluate the products at the nominal 50 mm (GUM H.1, Table H.1).

    Written for the deviation from nominal, y = l − 50 mm = (l_s − 50 mm) + d − L·(δα·θ + α_s·δθ)
    with L = 50 mm, so the central differences act on ~838 nm and round-off is negligible.
    """
    ins = h1_inputs(l_s=623.6)

    def deviation(dl_s, d, alpha_s, theta, dalpha, dtheta):
        return dl_s + d - 5e7 * (dalpha * theta + alpha_s * dtheta)

    r = propagate(deviation, ins, p=0.99)
    assert abs(r.u[0] - 31.6637674111) < 1e-6
    assert abs(r.dof_eff[0] - 16.7521475092) < 1e-6
    assert r.value[0] == pytest.approx(838.6, abs=1e-9)
    published(r.k[0], 2.92, 2)
    uc_ref, nu_ref = h1_closed_form(l_s=5e7)
    assert r.u[0] == pytest.approx(uc_ref, rel=1e-12)
    assert r.dof_eff[0] == pytest.approx(nu_ref, rel=1e-10)


def test_h1_second_order_terms_give_34_nm():
    r = propagate(h1_model, h1_inputs(), p=0.99, second_order=True)
    # GUM §5.1.2 note for this bilinear model: the squared mixed second derivatives
    # ∂²l/∂δα∂θ = −l_s, ∂²l/∂α_s∂δθ = −l_s, ∂²l/∂l_s∂δα = −θ, ∂²l/∂l_s∂δθ = −α_s
    # (all third derivatives of the §5.1.2-note form vanish).
    u_as, u_da, u_dt = 2e-6 / SQ3, 1e-6 / SQ3, 0.05 / SQ3
    var2 = (
        (L_S * u_da * U_THETA) ** 2
        + (L_S * u_as * u_dt) ** 2
        + (0.1 * 25.0 * u_da) ** 2
        + (11.5e-6 * 25.0 * u_dt) ** 2
    )
    uc1, _ = h1_closed_form()
    # round-off of differences of |y| = 5·10⁷ nm: ~1e-6 relative
    assert r.variance_second_order[0] == pytest.approx(var2, rel=1e-5)
    assert r.u[0] == pytest.approx(math.sqrt(uc1**2 + var2), rel=1e-7)
    assert round(r.u[0]) == 34  # GUM H.1.7
    # ν_eff stays that of the first-order terms
    assert r.dof_eff[0] == pytest.approx(h1_closed_form()[1], rel=1e-6)


def test_h1_ilac_rounding_of_the_result():
    r = propagate(h1_model, h1_inputs(), p=0.99)
    l_mm, u99_mm = r.value[0] * 1e-6, r.U[0] * 1e-6
    value_str, u_str = round_ilac(l_mm, u99_mm)
    # usual rounding of U = 92.48 nm → 92 nm; l = 50 000 838.6 nm → 50.000 839 mm
    assert (value_str, u_str) == ("50.000839", "0.000092")
    # rounded up (GUM §7.2.6) the uncertainty is the published 93 nm
    assert round_ilac(l_mm, u99_mm, round_up=True) == ("50.000839", "0.000093")
    # the published l = 50.000 838 mm comes from l_s quoted as 50.000 623 mm: within 1 nm
    assert abs(float(value_str) - 50.000838) <= 1e-6 + 1e-12


def test_h1_from_distributions_equals_the_hand_inputs():
    from rotacal.uncertainty.distributions import Arcsine, Normal, Rectangular

    u_d, nu_d = h1_d()
    ins = [
        Input.from_distribution("l_s", Normal(L_S, 25.0, dof=18), unit="nm"),
        Input.from_distribution("d", Normal(215.0, u_d, dof=nu_d), unit="nm"),
        Input.from_distribution("alpha_s", Rectangular.centered(11.5e-6, 2e-6), unit="/°C"),
        Input.from_distribution("theta_bar", Normal(-0.1, 0.2), unit="°C"),
        Input.from_distribution("Delta", Arcsine(0.0, 0.5), unit="°C"),
        Input.from_distribution("dalpha", Rectangular.centered(0.0, 1e-6, dof=50), unit="/°C"),
        Input.from_distribution("dtheta", Rectangular.centered(0.0, 0.05, dof=2), unit="°C"),
    ]

    def model(l_s, d, alpha_s, theta_bar, delta, dalpha, dtheta):
        return h1_model(l_s, d, alpha_s, theta_bar + delta, dalpha, dtheta)

    r = propagate(model, ins, p=0.99)
    ref = propagate(h1_model, h1_inputs(), p=0.99)
    assert r.u[0] == pytest.approx(ref.u[0], rel=1e-9)
    assert r.dof_eff[0] == pytest.approx(ref.dof_eff[0], rel=1e-9)
    assert ins[4].u == pytest.approx(0.5 / math.sqrt(2.0), rel=1e-15)
    assert ins[4].distribution == "arcsine"
    rows = {row.source: row for row in r.budget().rows}
    assert rows["dtheta"].distribution.startswith("rectangular")
    assert rows["dtheta"].dof == 2


def test_from_distribution_rejects_a_multivariate_distribution():
    from rotacal.uncertainty.distributions import MultivariateNormal

    mvn = MultivariateNormal(np.zeros(2), np.eye(2))
    with pytest.raises(ConfigError, match="one Input per component"):
        Input.from_distribution("v", mvn)


# ================================================================================ GUM H.2
H2_V = np.array([5.007, 4.994, 5.005, 4.990, 4.999])  # V
H2_I = np.array([19.663, 19.639, 19.640, 19.685, 19.678]) * 1e-3  # A
H2_PHI = np.array([1.0456, 1.0438, 1.0468, 1.0428, 1.0433])  # rad


def h2_inputs() -> tuple[list[Input], np.ndarray]:
    """Type A: means, standard deviations of the means, correlation of the means (= sample r)."""
    data = np.vstack([H2_V, H2_I, H2_PHI])
    n = data.shape[1]
    mean = data.mean(axis=1)
    dev = data - mean[:, None]
    cov_mean = dev @ dev.T / (n * (n - 1))  # GUM eq. (17) for the means
    u = np.sqrt(np.diag(cov_mean))
    r = cov_mean / np.outer(u, u)
    units = ("V", "A", "rad")
    ins = [
        Input(name, m, s, n - 1, unit=unit, source="Type A, 5 readings")
        for name, m, s, unit in zip(("V", "I", "phi"), mean, u, units, strict=True)
    ]
    return ins, r


def h2_model(v, i, phi):
    return np.array([v / i * np.cos(phi), v / i * np.sin(phi), v / i])


def h2_jacobian(v, i, phi):
    c, s = math.cos(phi), math.sin(phi)
    return np.array(
        [
            [c / i, -v / i**2 * c, -v / i * s],
            [s / i, -v / i**2 * s, v / i * c],
            [1.0 / i, -v / i**2, 0.0],
        ]
    )


def test_h2_type_a_inputs_match_gum_table_h2():
    ins, r = h2_inputs()
    published(ins[0].value, 4.9990, 4)
    published(ins[0].u, 0.0032, 4)
    published(ins[1].value * 1e3, 19.661, 3)
    published(ins[1].u * 1e3, 0.0095, 4)
    published(ins[2].value, 1.04446, 5)
    published(ins[2].u, 0.00075, 5)
    published(r[0, 1], -0.36, 2)
    published(r[0, 2], 0.86, 2)
    published(r[1, 2], -0.65, 2)
    # the correlation of the means equals the sample correlation of the readings
    np.testing.assert_allclose(r, np.corrcoef(np.vstack([H2_V, H2_I, H2_PHI])), rtol=1e-12)


def test_h2_resistance_reactance_impedance():
    ins, r = h2_inputs()
    res = propagate(h2_model, ins, correlation=r, names_out=["R", "X", "Z"], units_out=["Ω"] * 3)
    published(res.value[0], 127.732, 3)
    published(res.value[1], 219.847, 3)
    published(res.value[2], 254.260, 3)
    published(res.u[0], 0.071, 3)
    published(res.u[2], 0.236, 3)
    # GUM Table H.4 prints u(X) = 0.295 Ω from approach 2 (s of the five X_k: 0.29549);
    # approach 1 (this propagation) gives 0.29558 — the same to first order, one unit apart in
    # the third digit after rounding.
    assert abs(res.u[1] - 0.295) < 1e-3
    published(res.correlation[0, 1], -0.588, 3)
    published(res.correlation[0, 2], -0.485, 3)
    published(res.correlation[1, 2], 0.993, 3)
    assert np.all(res.dof_eff == 4.0)  # V, I, φ from the same 5 readings: one component, ν = 4
    np.testing.assert_allclose(res.k, coverage_factor(4, 0.95), rtol=1e-15)

    # approach 2 of GUM H.2.4, independent of propagate: R_k, X_k, Z_k of each reading set,
    # their means, standard deviations of the means and correlations.
    per = h2_model(H2_V, H2_I, H2_PHI)
    cov2 = np.cov(per) / per.shape[1]
    u2 = np.sqrt(np.diag(cov2))
    published(u2[1], 0.295, 3)
    np.testing.assert_allclose(res.value, per.mean(axis=1), rtol=1e-5)
    np.testing.assert_allclose(res.u, u2, rtol=5e-3)
    np.testing.assert_allclose(res.correlation, cov2 / np.outer(u2, u2), atol=1e-3)


def test_h2_numerical_and_analytic_jacobian_agree():
    ins, r = h2_inputs()
    num = propagate(h2_model, ins, correlation=r)
    ana = propagate(h2_model, ins, correlation=r, jacobian=h2_jacobian)
    exact = h2_jacobian(*(i.value for i in ins))
    nz = exact != 0.0
    assert np.max(np.abs(num.sensitivities[nz] / exact[nz] - 1.0)) < 1e-8
    assert np.max(np.abs(num.sensitivities[~nz])) < 1e-8 * np.max(np.abs(exact))
    np.testing.assert_allclose(ana.sensitivities, exact, rtol=0, atol=0)
    np.testing.assert_allclose(num.u, ana.u, rtol=1e-8)
    np.testing.assert_allclose(num.covariance, ana.covariance, rtol=1e-8)


def test_h2_correlation_as_named_pairs_equals_the_matrix():
    ins, r = h2_inputs()
    pairs = {("V", "I"): r[0, 1], ("V", "phi"): r[0, 2], ("phi", "I"): r[2, 1]}
    a = propagate(h2_model, ins, correlation=r)
    b = propagate(h2_model, ins, correlation=pairs)
    np.testing.assert_array_equal(a.covariance, b.covariance)


# ================================================================================ GUM H.3
H3_T = np.array(
    [21.521, 22.012, 22.512, 23.003, 23.507, 23.999, 24.513, 25.002, 25.503, 26.010, 26.511]
)
H3_B = np.array(
    [-0.171, -0.169, -0.166, -0.159, -0.164, -0.165, -0.156, -0.157, -0.159, -0.161, -0.160]
)


def test_h3_thermometer_straight_line_fit():
    fit = linear_fit_uncertainty(H3_T, H3_B, x0=20.0)
    published(fit.intercept, -0.1712, 4)
    published(fit.u_intercept, 0.0029, 4)
    published(fit.slope, 0.00218, 5)
    published(fit.u_slope, 0.00067, 5)
    published(fit.correlation, -0.930, 3)
    published(fit.residual_std, 0.0035, 4)
    assert fit.dof == 9
    # independent least squares: design matrix, lstsq, s²·(AᵀA)⁻¹
    a = np.column_stack([np.ones_like(H3_T), H3_T - 20.0])
    coef, rss, *_ = np.linalg.lstsq(a, H3_B, rcond=None)
    cov = rss[0] / 9 * np.linalg.inv(a.T @ a)
    np.testing.assert_allclose([fit.intercept, fit.slope], coef, rtol=1e-12)
    np.testing.assert_allclose(fit.covariance, cov, rtol=1e-9)


def test_h3_correction_at_30_degrees_via_propagate():
    fit = linear_fit_uncertainty(H3_T, H3_B, x0=20.0)
    ins, r = fit.inputs(unit_y="°C", unit_x="°C")
    res = propagate(
        lambda y1, y2: y1 + y2 * (30.0 - 20.0), ins, correlation=r, names_out=["b(30 °C)"]
    )
    published(res.value[0], -0.1494, 4)
    published(res.u[0], 0.0041, 4)
    assert res.dof_eff[0] == pytest.approx(9.0, rel=1e-12)
    assert res.k[0] == pytest.approx(coverage_factor(9, 0.95), rel=1e-15)
    # closed form: u² = u1² + 100·u2² + 2·10·cov
    c = fit.covariance
    assert res.u[0] == pytest.approx(math.sqrt(c[0, 0] + 100 * c[1, 1] + 20 * c[0, 1]), rel=1e-10)


def test_linear_fit_rejects_bad_data():
    with pytest.raises(CaptureError, match="at least 3 points"):
        linear_fit_uncertainty([1.0, 2.0], [1.0, 2.0])
    with pytest.raises(CaptureError, match="all x values are equal"):
        linear_fit_uncertainty([1.0, 1.0, 1.0], [1.0, 2.0, 3.0])
    with pytest.raises(CaptureError, match=r"y\[1\]"):
        linear_fit_uncertainty([1.0, 2.0, 3.0], [1.0, math.nan, 3.0])
    with pytest.raises(CaptureError, match="one y per x"):
        linear_fit_uncertainty([1.0, 2.0, 3.0], [1.0, 2.0])


# ====================================================================== JCGM 101 §9.3 (mass)
def mass_inputs() -> list[Input]:
    return [
        Input("m_Rc", 100_000.0, 0.050, unit="mg"),
        Input("dm_Rc", 1.234, 0.020, unit="mg"),
        Input("rho_a", 1.20, 0.10 / SQ3, distribution="rectangular", unit="kg/m³"),
        Input("rho_W", 8000.0, 1000.0 / SQ3, distribution="rectangular", unit="kg/m³"),
        Input("rho_R", 8000.0, 50.0 / SQ3, distribution="rectangular", unit="kg/m³"),
    ]


def mass_model(m_rc, dm_rc, rho_a, rho_w, rho_r):
    return (m_rc + dm_rc) * (1.0 + (rho_a - 1.2) * (1.0 / rho_w - 1.0 / rho_r)) - 100_000.0


def test_mass_calibration_first_and_higher_order_gum():
    first = propagate(mass_model, mass_inputs())
    published(first.value[0], 1.2340, 4)
    published(first.u[0], 0.0539, 4)
    published(first.value[0] - first.U[0], 1.1285, 4)  # k = 1.96 (ν_eff = ∞)
    published(first.value[0] + first.U[0], 1.3395, 4)
    higher = propagate(mass_model, mass_inputs(), second_order=True)
    published(higher.u[0], 0.0750, 4)  # JCGM 101 §9.3.2.3: higher-order GUM u = 0.0750 mg
    # GUM §5.1.2 note by hand: the only non-zero second derivatives are ∂²δm/∂ρ_a∂ρ_W = −m/ρ_W² and
    # ∂²δm/∂ρ_a∂ρ_R = m/ρ_R² (m = m_Rc + δm_Rc); every third-derivative term has ∂f/∂x_i = 0
    # or ∂³f = 0 at the estimates.
    m = 100_001.234
    u_a, u_w, u_r = 0.10 / SQ3, 1000.0 / SQ3, 50.0 / SQ3
    var2 = (m * u_a * u_w / 8000.0**2) ** 2 + (m * u_a * u_r / 8000.0**2) ** 2
    assert higher.variance_second_order[0] == pytest.approx(var2, rel=1e-5)


# ================================================================== W–S and coverage factors
def test_welch_satterthwaite_closed_forms():
    assert welch_satterthwaite([1.0, 1.0], [7, 7]) == pytest.approx(14.0, rel=1e-15)
    assert welch_satterthwaite([3.0], [5]) == pytest.approx(5.0, rel=1e-15)
    assert welch_satterthwaite([1.0, 1.0], [math.inf, 10]) == pytest.approx(40.0, rel=1e-15)
    assert welch_satterthwaite([2.0, -1.0], [4, 9]) == pytest.approx(
        5**2 / (16 / 4 + 1 / 9), rel=1e-15
    )
    assert welch_satterthwaite([1.0, 2.0], [math.inf, math.inf]) == math.inf
    assert welch_satterthwaite([0.0, 0.0], [3, 4]) == math.inf
    assert welch_satterthwaite([1e-200, 1e-200], [3, 3]) == pytest.approx(6.0)  # no underflow
    with pytest.raises(ConfigError, match="one ν per contribution"):
        welch_satterthwaite([1.0, 2.0], [3])
    with pytest.raises(ConfigError, match="must be > 0"):
        welch_satterthwaite([1.0, 2.0], [3, 0])


# GUM Table G.2: t_p(ν) for p = 68.27, 90, 95, 95.45, 99, 99.73 % (68.27/95.45/99.73 are the
# fractions of a normal within 1, 2, 3 σ).
TABLE_G2 = {
    1: (1.84, 6.31, 12.71, 13.97, 63.66, 235.80),
    2: (1.32, 2.92, 4.30, 4.53, 9.92, 19.21),
    4: (1.14, 2.13, 2.78, 2.87, 4.60, 6.62),
    9: (1.06, 1.83, 2.26, 2.32, 3.25, 4.09),
    10: (1.05, 1.81, 2.23, 2.28, 3.17, 3.96),
    16: (1.03, 1.75, 2.12, 2.17, 2.92, 3.54),
    20: (1.03, 1.72, 2.09, 2.13, 2.85, 3.42),
    50: (1.01, 1.68, 2.01, 2.05, 2.68, 3.16),
}
TABLE_G2_100 = (1.005, 1.660, 1.984, 2.025, 2.626, 3.077)
TABLE_G2_INF = (1.000, 1.645, 1.960, 2.000, 2.576, 3.000)
P_G2 = (math.erf(1 / math.sqrt(2)), 0.90, 0.95, math.erf(2 / math.sqrt(2)), 0.99)
P_G2 += (math.erf(3 / math.sqrt(2)),)


@pytest.mark.parametrize("nu", sorted(TABLE_G2))
def test_coverage_factor_matches_gum_table_g2(nu):
    for p, ref in zip(P_G2, TABLE_G2[nu], strict=True):
        published(coverage_factor(nu, p), ref, 2)


def test_coverage_factor_large_and_infinite_dof():
    for p, ref in zip(P_G2, TABLE_G2_100, strict=True):
        published(coverage_factor(100, p), ref, 3)
    for p, ref in zip(P_G2, TABLE_G2_INF, strict=True):
        published(coverage_factor(math.inf, p), ref, 3)
    assert abs(coverage_factor(math.inf, 0.95) - 1.959964) < 1e-6
    published(coverage_factor(16, 0.99), 2.92, 2)


def test_coverage_factor_equals_scipy_stats_bit_for_bit():
    # the quantiles come from scipy.special (cheaper to import); scipy.stats' t and normal
    # distributions must give the very same numbers, or every reported U would shift
    stats = pytest.importorskip("scipy.stats")
    for p in (*P_G2, 0.5, 0.999):
        tail = 0.5 * (1.0 - p)
        assert coverage_factor(math.inf, p) == float(stats.norm.isf(tail))
        for nu in (1, 2, 3, 16, 50, 1e4, 99_999):
            assert coverage_factor(nu, p) == float(stats.t.isf(tail, nu))
        # from LARGE_DOF on, the asymptotic series (no SciPy import): within an ulp or two
        for nu in (LARGE_DOF, 1e6, 18_000_391.0, 1e12):
            assert coverage_factor(nu, p) == pytest.approx(float(stats.t.isf(tail, nu)), rel=1e-15)
        assert coverage_factor(7.3, p, truncate=False) == float(stats.t.isf(tail, 7.3))


def test_prefetched_quantiles_are_the_same_quantiles():
    # the CLI starts importing scipy.special in a thread beside the analysis: the import
    # completes and coverage_factor's numbers are scipy's, as without it
    import sys
    import threading

    from rotacal.uncertainty.coverage import prefetch_quantiles

    prefetch_quantiles()
    for thread in threading.enumerate():
        if thread.name == "rotacal-import-quantiles":
            thread.join(timeout=60)
    assert "scipy.special" in sys.modules
    stats = pytest.importorskip("scipy.stats")
    assert coverage_factor(16.0) == float(stats.t.isf(0.5 * (1 - 0.95), 16.0))


def test_coverage_factor_truncates_fractional_dof():
    assert coverage_factor(16.7521, 0.99) == coverage_factor(16, 0.99)
    assert coverage_factor(16.7521, 0.99, truncate=False) < coverage_factor(16, 0.99)
    assert coverage_factor(9 - 1e-13, 0.95) == coverage_factor(9, 0.95)  # round-off of ν = 9
    for bad in (0.0, -1.0, math.nan):
        with pytest.raises(ConfigError, match="must be > 0"):
            coverage_factor(bad)
    with pytest.raises(ConfigError, match="truncates to 0"):
        coverage_factor(0.5)
    for bad_p in (0.0, 1.0, 95.0):
        with pytest.raises(ConfigError, match=r"must be in \(0, 1\)"):
            coverage_factor(10, bad_p)


# ====================================================================== correlation matrices
def one_line(exc: pytest.ExceptionInfo[BaseException]) -> str:
    text = str(exc.value)
    assert "\n" not in text and text.endswith(".")
    return text


@pytest.mark.parametrize(
    ("r", "match"),
    [
        ([[1, 0.2, 0], [0.3, 1, 0], [0, 0, 1]], r"not symmetric: r\[a, b\] = 0.2"),
        ([[1, 1.2, 0], [1.2, 1, 0], [0, 0, 1]], r"r\[a, b\] = 1.2 is outside"),
        ([[0.9, 0, 0], [0, 1, 0], [0, 0, 1]], r"r\[a, a\] = 0.9; the diagonal"),
        ([[1, 0.9, -0.9], [0.9, 1, 0.9], [-0.9, 0.9, 1]], "not positive semi-definite"),
        ([[1, 0], [0, 1]], r"shape \(2, 2\); give an 3×3"),
        ([[1, math.nan, 0], [math.nan, 1, 0], [0, 0, 1]], "is not finite"),
        ({("a", "q"): 0.5}, "unknown input 'q'"),
        ({("a", "b"): 0.5, ("b", "a"): 0.4}, "given twice"),
    ],
)
def test_correlation_matrix_faults_are_one_line(r, match):
    with pytest.raises(ConfigError, match=match) as exc:
        correlation_matrix(r, 3, names=["a", "b", "c"])
    one_line(exc)


def test_correlation_matrix_accepts_valid_forms():
    np.testing.assert_array_equal(correlation_matrix(None, 3), np.eye(3))
    full = correlation_matrix({(0, 2): -1.0}, 3)
    assert full[2, 0] == -1.0 and full[0, 2] == -1.0  # |r| = 1 is PSD
    m = np.array([[1.0, 0.5], [0.5, 1.0]])
    out = correlation_matrix(m, 2)
    assert out is not m


# ========================================================================== input mistakes
def test_input_mistakes_raise_config_error_naming_the_input():
    with pytest.raises(ConfigError, match=r"input 'd': u = -1.0 is negative") as exc:
        Input("d", 215.0, -1.0)
    one_line(exc)
    with pytest.raises(ConfigError, match=r"input 'd': value"):
        Input("d", math.nan, 1.0)
    with pytest.raises(ConfigError, match=r"input 'd': dof = 0.0 must be > 0"):
        Input("d", 1.0, 1.0, dof=0)
    with pytest.raises(ConfigError, match=r"input 'd': u = 'x' is not a number"):
        Input("d", 1.0, "x")  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="non-empty name"):
        Input("", 1.0, 1.0)


def test_model_mistakes_raise_config_error():
    ins = [Input("a", 1.0, 0.1), Input("b", 0.0, 0.1)]
    with pytest.raises(ConfigError, match=r"returned nan for output 'q' at the input") as exc:
        propagate(lambda a, b: a * math.nan, ins, names_out=["q"])
    one_line(exc)
    with pytest.raises(ConfigError, match=r"output 'y' with input 'b' to -0.0001 \(finite-diff"):
        propagate(lambda a, b: math.nan if b < 0 else a + b, ins)
    with pytest.raises(ConfigError, match=r"returned an array of shape \(2, 2\)"):
        propagate(lambda a, b: np.eye(2), ins)
    with pytest.raises(ConfigError, match="same number of outputs"):
        propagate(lambda a, b: np.ones(2) if a == 1.0 else np.ones(3), ins)
    with pytest.raises(ConfigError, match=r"the jacobian returned shape \(3,\)"):
        propagate(lambda a, b: a + b, ins, jacobian=lambda a, b: [1.0, 1.0, 1.0])
    with pytest.raises(ConfigError, match="appear more than once"):
        propagate(lambda a, b: a + b, [ins[0], ins[0]])
    with pytest.raises(ConfigError, match="needs uncorrelated inputs"):
        propagate(lambda a, b: a * b, ins, correlation={("a", "b"): 0.5}, second_order=True)
    with pytest.raises(ConfigError, match="2 names_out were given"):
        propagate(lambda a, b: a + b, ins, names_out=["x", "y"])
    with pytest.raises(ConfigError, match="not an Input"):
        propagate(lambda a, b: a + b, [ins[0], (0.0, 1.0)])  # type: ignore[list-item]
    with pytest.raises(ConfigError, match=r"coverage factor k = -2.0"):
        propagate(lambda a, b: a + b, ins, k=-2)


# ======================================================================== linear models
def test_linear_correlated_model_equals_matrix_closed_form():
    c = np.array([2.0, -3.0, 0.5])
    u = np.array([0.1, 0.2, 0.4])
    r = np.array([[1.0, 0.3, -0.2], [0.3, 1.0, 0.5], [-0.2, 0.5, 1.0]])
    ins = [
        Input(f"x{i}", v, s, dof)
        for i, (v, s, dof) in enumerate(zip([1, 2, 3], u, [5, 5, 5], strict=True))
    ]
    res = propagate(lambda a, b, d: c[0] * a + c[1] * b + c[2] * d, ins, correlation=r, k=2)
    expected = math.sqrt(
        sum(c[i] * c[j] * u[i] * u[j] * r[i, j] for i in range(3) for j in range(3))
    )
    assert res.u[0] == pytest.approx(expected, rel=1e-10)
    np.testing.assert_allclose(res.sensitivities[0], c, rtol=1e-9)
    assert res.k[0] == 2.0 and res.U[0] == pytest.approx(2 * expected, rel=1e-10)
    assert res.dof_eff[0] == pytest.approx(5.0, rel=1e-12)
    assert any("k = 2 was given" in note for note in res.notes)


def test_correlated_inputs_with_different_dof_take_the_smallest():
    ins = [Input("a", 1.0, 1.0, 4), Input("b", 1.0, 1.0, 30), Input("c", 0.0, 1.0, 10)]
    res = propagate(lambda a, b, c: a + b + c, ins, correlation={("a", "b"): 0.5})
    # block (a, b): variance 1 + 1 + 2·0.5 = 3 with ν = 4; c: variance 1 with ν = 10
    assert res.dof_eff[0] == pytest.approx(16 / (9 / 4 + 1 / 10), rel=1e-12)
    assert any("smallest" in note for note in res.notes)


def test_uncorrelated_sum_ws_and_exact_input():
    ins = [Input("a", 1.0, 3.0, 5), Input("b", 2.0, 4.0, 10), Input("z", 7.0, 0.0)]
    res = propagate(lambda a, b, z: a + b + z, ins)
    assert res.u[0] == pytest.approx(5.0, rel=1e-12)
    assert res.dof_eff[0] == pytest.approx(625 / (81 / 5 + 256 / 10), rel=1e-12)
    assert res.contributions[0, 2] == 0.0


def test_result_is_frozen_and_json_ready():
    ins, r = h2_inputs()
    res = propagate(h2_model, ins, correlation=r, names_out=["R", "X", "Z"])
    assert isinstance(res, GUMResult)
    text = json.dumps(res.to_dict())
    back = json.loads(text)
    assert back["names_out"] == ["R", "X", "Z"]
    assert len(back["sensitivities"]) == 3 and len(back["sensitivities"][0]) == 3
    assert "_notes_by_output" not in back
    with pytest.raises(ValueError, match="read-only"):
        res.u[0] = 0.0
    exact = propagate(lambda a: a, [Input("a", 1.0, 0.0)])
    assert exact.u[0] == 0.0 and math.isinf(exact.dof_eff[0])
    assert json.loads(json.dumps(exact.to_dict()))["dof_eff"] == [None]


def test_an_overflowing_contribution_names_the_input() -> None:
    # a u stated in the wrong unit by many orders: one line naming the input, no "np.float64(inf)"
    with pytest.raises(ConfigError) as exc:
        propagate(lambda a, b: a + 1e10 * b, [Input("a", 0.0, 1.0), Input("big", 0.0, 1e300)])
    msg = str(exc.value)
    assert msg.startswith("input 'big':") and "too large" in msg
    assert "\n" not in msg and "np.float64" not in msg
