"""Uncertainty budgets of the constant-rate calibration (seed 004 §5): closed forms and the twin."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from rotacal.encoder.pulses import pulse_rate
from rotacal.encoder.selfcal import UNDETECTABLE_SPEC
from rotacal.errors import ConfigError
from rotacal.report.html import Report, write_html
from rotacal.report.pulses import rate_section, selfcal_section
from rotacal.sim.pulses import simulate_pulses, table_angle_deg
from rotacal.table.rate import (
    allan_uncertainty,
    allan_versus_angle,
    calibrate_rate,
    timing_jitter,
)
from rotacal.uncertainty import InstrumentSpecs, Normal, load_specs

M = 3600
#: Lines of the honesty twins whose bounds depend on the number of runs alone (binomial, χ²
#: over runs): half the lines of M, half the cost of a run, the same paths (self-calibration,
#: compensation, every budget) and the same bounds.
M_COVER = 1800
RUNS = 40
CRYSTAL = '[timebase]\nrelative_error = { distribution = "rectangular", half_width = 2e-6 }\n'


def _heads(cap):
    return [cap.columns[f"head_{i}"] for i in range(cap.truth["heads"])]


def _chi2_bounds(n: int) -> tuple[float, float]:
    """99.9 % bounds of rms/σ from n independent errors about a known truth (n dof)."""
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n)
    return math.sqrt(lo / n), math.sqrt(hi / n)


def _most_misses(n: int, p: float = 0.95) -> int:
    """Largest count of misses of a p-interval in n runs within the 99.9 % binomial bounds."""
    return int(stats.binom.ppf(0.9995, n, 1.0 - p))


def _true_deviation(cap) -> np.ndarray:
    """The table's true rate deviation (%) over the same 10-pulse blocks as the measurement."""
    t = cap.columns["head_0"]
    _, rate_true = pulse_rate(t, table_angle_deg(cap.truth, t), average=10)
    omega = cap.truth["mean_rate_whole_revs_deg_s"]
    return 100.0 * (rate_true - omega) / omega


def _train(rate, revs, jitter, seed, grad_arcsec=2.0, wobble=0.0):
    """One head: line j at j·Δθ + e_j (iid, arcsec), a rate ω(1 + wobble·cos 2πft), jitter (s)."""
    rng = np.random.default_rng(seed)
    n = int(revs * M) + 1
    e = rng.normal(0.0, grad_arcsec, M)
    angle = np.arange(n) * (360.0 / M) + e[np.arange(n) % M] / 3600.0
    t = angle / rate  # then bend time by the (slow) wobble: θ = ω(t + w/(2πf)·sin 2πft)
    f = 1.7
    for _ in range(3):
        t = angle / rate - wobble / (2 * np.pi * f) * np.sin(2 * np.pi * f * t)
    return t + rng.normal(0.0, jitter, n)


# ------------------------------------------------------------------ timing jitter (Type A)
def test_timing_jitter_sees_through_graduation_and_rate_wobble():
    sigma = 5e-9
    est = [timing_jitter(_train(100.0, 3.3, sigma, s, wobble=1e-3), M) for s in range(4)]
    for s_hat, dof, exact in est:
        assert exact and dof > 1000
        assert s_hat == pytest.approx(sigma, rel=4 / math.sqrt(2 * dof))
    # without the same-line difference the 2-arcsec graduation would swamp the jitter
    s_short, _, exact = timing_jitter(_train(100.0, 1.5, sigma, 9), M)
    assert not exact and s_short > 10 * sigma


def test_timing_jitter_degrees_of_freedom_are_honest():
    """The stated ν of σ̂_t matches the scatter of σ̂_t² over 60 records (var = 2σ⁴/ν); a record
    shorter than the lag 2m of the same-line difference has fewer correlated pairs."""
    runs, sigma = 60, 2e-8
    est = [
        timing_jitter(_train(100.0, 3.2, sigma, 400 + s, grad_arcsec=0.5), M) for s in range(runs)
    ]
    v = np.asarray([e[0] ** 2 for e in est])
    nu = float(np.mean([e[1] for e in est]))
    ratio = v.std(ddof=1) / (v.mean() * math.sqrt(2.0 / nu))
    lo, hi = _chi2_bounds(runs - 1)
    assert lo < ratio < hi, (ratio, nu)


