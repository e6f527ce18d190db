"""Uncertainty budgets of the sinusoidal-motion calibration (seed 000) against truths they do not make.

Closed forms (sensitivities and u by hand), recalibration with a changed input (finite differences
through the calibration, not through the budget), JCGM 102's magnitude example, and the twin run
many times: the spread of the results must agree with the reported u within the χ² bounds of the
number of repeats (99.9 %), with Type A only and with systematic effects the twin draws per run
from the same distributions the specifications state.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from rotacal import sim
from rotacal.errors import ConfigError
from rotacal.report.html import Report, render_html
from rotacal.report.motion import comparison_section, motion_section
from rotacal.report.uncertainty import plain_name
from rotacal.table import (
    calibrate_encoder_motion,
    calibrate_encoder_motion_chunked,
    calibrate_fog_motion,
    calibrate_lts_motion,
    compare_schemes,
)
from rotacal.table.motion_uncertainty import (
    reversal_time_u_argmax,
    reversal_time_u_argmax_tabulated,
    reversal_time_u_parabola,
    thd_bias_corrected_percent,
    thd_uncertainty,
)
from rotacal.uncertainty import load_specs

LINES = 36000
#: THD well above the noise of every scheme (≈ 1.28 %).
DISTORTED = sim.SineMotion(
    amplitude_deg=0.5, frequency_hz=2.0, harmonics={2: (0.010, 0.4), 3: (0.008, 1.1)}
)
#: Small harmonics (THD ≈ 0.25 %): the LTS's parabola is then not biased by asymmetric extremes.
MILD_LTS = sim.SineMotion(
    amplitude_deg=0.025, frequency_hz=10.0, harmonics={2: (0.002, 0.4), 3: (0.0015, 1.1)}
)
PURE = sim.SineMotion(amplitude_deg=0.5, frequency_hz=2.0)
ENC = {"noise_rms": 0.01, "fs_hz": 20_000.0, "duration_s": 3.125 / 2.0}
FOG = {"snr_db": 20.0, "fs_hz": 2000.0, "duration_s": 10.125 / 2.0}  # 10 125 samples
LTS = {"noise_mm": 3e-5}  # 6125 samples at 10 kHz

ALL_KEYS = (
    "amplitude_deg",
    "frequency_hz",
    "angular_acceleration_amplitude_deg_s2",
    "thd_percent",
    "reversal_times_s",
)
ERROR_KEYS = (
    "amplitude_error_percent",
    "frequency_error_percent",
    "angular_acceleration_error_percent",
)


def _specs(**sections):
    return load_specs(sections)


def _rect(half_width):
    return {"distribution": "rectangular", "half_width": half_width}


def _calibrate(kind, columns, specs=None, radius_mm=100.0, **kw):
    c = columns
    if kind == "encoder":
        return calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=LINES, specs=specs, **kw)
    if kind == "lts":
        return calibrate_lts_motion(
            c["time_s"], c["displacement_mm"], radius_mm=radius_mm, specs=specs, **kw
        )
    return calibrate_fog_motion(c["time_s"], c["rate_deg_s"], specs=specs, **kw)


def _nearest(found, truth):
    """found − the nearest true reversal (the capture may cut one at either end)."""
    truth = np.asarray(truth)
    i = np.clip(np.searchsorted(truth, found), 1, truth.size - 1)
    left, right = truth[i - 1], truth[i]
    return found - np.where(np.abs(found - left) < np.abs(found - right), left, right)


def _chi2_bounds(n, dof):
    """Bounds of (sample std)/σ at 99.9 % for a χ² with ``dof`` from n values."""
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], dof)
    return math.sqrt(lo / dof), math.sqrt(hi / dof)


# ------------------------------------------------------------------------------ closed forms
def test_frequency_and_acceleration_budgets_are_the_closed_form():
    """f = f_fit(1 + e): u² = u_A² + (f·a/√3)²; α = Aω²: ∂α/∂A = ω², ∂α/∂f = 2α/f, ∂α/∂e = 2α."""
    a = 2e-6
    c = sim.simulate_encoder(DISTORTED, noise_rms=0.004, seed=1).columns
    r = calibrate_encoder_motion(
        c["time_s"],
        c["a"],
        c["b"],
        lines=LINES,
        specs=_specs(timebase={"relative_error": _rect(a)}),
    )
    fit = r._fit
    f, amp = r.frequency_hz, r.amplitude_deg
    u_e = a / math.sqrt(3)
    u_f = math.hypot(fit.frequency_u_hz, f * u_e)
    b = r._budgets["frequency_hz"]
    assert b.u == pytest.approx(u_f, rel=1e-12)
    assert r.frequency_hz_u == b.u  # one number, one truth
    row = next(x for x in b.rows if x.source.startswith("timebase"))
    assert row.sensitivity == pytest.approx(f, rel=1e-12)
    w2 = (2 * math.pi * f) ** 2
    alpha = r.angular_acceleration_amplitude_deg_s2
    u_alpha = math.sqrt(
        (w2 * fit.amplitudes_u[0]) ** 2
        + (2 * alpha / f * fit.frequency_u_hz) ** 2
        + (2 * alpha * u_e) ** 2
    )
    assert r._budgets["angular_acceleration_amplitude_deg_s2"].u == pytest.approx(
        u_alpha, rel=1e-12
    )
    assert alpha == pytest.approx(amp * w2, rel=1e-12)
    # the timebase dominates: ν_eff is huge and k the normal quantile
    assert b.k == pytest.approx(1.959964, abs=1e-5)
    assert b.U == pytest.approx(b.k * b.u, rel=1e-12)


def test_encoder_graduation_error_enters_at_both_extremes():
    """A = A_fit + (g₊ − g₋)/7200: u(A)² = u_fit² + 2·(u_g/7200)², u_g = a/√3 (arcsec)."""
    a = 1.0
    c = sim.simulate_encoder(DISTORTED, noise_rms=0.004, seed=2).columns
    r = calibrate_encoder_motion(
        c["time_s"],
        c["a"],
        c["b"],
        lines=LINES,
        specs=_specs(encoder={"graduation_error_arcsec": _rect(a)}),
        set_amplitude_deg=0.5,
        set_frequency_hz=2.0,
    )
    u_g = a / math.sqrt(3) / 7200
    u_a = math.hypot(r._fit.amplitudes_u[0], math.sqrt(2) * u_g)
    assert r.amplitude_deg_u == pytest.approx(u_a, rel=1e-12)
    assert r._budgets["amplitude_error_percent"].u == pytest.approx(100 * u_a / 0.5, rel=1e-12)
    rows = [x for x in r._budgets["amplitude_deg"].rows if "graduation" in x.source]
    # reading = true + g: A = A_fit − (g₊ − g₋)/7200
    assert [x.sensitivity for x in rows] == pytest.approx([-1 / 7200, 1 / 7200])
    # the timebase is not stated: the budget says so, and the frequency is Type A alone
    assert any("timebase.relative_error" in n for n in r._budgets["frequency_hz"].notes)
    assert r.frequency_hz_u == r._fit.frequency_u_hz


def test_lts_radius_sensitivity_equals_a_recalibration_with_another_radius():
    """∂A/∂R of the budget against (A(R + δ) − A(R − δ))/2δ through the whole calibration."""
    m = sim.SineMotion(amplitude_deg=2.0, frequency_hz=1.0, harmonics={3: (0.01, 0.3)})
    c = sim.simulate_lts(m, radius_mm=100.0, noise_mm=0.0, fs_hz=2000.0, seed=0).columns
    specs = _specs(lts={"radius_mm": {"distribution": "normal", "value": 100.0, "u": 0.05}})
    r = calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0, specs=specs)
    row = next(x for x in r._budgets["amplitude_deg"].rows if "radius" in x.source)
    d = 0.01
    up = calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0 + d)
    dn = calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0 - d)
    numeric = (up.amplitude_deg - dn.amplitude_deg) / (2 * d)
    assert row.sensitivity == pytest.approx(numeric, rel=1e-4)
    assert row.sensitivity == pytest.approx(-r.amplitude_deg / 100.0, rel=2e-3)  # ≈ −A/R
    assert row.contribution == pytest.approx(row.sensitivity * 0.05, rel=1e-12)


def test_lts_resolution_sensitivity_is_half_dtheta_dd_at_each_extreme():
    m = sim.SineMotion(amplitude_deg=5.0, frequency_hz=1.0)
    c = sim.simulate_lts(m, radius_mm=100.0, noise_mm=0.0, fs_hz=2000.0, seed=0).columns
    specs = _specs(lts={"resolution_um": _rect(0.05)})
    r = calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0, specs=specs)
    rows = [x for x in r._budgets["amplitude_deg"].rows if "resolution" in x.source]
    d = 100.0 * math.tan(math.radians(5.0))
    c_closed = 0.5 * math.degrees(100.0 / (100.0**2 + d**2)) * 1e-3  # deg per µm
    assert [abs(x.sensitivity) for x in rows] == pytest.approx([c_closed, c_closed], rel=1e-4)
    assert rows[0].u == pytest.approx(0.05 / math.sqrt(3))


def test_fog_scale_factor_and_timebase_sensitivities_match_recalibrations():
    """∂A/∂s = −A, ∂A/∂e = −A, ∂α/∂e = α, ∂α/∂s = −α: scale the rate, then the time stamps."""
    c = sim.simulate_fog(DISTORTED, snr_db=30.0, seed=3, **{"duration_s": 10.125 / 2.0}).columns
    specs = _specs(
        timebase={"relative_error": _rect(1e-5)},
        fog={"scale_factor_relative": {"distribution": "normal", "u": 1e-3}},
    )
    r = calibrate_fog_motion(c["time_s"], c["rate_deg_s"], specs=specs)
    d = 1e-4
    by_s = calibrate_fog_motion(c["time_s"], c["rate_deg_s"] / (1 + d))  # true rate if s = d
    t0 = c["time_s"][0]
    by_e = calibrate_fog_motion(t0 + (c["time_s"] - t0) / (1 + d), c["rate_deg_s"])
    for key in ("amplitude_deg", "angular_acceleration_amplitude_deg_s2"):
        rows = {x.source.split(" (")[0]: x for x in r._budgets[key].rows}
        ds = (getattr(by_s, key) - getattr(r, key)) / d
        de = (getattr(by_e, key) - getattr(r, key)) / d
        assert rows["FOG scale-factor error s"].sensitivity == pytest.approx(ds, rel=2e-4)
        assert rows["timebase error e"].sensitivity == pytest.approx(de, rel=2e-4)


# ------------------------------------------------------------------------------ reversal times
def test_parabola_vertex_formula_against_a_direct_simulation():
    """u = σ√3/(κW√n) against np.polyfit on noisy parabolas (not the budget's code)."""
    rng = np.random.default_rng(0)
    kappa, sigma, dt, w = 80.0, 2e-5, 1e-4, 5e-3
    tau = np.arange(-w, w + dt / 2, dt)
    est = []
    for _ in range(3000):
        y = -0.5 * kappa * tau**2 + sigma * rng.standard_normal(tau.size)
        c2, c1, _ = np.polyfit(tau, y, 2)
        est.append(-c1 / (2 * c2))
    u = float(reversal_time_u_parabola(sigma, kappa, w, dt)[0])
    assert np.std(est) == pytest.approx(u, rel=0.05)


def test_argmax_estimator_without_noise_is_the_sampling_quantisation():
    assert reversal_time_u_argmax(0.0, 80.0, 2e-5) == pytest.approx(2e-5 / math.sqrt(12))
    # with noise: between the quantisation and the width where the parabola drops by ~σ
    u = reversal_time_u_argmax(1e-5, 80.0, 2e-5)
    assert 2e-5 / math.sqrt(12) < u < math.sqrt(2 * 10 * 1e-5 / 80.0)


@pytest.mark.parametrize("g", [3e-4, 0.05, 0.7, 30.0, 2.4e3, 1e5])
def test_tabulated_argmax_u_equals_a_fresh_monte_carlo(g):
    # truth: the estimator simulated anew (another seed than the table's), σ = g·κ·dt²
    kappa, dt = 80.0, 2e-5
    sigma = g * kappa * dt * dt
    draws = 20_000 if g < 1e3 else 3_000
    mc = reversal_time_u_argmax(sigma, kappa, dt, draws=draws, seed=11)
    tab = reversal_time_u_argmax_tabulated(sigma, kappa, dt)
    # the rms of draws has a relative standard error ≈ 1/√(2·draws)·√(kurtosis-ish): 4 of them
    assert tab == pytest.approx(mc, rel=4.0 * 1.5 / math.sqrt(2 * draws) + 0.01)


def test_tabulated_argmax_u_limits():
    # no noise: the quantisation; beyond the table: the Monte Carlo itself
    assert reversal_time_u_argmax_tabulated(0.0, 80.0, 2e-5) == pytest.approx(
        2e-5 / math.sqrt(12), rel=1e-3
    )
    sigma = 1e8 * 80.0 * 1e-10
    assert reversal_time_u_argmax_tabulated(sigma, 80.0, 1e-5) == reversal_time_u_argmax(
        sigma, 80.0, 1e-5
    )


# ------------------------------------------------------------------------------ THD
def test_jcgm102_magnitude_example_through_the_thd_code_path():
    """|Z| with Re ~ N(0.001, 0.01²), Im ~ N(0, 0.01²): as a THD of A_2 over A_1 = 1 (JCGM 102).

    Published: first-order |Z| = 0.001, u = 0.010; Monte Carlo |Z| = 0.013, u = 0.007. The
    estimator is simulated at the bias-corrected value (0 here: 0.001² < 2·0.01²), which is where
    JCGM 102's numbers are (a Rayleigh distribution: mean 0.01·√(π/2), sd 0.01·√(2 − π/2)).
    """
    t = thd_uncertainty([1.0, 0.001], [0.0, 0.01], trials=1_000_000)
    assert t.plain == pytest.approx(0.1)  # percent of A_1 = 1
    assert t.bias_corrected == 0.0
    assert round(t.mc_mean / 100, 3) == 0.013
    assert round(t.u / 100, 3) == 0.007
    assert t.mc_mean == pytest.approx(100 * 0.01 * math.sqrt(math.pi / 2), rel=3e-3)
    assert any("GUM gives u = 1 %" in n and "does not agree" in n for n in t.budget.notes)
    assert t.budget.method == "Monte Carlo"
    lo, hi = t.interval
    assert lo == 0.0 and t.U == pytest.approx((hi - lo) / 2)
    assert t.budget.interval == t.interval and t.budget.value == t.plain


def _belt_by_ncx2(observed, a1, u, nh, p=0.95):
    """The belt of thd_uncertainty for equal u_h and an exact A_1, from scipy's noncentral χ².

    T/u² ~ χ'²(2(N − 1), P/u²); the tail split α_lo = (1 − p)/2·min(1, P/P*), P* = 4u²√(N − 1)
    (thd_uncertainty's documented rule). An implementation independent of the Monte Carlo.
    """
    nu = 2 * (nh - 1)
    p_star = 4 * u**2 * math.sqrt(nh - 1)
    alpha = 1 - p

    def quantile(theta, q):
        lam = (theta * a1 / 100) ** 2 / u**2
        if q <= 0:
            return 0.0
        x = stats.chi2.ppf(q, nu) if lam == 0 else stats.ncx2.ppf(q, nu, lam)
        return 100 * u * math.sqrt(x) / a1

    def a_lo(theta):
        return 0.5 * alpha * min(1.0, (theta * a1 / 100) ** 2 / p_star)

    def lower(theta):
        return quantile(theta, a_lo(theta)) - observed

    def upper(theta):
        return quantile(theta, 1 - (alpha - a_lo(theta))) - observed

    from scipy.optimize import brentq

    lo = 0.0 if upper(0.0) >= 0 else brentq(upper, 0.0, 10 * observed + 1.0)
    hi = brentq(lower, 1e-12, 10 * observed + 1.0)
    return lo, hi


@pytest.mark.parametrize(
    "harmonics",
    [
        [1.2e-4, 0.8e-4, 0.0, 0.5e-4],  # power consistent with noise: [0, high]
        [4e-4, 3e-4, 0.5e-4, 0.0],  # just detected
        [4e-3, 3e-3, 1e-4, 0.0],  # well above the noise
    ],
)
def test_thd_interval_is_the_noncentral_chi2_belt_for_equal_u(harmonics):
    a = np.array([0.5, *harmonics])
    u = np.array([0.0, *([1e-4] * len(harmonics))])
    t = thd_uncertainty(a, u)
    lo, hi = _belt_by_ncx2(t.plain, 0.5, 1e-4, a.size)
    # within the Monte Carlo's stated error (M chosen for U's two significant digits; the
    # error of an end is at most twice that of U = (hi − lo)/2), and that error is small
    assert t.U_mc_error <= 0.015 * t.U
    assert t.interval[1] == pytest.approx(hi, abs=3 * 2 * t.U_mc_error)
    if lo == 0.0:
        assert t.interval[0] == 0.0
    else:
        assert t.interval[0] == pytest.approx(lo, rel=0.01)
    assert t.U_mc_error < 0.02 * t.U  # the Monte Carlo's own error of U, stated in the budget
    assert any("Monte Carlo standard error of U" in n for n in t.budget.notes)


def test_thd_u_and_bias_against_a_direct_simulation_of_the_estimator():
    """u and bias at a known truth: draw the fitted components, apply eq. (1), no belt code."""
    rng = np.random.default_rng(7)
    truth = np.array([0.5, 3e-4, 2e-4, 0.0, 0.0])
    u = np.array([1e-4, 1e-4, 1e-4, 1e-4, 1e-4])
    z = rng.standard_normal((200_000, truth.size, 2)) * u[None, :, None]
    comp = truth[None, :, None] * np.array([1.0, 0.0]) + z
    amp = np.hypot(comp[..., 0], comp[..., 1])
    est = 100 * np.sqrt(np.sum(amp[:, 1:] ** 2, axis=1)) / amp[:, 0]
    true_thd = 100 * math.sqrt(float(truth[1:] @ truth[1:])) / 0.5
    # thd_uncertainty at a measurement whose bias-corrected THD is the truth (T − 2Σu² = P):
    # its Monte Carlo then runs at that truth
    # (equal u_h: how the power splits over the harmonics does not change the distribution)
    meas = np.array([0.5, math.sqrt(3e-4**2 + 2e-4**2 + 2 * 4 * 1e-8), 0.0, 0.0, 0.0])
    t = thd_uncertainty(meas, u)
    assert t.bias_corrected == pytest.approx(true_thd, rel=1e-12)
    assert t.u == pytest.approx(np.std(est), rel=0.02)
    assert t.bias == pytest.approx(np.mean(est) - true_thd, abs=0.02 * t.u)
    assert t.bias > 0.1 * t.u  # a bias that matters: the check is not vacuous


def _fog_thd(motion, seed, snr_db):
    c = sim.simulate_fog(motion, snr_db=snr_db, fs_hz=2000.0, duration_s=10.125 / 2, seed=seed)
    return calibrate_fog_motion(c.columns["time_s"], c.columns["rate_deg_s"])


def test_bias_corrected_thd_of_a_pure_sine_is_near_zero_and_the_interval_one_sided():
    """True THD 0 at 10 dB SNR: the plain THD is all noise; the noise-power subtraction removes
    most of it, the bias is positive, and the interval is [0, high] when nothing is detected."""
    plain, corrected, one_sided = [], [], 0
    for seed in range(8):
        r = _fog_thd(PURE, seed, 10.0)
        plain.append(r.thd_percent)
        corrected.append(r.thd_percent_bias_corrected)
        assert r.thd_percent_bias > 0  # noise only pushes up
        lo, hi = r._budgets["thd_percent"].interval
        one_sided += lo == 0.0
        assert hi > r.thd_percent_bias_corrected
    assert np.mean(corrected) < 0.5 * np.mean(plain)
    assert one_sided >= 6  # P(lo = 0) = 95 % at a true THD of 0: ≥ 6 of 8 at 99.4 %


def test_bias_correction_is_negligible_for_a_thd_well_above_the_noise():
    """THD ≈ 25 u: the correction and the bias stay below u/5 (added in quadrature to the
    uncertainty they would change U by less than 2 %); the interval is about ±1.96 u."""
    for seed in range(3):
        r = _fog_thd(DISTORTED, seed, 20.0)
        b = r._budgets["thd_percent"]
        assert r.thd_percent > 10 * r.thd_percent_u
        assert abs(r.thd_percent_bias_corrected - r.thd_percent) < 0.2 * r.thd_percent_u
        assert abs(r.thd_percent_bias) < 0.2 * r.thd_percent_u
        lo, hi = b.interval
        assert lo < r.thd_percent < hi
        assert b.k == pytest.approx(1.96, abs=0.1)


def test_thd_bias_corrected_closed_form():
    a = np.array([2.0, 0.03, 0.04, 0.001])
    u = np.array([1e-3, 0.002, 0.002, 0.002])
    expect = 100 * math.sqrt(0.03**2 + 0.04**2 + 0.001**2 - 3 * 2 * 0.002**2) / 2.0
    assert thd_bias_corrected_percent(a, u) == pytest.approx(expect, rel=1e-12)
    assert thd_bias_corrected_percent([1.0, 1e-4], [0, 1e-3]) == 0.0


#: Twin runs per coverage test of the THD interval.
COVERAGE_RUNS = 50


def _thd_motion(thd_percent):
    """A 0.5° motion at 2 Hz of the given true THD (%): harmonics 2 and 3 in the ratio 1 : 0.8."""
    if thd_percent == 0:
        return PURE
    r2 = thd_percent / 100 / math.hypot(1.0, 0.8)  # relative to the fundamental
    return sim.SineMotion(
        amplitude_deg=0.5, frequency_hz=2.0, harmonics={2: (r2, 0.4), 3: (0.8 * r2, 1.1)}
    )


def _misses(kind, sensor, thd_percent, n):
    motion = _thd_motion(thd_percent)
    misses = 0
    for i in range(n):
        cap = sim.simulate(kind, motion=motion, seed=5000 + i, start_s=0.001 * i, **sensor)
        r = _calibrate(kind, cap.columns)
        truth = motion.truth(r.analysis_start_s, r.analysis_stop_s)["thd_percent"]
        assert truth == pytest.approx(thd_percent, abs=1e-9)
        lo, hi = r._budgets["thd_percent"].interval
        misses += not lo <= truth <= hi
    return misses


@pytest.mark.parametrize(
    ("kind", "thd_percent"),
    [
        ("fog", 0.0),
        ("fog", 0.1),
        ("fog", 1.0),
        ("encoder", 0.0),
        ("encoder", 3e-4),  # about the encoder's noise level (FOG: 0.1 % is)
        # 300 times the encoder's noise: detected harmonics, the central belt (P ≫ P*). A THD
        # ten times larger takes the same path (its u against the runs' spread: the honesty
        # twin of DISTORTED, 1.28 %, below)
        ("encoder", 0.1),
    ],
)
def test_thd_interval_covers_the_true_thd(kind, thd_percent):
    """The 95 % interval holds the twin's true THD in 95 % of the runs — also at a true THD of
    0 (FOG at 20 dB; encoder with noise): the count of misses within the binomial bounds of
    COVERAGE_RUNS runs at 99.9 %."""
    sensor = FOG if kind == "fog" else ENC
    misses = _misses(kind, sensor, thd_percent, COVERAGE_RUNS)
    lo, hi = stats.binom.ppf([0.0005, 0.9995], COVERAGE_RUNS, 0.05)
    assert lo <= misses <= hi, f"{misses} misses of {COVERAGE_RUNS} outside [{lo:g}, {hi:g}]"


# ------------------------------------------------------------------------------ honesty
def _honesty(kind, motion, sensor, *, n, specs=None, draw=None, nominal_radius=100.0):
    """Run the twin n times; return {quantity: (std/mean u, lower bound, upper bound)}.

    Without drawn systematic effects (``draw``) also the harmonics above the fundamental that
    the motion has: their U in the report's table is the fit's Type A u (``_plot``).
    """
    rng = np.random.default_rng(2024)
    errs = {k: [] for k in ALL_KEYS if k != "reversal_times_s"}
    us = {k: [] for k in errs}
    orders = [h for h, (rel, _) in motion.harmonics.items() if rel > 0] if draw is None else []
    for h in orders:
        errs[f"harmonic {h}"], us[f"harmonic {h}"] = [], []
    rev_e, rev_u = [], []
    for i in range(n):
        opts = {**sensor, "seed": 100 + i, "start_s": float(rng.uniform(0.0, 0.01))}
        if draw is not None:
            opts.update(draw(rng))
        cap = sim.simulate(kind, motion=motion, **opts)
        r = _calibrate(kind, cap.columns, specs, radius_mm=nominal_radius)
        truth = motion.truth(r.analysis_start_s, r.analysis_stop_s)
        for k in errs:
            if k.startswith("harmonic "):
                h = int(k.split()[1])
                errs[k].append(
                    r.harmonic_amplitudes_deg[h - 1] - truth["harmonic_amplitudes_deg"][h - 1]
                )
                us[k].append(r._plot["harmonic_amplitudes_u_deg"][h - 1])
            else:
                errs[k].append(getattr(r, k) - truth[k])
                us[k].append(r._budgets[k].u)
        e = _nearest(r.reversal_times_s, cap.truth["reversal_times_s"])
        u = r._budgets["reversal_times_s"].u
        if kind == "fog":  # the zero crossings of one fitted model are correlated: one per run
            e = e[[i % e.size]]
        rev_e.append(e)
        rev_u.append(np.full(e.size, u))
    out = {}
    for k in errs:
        out[k] = (np.std(errs[k], ddof=1) / np.mean(us[k]), *_chi2_bounds(n, n - 1))
    e, u = np.concatenate(rev_e), np.concatenate(rev_u)
    # about the truth (no mean removed): a χ² with one degree of freedom per reversal
    out["reversal_times_s"] = (
        math.sqrt(np.mean(e**2) / np.mean(u**2)),
        *_chi2_bounds(e.size, e.size),
    )
    return out


def _assert_honest(out, keys=None):
    for k in keys or out:
        ratio, lo, hi = out[k]
        assert lo < ratio < hi, f"{k}: std/u = {ratio:.3f} outside [{lo:.3f}, {hi:.3f}]"


@pytest.mark.slow
def test_encoder_budgets_are_honest_type_a():
    _assert_honest(_honesty("encoder", DISTORTED, ENC, n=30))


@pytest.mark.slow
def test_encoder_frequency_budget_is_honest_with_a_drawn_timebase_error():
    """A clock error of ±2e-8 (rectangular), drawn per run: comparable to the fit's own u(f)."""
    a = 2e-8
    out = _honesty(
        "encoder",
        DISTORTED,
        ENC,
        n=30,
        specs=_specs(timebase={"relative_error": _rect(a)}),
        draw=lambda rng: {"timebase_relative_error": float(rng.uniform(-a, a))},
    )
    _assert_honest(out)


def _graduation_draw(motion, a):
    """A reading error linear across the stroke, its two end values drawn from U(−a, a) arcsec:
    the budget's model (the error at the two extremes, independent), drawn per run."""
    theta = motion.angle_deg(np.linspace(0.0, 1.0 / motion.frequency_hz, 20_001))
    ends = [float(theta.min()), float(theta.max())]

    def draw(rng):
        return {"graduation_error_arcsec": (ends, rng.uniform(-a, a, 2))}

    return draw


@pytest.mark.slow
def test_encoder_amplitude_budget_is_honest_with_a_drawn_graduation_error():
    """±0.003″ (rectangular) per reading: ~80 % of u(A), the rest the fit's Type A."""
    a = 0.003
    out = _honesty(
        "encoder",
        DISTORTED,
        ENC,
        n=30,
        specs=_specs(encoder={"graduation_error_arcsec": _rect(a)}),
        draw=_graduation_draw(DISTORTED, a),
    )
    _assert_honest(out)


@pytest.mark.slow
def test_lts_budgets_are_honest_type_a():
    _assert_honest(_honesty("lts", MILD_LTS, LTS, n=30))


@pytest.mark.slow
def test_lts_budgets_are_honest_with_a_drawn_radius_and_timebase():
    """The reflector's true R is drawn from N(100, 0.002²) mm per run, the user states 100 mm."""
    specs = _specs(
        timebase={"relative_error": _rect(1e-6)},
        lts={"radius_mm": {"distribution": "normal", "value": 100.0, "u": 0.002}},
    )
    out = _honesty(
        "lts",
        MILD_LTS,
        LTS,
        n=30,
        specs=specs,
        draw=lambda rng: {
            "timebase_relative_error": float(rng.uniform(-1e-6, 1e-6)),
            "radius_mm": float(rng.normal(100.0, 0.002)),
        },
    )
    _assert_honest(out)


@pytest.mark.slow
def test_fog_budgets_are_honest_type_a():
    _assert_honest(_honesty("fog", DISTORTED, FOG, n=30))


@pytest.mark.slow
def test_fog_budgets_are_honest_with_a_drawn_scale_factor_and_timebase():
    specs = _specs(
        timebase={"relative_error": _rect(2e-5)},
        fog={"scale_factor_relative": {"distribution": "normal", "u": 1e-3}},
    )
    out = _honesty(
        "fog",
        DISTORTED,
        FOG,
        n=30,
        specs=specs,
        draw=lambda rng: {
            "timebase_relative_error": float(rng.uniform(-2e-5, 2e-5)),
            "scale_factor_error": float(rng.normal(0.0, 1e-3)),
        },
    )
    _assert_honest(out)


# ------------------------------------------------------------------------------ JSON, paths, errors
@pytest.mark.parametrize("kind", ["encoder", "lts", "fog"])
def test_every_quantity_has_u_big_u_and_k_in_the_json(kind):
    motion = MILD_LTS if kind == "lts" else DISTORTED
    set_values = {
        "set_amplitude_deg": motion.amplitude_deg,
        "set_frequency_hz": motion.frequency_hz,
    }
    c = sim.simulate(kind, motion=motion, seed=0).columns
    r = _calibrate(kind, c, **set_values)
    d = r.to_dict()
    for key in ALL_KEYS + ERROR_KEYS:
        assert d[f"{key}_u"] > 0, key
        assert d[f"{key}_U"] == pytest.approx(d["k"][key] * d[f"{key}_u"], rel=1e-9), key
        assert d["uncertainty_budgets"][key]["rows"], key
    assert d["coverage_probability"] == 0.95
    assert d["thd_percent_u"] == r.thd_percent_u == r._budgets["thd_percent"].u
    assert d["amplitude_deg_u"] == r.amplitude_deg_u
    # one truth: every reported value is its budget's value (the THD's is the plain estimate)
    for key in ALL_KEYS + ERROR_KEYS:
        if key != "reversal_times_s":
            assert d[key] == d["uncertainty_budgets"][key]["value"], key
    for key in ("thd_percent_bias", "thd_percent_bias_corrected"):
        assert math.isfinite(d[key])
    lo, hi = d["thd_percent_interval"]
    assert d["thd_percent_U"] == pytest.approx((hi - lo) / 2)
    tol = 1e-9 * d["thd_percent"]
    assert lo - tol <= d["thd_percent_bias_corrected"] <= hi + tol
    notes = d["uncertainty_budgets"]["amplitude_deg"]["notes"]
    assert any(n.startswith("no instrument specification stated: Type A only") for n in notes)


def test_compare_schemes_difference_u_is_its_budget():
    c = sim.simulate_encoder(DISTORTED, seed=0).columns
    a = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=LINES)
    f = sim.simulate_fog(DISTORTED, snr_db=20.0, seed=0).columns
    b = calibrate_fog_motion(f["time_s"], f["rate_deg_s"])
    row = compare_schemes(a, b)
    d = row.to_dict()
    assert row.thd_difference_percent_u == pytest.approx(
        math.hypot(a.thd_percent_u, b.thd_percent_u)
    )
    assert d["thd_difference_percent_u"] == row.thd_difference_percent_u
    u_amp = 100 * math.hypot(
        b.amplitude_deg / a.amplitude_deg**2 * a.amplitude_deg_u,
        b.amplitude_deg_u / a.amplitude_deg,
    )
    assert d["amplitude_difference_percent_u"] == pytest.approx(u_amp, rel=1e-9)
    for key in (
        "thd_difference_percent",
        "amplitude_difference_percent",
        "frequency_difference_percent",
    ):
        assert d[f"{key}_U"] == pytest.approx(d["k"][key] * d[f"{key}_u"])


