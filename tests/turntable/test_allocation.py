"""Error allocation (seed 001, eqs. (28)–(34)), its Lemma 1 check and the Monte Carlo check.

Truth used here, none of it from the optimiser:

* the closed-form KKT solution of the seed's γ and ψ problems (max over φ2 of A|sin| + B|cos| + C
  is √(A² + B²) + C; stationarity gives χ_i³ ∝ W_i²/g_i), solved by a 1-D root find below;
* eq. (26) and eqs. (17)–(24) written out again here from the paper (matrix products per point);
* Table 4's published allocation and its worst cases computed by hand from eq. (26);
* the distribution of a sum of two uniform errors (triangular) for the Monte Carlo histograms;
* a KKT certificate (non-negative multipliers by NNLS) for tables without a closed form.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re

import numpy as np
import pytest
from scipy.optimize import brentq, nnls

from rotacal.errors import ConfigError
from rotacal.turntable.allocation import (
    Allocation,
    MonteCarloCheck,
    allocate,
    monte_carlo_check,
    worst_case,
)
from rotacal.turntable.config import seed_table_toml
from rotacal.turntable.model import load_turntable, seed_table

ARCMIN = math.pi / 10_800.0
ARCSEC = math.pi / 648_000.0
I_SEED = 1.62 * ARCMIN  # eq. (16): 0.027°
NAMES = ("phi_y1", "phi_z2", "alpha_x1", "alpha_z1", "alpha_x2", "alpha_y2", "eps_x", "eps_y")
#: Table 4 of the seed (arcmin).
TABLE4 = {
    "phi_y1": 0.4235,
    "phi_z2": 0.7800,
    "alpha_x1": 0.4234,
    "alpha_z1": 0.7800,
    "alpha_x2": 0.2825,
    "alpha_y2": 0.2824,
    "eps_x": 0.4234,
    "eps_y": 0.4233,
}
#: Mean |cos| and |sin| over 0°, 45°, …, 360° (the sensitivities of eq. (28), Figure 8).
_GRID = np.radians(np.arange(0.0, 361.0, 45.0))
C_COS = float(np.mean(np.abs(np.cos(_GRID))))
C_SIN = float(np.mean(np.abs(np.sin(_GRID))))


def grid_means(step_deg: float, endpoint: bool) -> tuple[float, float]:
    """Mean |sin φ| and |cos φ| over a table's sensitivity grid, computed here (numpy only)."""
    deg = (
        np.linspace(0.0, 360.0, round(360 / step_deg) + 1)
        if endpoint
        else np.arange(0.0, 360.0, step_deg)
    )
    phi = np.radians(deg)
    return float(np.mean(np.abs(np.sin(phi)))), float(np.mean(np.abs(np.cos(phi))))


def seed_chain_unbiased():
    """The packaged seed table without its [sensitivity] table: rotacal's default averaging."""
    text = seed_table_toml()
    start, stop = text.index("[sensitivity]"), text.index("[monte_carlo]")
    return load_turntable(text[:start] + text[stop:])