# ------------------------------------------------------------------ mean rate: closed form
def test_mean_rate_budget_closed_form():
    """ω = 360R/T·(1 + δ): ∂ω/∂δ = ω, ∂ω/∂(end − start timing error) = ω/T; a ±a rectangular
    timebase that dominates gives the 95 % half-width 0.95·a·ω, i.e. k = 0.95·√3."""
    t = _train(100.0, 3.2, 5e-9, 1)
    r = calibrate_rate([t], pulses_per_rev=M, compensate=False, specs=load_specs(CRYSTAL))
    b = r.budgets["mean_rate_deg_s"]
    span = t[3 * M] - t[0]
    omega = 3 * 360.0 / span
    assert r.mean_rate_deg_s == b.value == pytest.approx(omega, rel=1e-15)
    rows = {row.source: row for row in b.rows}
    tb = rows["timebase relative error"]
    assert tb.sensitivity == pytest.approx(omega, rel=1e-6)
    assert tb.contribution == pytest.approx(omega * 2e-6 / math.sqrt(3), rel=1e-6)
    jit = rows["pulse timing jitter at the window's two ends"]
    assert jit.u == pytest.approx(math.sqrt(2) * r.timing_jitter_s)
    assert jit.sensitivity == pytest.approx(omega / span, rel=1e-6)
    assert rows["graduation error over whole revolutions"].u == 0.0
    assert b.u == pytest.approx(math.hypot(tb.contribution, jit.contribution), rel=1e-9)
    assert b.method == "Monte Carlo"  # the GUM's k = 1.96 fails JCGM 101 §8 here
    assert b.k == pytest.approx(0.95 * math.sqrt(3), rel=0.01)
    # Type A only: normal, validated, and says so
    r0 = calibrate_rate([t], pulses_per_rev=M, compensate=False)
    b0 = r0.budgets["mean_rate_deg_s"]
    assert b0.method == "GUM, validated by Monte Carlo"
    assert b0.u == pytest.approx(jit.contribution, rel=1e-9)
    assert b0.k == pytest.approx(1.96, abs=0.01)
    assert any("Type A only" in note for note in b0.notes)


def test_bias_budget_adds_the_tables_wander_per_revolution():
    t = _train(100.0, 4.2, 5e-9, 2, wobble=2e-4)
    r = calibrate_rate([t], pulses_per_rev=M, compensate=False, set_rate_deg_s=-100.0)
    per_rev = 360.0 / np.diff(t[: 4 * M + 1 : M])
    rows = {row.source: row for row in r.budgets["rate_bias_deg_s"].rows}
    wander = rows["table rate wander between revolutions"]
    assert wander.u == pytest.approx(np.std(per_rev, ddof=1) / 2.0, rel=1e-9)
    assert wander.dof == 3 and wander.sensitivity == pytest.approx(1.0)
    pct = {row.source: row for row in r.budgets["rate_bias_percent"].rows}
    assert pct["table rate wander between revolutions"].sensitivity == pytest.approx(1.0)
    assert r.budgets["rate_bias_percent"].u == pytest.approx(r.budgets["rate_bias_deg_s"].u)
    assert r.rate_bias_deg_s == pytest.approx(r.mean_rate_deg_s - 100.0)
    assert r.budgets["rate_bias_deg_s"].k == pytest.approx(stats.t.ppf(0.975, 3), rel=0.05)


# ------------------------------------------------------------------ honesty with the twin
@pytest.fixture(scope="module")
def twin_mean_rates():
    """RUNS captures without and with a ±2 ppm timebase error drawn per run by the twin
    (M_COVER lines: the bounds are the runs')."""
    specs = load_specs(CRYSTAL)
    out: dict[str, list[tuple[float, float]]] = {"A": [], "B": []}
    for k in range(RUNS):
        for kind, half, sp in (("A", 0.0, None), ("B", 2e-6, specs)):
            cap = simulate_pulses(
                heads=4,
                pulses_per_rev=M_COVER,
                revolutions=3.2,
                timebase_error_half_width=half,
                seed=300 + k,
            )
            r = calibrate_rate(
                [cap.columns["head_0"]], pulses_per_rev=M_COVER, compensate=False, specs=sp
            )
            true = cap.truth["mean_rate_whole_revs_deg_s"]
            out[kind].append((r.mean_rate_deg_s - true, r.budgets["mean_rate_deg_s"].u))
    return out