def test_chunked_path_gives_the_in_memory_budgets(monkeypatch):
    import rotacal.table.streaming as streaming

    monkeypatch.setattr(streaming, "_GATHER_MAX_SAMPLES", 1000)  # the accumulated fit
    c = sim.simulate_encoder(DISTORTED, noise_rms=0.004, seed=3).columns
    specs = _specs(timebase={"relative_error": _rect(1e-6)})
    kw = {"lines": LINES, "specs": specs, "set_amplitude_deg": 0.5, "set_frequency_hz": 2.0}
    r0 = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], **kw)

    def chunks():
        for i in range(0, c["a"].size, 20_011):
            yield {k: c[k][i : i + 20_011] for k in ("time_s", "a", "b")}

    r = calibrate_encoder_motion_chunked(chunks, **kw)
    assert r._budgets.keys() == r0._budgets.keys()
    for key, b0 in r0._budgets.items():
        assert r._budgets[key].u == pytest.approx(b0.u, rel=1e-4), key
        assert r._budgets[key].value == pytest.approx(b0.value, rel=1e-9, abs=1e-12), key
    # the report's table of harmonics: the same U per harmonic on both paths
    harmonics = [
        next(t for t in motion_section(x, figures=False).tables if "Harmonic" in t.caption).rows
        for x in (r0, r)
    ]
    assert [row[1] for row in harmonics[0]] == [row[1] for row in harmonics[1]]