# --------------------------------------------------------------------- independent references
def eq26(phi2: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
    """∂(Δψ, Δθ, Δγ)/∂χ of eq. (26), as printed."""
    c, s = np.cos(phi2), np.sin(phi2)
    one, zero = np.ones_like(phi2), np.zeros_like(phi2)
    return {
        "psi": {"phi_y1": c, "alpha_x1": -s, "alpha_y2": one, "eps_x": -s, "eps_y": c},
        "theta": {"phi_z2": one, "alpha_z1": one},
        "gamma": {"phi_y1": s, "alpha_x1": c, "alpha_x2": one, "eps_x": c, "eps_y": s},
        "zero": {"x": zero},
    }


def seed_delta(phi1: float, phi2: float, chi: dict[str, float]) -> np.ndarray:
    """(Δψ, Δθ, Δγ) of eqs. (17)–(24): the small-angle matrices multiplied as printed."""
    g = {n: 0.0 for n in NAMES} | chi

    def e(ex: float, ey: float, ez: float) -> np.ndarray:
        return np.array([[1.0, -ez, ey], [ez, 1.0, -ex], [-ey, ex, 1.0]])

    c1, s1, c2, s2 = math.cos(phi1), math.sin(phi1), math.cos(phi2), math.sin(phi2)
    ry = np.array([[c1, 0.0, s1], [0.0, 1.0, 0.0], [-s1, 0.0, c1]])
    rz = np.array([[c2, -s2, 0.0], [s2, c2, 0.0], [0.0, 0.0, 1.0]])
    rt = (
        ry
        @ e(g["alpha_x1"], g["phi_y1"], g["alpha_z1"])
        @ e(g["eps_x"], g["eps_y"], 0.0)
        @ rz
        @ e(g["alpha_x2"], g["alpha_y2"], g["phi_z2"])
    )
    dr = (ry @ rz).T @ rt
    return np.array([dr[0, 2], dr[1, 0], dr[2, 1]])


def kkt(
    w_sin: list[float], w_cos: list[float], w_const: list[float], limit: float
) -> tuple[list[float], list[float], list[float]]:
    """min Σ W²/χ² s.t. √(S² + C²) + K ≤ limit (S, C, K: sums of the sin, cos, constant groups).

    Stationarity: χ_i³ = λ·W_i²/g_i with g = sin t, cos t, 1 for the three groups, t = atan2(S, C).
    The shape does not depend on λ, so t is a 1-D root (brentq); λ then scales onto the limit.
    """

    def shape(t: float) -> tuple[list[float], list[float], list[float]]:
        return (
            [(w * w / math.sin(t)) ** (1 / 3) for w in w_sin],
            [(w * w / math.cos(t)) ** (1 / 3) for w in w_cos],
            [(w * w) ** (1 / 3) for w in w_const],
        )

    if w_sin and w_cos:
        t = brentq(
            lambda t: math.atan2(sum(shape(t)[0]), sum(shape(t)[1])) - t,
            1e-9,
            math.pi / 2 - 1e-9,
            xtol=1e-15,
            rtol=1e-15,
        )
        s, c, k = shape(t)
    else:  # one group or none: the constraint is a plain sum, g_i = 1
        s, c, k = ([(w * w) ** (1 / 3) for w in ws] for ws in (w_sin, w_cos, w_const))
    g = math.hypot(sum(s), sum(c)) + sum(k)
    f = limit / g
    return [f * v for v in s], [f * v for v in c], [f * v for v in k]


def kkt_certificate(table, alloc: Allocation, comp: str) -> float:
    """Relative residual of −∇J = Σ_k μ_k·|c_j(φ_k)| with μ ≥ 0 at the reported active angles."""
    names = list(alloc.per_component[comp])
    cols = [table.angular_error_names.index(n) for n in names]
    chi = np.array([alloc.per_component[comp][n] for n in names])
    w = np.array([alloc.weights[comp][n] for n in names])
    assert np.all(chi > np.array([alloc.lower_bounds_rad[n] for n in names]) * 1.001)
    grad = -2.0 * w**2 / chi**3
    active = np.radians(np.asarray(alloc.optimiser["components"][comp]["active_angles_deg"]))
    j = ("psi", "theta", "gamma").index(comp)
    rows = np.abs(table.linear_coefficients([active[:, k] for k in range(active.shape[1])]))
    rows = rows[:, j, :][:, cols]
    # the constraint rows are in χ (rad); scale to keep NNLS well conditioned
    _mu, resid = nnls(rows.T, -grad / np.linalg.norm(grad))
    return float(resid)


# ---------------------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def seed():
    return seed_table()


@pytest.fixture(scope="module")
def alloc(seed) -> Allocation:
    return allocate(seed, I_SEED)


@pytest.fixture(scope="module")
def mc(seed, alloc) -> MonteCarloCheck:
    return monte_carlo_check(seed, alloc, runs=1_000_000, seed=2026)


SINGLE = """
name = "single-axis test table"
units = "arcsec"

[requirement]
psi = 10.0
theta = 12.0
gamma = 8.0

[[chain]]
rotations = { eps_x = "x", eps_y = "y" }

[[chain]]
axis = "z"
angle = "phi1"
rotations = { phi_z1 = "z", alpha_x1 = "x", alpha_y1 = "y" }

[errors]
eps_x = { lower = 0.1 }
eps_y = { lower = 0.1 }
phi_z1 = { lower = 0.1 }
alpha_x1 = { lower = 0.1 }
alpha_y1 = { lower = 0.1 }
"""

THREE = """
name = "three-axis test table"
units = "arcsec"

[requirement]
psi = 20.0
theta = 30.0
gamma = 25.0

[[chain]]
axis = "z"
angle = "phi1"
rotations = { phi_z1 = "z", alpha_x1 = "x", alpha_y1 = "y" }

[[chain]]
rotations = { eps_x1 = "x", eps_y1 = "y" }

[[chain]]
axis = "y"
angle = "phi2"
rotations = { phi_y2 = "y", alpha_x2 = "x", alpha_z2 = "z" }

[[chain]]
axis = "x"
angle = "phi3"
rotations = { phi_x3 = "x", alpha_y3 = "y", alpha_z3 = "z" }

[errors]
phi_z1 = { lower = 0.5 }
alpha_x1 = { lower = 0.5 }
alpha_y1 = { lower = 0.5 }
eps_x1 = { lower = 0.5 }
eps_y1 = { lower = 0.5 }
phi_y2 = { lower = 0.5 }
alpha_x2 = { lower = 0.5 }
alpha_z2 = { lower = 0.5, weight = 3.0 }
phi_x3 = { lower = 0.5 }
alpha_y3 = { lower = 0.5 }
alpha_z3 = { lower = 0.5 }
"""


# ------------------------------------------------------------------------- the seed's model
def test_linear_coefficients_are_eq26(seed) -> None:
    phi1 = np.radians(np.arange(0.0, 360.0, 7.0))
    phi2 = np.radians(np.arange(0.0, 360.0, 5.0))[:, None]
    c = seed.linear_coefficients([phi1, phi2])
    ref = eq26(np.broadcast_to(phi2, (phi2.size, phi1.size)))
    for j, comp in enumerate(("psi", "theta", "gamma")):
        for i, name in enumerate(seed.angular_error_names):
            expected = ref[comp].get(name, ref["zero"]["x"] * 0.0)
            np.testing.assert_allclose(c[..., j, i], expected, atol=1e-15)


def test_sensitivities_are_figure8(alloc) -> None:
    s = alloc.sensitivities
    assert round(s["psi"]["phi_y1"], 4) == 0.6476  # Figure 8 (a)
    assert round(s["psi"]["alpha_x1"], 4) == 0.5365
    assert s["psi"]["alpha_y2"] == pytest.approx(1.0)
    assert s["theta"]["phi_z2"] == pytest.approx(1.0) and s["theta"]["phi_y1"] == 0.0
    assert round(s["gamma"]["alpha_x1"], 4) == 0.6476  # Figure 8 (c)
    assert alloc.weights["gamma"]["phi_y1"] == pytest.approx(1.0 / C_SIN, rel=1e-12)


# ------------------------------------------------------------------ (a) closed-form KKT
def test_seed_per_component_optimum_matches_closed_form_kkt(alloc) -> None:
    ws, wc = 1.0 / C_SIN, 1.0 / C_COS
    (g_s, g_c, g_k) = kkt([ws, ws], [wc, wc], [1.0], I_SEED)
    pc = alloc.per_component
    # γ: sin φ2 for φy1, εy; cos φ2 for αx1, εx; αx2 constant (eq. (26))
    for name, ref in (("phi_y1", g_s[0]), ("eps_y", g_s[1]), ("alpha_x1", g_c[0]),
                      ("eps_x", g_c[1]), ("alpha_x2", g_k[0])):  # fmt: skip
        assert pc["gamma"][name] == pytest.approx(ref, rel=1e-6), name
    # ψ: cos φ2 for φy1, εy; |sin φ2| for αx1, εx; αy2 constant
    for name, ref in (("phi_y1", g_c[0]), ("eps_y", g_c[1]), ("alpha_x1", g_s[0]),
                      ("eps_x", g_s[1]), ("alpha_y2", g_k[0])):  # fmt: skip
        assert pc["psi"][name] == pytest.approx(ref, rel=1e-6), name
    # θ: φz2 + αz1 ≤ I with equal weights → I/2 each
    assert pc["theta"]["phi_z2"] == pytest.approx(I_SEED / 2, rel=1e-9)
    assert pc["theta"]["alpha_z1"] == pytest.approx(I_SEED / 2, rel=1e-9)
    assert set(pc["theta"]) == {"phi_z2", "alpha_z1"}
    for comp in ("psi", "gamma"):
        assert alloc.optimiser["components"][comp]["success"]


def test_seed_upper_bounds_are_eq34_of_the_kkt_optima(alloc) -> None:
    ws, wc = 1.0 / C_SIN, 1.0 / C_COS
    (g_s, g_c, g_k) = kkt([ws, ws], [wc, wc], [1.0], I_SEED)
    ub = alloc.upper_bounds_rad
    assert g_c[0] < g_s[0]  # the |cos| group is the more sensitive: it binds all four
    for name in ("phi_y1", "alpha_x1", "eps_x", "eps_y"):
        assert ub[name] == pytest.approx(g_c[0], rel=1e-6), name
    assert ub["alpha_x2"] == pytest.approx(g_k[0], rel=1e-6)
    assert ub["alpha_y2"] == pytest.approx(g_k[0], rel=1e-6)
    assert alloc.binding["phi_y1"] == "psi" and alloc.binding["alpha_x1"] == "gamma"
    assert alloc.binding["alpha_x2"] == "gamma" and alloc.binding["alpha_y2"] == "psi"
    # θ: I/2, shrunk by the full-model guard by a second-order amount only
    scale = alloc.optimiser["full_model_scale"]["theta"]
    assert scale < 1.0 and scale == pytest.approx(1.0, abs=1e-3)
    assert ub["phi_z2"] == pytest.approx(I_SEED / 2 * scale, rel=1e-12)
    assert ub["alpha_z1"] == pytest.approx(I_SEED / 2 * scale, rel=1e-12)
    assert ub["eta"] is None  # "the intersection error has no effect"
    assert alloc.within
    json.dumps(alloc.to_dict())  # JSON-able


def test_linear_allocation_fails_full_model_by_second_order(seed, alloc) -> None:
    """Why the guard exists: θ = I/2 + I/2 meets eq. (26) exactly but not eqs. (17)–(24)."""
    ub = {n: v for n, v in alloc.upper_bounds_rad.items() if v is not None}
    ub["phi_z2"] = ub["alpha_z1"] = I_SEED / 2
    wc = worst_case(seed, ub, I_SEED)
    assert wc["theta"]["linear_rad"] == pytest.approx(I_SEED, rel=1e-12)
    assert wc["theta"]["full_rad"] > I_SEED * (1 + 1e-6)
    assert not wc["theta"]["within"]
    # the reported worst point, re-evaluated with the matrices of eqs. (17)–(24) written here
    a = wc["theta"]["angles_deg"]
    chi = {n: wc["theta"]["signs"][n] * ub[n] for n in NAMES}
    d = seed_delta(math.radians(a["phi1"]), math.radians(a["phi2"]), chi)
    assert abs(d[1]) == pytest.approx(wc["theta"]["full_rad"], rel=1e-12)
    # the second-order excess is ~1e-4 of I, as the products of the bounds say
    assert wc["theta"]["full_rad"] / I_SEED - 1 < 1e-3


# ---------------------------------------------------------------------- (b), (c) Table 4
def test_table4_passes_the_lemma_check_with_its_slack(seed) -> None:
    ub = {n: v * ARCMIN for n, v in TABLE4.items()}
    wc = worst_case(seed, ub, I_SEED)
    t = TABLE4
    gamma = math.hypot(t["phi_y1"] + t["eps_y"], t["alpha_x1"] + t["eps_x"]) + t["alpha_x2"]
    psi = math.hypot(t["alpha_x1"] + t["eps_x"], t["phi_y1"] + t["eps_y"]) + t["alpha_y2"]
    assert wc["gamma"]["linear_rad"] / ARCMIN == pytest.approx(gamma, rel=1e-9)
    assert wc["psi"]["linear_rad"] / ARCMIN == pytest.approx(psi, rel=1e-9)
    assert wc["theta"]["linear_rad"] / ARCMIN == pytest.approx(1.56, rel=1e-12)
    assert round(gamma, 2) == 1.48 and round(psi, 2) == 1.48
    for comp in ("psi", "theta", "gamma"):
        assert wc[comp]["within"]
        assert wc[comp]["full_rad"] < I_SEED
        # the full model differs from the linear bound by second-order terms only
        assert wc[comp]["full_rad"] == pytest.approx(wc[comp]["linear_rad"], rel=1e-3)


def test_rotacal_bounds_are_not_tighter_than_table4(alloc) -> None:
    for name, paper in TABLE4.items():
        assert alloc.upper_bounds_rad[name] / ARCMIN >= paper, name


# ------------------------------------------------------------------------- (d) Monte Carlo
def test_monte_carlo_1e6_draws_within(mc, alloc) -> None:
    assert mc.runs == 1_000_000 and mc.signs == "random"
    assert mc.all_within and mc.outside == 0
    for comp in ("psi", "theta", "gamma"):
        assert mc.max_abs_rad[comp] <= I_SEED
        # a draw cannot beat the worst vertex of the box
        assert mc.max_abs_rad[comp] <= alloc.worst_case[comp]["full_rad"] * (1 + 1e-12)
        assert sum(mc.histograms[comp]["counts"]) == mc.runs
        edges = mc.histograms[comp]["edges_rad"]
        assert len(edges) == 61 and edges[0] == -I_SEED and edges[-1] == I_SEED
    # θ is the sum of two errors only: its corners are reached closely in 10⁶ draws
    assert mc.max_abs_rad["theta"] > 0.99 * I_SEED
    assert mc.max_abs_arcmin["theta"] == pytest.approx(mc.max_abs_rad["theta"] / ARCMIN)
    json.dumps(mc.to_dict())


def test_monte_carlo_theta_histogram_is_triangular(seed, alloc) -> None:
    """With LB = 0 and random signs, Δθ ≈ φz2 + αz1 is a sum of two U(−u, u): triangular."""
    zero = dataclasses.replace(alloc, lower_bounds_rad=dict.fromkeys(alloc.lower_bounds_rad, 0.0))
    runs = 400_000
    res = monte_carlo_check(seed, zero, runs=runs, seed=7)
    u_phi, u_alpha = alloc.upper_bounds_rad["phi_z2"], alloc.upper_bounds_rad["alpha_z1"]
    # Equal weights and equal unit coefficients make the θ optimum exactly symmetric, but not to
    # the bit (they were 1 ulp apart): SLSQP stops when the objective Σ W²/χ² changes by less than
    # ftol = 1e-14 (relative), and on the constraint φz2 + αz1 = Iθ the objective is flat to second
    # order in φz2 − αz1, so the two may differ by up to ~√ftol = 1e-7 (relative).
    assert u_phi == pytest.approx(u_alpha, rel=1e-6)
    # a 1e-7 difference moves the CDF by ~1e-7, far below the 4/√runs = 0.006 tolerance below
    u = 0.5 * (u_phi + u_alpha)

    def cdf(z: np.ndarray) -> np.ndarray:
        z = np.clip(z, -2 * u, 2 * u)
        return np.where(z < 0, (z + 2 * u) ** 2 / (8 * u * u), 1 - (2 * u - z) ** 2 / (8 * u * u))

    edges = np.asarray(res.histograms["theta"]["edges_rad"])
    counts = np.asarray(res.histograms["theta"]["counts"])
    emp = np.concatenate([[0.0], np.cumsum(counts)]) / runs
    assert np.max(np.abs(emp - cdf(edges))) < 4.0 / math.sqrt(runs)
    # a wrong law (uniform magnitudes without random signs) would be far off
    assert np.max(np.abs(emp - np.clip((edges + 2 * u) / (4 * u), 0, 1))) > 0.05


def test_monte_carlo_positive_signs(seed, alloc) -> None:
    res = monte_carlo_check(seed, alloc, runs=100_000, signs="positive")
    lb = alloc.lower_bounds_rad["phi_z2"] + alloc.lower_bounds_rad["alpha_z1"]
    edges = np.asarray(res.histograms["theta"]["edges_rad"])
    counts = np.asarray(res.histograms["theta"]["counts"])
    assert counts[edges[1:] < lb * (1 - 1e-3)].sum() == 0  # Δθ ≥ LB + LB
    assert res.all_within


def test_monte_carlo_same_for_any_chunk(seed, alloc) -> None:
    calls: list[tuple[int, int]] = []
    a = monte_carlo_check(
        seed, alloc, runs=50_000, seed=11, chunk=4_096, progress=lambda d, t: calls.append((d, t))
    )
    b = monte_carlo_check(seed, alloc, runs=50_000, seed=11, chunk=50_000)
    c = monte_carlo_check(seed, alloc, runs=50_000, seed=12, chunk=50_000)
    da, db = a.to_dict(), b.to_dict()
    da.pop("draws_per_second"), db.pop("draws_per_second")
    assert da == db
    assert c.max_abs_rad != a.max_abs_rad  # another seed, other draws
    assert calls[-1] == (50_000, 50_000) and len(calls) == math.ceil(50_000 / 4_096)


@pytest.mark.parametrize("signs", ["random", "positive"])
def test_monte_carlo_compiled_equals_the_numpy_path(seed, alloc, signs, monkeypatch) -> None:
    """Numba's draws, kernel and tallies give the NumPy path's result to the last bit; bounds 3 %
    above the allocation put draws outside the requirement, so the count and the histograms'
    exclusion of those draws are compared too."""
    over = {n: (None if v is None else 1.03 * v) for n, v in alloc.upper_bounds_rad.items()}
    results = []
    for flag in ("1", "0"):
        monkeypatch.setenv("ROTACAL_NUMBA", flag)
        res = monte_carlo_check(
            seed,
            dataclasses.replace(alloc, upper_bounds_rad=over),
            runs=300_000,
            seed=5,
            signs=signs,
            chunk=70_000,
        ).to_dict()
        res.pop("draws_per_second")
        results.append(res)
    assert results[0] == results[1]
    assert signs == "positive" or results[0]["outside"] > 0


def test_bounds_above_the_allocation_fail_the_checks(seed, alloc) -> None:
    over = {n: (None if v is None else 1.05 * v) for n, v in alloc.upper_bounds_rad.items()}
    wc = worst_case(seed, over, I_SEED)
    for comp in ("psi", "theta", "gamma"):
        assert not wc[comp]["within"]
        assert wc[comp]["full_rad"] > I_SEED
    # the vertex found does exceed the requirement in the model of eqs. (17)–(24) written here
    a = wc["psi"]["angles_deg"]
    chi = {n: wc["psi"]["signs"][n] * over[n] for n in NAMES}
    assert abs(seed_delta(math.radians(a["phi1"]), math.radians(a["phi2"]), chi)[0]) > I_SEED
    # θ's corners are common enough for the Monte Carlo to see it too
    res = monte_carlo_check(seed, dataclasses.replace(alloc, upper_bounds_rad=over), runs=200_000)
    assert not res.all_within and res.outside > 0
    assert res.max_abs_rad["theta"] > I_SEED


# --------------------------------------------------------------------------- (e) bad input
def test_infeasible_lower_bounds_one_line(seed) -> None:
    with pytest.raises(ConfigError) as exc:
        allocate(seed, 0.08 * ARCMIN)
    msg = str(exc.value)
    assert "\n" not in msg
    assert "psi" in msg and "arcmin" in msg and "0.08" in msg and "lower bounds" in msg
    t = load_turntable(
        SINGLE.replace("eps_x = { lower = 0.1 }", "eps_x = { lower = 6.0 }").replace(
            "eps_y = { lower = 0.1 }", "eps_y = { lower = 6.0 }"
        )
    )
    with pytest.raises(ConfigError) as exc:
        allocate(t)
    msg = str(exc.value)
    # γ: √(6² + 6²) + 0.1 = 8.59″ > 8″ at 45° (mod 90°); ψ (10″) is still feasible
    assert "\n" not in msg and "gamma" in msg and "arcsec" in msg
    assert "8.585" in msg and "eps_x" in msg and "eps_y" in msg
    angle = float(re.search(r"phi1 = ([0-9.]+)°", msg).group(1))  # type: ignore[union-attr]
    assert angle % 90.0 == pytest.approx(45.0, abs=0.01)


@pytest.mark.parametrize(
    ("requirement", "fragment"),
    [
        ({"psi": 1e-3, "theta": 1e-3}, "missing gamma"),
        ({"psi": 1e-3, "theta": 1e-3, "gamma": -1.0}, "gamma"),
        ({"psi": 1e-3, "theta": 1e-3, "gamma": 1e-3, "phi": 1.0}, "unknown phi"),
        ("abc", "psi"),
    ],
)
def test_bad_requirement(seed, requirement, fragment) -> None:
    with pytest.raises(ConfigError, match=fragment):
        allocate(seed, requirement)


def test_bad_settings(seed, alloc) -> None:
    with pytest.raises(ConfigError, match="signs"):
        monte_carlo_check(seed, alloc, runs=10, signs="negative")
    with pytest.raises(ConfigError, match="runs"):
        monte_carlo_check(seed, alloc, runs=0)
    with pytest.raises(ConfigError, match="angle_step_deg"):
        allocate(seed, I_SEED, angle_step_deg=0.0)
    with pytest.raises(ConfigError, match="lower bound of phi_y1"):
        worst_case(seed, {"phi_y1": 1e-5}, I_SEED, lower_bounds={"phi_y1": 2e-5})


# -------------------------------------------------------------------- (f) other tables
def test_single_axis_table_matches_closed_form(seed) -> None:
    t = load_turntable(SINGLE)
    c = t.linear_coefficients([np.radians(np.arange(0.0, 360.0, 10.0))])
    phi = np.radians(np.arange(0.0, 360.0, 10.0))
    i = {n: k for k, n in enumerate(t.angular_error_names)}
    # ΔR = Rz(φ)ᵀ·E(εx, εy, 0)·Rz(φ)·E(αx1, αy1, φz1), linearised
    np.testing.assert_allclose(c[:, 2, i["eps_x"]], np.cos(phi), atol=1e-15)
    np.testing.assert_allclose(c[:, 2, i["eps_y"]], np.sin(phi), atol=1e-15)
    np.testing.assert_allclose(c[:, 0, i["eps_x"]], -np.sin(phi), atol=1e-15)
    np.testing.assert_allclose(c[:, 0, i["eps_y"]], np.cos(phi), atol=1e-15)
    a = allocate(t)
    ig, ip, it = 8.0 * ARCSEC, 10.0 * ARCSEC, 12.0 * ARCSEC
    # the table's own averaging (no [sensitivity]: 1° steps over a turn), its means computed here
    assert t.sensitivity_grid == (1.0, False)
    assert a.optimiser["sensitivity_grid"] == {"step_deg": 1.0, "endpoint": False}
    m_sin, m_cos = grid_means(*t.sensitivity_grid)
    ws, wc = 1.0 / m_sin, 1.0 / m_cos
    assert a.weights["gamma"]["eps_y"] == pytest.approx(ws, rel=1e-12)
    assert a.weights["gamma"]["eps_x"] == pytest.approx(wc, rel=1e-12)
    (gs, gc, gk) = kkt([ws], [wc], [1.0], ig)  # γ: εy |sin|, εx |cos|, αx1
    (ps, pc, pk) = kkt([ws], [wc], [1.0], ip)  # ψ: εx |sin|, εy |cos|, αy1
    assert a.per_component["gamma"]["eps_y"] == pytest.approx(gs[0], rel=1e-6)
    assert a.per_component["gamma"]["eps_x"] == pytest.approx(gc[0], rel=1e-6)
    assert a.per_component["gamma"]["alpha_x1"] == pytest.approx(gk[0], rel=1e-6)
    assert a.per_component["psi"]["eps_x"] == pytest.approx(ps[0], rel=1e-6)
    assert a.per_component["psi"]["alpha_y1"] == pytest.approx(pk[0], rel=1e-6)
    ub = a.upper_bounds_rad
    assert ub["eps_x"] == pytest.approx(min(gc[0], ps[0]), rel=1e-6)
    assert ub["eps_y"] == pytest.approx(min(gs[0], pc[0]), rel=1e-6)
    assert a.per_component["theta"] == {"phi_z1": pytest.approx(it, rel=1e-12)}
    assert it * (1 - 1e-3) < ub["phi_z1"] <= it
    assert a.within
    for comp in ("psi", "theta", "gamma"):
        assert a.worst_case[comp]["linear_rad"] <= a.requirement_rad[comp] * (1 + 1e-9)
        assert a.worst_case[comp]["full_rad"] <= a.requirement_rad[comp]
    res = monte_carlo_check(t, a, runs=100_000)
    assert res.all_within


def test_component_without_errors_is_noted_not_raised() -> None:
    t = load_turntable(
        """
units = "arcsec"
[requirement]
psi = 5.0
theta = 5.0
gamma = 5.0
[[chain]]
axis = "z"
angle = "phi1"
rotations = { phi_z1 = "z" }
[errors]
phi_z1 = { lower = 0.0 }
"""
    )
    a = allocate(t)
    assert a.per_component["psi"] == {} and a.per_component["gamma"] == {}
    assert any("psi" in n and "nothing to allocate" in n for n in a.optimiser["notes"])
    # ΔR = E(0, 0, φz1) exactly: the full model is the linear one, UB = I
    assert a.upper_bounds_rad["phi_z1"] == pytest.approx(5.0 * ARCSEC, rel=1e-12)
    assert a.within and a.worst_case["psi"]["full_rad"] == 0.0


def test_three_axis_table_is_optimal_and_passes(seed) -> None:
    t = load_turntable(THREE)
    a = allocate(t)
    assert a.within
    assert a.weights["psi"]["alpha_z2"] == 3.0  # the weight override
    for comp in ("psi", "theta", "gamma"):
        assert a.optimiser["components"][comp]["success"]
        assert kkt_certificate(t, a, comp) < 1e-5, comp
        # eq. (34)
        for name, value in a.per_component[comp].items():
            assert a.upper_bounds_rad[name] <= value * (1 + 1e-12)
    # the Lemma 1 bound on 2·10⁵ random angles (not the allocation's grid)
    rng = np.random.default_rng(5)
    phis = rng.uniform(0.0, 2 * math.pi, size=(3, 200_000))
    c = np.abs(t.linear_coefficients(list(phis)))
    ub = np.array([a.upper_bounds_rad[n] for n in t.angular_error_names])
    req = np.array([a.requirement_rad[k] for k in ("psi", "theta", "gamma")])
    assert np.all(c @ ub <= req * (1 + 1e-9))
    assert np.max(c @ ub / req) > 0.999  # and it is tight somewhere
    res = monte_carlo_check(t, a, runs=100_000)
    assert res.all_within


def test_seed_kkt_certificate(seed, alloc) -> None:
    for comp in ("psi", "gamma"):
        assert kkt_certificate(seed, alloc, comp) < 1e-5


# ------------------------------------------------------------- the default (unbiased) averaging
def test_seed_chain_with_the_default_averaging_matches_closed_form_kkt() -> None:
    """Without [sensitivity] every |sin| and |cos| term weighs 1/(2/π): the KKT with those weights."""
    t = seed_chain_unbiased()
    a = allocate(t, I_SEED)
    assert a.optimiser["sensitivity_grid"] == {"step_deg": 1.0, "endpoint": False}
    m_sin, m_cos = grid_means(1.0, False)
    assert m_sin == pytest.approx(2 / math.pi, rel=1e-4) and m_cos == pytest.approx(m_sin)
    ws, wc = 1.0 / m_sin, 1.0 / m_cos
    assert a.weights["psi"]["phi_y1"] == pytest.approx(wc, rel=1e-12)
    assert a.weights["gamma"]["phi_y1"] == pytest.approx(ws, rel=1e-12)
    (g_s, g_c, g_k) = kkt([ws, ws], [wc, wc], [1.0], I_SEED)
    pc = a.per_component
    for name, ref in (("phi_y1", g_s[0]), ("eps_y", g_s[1]), ("alpha_x1", g_c[0]),
                      ("eps_x", g_c[1]), ("alpha_x2", g_k[0])):  # fmt: skip
        assert pc["gamma"][name] == pytest.approx(ref, rel=1e-6), name
    for name, ref in (("phi_y1", g_c[0]), ("eps_y", g_c[1]), ("alpha_x1", g_s[0]),
                      ("eps_x", g_s[1]), ("alpha_y2", g_k[0])):  # fmt: skip
        assert pc["psi"][name] == pytest.approx(ref, rel=1e-6), name
    # eq. (34), then the full-model guard's second-order shrink of ψ's errors (all five of them)
    ub = a.upper_bounds_rad
    s_psi = a.optimiser["full_model_scale"]["psi"]
    assert s_psi <= 1.0 and s_psi == pytest.approx(1.0, abs=1e-3)
    assert a.optimiser["full_model_scale"]["gamma"] == 1.0
    for name in ("phi_y1", "alpha_x1", "eps_x", "eps_y"):
        assert ub[name] == pytest.approx(min(g_s[0], g_c[0]) * s_psi, rel=1e-6), name
    assert ub["alpha_x2"] == pytest.approx(g_k[0], rel=1e-6)
    assert ub["alpha_y2"] == pytest.approx(g_k[0] * s_psi, rel=1e-6)
    assert a.within
    # equal weights spread the sin and cos groups evenly; the paper's weights do not
    paper = allocate(seed_table(), I_SEED)
    assert ub["phi_y1"] != pytest.approx(paper.upper_bounds_rad["phi_y1"], rel=1e-3)


# ----------------------------------------------------------------------- more bad input
def test_a_table_whose_errors_do_not_rotate_is_one_line() -> None:
    t = load_turntable(
        """
units = "arcsec"
[requirement]
psi = 5.0
theta = 5.0
gamma = 5.0
[[chain]]
axis = "z"
angle = "phi1"
translations = { d = "x" }
[errors]
d = {}
"""
    )
    for call in (
        lambda: allocate(t),
        lambda: worst_case(t, {}),
        lambda: monte_carlo_check(t, None, runs=10),  # type: ignore[arg-type]
    ):
        with pytest.raises(ConfigError) as exc:
            call()
        msg = str(exc.value)
        assert "\n" not in msg and msg.startswith("turntable TOML text: ")
        assert (
            "no error of the chain changes the orientation" in msg and "nothing to allocate" in msg
        )


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"seed": -1}, "seed must be an integer ≥ 0, got -1"),
        ({"seed": 1.5}, "seed must be an integer ≥ 0, got 1.5"),
        ({"seed": True}, "seed must be an integer ≥ 0, got True"),
        ({"seed": "7"}, "seed must be an integer ≥ 0, got '7'"),
        ({"runs": True}, "runs must be an integer ≥ 1, got True"),
        ({"runs": 2.0}, "runs must be an integer ≥ 1, got 2.0"),
        ({"runs": 0}, "runs must be an integer ≥ 1, got 0"),
        ({"chunk": False}, "chunk must be an integer ≥ 1, got False"),
    ],
)
def test_monte_carlo_seed_and_runs_must_be_integers(seed, alloc, kwargs, fragment) -> None:
    args = {"runs": 10} | kwargs
    with pytest.raises(ConfigError, match=re.escape(fragment)) as exc:
        monte_carlo_check(seed, alloc, **args)
    assert "\n" not in str(exc.value)


