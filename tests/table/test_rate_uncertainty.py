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
from rotacal.table.rate import calibrate_rate, timing_jitter
from rotacal.uncertainty import InstrumentSpecs, Normal, load_specs

M = 3600
RUNS = 40
CRYSTAL = '[timebase]\nrelative_error = { distribution = "rectangular", half_width = 2e-6 }\n'


def _heads(cap):
    return [cap.columns[f"head_{i}"] for i in range(cap.truth["heads"])]


def _chi2_bounds(n: int) -> tuple[float, float]:
    """99.9 % bounds of rms/σ from n independent errors about a known truth (n dof)."""
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], n)
    return math.sqrt(lo / n), math.sqrt(hi / n)


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
    """RUNS captures without and with a ±2 ppm timebase error drawn per run by the twin."""
    specs = load_specs(CRYSTAL)
    out: dict[str, list[tuple[float, float]]] = {"A": [], "B": []}
    for k in range(RUNS):
        for kind, half, sp in (("A", 0.0, None), ("B", 2e-6, specs)):
            cap = simulate_pulses(
                heads=4,
                pulses_per_rev=M,
                revolutions=3.2,
                timebase_error_half_width=half,
                seed=300 + k,
            )
            r = calibrate_rate(
                [cap.columns["head_0"]], pulses_per_rev=M, compensate=False, specs=sp
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
    assert r.timebase_correction == 1e-5 and any("timebase error" in n for n in r.notes)
    assert r.mean_rate_deg_s == pytest.approx(true, rel=1e-9)
    assert abs(r.mean_rate_deg_s - true) < 3 * r.budgets["mean_rate_deg_s"].u
    raw = calibrate_rate([cap.columns["head_0"]], pulses_per_rev=M, compensate=False)
    assert raw.mean_rate_deg_s == pytest.approx(true / (1 + 1e-5), rel=1e-9)


@pytest.mark.slow
def test_rate_deviation_rms_and_peak_are_honest():
    """The Monte Carlo budgets of the rms and peak rate deviation against the twin's true rate.

    The twin's random graduation leaves 1/n of its variance at orders no head arrangement sees;
    stated as encoder.undetectable_harmonics_arcsec, it is what the compensated rate still holds.
    """
    sigma_g, runs = 0.1, 30
    q = np.arange(M // 2 + 1)
    weight = np.where((q == 0) | (2 * q == M), 1.0, 2.0)
    frac = float(np.sum(weight[(q % 4 == 0) & (q > 0)]) / M)
    specs = InstrumentSpecs(
        entries={UNDETECTABLE_SPEC: Normal(0.0, sigma_g * math.sqrt(frac))}, source="test"
    )
    err = {"rms": [], "peak": []}
    us = {"rms": [], "peak": []}
    for k in range(runs):
        cap = simulate_pulses(
            heads=4,
            pulses_per_rev=M,
            revolutions=3.2,
            harmonics=((1, 3.0, 0.3), (2, 0.4, 1.1)),
            graduation_noise_arcsec=sigma_g,
            seed=6000 + k,
        )
        r = calibrate_rate(_heads(cap), pulses_per_rev=M, specs=specs)
        t = cap.columns["head_0"]
        _, rate_true = pulse_rate(t, table_angle_deg(cap.truth, t), average=10)
        omega = cap.truth["mean_rate_whole_revs_deg_s"]
        dev = 100.0 * (rate_true - omega) / omega
        for key, value in (("rms", np.sqrt(np.mean(dev**2))), ("peak", np.max(np.abs(dev)))):
            b = r.budgets[f"rate_deviation_{key}_percent"]
            err[key].append(b.value - value)
            us[key].append(b.u)
    lo, hi = _chi2_bounds(runs)
    for key in ("rms", "peak"):
        e = np.asarray(err[key])
        assert lo < math.sqrt(np.mean(e**2)) / np.mean(us[key]) < hi, key
    e = np.asarray(err["rms"])
    assert abs(e.mean()) < 4 * e.std(ddof=1) / math.sqrt(runs)  # the bias is removed


def test_allan_uncertainty_is_honest_for_white_timing_noise():
    """s(φ) of white timing noise scatters over runs as its edf says (Greenhall & Riley)."""
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
        r = calibrate_rate(
            [cap.columns["head_0"]], pulses_per_rev=M, allan_angles_deg=[0.1, 1, 10, 100, 300]
        )
        values.append(r.allan_relative)
        us.append(r.allan_relative_u)
    assert r.allan_noise_alpha == [2] * 5
    values, us = np.asarray(values), np.asarray(us)
    lo, hi = _chi2_bounds(RUNS - 1)  # about the runs' own mean
    ratio = values.std(axis=0, ddof=1) / us.mean(axis=0)
    assert np.all((lo < ratio) & (ratio < hi)), ratio
    lows, highs = np.asarray(r.allan_relative_interval).T
    assert np.all(lows < r.allan_relative) and np.all(r.allan_relative < highs)


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
    assert d["timing_jitter_s"] > 0 and d["rate_deviation_rms_corrected_percent"] > 0


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
    for name in ("mean_rate_deg_s", "rate_bias_percent", "rate_deviation_rms_percent"):
        assert f"Uncertainty budget of {name}" in text
    assert "Uncertainty budget of deviation_pp_arcsec" in text
    assert "each point of the deviation curve" in text
    assert "relative root Allan variance with its uncertainty".lower() in text.lower()
    assert ">nan<" not in text.lower() and " nan " not in text.lower()