def test_bad_specifications_are_one_line_config_errors():
    with pytest.raises(ConfigError, match=r"must be ≥ 0"):
        load_specs({"timebase": {"relative_error": {"distribution": "normal", "u": -1e-6}}})
    with pytest.raises(ConfigError, match="unknown distribution"):
        load_specs({"timebase": {"relative_error": {"distribution": "lognormal", "u": 1e-6}}})
    c = sim.simulate_lts(MILD_LTS, seed=0).columns
    other_r = _specs(lts={"radius_mm": {"distribution": "normal", "value": 150.0, "u": 0.1}})
    with pytest.raises(ConfigError, match="radius-mm 100"):
        _calibrate("lts", c, other_r)


def test_a_stated_timebase_mean_is_corrected_for():
    """Policy A: a clock stated 5e-3 fast (the twin's clock is) — the frequency, the
    acceleration and the reversal times come back to the truth; the row keeps value and u."""
    e0 = 5e-3
    c = sim.simulate_encoder(DISTORTED, noise_rms=0.004, seed=5, timebase_relative_error=e0)
    stated = {"distribution": "normal", "value": e0, "u": 1e-7}
    r0 = _calibrate("encoder", c.columns)
    r = _calibrate("encoder", c.columns, _specs(timebase={"relative_error": stated}))
    truth = DISTORTED.truth(0.0, 1.0)
    assert abs(r0.frequency_hz - 2.0) > 50 * r0.frequency_hz_u  # uncorrected: far off
    assert r.frequency_hz == pytest.approx(r0.frequency_hz * (1 + e0), rel=1e-12)
    assert abs(r.frequency_hz - 2.0) < 3 * r.frequency_hz_u
    alpha = truth["angular_acceleration_amplitude_deg_s2"]
    assert abs(r.angular_acceleration_amplitude_deg_s2 - alpha) < 3 * (
        r._budgets["angular_acceleration_amplitude_deg_s2"].u
    )
    err = _nearest(r.reversal_times_s, c.truth["reversal_times_s"])
    err0 = _nearest(r0.reversal_times_s, c.truth["reversal_times_s"])
    assert np.max(np.abs(err)) < 0.1 * np.max(np.abs(err0))
    b = r._budgets["frequency_hz"]
    row = next(x for x in b.rows if x.source.startswith("timebase"))
    assert (row.value, row.u) == (e0, 1e-7)
    assert any("corrected for the stated mean of timebase.relative_error" in n for n in b.notes)
    assert r.amplitude_deg == r0.amplitude_deg  # the encoder's amplitude needs no clock