@pytest.mark.parametrize("kind", ["A", "B"])
def test_mean_rate_is_honest(twin_mean_rates, kind):
    """Type A: jitter only (the table's 0.01 % fluctuation is in the window's true mean);
    Type B: the twin's clock error, drawn per run from the stated rectangular distribution."""
    err, u = np.asarray(twin_mean_rates[kind]).T
    lo, hi = _chi2_bounds(RUNS)
    assert lo < math.sqrt(np.mean(err**2)) / np.mean(u) < hi


def test_twin_timebase_and_its_correction():
    """The twin's clock makes every time (1 + δ) long; a stated δ̂ corrects the rate back."""
    base = simulate_pulses(heads=2, pulses_per_rev=M, revolutions=2.2, seed=5)
    cap = simulate_pulses(
        heads=2, pulses_per_rev=M, revolutions=2.2, seed=5, timebase_relative_error=1e-5
    )
    assert cap.truth["timebase_relative_error_drawn"] == 1e-5
    assert np.allclose(cap.columns["head_1"], base.columns["head_1"] * (1 + 1e-5), rtol=1e-15)
    drawn = {
        simulate_pulses(
            heads=2, pulses_per_rev=M, revolutions=1.2, seed=s, timebase_error_half_width=1e-6
        ).truth["timebase_relative_error_drawn"]
        for s in range(5)
    }
    assert len(drawn) == 5 and all(abs(d) <= 1e-6 for d in drawn)
    specs = load_specs(
        '[timebase]\nrelative_error = { distribution = "normal", value = 1e-5, u = 1e-8 }\n'
    )
    r = calibrate_rate([cap.columns["head_0"]], pulses_per_rev=M, compensate=False, specs=specs)
    true = cap.truth["mean_rate_whole_revs_deg_s"]
    assert r.timebase_correction == 1e-5
    assert any("corrected for the stated mean of timebase.relative_error" in n for n in r.notes)
    b = r.budgets["mean_rate_deg_s"]
    assert any("corrected for the stated mean" in n for n in b.notes)
    assert {row.source: row.value for row in b.rows}["timebase relative error"] == 1e-5
    assert r.mean_rate_deg_s == pytest.approx(true, rel=1e-9)
    assert abs(r.mean_rate_deg_s - true) < 3 * r.budgets["mean_rate_deg_s"].u
    raw = calibrate_rate([cap.columns["head_0"]], pulses_per_rev=M, compensate=False)
    assert raw.mean_rate_deg_s == pytest.approx(true / (1 + 1e-5), rel=1e-9)


# ------------------------------------------------------------------ mean rate and bias agree
def test_bias_and_mean_rate_get_the_same_validation():
    """P1-5: the same inputs give the same U. Without the table's wander (one revolution) the bias
    is the mean rate less an exact set rate: with a dominating rectangular timebase both fall
    back to the Monte Carlo interval (k ≈ 0.95·√3); with wander, deg/s and % share one method."""
    t = _train(100.0, 1.6, 5e-9, 8, grad_arcsec=0.0)  # the jitter bound then is the jitter
    r = calibrate_rate(
        [t], pulses_per_rev=M, compensate=False, set_rate_deg_s=100.0, specs=load_specs(CRYSTAL)
    )
    mean_b, bias_b = r.budgets["mean_rate_deg_s"], r.budgets["rate_bias_deg_s"]
    assert mean_b.method == bias_b.method == "Monte Carlo"
    assert bias_b.U == pytest.approx(mean_b.U, rel=1e-9) and bias_b.k == pytest.approx(mean_b.k)
    assert bias_b.k == pytest.approx(0.95 * math.sqrt(3), rel=0.01)
    pct = r.budgets["rate_bias_percent"]
    assert pct.method == bias_b.method and pct.U == pytest.approx(bias_b.U, rel=1e-9)
    r4 = calibrate_rate(
        [_train(100.0, 4.2, 5e-9, 2, wobble=2e-4)],
        pulses_per_rev=M,
        compensate=False,
        set_rate_deg_s=100.0,
        specs=load_specs(CRYSTAL),
    )
    methods = {r4.budgets[k].method for k in ("rate_bias_deg_s", "rate_bias_percent")}
    assert len(methods) == 1
    assert any("JCGM 101 §8" in n for n in r4.budgets["rate_bias_deg_s"].notes)