def test_monte_carlo_accepts_numpy_integers(seed, alloc) -> None:
    a = monte_carlo_check(seed, alloc, runs=np.int64(2_000), seed=np.uint32(3))
    b = monte_carlo_check(seed, alloc, runs=2_000, seed=3)
    assert a.runs == 2_000 and a.seed == 3 and a.max_abs_rad == b.max_abs_rad


def test_infeasible_message_names_the_source_and_only_the_angles_that_matter(seed) -> None:
    # ψ of the seed table depends on φ2 only (eq. (26)): φ1 must not be named
    with pytest.raises(ConfigError) as exc:
        allocate(seed, 0.08 * ARCMIN)
    msg = str(exc.value)
    assert msg.startswith("packaged seed001.toml: the allocation of psi is infeasible")
    assert "phi2 = " in msg and "phi1" not in msg
    # θ = φz2 + αz1 depends on no angle: no angle is named
    big = (
        seed_table_toml()
        .replace("phi_z2 = { lower = 0.05,", "phi_z2 = { lower = 1.0,")
        .replace("alpha_z1 = { lower = 0.05,", "alpha_z1 = { lower = 1.0,")
    )
    with pytest.raises(ConfigError) as exc:
        allocate(load_turntable(big), I_SEED)
    msg = str(exc.value)
    assert msg.startswith(
        "turntable TOML text: the allocation of theta is infeasible: at every angle the lower"
    )
    assert "phi1" not in msg and "phi2" not in msg and "2 arcmin" in msg
    # a table built in code is named by its name
    t = dataclasses.replace(seed, source="")
    with pytest.raises(ConfigError, match=r"^turntable 'Two-axis turntable of the GyroWheel study"):
        allocate(t, 0.08 * ARCMIN)