def test_a_stated_fog_scale_factor_mean_is_corrected_for():
    s0 = 0.005
    c = sim.simulate_fog(
        DISTORTED, snr_db=30.0, seed=6, scale_factor_error=s0, duration_s=10.125 / 2.0
    )
    stated = {"distribution": "normal", "value": s0, "u": 1e-4}
    r = _calibrate("fog", c.columns, _specs(fog={"scale_factor_relative": stated}))
    r0 = _calibrate("fog", c.columns)
    truth = DISTORTED.truth(r.analysis_start_s, r.analysis_stop_s)
    assert abs(r0.amplitude_deg - truth["amplitude_deg"]) > 10 * r0.amplitude_deg_u
    assert abs(r.amplitude_deg - truth["amplitude_deg"]) < 3 * r.amplitude_deg_u
    assert r.thd_percent == pytest.approx(r0.thd_percent, rel=1e-12)  # a ratio: unchanged
    assert r.harmonic_amplitudes_deg[0] == r.amplitude_deg


def test_a_stated_graduation_mean_cancels_in_the_amplitude():
    c = sim.simulate_encoder(DISTORTED, noise_rms=0.004, seed=7).columns
    stated = {"distribution": "rectangular", "value": 0.5, "half_width": 1.0}
    r0 = _calibrate("encoder", c)
    r = _calibrate("encoder", c, _specs(encoder={"graduation_error_arcsec": stated}))
    assert r.amplitude_deg == r0.amplitude_deg
    notes = r._budgets["amplitude_deg"].notes
    assert any("graduation_error_arcsec" in n and "the correction is 0" in n for n in notes)


