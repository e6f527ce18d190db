"""Uncertainty of the self-calibrated deviation (seed 004) against closed forms and the twin.

Also the summaries engine (rotacal.uncertainty.summaries) the deviation's peak-to-peak and rms use,
against closed forms and brute-force simulation.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import integrate, optimize, stats

from rotacal.encoder.selfcal import (
    UNDETECTABLE_SPEC,
    head_shifts,
    noise_gain,
    self_calibrate,
)
from rotacal.errors import ConfigError
from rotacal.sim.pulses import simulate_pulses
from rotacal.uncertainty import Input, InstrumentSpecs, Normal, load_specs
from rotacal.uncertainty.summaries import (
    CirculantError,
    FilteredWhite,
    mc_budget,
    rms_budget,
)

M, N_HEADS = 3600, 4
#: Lines of the coverage twins whose bounds depend on the number of runs alone (binomial, χ²
#: over runs): half the lines of M, half the cost of a run, the same paths and bounds.
M_COVER = 1800
RUNS = 40


def _heads(cap):
    return [cap.columns[f"head_{i}"] for i in range(cap.truth["heads"])]


def _chi2_bounds(n: int) -> tuple[float, float]:
    """99.9 % bounds of std/σ from n degrees of freedom."""
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n)
    return math.sqrt(lo / n), math.sqrt(hi / n)


def _most_misses(n: int, p: float = 0.95) -> int:
    """Largest count of misses of a p-interval in n runs within the 99.9 % binomial bounds."""
    return int(stats.binom.ppf(0.9995, n, 1.0 - p))


def _undetectable_fraction(m: int, n: int) -> float:
    """Share of an iid curve's variance (its mean removed) at the orders that are multiples of n."""
    q = np.arange(m // 2 + 1)
    weight = np.where((q == 0) | (2 * q == m), 1.0, 2.0)
    hit = (q % n == 0) & (q > 0)
    return float(np.sum(weight[hit]) / m)


def _white(sigma: float, n: int, role: str = "noise", dof: float = math.inf) -> CirculantError:
    c = np.zeros(n)
    c[0] = sigma**2
    return CirculantError(Input("noise", 0.0, sigma, dof=dof, unit="a"), role, autocov=c)


# ------------------------------------------------------------------ the summaries engine
def test_rms_budget_closed_form_and_brute_force():
    """ms(f + e), e white N(0, σ²): E = ms(f) + σ², Var = 4σ²·ms(f)/N + 2σ⁴/N (hand), and a
    brute-force simulation of the same model agrees; the bias is rms − √(ms − σ²)."""
    n, sigma, nu = 2000, 0.3, 500.0
    f = np.sin(2 * np.pi * np.arange(n) / 100.0)  # ms(f) = 1/2 exactly
    rng = np.random.default_rng(11)
    d = f + rng.normal(0.0, sigma, n)
    s = rms_budget("rms", "a", d, [_white(sigma, n, dof=nu)])
    b = s.budget
    ms = float(np.mean(d**2))
    assert b.value == math.sqrt(ms) and s.bias_corrected == pytest.approx(math.sqrt(ms - sigma**2))
    assert s.bias == pytest.approx(b.value - s.bias_corrected)
    # hand: the variance, with f estimated from d (dᵀCd − tr C² = σ²(N·ms(d) − Nσ²))
    var = 4 * sigma**2 * (ms - sigma**2) / n + 2 * sigma**4 / n + 2 * sigma**4 / nu
    centre = ms - sigma**2
    t = stats.t.ppf(0.975, nu)  # one source: ν_eff is its ν
    lo, hi = math.sqrt(centre - t * math.sqrt(var)), math.sqrt(centre + t * math.sqrt(var))
    assert b.interval[0] == pytest.approx(lo, rel=1e-3)
    assert b.interval[1] == pytest.approx(hi, rel=1e-3)
    assert b.u == pytest.approx(math.sqrt(var) / (2 * math.sqrt(centre)), rel=1e-9)
    assert b.U == pytest.approx(0.5 * (hi - lo), rel=1e-3) and b.k == pytest.approx(b.U / b.u)
    # brute force: the mean square of many re-draws has the stated mean and spread
    draws = f + rng.normal(0.0, sigma, (4000, n))
    ms_all = np.mean(draws**2, axis=1)
    assert ms_all.mean() == pytest.approx(0.5 + sigma**2, abs=4 * ms_all.std() / math.sqrt(4000))
    hand_sd = math.sqrt(4 * sigma**2 * 0.5 / n + 2 * sigma**4 / n)
    assert ms_all.std(ddof=1) == pytest.approx(hand_sd, rel=0.05)


def test_rms_budget_of_a_filtered_noise_matches_brute_force():
    """A difference-filtered white noise (a rate from two pulse times) plus a repeating curve:
    the closed-form mean and spread of ms(d) against 3000 direct simulations of the model."""
    n, period = 1500, 50
    rng = np.random.default_rng(5)
    f = 0.4 * np.cos(2 * np.pi * np.arange(n) / 300.0)
    jit = FilteredWhite(
        Input("jitter", 0.0, 0.1, unit="s"), "noise", taps=np.array([-1.0, 1.0]), sigma=0.1
    )
    c = 0.02 * np.exp(-np.minimum(np.arange(period), period - np.arange(period)) / 3.0)
    cyc = CirculantError(Input("curve", 0.0, math.sqrt(c[0])), "noise", autocov=c)
    lam = np.maximum(np.fft.rfft(c).real, 0.0) * period

    def draw(size):
        w = rng.standard_normal((size, n + 1)) * 0.1
        z = rng.standard_normal((size, lam.size * 2)).view(np.complex128) * np.sqrt(0.5 * lam)
        z[:, 0] = z[:, 0].real * math.sqrt(2)
        z[:, -1] = z[:, -1].real * math.sqrt(2)
        curve = np.fft.irfft(z, period, axis=-1)
        return np.diff(w, axis=-1) + np.tile(curve, n // period)

    ms = np.mean((f + draw(3000)) ** 2, axis=1)
    d = f + draw(1)[0]
    s = rms_budget("rms", "a", d, [jit, cyc])
    e_noise = 2 * 0.1**2 + c[0]
    assert s.bias_corrected == pytest.approx(math.sqrt(max(np.mean(d**2) - e_noise, 0)), rel=1e-9)
    assert ms.mean() - np.mean(f**2) == pytest.approx(e_noise, rel=0.01)
    # the stated spread (the data's f in place of the truth's) against the simulated one
    centre = s.bias_corrected**2
    sd = s.budget.u * 2 * math.sqrt(centre)
    assert sd == pytest.approx(ms.std(ddof=1), rel=0.1)


def _range_quantile(p: float, n: int) -> float:
    """p-quantile of the range of n iid standard normals, from its exact distribution
    P(W ≤ w) = n·∫ φ(x)·[Φ(x + w) − Φ(x)]^(n−1) dx (Tippett 1925; David & Nagaraja, Order
    Statistics, 3rd ed., eq. 2.3.3 for the normal), integrated numerically."""

    def cdf(w: float) -> float:
        def f(x: float) -> float:
            return float(stats.norm.pdf(x) * (stats.norm.cdf(x + w) - stats.norm.cdf(x)) ** (n - 1))

        return n * integrate.quad(f, -10.0, 10.0, points=[-3.0, 0.0, 3.0], limit=200)[0]

    return float(optimize.brentq(lambda w: cdf(w) - p, 0.0, 20.0))


def test_range_quantile_closed_form_for_two_normals():
    """For n = 2 the range is |x₁ − x₂| ~ half-normal of scale √2: its quantile in closed form."""
    assert _range_quantile(0.975, 2) == pytest.approx(
        math.sqrt(2) * stats.norm.ppf(0.9875), rel=1e-8
    )


def test_peak_to_peak_interval_against_closed_forms():
    """A single sharp spike (only two elements can hold the extremes): both ends are the plain
    value ∓ 1.96·√2·σ. Near zero: the lower end is the plain value less the 97.5 % quantile of
    the range of N independent normals (from the range's exact distribution: no simulation)."""
    n, sigma = 3000, 0.01
    rng = np.random.default_rng(3)
    f = np.zeros(n)
    f[700], f[2100] = 5.0, -4.0
    d = f + rng.normal(0.0, sigma, n)
    s = mc_budget("pp", "a", d, [_white(sigma, n)], statistic="pp")
    lo, hi = s.budget.interval
    half = stats.norm.ppf(0.975) * math.sqrt(2) * sigma
    assert hi == pytest.approx(np.ptp(d) + half, rel=1e-9)
    assert lo == pytest.approx(np.ptp(d) - half, abs=0.1 * half)  # Monte Carlo quantile
    assert s.budget.u == pytest.approx(math.sqrt(2) * sigma, rel=0.1)
    assert abs(s.bias) < 0.5 * sigma
    # pure noise: every element competes
    d0 = rng.normal(0.0, sigma, n)
    s0 = mc_budget("pp", "a", d0, [_white(sigma, n)], statistic="pp")
    q = sigma * _range_quantile(0.975, n)
    assert s0.budget.interval[0] == pytest.approx(max(np.ptp(d0) - q, 0.0), abs=0.05 * q)
    assert s0.bias == pytest.approx(np.ptp(d0), rel=0.3)  # nearly all of it is noise


def test_noise_gain_of_equally_spaced_heads_is_one_over_n():
    """For n equally spaced heads the fit averages the n shifted copies: every head's own noise
    enters the curve at the line it reads with the gain 1/n (0 at the multiples of n)."""
    for head in range(N_HEADS):
        k = noise_gain(head_shifts(N_HEADS, M), M, head)
        q = np.arange(M // 2 + 1)
        det = (q % N_HEADS != 0) & (q > 0)
        assert np.allclose(k[det], 1.0 / N_HEADS, atol=1e-12)
        assert np.all(k[~det] == 0.0)


# ------------------------------------------------------------------ the point budget
@pytest.fixture(scope="module")
def type_a_runs():
    """RUNS twin captures (4 heads × 3600 lines, 3 revolutions), each self-calibrated."""
    out = []
    for k in range(RUNS):
        cap = simulate_pulses(heads=N_HEADS, pulses_per_rev=M, revolutions=3.2, seed=700 + k)
        out.append((cap, self_calibrate(_heads(cap), pulses_per_rev=M)))
    return out


def test_point_u_is_the_revolutions_spread_pooled(type_a_runs):
    """u of every point = √(mean over lines of s²/R): one truth in the field, arrays and budget."""
    _, r = type_a_runs[0]
    per_rev = r.per_revolution_arcsec
    revs = per_rev.shape[0]
    hand = math.sqrt(float(np.mean(per_rev.var(axis=0, ddof=1) / revs)))
    assert r.deviation_u_arcsec == pytest.approx(hand, rel=1e-12)
    assert r.point_budget is not None and r.point_budget.u == r.deviation_u_arcsec
    assert r.deviation_arcsec_u.shape == (M,)
    assert np.all(r.deviation_arcsec_u == r.deviation_u_arcsec)
    # ν from 2(R − 1) per detectable order: thousands, so k is the normal 1.96
    assert r.deviation_dof > 100 * (revs - 1)
    assert r.point_budget.k == pytest.approx(stats.norm.ppf(0.975), abs=2e-3)
    assert r.point_budget.U == pytest.approx(r.point_budget.k * hand)
    assert r.point_budget.rows[0].dof == pytest.approx(r.deviation_dof, rel=1e-9)
    assert any("Type A only" in note for note in r.point_budget.notes)


def test_points_are_honest_type_a(type_a_runs):
    """The curve's error against the twin's detectable truth has the stated u at every line.

    The pooled ratio mean(err²)/mean(u²) is an F(ν₁, ν₂) variable: ν₁ the independent values in
    the errors (2 per detectable order: 2·1350 per run of white noise), ν₂ the stated degrees of
    freedom of u² (Σ of the runs' ν) — so its bounds are as tight as 40 × 3600 lines allow.
    """
    err2, u2, nu2 = [], [], 0.0
    for cap, r in type_a_runs:
        err = r.deviation_arcsec - np.asarray(cap.truth["deviation_detectable_arcsec"])
        err2.append(np.mean(err**2))
        u2.append(r.deviation_u_arcsec**2)
        nu2 += r.deviation_dof
    q = np.arange(M // 2 + 1)
    detectable = int(np.sum((q % N_HEADS != 0) & (q > 0)))
    nu1 = RUNS * 2 * detectable
    lo, hi = np.sqrt(stats.f.ppf([0.0005, 0.9995], nu1, nu2))
    ratio = math.sqrt(np.mean(err2) / np.mean(u2))
    assert lo < ratio < hi, (ratio, lo, hi)
    assert hi - lo < 0.05  # the bounds now reflect the values pooled (a 30 % error cannot pass)


# ------------------------------------------------------------------ pp and rms: coverage
def _summaries(
    cfg: dict,
    seed0: int,
    runs: int = RUNS,
    specs=None,
    truth_key="detectable",
    fixed=False,
    m: int = M,
):
    """Self-calibrate ``runs`` twin captures of m lines; ``fixed``: one truth (scale, heads,
    table: seed0), new timing noise per run (noise_seed) — repeated measurements of the same
    curve."""
    out = []
    for k in range(runs):
        seeds = {"seed": seed0, "noise_seed": k} if fixed else {"seed": seed0 + k}
        cap = simulate_pulses(heads=N_HEADS, pulses_per_rev=m, revolutions=3.2, **seeds, **cfg)
        r = self_calibrate(_heads(cap), pulses_per_rev=m, specs=specs)
        key = "deviation_detectable_arcsec" if truth_key == "detectable" else "deviation_arcsec"
        t = np.asarray(cap.truth[key])
        truth = {"pp": float(np.ptp(t)), "rms": float(np.sqrt(np.mean(t**2))), "curve": t}
        out.append((r, truth))
    return out


NOISY = {"jitter_s": 2e-8}  # curve noise ≈ 0.005 arcsec per line


@pytest.fixture(scope="module")
def zero_runs():
    """The true (detectable) deviation is exactly 0: pp and rms of the data are all noise
    (M_COVER lines: its tests' bounds are the runs')."""
    cfg = {**NOISY, "harmonics": None, "graduation_noise_arcsec": 0.0}
    return _summaries(cfg, 1000, m=M_COVER)


@pytest.fixture(scope="module")
def moderate_runs():
    """One true deviation of 0.1 arcsec peak-to-peak (about 20 times the noise of a line),
    measured RUNS times with new timing noise (M_COVER lines: its tests' bounds are the runs')."""
    cfg = {**NOISY, "harmonics": ((1, 0.05, 0.3), (2, 0.02, 1.1)), "graduation_noise_arcsec": 0.003}
    runs = _summaries(cfg, 3000, fixed=True, m=M_COVER)
    assert len({t["pp"] for _, t in runs}) == 1  # the twin kept the truth
    return runs


@pytest.mark.parametrize("case", ["zero_runs", "moderate_runs"])
@pytest.mark.parametrize("key", ["pp", "rms"])
def test_intervals_cover_the_true_value(request, case, key):
    """Policy B: the stated 95 % interval holds the twin's true value, also at 0 (misses within
    the 99.9 % binomial bounds of 40 runs); the JSON value is the plain value of the data."""
    runs = request.getfixturevalue(case)
    misses = 0
    for r, truth in runs:
        b = r.budgets[f"deviation_{key}_arcsec"]
        assert b.value == getattr(r, f"deviation_{key}_arcsec")
        lo, hi = b.interval
        misses += not lo <= truth[key] <= hi
    assert misses <= _most_misses(len(runs)), misses


@pytest.mark.parametrize("key", ["pp", "rms"])
def test_u_is_the_spread_of_the_plain_value(moderate_runs, key):
    """u = the standard deviation of the plain estimator: its spread over repeated measurements
    of one truth."""
    err = np.asarray([getattr(r, f"deviation_{key}_arcsec") - t[key] for r, t in moderate_runs])
    us = [r.budgets[f"deviation_{key}_arcsec"].u for r, _ in moderate_runs]
    lo, hi = _chi2_bounds(len(err) - 1)
    assert lo < err.std(ddof=1) / np.mean(us) < hi


def test_rms_bias_correction_is_honest(zero_runs, moderate_runs):
    """The rms less its noise bias (exact for a mean square) scatters about the truth by u."""
    for runs in (zero_runs, moderate_runs):
        err = np.asarray([r.deviation_rms_arcsec_bias_corrected - t["rms"] for r, t in runs])
        us = [r.budgets["deviation_rms_arcsec"].u for r, _ in runs]
        lo, hi = _chi2_bounds(len(err))
        assert lo < math.sqrt(np.mean(err**2)) / np.mean(us) < hi


def test_noise_bias_of_the_peak_to_peak(moderate_runs):
    """The stated bias of the plain peak-to-peak is of the size the runs show (it is large: many
    lines near the flat peaks compete; a Monte Carlo on a denoised curve sees it only roughly)."""
    err = np.asarray([r.deviation_pp_arcsec - t["pp"] for r, t in moderate_runs])
    bias = np.asarray([r.deviation_pp_arcsec_bias for r, _ in moderate_runs])
    assert err.mean() > 3 * err.std(ddof=1) / math.sqrt(len(err))  # a real bias ...
    assert 0.5 < bias.mean() / err.mean() < 2.0  # ... that the budget sees


def test_points_and_intervals_with_the_undetectable_specification():
    """The twin's random graduation puts 1/n of its variance at the undetectable orders; stating
    that rms makes the curve's u and the summaries' intervals cover the full truth (Type B)."""
    sigma_g, runs = 0.3, 30  # M_COVER lines: the bounds are the runs'
    u_spec = sigma_g * math.sqrt(_undetectable_fraction(M_COVER, N_HEADS))
    specs = InstrumentSpecs(entries={UNDETECTABLE_SPEC: Normal(0.0, u_spec)}, source="test")
    cfg = {
        "harmonics": ((1, 3.0, 0.3), (2, 0.4, 1.1), (3, 0.15, 2.0)),  # detectable orders only
        "graduation_noise_arcsec": sigma_g,
    }
    out = _summaries(cfg, 900, runs, specs=specs, truth_key="full", m=M_COVER)
    err2, u2, misses, rms_err, rms_u = [], [], {"pp": 0, "rms": 0}, [], []
    for r, truth in out:
        err2.append(np.mean((r.deviation_arcsec - truth["curve"]) ** 2))
        u2.append(r.deviation_u_arcsec**2)
        for key in ("pp", "rms"):
            lo, hi = r.budgets[f"deviation_{key}_arcsec"].interval
            misses[key] += not lo <= truth[key] <= hi
        # the rms of the full truth: the corrected rms with the stated part added in quadrature
        rms_err.append(math.hypot(r.deviation_rms_arcsec_bias_corrected, u_spec) - truth["rms"])
        rms_u.append(r.budgets["deviation_rms_arcsec"].u)
    lo, hi = _chi2_bounds(runs)
    assert lo < math.sqrt(np.mean(err2) / np.mean(u2)) < hi
    assert lo < math.sqrt(np.mean(np.square(rms_err))) / np.mean(rms_u) < hi
    assert max(misses.values()) <= _most_misses(runs), misses
    # the Type B row dominates and the pieces combine in quadrature
    assert math.sqrt(u2[-1]) > 0.9 * u_spec
    rows = r.point_budget.rows
    assert rows[1].u == pytest.approx(u_spec)
    assert r.point_budget.u == pytest.approx(math.hypot(rows[0].u, rows[1].u))
    assert [row.source for row in r.budgets["deviation_pp_arcsec"].rows][1].startswith("orders")


# ------------------------------------------------------------------ one revolution, specs, JSON
def test_one_revolution_without_specification_has_no_uncertainty():
    cap = simulate_pulses(heads=4, pulses_per_rev=M, revolutions=1.4, seed=3)
    r = self_calibrate(_heads(cap), pulses_per_rev=M)
    assert r.revolutions_used == 1 and r.deviation_u_arcsec is None and not r.budgets
    d = r.to_dict()
    assert d["deviation_arcsec_u"] is None and d["k"] == {}
    assert any("one whole revolution" in note for note in r.notes)


def test_one_revolution_with_the_specification_has_a_type_b_budget():
    """P2-7: the stated undetectable orders alone still give every budget (no noise estimate)."""
    cap = simulate_pulses(heads=4, pulses_per_rev=M, revolutions=1.4, seed=3)
    specs = load_specs(
        '[encoder]\nundetectable_harmonics_arcsec = { distribution = "normal", u = 0.05 }\n'
    )
    r = self_calibrate(_heads(cap), pulses_per_rev=M, specs=specs)
    assert r.deviation_u_arcsec == pytest.approx(0.05)
    assert len(r.point_budget.rows) == 1 and r.point_budget.rows[0].u == pytest.approx(0.05)
    d = json.loads(json.dumps(r.to_dict()))
    assert d["deviation_arcsec_u"][0] == pytest.approx(0.05)
    for name in ("deviation_arcsec", "deviation_pp_arcsec", "deviation_rms_arcsec"):
        assert d["k"][name] > 0
    assert d["deviation_pp_arcsec_bias"] is None  # no noise of known level: not corrected
    lo = d["deviation_rms_arcsec_interval"][0]
    assert lo > d["deviation_rms_arcsec"]  # the missing orders raise the true rms
    assert any("cannot be estimated" in n for n in r.point_budget.notes)


def test_stated_mean_of_the_undetectable_orders_is_used_not_dropped():
    """Policy A: a non-zero mean is shown in the row and counts in the rms of the missing orders
    (√(mean² + u²)), with a note — never silently dropped."""
    cap = simulate_pulses(heads=4, pulses_per_rev=M, revolutions=2.2, seed=4)
    toml = '[encoder]\nundetectable_harmonics_arcsec = { distribution = "normal", value = 0.06, u = 0.08 }\n'
    r = self_calibrate(_heads(cap), pulses_per_rev=M, specs=load_specs(toml))
    row = r.point_budget.rows[1]
    assert row.value == pytest.approx(0.06) and row.u == pytest.approx(0.1)
    assert r.point_budget.value == 0.0
    assert any("√(mean² + u²)" in n for n in r.point_budget.notes)


def test_json_keys_and_one_truth(type_a_runs):
    _, r = type_a_runs[0]
    d = json.loads(json.dumps(r.to_dict()))
    assert len(d["deviation_arcsec_u"]) == len(d["deviation_arcsec_U"]) == M
    assert d["deviation_arcsec_u"][0] == d["deviation_u_arcsec"]
    for name in ("deviation_pp_arcsec", "deviation_rms_arcsec"):
        b = d["uncertainty_budgets"][name]
        assert d[name] == b["value"]  # one truth: the plain value in both places
        assert d[f"{name}_u"] == r.budgets[name].u and f"{name}_U" in d
        assert d["k"][name] == pytest.approx(d[f"{name}_U"] / d[f"{name}_u"])
        lo, hi = d[f"{name}_interval"]
        assert d[f"{name}_U"] == pytest.approx(0.5 * (hi - lo))
        assert isinstance(d[f"{name}_bias"], float)
        assert d[f"{name}_bias_corrected"] == pytest.approx(d[name] - d[f"{name}_bias"])
        assert "the true value lies in" in r.budgets[name].statement()
    assert d["uncertainty_budgets"]["deviation_pp_arcsec"]["method"] == "Monte Carlo"
    assert d["k"]["deviation_arcsec"] == pytest.approx(1.96, abs=2e-3)
    assert d["coverage_probability"] == 0.95


def test_bad_specifications_are_one_line_config_errors():
    with pytest.raises(ConfigError) as e:
        load_specs('[timebase]\nrelative_error = { distribution = "normal", u = -1e-6 }\n')
    assert "\n" not in str(e.value) and "'u'" in str(e.value)
    with pytest.raises(ConfigError) as e:
        load_specs('[timebase]\nrelative_error = { distribution = "lorentz", half_width = 1 }\n')
    assert "\n" not in str(e.value) and "unknown distribution" in str(e.value)
    cap = simulate_pulses(heads=4, pulses_per_rev=M, revolutions=2.2, seed=3)
    with pytest.raises(ConfigError, match="InstrumentSpecs"):
        self_calibrate(_heads(cap), pulses_per_rev=M, specs={"timebase": 1})  # type: ignore[arg-type]