# ------------------------------------------------------------------ rate deviation: policy B
DETECTABLE = ((1, 3.0, 0.3), (2, 0.4, 1.1))  # scale orders 4 heads can see


def _undetectable_specs(sigma_g: float, m: int = M) -> InstrumentSpecs:
    """The rms that iid line errors of σ_g leave at the orders 4 heads cannot see (1/4 of their
    variance, m lines) as encoder.undetectable_harmonics_arcsec."""
    q = np.arange(m // 2 + 1)
    weight = np.where((q == 0) | (2 * q == m), 1.0, 2.0)
    frac = float(np.sum(weight[(q % 4 == 0) & (q > 0)]) / m)
    return InstrumentSpecs(
        entries={UNDETECTABLE_SPEC: Normal(0.0, sigma_g * math.sqrt(frac))}, source="test"
    )


def _rate_runs(
    revs: float,
    fluct: float,
    seed0: int,
    runs: int = RUNS,
    fixed: bool = False,
    sigma_g: float = 0.003,
    specs: InstrumentSpecs | None = None,
    m: int = M,
):
    """``runs`` compensated rate calibrations of the 4-head twin of m lines with 20 ns timing
    noise (about 9·10⁻⁴ % per rate point at 3600 lines) and a scale the heads nearly fully see
    (the 0.003″ random lines leave ~6·10⁻⁵ % at the orders they cannot); ``fixed``: one truth
    (table and scale), new timing noise per run."""
    out = []
    for k in range(runs):
        seeds = {"seed": seed0, "noise_seed": k} if fixed else {"seed": seed0 + k}
        cap = simulate_pulses(
            heads=4,
            pulses_per_rev=m,
            revolutions=revs,
            harmonics=DETECTABLE,
            graduation_noise_arcsec=sigma_g,  # a little: the lines' pattern confirms m
            rate_fluctuation_percent=fluct,
            jitter_s=2e-8,
            **seeds,
        )
        r = calibrate_rate(_heads(cap), pulses_per_rev=m, specs=specs)
        dev = _true_deviation(cap)
        out.append(
            (r, {"rms": float(np.sqrt(np.mean(dev**2))), "peak": float(np.max(np.abs(dev)))})
        )
    return out


@pytest.fixture(scope="module")
def rate_zero_runs():
    """More than two revolutions, a table without fluctuation: the true deviation is 0."""
    return _rate_runs(3.2, 0.0, 2000)


@pytest.fixture(scope="module")
def rate_moderate_runs():
    """One table with a 0.003 % fluctuation (several times the noise of a point), measured anew
    (M_COVER lines: its tests' bounds are the runs')."""
    return _rate_runs(3.2, 0.003, 2100, fixed=True, m=M_COVER)


@pytest.fixture(scope="module")
def rate_short_runs():
    """1.5 revolutions (timing noise only bounded, one-revolution self-calibration: its noise
    unknown), both a table without fluctuation and one with 0.003 %; the twin's usual 0.03″
    random lines, their undetectable part stated (Type B); M_COVER lines (binomial bounds)."""
    specs = _undetectable_specs(0.03, M_COVER)
    return _rate_runs(1.5, 0.0, 2200, sigma_g=0.03, specs=specs, m=M_COVER) + _rate_runs(
        1.5, 0.003, 2300, sigma_g=0.03, specs=specs, m=M_COVER
    )


@pytest.mark.parametrize("case", ["rate_zero_runs", "rate_moderate_runs", "rate_short_runs"])
@pytest.mark.parametrize("key", ["rms", "peak"])
def test_rate_deviation_intervals_cover_the_truth(request, case, key):
    """Policy B: the 95 % interval holds the table's true rms/peak deviation, at 0 and at a
    moderate value, with more and with fewer than two revolutions (misses within the 99.9 %
    binomial bounds); the JSON value is the plain value of the data."""
    runs = request.getfixturevalue(case)
    misses = 0
    for r, truth in runs:
        b = r.budgets[f"rate_deviation_{key}_percent"]
        assert b.value == getattr(r, f"rate_deviation_{key}_percent")
        lo, hi = b.interval
        misses += not lo <= truth[key] <= hi
    assert misses <= _most_misses(len(runs)), misses


@pytest.mark.parametrize("key", ["rms", "peak"])
def test_rate_deviation_u_is_the_spread_of_the_plain_value(rate_moderate_runs, key):
    err = np.asarray(
        [getattr(r, f"rate_deviation_{key}_percent") - t[key] for r, t in rate_moderate_runs]
    )
    us = [r.budgets[f"rate_deviation_{key}_percent"].u for r, _ in rate_moderate_runs]
    lo, hi = _chi2_bounds(len(err) - 1)
    assert lo < err.std(ddof=1) / np.mean(us) < hi


def test_rate_rms_bias_correction_is_honest(rate_zero_runs, rate_moderate_runs):
    """The rms less the bias of the noise of known level scatters about the truth by u — only
    when the model holds every part of that noise, including the rate head's own timing noise
    that the self-calibration of the same capture carries (it cancels an eighth of it here)."""
    for runs in (rate_zero_runs, rate_moderate_runs):
        err = np.asarray([r.rate_deviation_rms_percent_bias_corrected - t["rms"] for r, t in runs])
        us = [r.budgets["rate_deviation_rms_percent"].u for r, _ in runs]
        lo, hi = _chi2_bounds(len(err))
        assert lo < math.sqrt(np.mean(err**2)) / np.mean(us) < hi


def test_noise_of_the_rate_points_is_modelled(rate_zero_runs):
    """With a still table the data are all noise: their mean square equals the stated noise mean
    square (bias of the rms) — 12 % less than jitter plus curve noise taken as independent."""
    actual = np.mean([r.rate_deviation_rms_percent**2 for r, _ in rate_zero_runs])
    stated = np.mean(
        [
            r.rate_deviation_rms_percent**2 - r.rate_deviation_rms_percent_bias_corrected**2
            for r, _ in rate_zero_runs
        ]
    )
    # 40 × 1145 points: ±1 % (1σ); the 0.003″ lines leave ~0.5 % at orders no head sees
    assert actual == pytest.approx(stated, rel=0.04)
    notes = rate_zero_runs[0][0].budgets["rate_deviation_rms_percent"].notes
    assert any("correlation of the rate head's timing noise" in n for n in notes)


def test_short_records_and_specifications_are_never_subtracted(rate_short_runs):
    """P1-2: with fewer than two revolutions the timing noise is only an upper bound (it holds
    the graduation): nothing is subtracted, the statement is one-sided; and a stated graduation
    (Type B) widens the interval but never lowers the value or its upper end."""
    for r, _ in rate_short_runs[:5]:
        assert r.rate_deviation_rms_percent_bias is None
        assert r.rate_deviation_peak_percent_bias_corrected is None
        b = r.budgets["rate_deviation_rms_percent"]
        assert b.interval[0] == 0.0 or b.interval[0] < b.value
        assert any("firm statement is the upper end" in n for n in b.notes)
    cap = simulate_pulses(heads=2, pulses_per_rev=M, revolutions=3.2, seed=31)
    grad = load_specs('[encoder]\ngraduation_error_arcsec = { distribution = "normal", u = 1.0 }\n')
    plain = calibrate_rate([cap.columns["head_0"]], pulses_per_rev=M, compensate=False)
    spec = calibrate_rate([cap.columns["head_0"]], pulses_per_rev=M, compensate=False, specs=grad)
    for key, rel in (("rms", 1e-12), ("peak", 1e-3)):  # the peak's: Monte Carlo noise only
        name = f"rate_deviation_{key}_percent"
        assert getattr(spec, name) == getattr(plain, name)
        assert getattr(spec, f"{name}_bias_corrected") == pytest.approx(
            getattr(plain, f"{name}_bias_corrected"), rel=rel
        )
        assert spec.budgets[name].interval[1] >= plain.budgets[name].interval[1]
        assert spec.budgets[name].interval[0] <= plain.budgets[name].interval[0]
    true_rms = float(np.sqrt(np.mean(_true_deviation(cap) ** 2)))
    lo, hi = spec.budgets["rate_deviation_rms_percent"].interval
    assert lo <= true_rms <= hi  # the 0.03″ graduation, stated as 1″: well inside


@pytest.mark.slow
def test_rate_deviation_intervals_with_the_undetectable_specification():
    """The twin's random graduation leaves 1/n of its variance at orders no head arrangement
    sees; stated as encoder.undetectable_harmonics_arcsec, it is what the compensated rate still
    holds (Type B: the intervals must cover the truth, the value is not corrected for it);
    M_COVER lines (binomial bounds)."""
    sigma_g, runs = 0.1, 40
    specs = _undetectable_specs(sigma_g, M_COVER)
    misses = {"rms": 0, "peak": 0}
    for k in range(runs):
        cap = simulate_pulses(
            heads=4,
            pulses_per_rev=M_COVER,
            revolutions=3.2,
            harmonics=DETECTABLE,
            graduation_noise_arcsec=sigma_g,
            seed=6000 + k,
        )
        r = calibrate_rate(_heads(cap), pulses_per_rev=M_COVER, specs=specs)
        dev = _true_deviation(cap)
        for key, value in (("rms", np.sqrt(np.mean(dev**2))), ("peak", np.max(np.abs(dev)))):
            lo, hi = r.budgets[f"rate_deviation_{key}_percent"].interval
            misses[key] += not lo <= value <= hi
    assert max(misses.values()) <= _most_misses(runs), misses
    rows = [row.source for row in r.budgets["rate_deviation_peak_percent"].rows]
    assert "orders no head arrangement sees (multiples of n)" in rows


def test_allan_uncertainty_is_honest_for_white_timing_noise():
    """s(φ) of white timing noise scatters over runs as its edf says (Greenhall & Riley).

    calibrate_rate's s(φ) and u of one head are allan_versus_angle of its nominal angles at the
    mean rate over whole revolutions and allan_uncertainty of those (checked to 1e-12 on the
    first run); the runs take that path, without the rate's Monte Carlo budgets that this test
    does not read (39 of 40 calibrations' time)."""
    phis = [0.1, 1, 10, 100, 300]
    values, us = [], []
    for k in range(RUNS):
        cap = simulate_pulses(
            heads=2,
            pulses_per_rev=M,
            rate_deg_s=100.0,
            revolutions=6,
            harmonics=None,
            graduation_noise_arcsec=0.0,
            rate_fluctuation_percent=0.0,
            jitter_s=2e-7,
            seed=5000 + k,
        )
        t = cap.columns["head_0"]
        revs = (t.size - 1) // M
        omega = 360.0 * revs / (t[revs * M] - t[0])
        phi, s = allan_versus_angle(
            t, np.arange(t.size) * (360.0 / M), mean_rate_deg_s=omega, angles_deg=phis
        )
        u, _, _, low, high, alpha = allan_uncertainty(s, phi, 360.0 / M, t.size)
        if k == 0:
            r = calibrate_rate([t], pulses_per_rev=M, allan_angles_deg=phis)
            assert r.mean_rate_deg_s == pytest.approx(omega, rel=1e-12)
            np.testing.assert_allclose(r.allan_angle_deg, phi, rtol=1e-12)
            np.testing.assert_allclose(r.allan_relative, s, rtol=1e-12)
            np.testing.assert_allclose(r.allan_relative_u, u, rtol=1e-12)
            np.testing.assert_allclose(r.allan_relative_interval, np.c_[low, high], rtol=1e-12)
            assert r.allan_noise_alpha == alpha.tolist()
        assert alpha.tolist() == [2] * 5
        assert np.all(low < s) and np.all(s < high)
        values.append(s)
        us.append(u)
    values, us = np.asarray(values), np.asarray(us)
    lo, hi = _chi2_bounds(RUNS - 1)  # about the runs' own mean
    ratio = values.std(axis=0, ddof=1) / us.mean(axis=0)
    assert np.all((lo < ratio) & (ratio < hi)), ratio


# ------------------------------------------------------------------ keys, notes, errors, report
@pytest.fixture(scope="module")
def full():
    cap = simulate_pulses(heads=4, pulses_per_rev=M, revolutions=3.2, seed=21)
    specs = load_specs(CRYSTAL)
    return calibrate_rate(_heads(cap), pulses_per_rev=M, set_rate_deg_s=300.0, specs=specs)


def test_json_keys(full):
    d = json.loads(json.dumps(full.to_dict()))
    for name in (
        "mean_rate_deg_s",
        "rate_bias_deg_s",
        "rate_bias_percent",
        "rate_deviation_rms_percent",
        "rate_deviation_peak_percent",
    ):
        assert d[f"{name}_u"] > 0 and d[f"{name}_U"] > d[f"{name}_u"]
        assert d["k"][name] == pytest.approx(d[f"{name}_U"] / d[f"{name}_u"])
        assert name in d["uncertainty_budgets"]
    n = len(d["allan_relative"])
    assert len(d["allan_relative_u"]) == len(d["allan_relative_U"]) == len(d["k"]["allan_relative"])
    assert len(d["allan_relative_edf"]) == len(d["allan_relative_interval"]) == n
    assert d["coverage_probability"] == 0.95
    assert d["timing_jitter_s"] > 0 and d["rate_deviation_rms_percent_bias_corrected"] > 0
    for name in ("rate_deviation_rms_percent", "rate_deviation_peak_percent"):
        lo, hi = d[f"{name}_interval"]
        assert d[f"{name}_U"] == pytest.approx(0.5 * (hi - lo))
        assert d[name] == d["uncertainty_budgets"][name]["value"]  # one truth
        assert d[f"{name}_bias_corrected"] == pytest.approx(d[name] - d[f"{name}_bias"])


def test_compensation_sources_and_notes():
    cap = simulate_pulses(heads=4, pulses_per_rev=M, revolutions=3.2, seed=22)
    heads = _heads(cap)
    own = calibrate_rate(heads, pulses_per_rev=M)
    sources = [row.source for row in own.budgets["rate_deviation_rms_percent"].rows]
    assert "noise of the self-calibrated deviation" in sources
    assert any(UNDETECTABLE_SPEC in n for n in own.budgets["rate_deviation_rms_percent"].notes)
    # a selfcal JSON brings its per-line u along
    other = simulate_pulses(heads=4, pulses_per_rev=M, revolutions=3.2, seed=22, jitter_s=2e-9)
    assert own.selfcal is not None
    r = calibrate_rate(_heads(other), pulses_per_rev=M, selfcal=own.selfcal.to_dict())
    rows = {row.source: row for row in r.budgets["rate_deviation_rms_percent"].rows}
    assert rows["noise of the self-calibrated deviation"].u == pytest.approx(
        own.selfcal.deviation_u_arcsec
    )
    # one head, not compensated: the graduation is stated, or the budget says it is missing
    single = calibrate_rate([heads[0]], pulses_per_rev=M)
    assert any("not compensated" in n for n in single.budgets["rate_deviation_rms_percent"].notes)
    grad = load_specs('[encoder]\ngraduation_error_arcsec = { distribution = "normal", u = 0.5 }\n')
    single = calibrate_rate([heads[0]], pulses_per_rev=M, specs=grad)
    names = [row.source for row in single.budgets["rate_deviation_rms_percent"].rows]
    assert "graduation error (not compensated)" in names


def test_bad_specs_are_config_errors():
    cap = simulate_pulses(heads=2, pulses_per_rev=M, revolutions=2.2, seed=5)
    with pytest.raises(ConfigError, match="InstrumentSpecs"):
        calibrate_rate(_heads(cap), pulses_per_rev=M, specs="lab.toml")  # type: ignore[arg-type]
    with pytest.raises(ConfigError) as e:
        load_specs(
            '[timebase]\nrelative_error = { distribution = "rectangular", half_width = -2e-6 }\n'
        )
    assert "\n" not in str(e.value) and "half_width" in str(e.value)


def test_report_shows_the_budgets(full, tmp_path):
    assert full.selfcal is not None
    path = write_html(
        Report("rate", sections=[rate_section(full), selfcal_section(full.selfcal)]),
        tmp_path / "r.html",
    )
    text = path.read_text(encoding="utf-8")
    for name in ("mean rate", "rate bias", "rate fluctuation, rms"):
        assert f"Uncertainty budget of the {name}" in text
    assert "Uncertainty budget of the scale deviation, peak-to-peak" in text
    assert "each point of the deviation curve" in text
    assert "relative root Allan variance with its 95 % interval".lower() in text.lower()
    assert ">nan<" not in text.lower() and " nan " not in text.lower()