def test_a_specification_that_does_not_apply_is_ignored():
    c = sim.simulate_encoder(DISTORTED, noise_rms=0.004, seed=4).columns
    r0 = _calibrate("encoder", c)
    r = _calibrate("encoder", c, _specs(lts={"resolution_um": _rect(1.0)}))
    assert r.amplitude_deg_u == r0.amplitude_deg_u
    assert not any("LTS" in row.source for b in r._budgets.values() for row in b.rows)


def test_report_shows_the_budget_tables_without_nan():
    c = sim.simulate_encoder(DISTORTED, noise_rms=0.004, seed=1).columns
    specs = _specs(
        timebase={"relative_error": _rect(2e-6)}, encoder={"graduation_error_arcsec": _rect(1.0)}
    )
    r = _calibrate("encoder", c, specs, set_amplitude_deg=0.5, set_frequency_hz=2.0)
    f = sim.simulate_fog(DISTORTED, snr_db=20.0, seed=0).columns
    rf = calibrate_fog_motion(f["time_s"], f["rate_deg_s"])
    sec = motion_section(r, figures=False)
    captions = [t.caption for t in sec.details]
    for key in r._budgets:
        name = plain_name(key)
        assert any(cap.startswith(f"Uncertainty budget of the {name} (") for cap in captions), key
    cmp = comparison_section([("run", compare_schemes(r, rf), None)])
    text = render_html(Report("t", sections=[sec, motion_section(rf, figures=False), cmp]))
    assert "nan" not in text.lower()
    assert "0.50000 ± 0.00022 °" in text  # ILAC-P14: U to two digits, value to the same place