def test_values_beyond_the_small_angle_model_are_refused(seed, alloc) -> None:
    with pytest.raises(ConfigError, match=r"requirement psi = 0.5 rad \(28.65°\) .*give radians"):
        allocate(seed, {"psi": 0.5, "theta": 1e-3, "gamma": 1e-3})
    with pytest.raises(ConfigError, match=r"the upper bound of phi_y1 = 0.4235 rad .*give radians"):
        worst_case(seed, {"phi_y1": 0.4235}, I_SEED)  # Table 4's arcmin given as radians


def test_a_repeated_allocation_is_the_same_and_its_copy_is_the_callers() -> None:
    """The memo of :func:`allocate` (same table, same options → the result made before) gives an
    equal result, which a caller may change without changing the next one; other options or
    another table are allocated afresh."""
    from rotacal.turntable import allocation

    t = load_turntable(SINGLE)
    first = allocate(t)
    first.upper_bounds_rad["eps_x"] = -1.0  # a caller's change stays with the caller
    again = allocate(t)
    assert again.upper_bounds_rad["eps_x"] > 0.0
    assert again == allocate(dataclasses.replace(t, source="elsewhere.toml"))
    fresh = allocation._allocate(
        t,
        None,
        angle_step_deg=1.0,
        full_model_guard=True,
        max_evaluations=allocation._MAX_FULL_EVALUATIONS,
        constraint_step_deg=None,
    )
    assert again == fresh
    tighter = allocate(t, 0.5 * min(t.requirement.values()))
    assert tighter.upper_bounds_rad["eps_x"] < again.upper_bounds_rad["eps_x"]