def test_report_states_one_thing_about_a_thd_near_zero():
    """A pure sine on the FOG: the budget states the interval for the true THD (not plain ± U),
    the summary's one THD row shows the same interval — called an upper limit when the measured
    power is consistent with noise — and the bias-corrected value lies in it. Two runs: one of
    each."""
    kinds = set()
    for seed in (0, 3):
        f = sim.simulate_fog(PURE, snr_db=20.0, fs_hz=2000.0, duration_s=10.125 / 2, seed=seed)
        r = calibrate_fog_motion(f.columns["time_s"], f.columns["rate_deg_s"])
        b = r._budgets["thd_percent"]
        lo, hi = b.interval
        assert lo <= r.thd_percent_bias_corrected <= hi
        statement = b.statement()
        assert "the true value lies in [" in statement and "±" not in statement
        section = motion_section(r, figures=False)
        (row,) = (x for x in section.results if x.quantity == "total harmonic distortion")
        _, u_str = b.rounded()
        dec = len(u_str.split(".")[1])
        assert f"true value in [{max(lo, 0.0):.{dec}f}, {hi:.{dec}f}] %" in row.value
        assert ("consistent with noise" in row.note) == (lo == 0.0)
        text = render_html(Report("t", sections=[section]))
        assert "nan" not in text.lower()
        kinds.add(lo == 0.0)
    assert kinds == {True, False}


def test_budget_tidying_helpers():
    """rotacal.uncertainty.notes: the truncation note goes only when k moves < 10⁻³; rows with a
    zero sensitivity go; notes are appended in order, None skipped."""
    from rotacal.uncertainty import Input, propagate
    from rotacal.uncertainty.notes import drop_truncation_note, tidy, with_notes

    def budget(dof):
        ins = [Input("x", 1.0, 0.1, dof=dof), Input("y", 2.0, 0.1)]
        g = propagate(lambda x, y: x, ins, jacobian=lambda *v: np.array([1.0, 0.0]))
        return g.budget(0)

    small, large = budget(4.5), budget(400.5)
    assert any("truncated to 4" in n for n in small.notes)
    assert drop_truncation_note(small).notes == small.notes  # t(4) vs t(4.5): 3 % apart
    assert not any("truncated" in n for n in drop_truncation_note(large).notes)
    t = tidy(large, "first", None, "second")
    assert [r.source for r in t.rows] == ["x"] and t.u == large.u
    assert t.notes[-2:] == ("first", "second")
    assert with_notes(small, method="Monte Carlo").method == "Monte Carlo"


def test_the_belts_quantile_is_numpys_to_the_bit():
    # the THD belt's own quantile (one partition) against numpy.quantile's default method
    from rotacal.table.motion_thd import _quantile

    rng = np.random.default_rng(17)
    for trial in range(400):
        n = 10_000 if trial % 4 == 0 else int(rng.integers(1, 40))
        values = rng.standard_normal(n) * rng.uniform(0.1, 10.0)
        for q in (0.0, 1.0, 0.025, 0.5, 0.975, float(rng.uniform()), -0.1, 1.2):
            assert _quantile(values, q) == float(np.quantile(values, min(max(q, 0.0), 1.0)))
