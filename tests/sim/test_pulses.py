"""The multi-head pulse-encoder twin against closed forms written out here, not its own code paths.

The helpers below re-derive the model of ``rotacal.sim.pulses`` from the settings and drawn
values in the truth dict (table angle, line positions, head positions), so every test compares the
twin's Newton-solved timestamps and truth with an independent evaluation.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rotacal.errors import ConfigError
from rotacal.io import read_capture
from rotacal.sim.pulses import simulate_pulses, table_angle_deg, table_rate_deg_s
from rotacal.sim.sensors import simulate

# no scale errors, no head errors, constant rate, no jitter
IDEAL: dict[str, Any] = {
    "harmonics": (),
    "graduation_noise_arcsec": 0.0,
    "head_placement_arcsec": 0.0,
    "rate_fluctuation_percent": 0.0,
    "jitter_s": 0.0,
}


# ------------------------------------------------------------------ independent closed forms
def theta_abs(tr: dict[str, Any], t: np.ndarray) -> np.ndarray:
    """θ(t) = θ0 + ω·t + Σ (a_k·ω/(2π f_k))·sin(2π f_k t + ψ_k), deg."""
    w = tr["mean_rate_deg_s"]
    out = tr["theta0_deg"] + w * t
    for f, a, p in zip(
        tr["fluctuation_hz"],
        tr["fluctuation_relative_amplitudes"],
        tr["fluctuation_phases_rad"],
        strict=True,
    ):
        out = out + a * w / (2 * math.pi * f) * np.sin(2 * math.pi * f * t + p)
    return out


def rate_abs(tr: dict[str, Any], t: np.ndarray) -> np.ndarray:
    w = tr["mean_rate_deg_s"]
    out = np.full_like(t, w)
    for f, a, p in zip(
        tr["fluctuation_hz"],
        tr["fluctuation_relative_amplitudes"],
        tr["fluctuation_phases_rad"],
        strict=True,
    ):
        out = out + a * w * np.cos(2 * math.pi * f * t + p)
    return out


def line_errors(tr: dict[str, Any]) -> np.ndarray:
    """e_j in scale numbering (arcsec) from the truth's deviation (deviation[J] = e_{L0+J})."""
    dev = np.asarray(tr["deviation_arcsec"])
    return np.roll(dev, tr["first_line_head0"])


def harmonic_errors(harmonics: Any, m: int) -> np.ndarray:
    j = np.arange(m)
    e = np.zeros(m)
    for h, a, p in harmonics:
        e += a * np.cos(2 * math.pi * h * j / m + p)
    return e - e.mean()


# ------------------------------------------------------------------ counts, order, seeds
def test_counts_order_and_reproducibility() -> None:
    cap = simulate_pulses()
    tr = cap.truth
    n, m = tr["heads"], tr["pulses_per_rev"]
    pitch = 360.0 / m
    assert cap.kind == "pulses" and list(cap.columns) == [f"head_{i}" for i in range(n)]
    max_e = float(np.max(np.abs(tr["deviation_arcsec"]))) / 3600.0
    lengths = []
    for i in range(n):
        t = cap.columns[f"head_{i}"]
        assert t.dtype == np.float64 and t.ndim == 1
        assert np.all(np.diff(t) > 0)
        start, stop = tr["record_start_s"][i], tr["record_stop_s"][i]
        assert start <= tr["start_spread_s"] and tr["duration_s"] - stop <= tr["start_spread_s"]
        # revolutions·m minus the delays, and the same through the closed-form angle
        nominal = tr["revolutions"] * m - (start + tr["duration_s"] - stop) * 300.0 / pitch
        span = float(np.diff(theta_abs(tr, np.array([start, stop])))[0]) / pitch
        fluct = 2 * sum(
            a * 300.0 / (2 * math.pi * f) / pitch
            for f, a in zip(
                tr["fluctuation_hz"], tr["fluctuation_relative_amplitudes"], strict=True
            )
        )
        assert abs(t.size - span) <= 1 + 2 * max_e / pitch
        assert abs(t.size - nominal) <= 1 + 2 * max_e / pitch + fluct
        assert t.size == tr["pulses_per_head"][i]
        lengths.append(t.size)
    assert len(set(lengths)) > 1  # heads start and stop at different times
    again = simulate_pulses()
    other = simulate_pulses(seed=1)
    for name, t in cap.columns.items():
        np.testing.assert_array_equal(again.columns[name], t)
    assert again.truth == tr
    assert other.truth["theta0_deg"] != tr["theta0_deg"]
    assert not np.array_equal(other.columns["head_0"][:100], cap.columns["head_0"][:100])
    json.dumps(tr, allow_nan=False)


def test_dispatcher_knows_pulses() -> None:
    cap = simulate("pulses", heads=3, pulses_per_rev=360, revolutions=1.5, seed=4)
    assert cap.kind == "pulses" and len(cap.columns) == 3


# ------------------------------------------------------------------ ideal encoder
@pytest.mark.parametrize(
    ("heads", "m", "rate"),
    [(4, 360, 30.0), (12, 18000, 300.0), (7, 18000, 300.0), (5, 1001, 45.0)],
)
def test_ideal_intervals_and_head_offsets(heads: int, m: int, rate: float) -> None:
    cap = simulate_pulses(heads=heads, pulses_per_rev=m, rate_deg_s=rate, **IDEAL, seed=3)
    tr = cap.truth
    pitch = 360.0 / m
    period = pitch / rate
    t_end = tr["duration_s"]
    # 1e-12 relative, or what float64 timestamps near t_end can resolve (two roundings)
    rtol = max(1e-12, 4 * float(np.spacing(t_end)) / period)
    t0 = cap.columns["head_0"]
    for i in range(heads):
        t = cap.columns[f"head_{i}"]
        np.testing.assert_allclose(np.diff(t), period, rtol=rtol, atol=0)
        # head i crosses θ = jΔ − i·360/n: (t − t_0[0])·ω + i·360/n is a whole number of pitches
        k = ((t - t0[0]) * rate + i * 360.0 / heads) / pitch
        assert np.max(np.abs(k - np.round(k))) < 1e-9
        # and the absolute closed form t = (jΔ − i·360/n − θ0 + 360·w)/ω
        k_abs = (t * rate + tr["theta0_deg"] + i * 360.0 / heads) / pitch
        assert np.max(np.abs(k_abs - np.round(k_abs))) < 1e-9
    if (m % heads) and heads > 1:
        # heads not on the pulse grid of head 0: the lag is a non-trivial fraction of a period
        k1 = ((cap.columns["head_1"] - t0[0]) * rate) / pitch
        frac = float(np.mean(k1 - np.floor(k1)))
        assert frac == pytest.approx((-360.0 / heads / pitch) % 1.0, abs=1e-9)


def test_head_placement_errors_shift_heads_in_time() -> None:
    cap = simulate_pulses(**{**IDEAL, "head_placement_arcsec": 5.0}, seed=11)
    tr = cap.truth
    eps = np.asarray(tr["head_placement_arcsec_values"])
    assert eps[0] == 0.0 and np.all(eps[1:] != 0.0) and np.max(np.abs(eps)) < 0.4 * 72.0
    rate, pitch, n = 300.0, 0.02, 12
    t0 = cap.columns["head_0"]
    for i in range(1, n):
        h = i * 360.0 / n + eps[i] / 3600.0
        k = ((cap.columns[f"head_{i}"] - t0[0]) * rate + h) / pitch
        assert np.max(np.abs(k - np.round(k))) < 1e-8
        # without the placement error the heads would be off the grid by ε_i/3600/Δ pitches
        k_nominal = ((cap.columns[f"head_{i}"] - t0[0]) * rate + i * 30.0) / pitch
        off = np.median(k_nominal - np.round(k_nominal))
        assert off == pytest.approx(-eps[i] / 3600.0 / pitch, abs=1e-8)


# ------------------------------------------------------------------ scale errors
def test_eccentricity_intervals_closed_form() -> None:
    amp, phase = 3.0, 0.7
    cap = simulate_pulses(**{**IDEAL, "harmonics": ((1, amp, phase),)}, seed=5)
    tr = cap.truth
    m, rate = 18000, 300.0
    pitch = 360.0 / m
    j = np.arange(m)
    e = amp * np.cos(2 * math.pi * j / m + phase)
    # the first line head 0 sees: the first P_j at or after θ(start) (mod 360)
    p = j * pitch + e / 3600.0
    theta_start = tr["theta0_deg"] + rate * tr["record_start_s"][0]
    l0 = int(np.argmin(np.mod(p - theta_start, 360.0)))
    assert tr["first_line_head0"] == l0
    t = cap.columns["head_0"]
    lines = (l0 + np.arange(t.size)) % m
    expected = (pitch + (e[(lines[:-1] + 1) % m] - e[lines[:-1]]) / 3600.0) / rate
    np.testing.assert_allclose(np.diff(t), expected, rtol=1e-10, atol=0)
    # the eccentricity is visible: far above the tolerance
    assert np.max(np.abs(np.diff(t) * rate / pitch - 1)) > 1e-5
    np.testing.assert_allclose(tr["deviation_arcsec"], np.roll(e, -l0) - e.mean(), atol=1e-12)


def test_deviation_closed_form_and_detectable_part() -> None:
    harm = ((1, 3.0, 0.3), (2, 0.4, 1.1), (7, 0.2, 0.1), (14, 0.1, 2.2), (30, 0.05, 0.4))
    n, m = 7, 18000
    cap = simulate_pulses(
        heads=n, pulses_per_rev=m, harmonics=harm, graduation_noise_arcsec=0.0, seed=2
    )
    tr = cap.truth
    dev = np.asarray(tr["deviation_arcsec"])
    det = np.asarray(tr["deviation_detectable_arcsec"])
    e = harmonic_errors(harm, m)
    l0 = tr["first_line_head0"]
    np.testing.assert_allclose(dev, np.roll(e, -l0), atol=1e-12)
    # the orders that are multiples of n, written out: exactly what is missing
    undet = harmonic_errors([x for x in harm if x[0] % n == 0], m)
    np.testing.assert_allclose(dev - det, np.roll(undet, -l0), atol=1e-12)
    assert abs(np.mean(dev)) < 1e-12 and abs(np.mean(det)) < 1e-12


def test_detectable_has_no_power_at_multiples_of_n() -> None:
    cap = simulate_pulses()  # 12 heads, harmonics 12 and 24 included, graduation noise on
    tr = cap.truth
    n, m = tr["heads"], tr["pulses_per_rev"]
    dev_f = np.fft.rfft(tr["deviation_arcsec"])
    det_f = np.fft.rfft(tr["deviation_detectable_arcsec"])
    q = np.arange(dev_f.size)
    mult = q % n == 0
    scale = np.max(np.abs(dev_f))
    assert np.max(np.abs(det_f[mult])) < 1e-12 * scale
    np.testing.assert_allclose(det_f[~mult], dev_f[~mult], rtol=0, atol=1e-12 * scale)
    # the removed part is real: orders 12 and 24 carry their set amplitudes (plus noise)
    assert 2 * abs(dev_f[12]) / m == pytest.approx(0.08, abs=0.005)
    assert 2 * abs(dev_f[24]) / m == pytest.approx(0.03, abs=0.005)
    assert 2 * abs(dev_f[1]) / m == pytest.approx(3.0, abs=0.005)


# ------------------------------------------------------------------ the INTERFACE convention
def test_interface_convention_and_table_angle() -> None:
    cap = simulate_pulses(jitter_s=0.0)  # every other imperfection on
    tr = cap.truth
    m = tr["pulses_per_rev"]
    pitch = 360.0 / m
    dev = np.asarray(tr["deviation_arcsec"])
    t = cap.columns["head_0"]
    J = np.arange(t.size)
    assert t.size > 2 * m  # the check crosses whole revolutions
    assert tr["first_pulse_time_head0_s"] == t[0]
    got = table_angle_deg(tr, t) - table_angle_deg(tr, t[0])
    want = (J % m) * pitch + 360.0 * (J // m) + (dev[J % m] - dev[0]) / 3600.0
    assert np.max(np.abs(got - want)) < 1e-9
    # table_angle_deg / table_rate_deg_s equal the closed forms written out here
    ts = np.random.default_rng(0).uniform(0, tr["duration_s"], 1000)
    ref = theta_abs(tr, ts) - theta_abs(tr, np.array([t[0]]))[0]
    np.testing.assert_allclose(table_angle_deg(tr, ts), ref, rtol=0, atol=1e-10)
    np.testing.assert_allclose(table_rate_deg_s(tr, ts), rate_abs(tr, ts), rtol=1e-14)
    assert float(table_angle_deg(tr, t[0])) == 0.0
    # the rate truly fluctuates (the test above is not a straight line)
    assert np.ptp(table_rate_deg_s(tr, ts)) > 1e-5 * 300
    # the truth survives a JSON round trip
    back = json.loads(json.dumps(tr))
    np.testing.assert_array_equal(table_angle_deg(back, ts), table_angle_deg(tr, ts))
    with pytest.raises(ConfigError):
        table_angle_deg({"kind": "fog"}, ts)


def test_newton_converged_on_every_head() -> None:
    cap = simulate_pulses(jitter_s=0.0)
    tr = cap.truth
    assert tr["newton_max_step_s"] <= 1e-13
    m = tr["pulses_per_rev"]
    pitch = 360.0 / m
    e = line_errors(tr)
    heads = np.asarray(tr["head_positions_deg"])
    n = tr["heads"]
    np.testing.assert_allclose(
        heads, np.arange(n) * 360.0 / n + np.asarray(tr["head_placement_arcsec_values"]) / 3600
    )
    for i in range(n):
        t = cap.columns[f"head_{i}"]
        th = theta_abs(tr, t)
        g = np.round((th + heads[i]) / pitch).astype(np.int64)  # |e| ≪ half a pitch
        assert np.all(np.diff(g) == 1)  # every line, none twice
        assert int(g[0] % m) == tr["first_line_per_head"][i]
        target = g * pitch + e[g % m] / 3600.0 - heads[i]
        time_error = (th - target) / rate_abs(tr, t)
        assert np.max(np.abs(time_error)) <= 1e-13


def test_jitter_is_gaussian_with_the_set_std() -> None:
    clean = simulate_pulses(jitter_s=0.0, seed=8)
    noisy = simulate_pulses(jitter_s=2e-9, seed=8)
    d = np.concatenate([noisy.columns[k] - clean.columns[k] for k in clean.columns])
    assert d.size > 500_000
    assert np.std(d) == pytest.approx(2e-9, rel=0.01)
    assert abs(np.mean(d)) < 5 * 2e-9 / math.sqrt(d.size)


# ------------------------------------------------------------------ rate
def test_rate_fluctuation_rms_from_intervals() -> None:
    pct = 0.05
    cap = simulate_pulses(
        heads=2,
        pulses_per_rev=3600,
        revolutions=40.0,
        harmonics=(),
        graduation_noise_arcsec=0.0,
        head_placement_arcsec=0.0,
        rate_fluctuation_percent=pct,
        jitter_s=0.0,
        seed=6,
    )
    tr = cap.truth
    assert tr["fluctuation_hz"] == pytest.approx([300.0 / 360.0, 2.3, 7.9])
    t = cap.columns["head_0"]
    pitch = 0.1
    rate = pitch / np.diff(t)
    rel = rate / np.mean(rate) - 1.0
    assert np.sqrt(np.mean(rel**2)) * 100 == pytest.approx(pct, rel=0.03)
    assert tr["rate_fluctuation_rms_percent"] == pct
    # each interval's rate is the closed-form rate at its midpoint (curvature ≪ 1e-7)
    mid = 0.5 * (t[1:] + t[:-1])
    assert np.max(np.abs(rate / rate_abs(tr, mid) - 1)) < 1e-7


def test_mean_rate_bias_and_whole_revolutions() -> None:
    cap = simulate_pulses(**{**IDEAL, "rate_bias_percent": 0.5}, pulses_per_rev=3600, seed=9)
    tr = cap.truth
    assert tr["mean_rate_deg_s"] == pytest.approx(300.0 * 1.005, rel=1e-15)
    t = cap.columns["head_0"]
    r = tr["whole_revolutions_head0"]
    assert r == (t.size - 1) // 3600 and r >= 2
    assert 360.0 * r / (t[r * 3600] - t[0]) == pytest.approx(301.5, rel=1e-12)
    assert tr["mean_rate_whole_revs_deg_s"] == pytest.approx(301.5, rel=1e-12)
    # with fluctuation, the whole-revolution mean is the closed form 360·R/(T_R − T_0)
    fl = simulate_pulses(jitter_s=0.0, rate_fluctuation_percent=0.5, seed=9)
    tf, trf = fl.columns["head_0"], fl.truth
    r = trf["whole_revolutions_head0"]
    whole = 360.0 * r / (tf[r * 18000] - tf[0])
    assert trf["mean_rate_whole_revs_deg_s"] == pytest.approx(whole, rel=1e-13)
    assert whole != pytest.approx(300.0, rel=1e-7)  # the fluctuation moves it off ω


# ------------------------------------------------------------------ files
@pytest.mark.parametrize("suffix", [".npz", ".h5", ".csv"])
def test_write_and_read_back_ragged(tmp_path: Path, suffix: str) -> None:
    cap = simulate_pulses(heads=3, pulses_per_rev=360, revolutions=2.0, seed=7)
    lengths = {k: v.size for k, v in cap.columns.items()}
    assert len(set(lengths.values())) == 3
    path = cap.write(tmp_path / f"pulses{suffix}")
    back = read_capture(path, ragged=True)
    assert list(back.columns) == list(cap.columns)
    for name, t in cap.columns.items():
        np.testing.assert_array_equal(back.columns[name], t)
    truth = json.loads(Path(str(path) + ".truth.json").read_text())
    assert truth["kind"] == "pulses" and truth["pulses_per_head"] == list(lengths.values())
    np.testing.assert_array_equal(truth["deviation_arcsec"], cap.truth["deviation_arcsec"])


# ------------------------------------------------------------------ bad settings
@pytest.mark.parametrize(
    ("kwargs", "word"),
    [
        ({"heads": 1}, "heads"),
        ({"heads": 2.5}, "heads"),
        ({"heads": True}, "heads"),
        ({"heads": "12"}, "heads"),
        ({"pulses_per_rev": 8}, "pulses_per_rev"),
        ({"pulses_per_rev": 18000.5}, "pulses_per_rev"),
        ({"rate_deg_s": 0.0}, "forward"),
        ({"rate_deg_s": -300.0}, "forward"),
        ({"rate_deg_s": float("nan")}, "rate_deg_s"),
        ({"rate_deg_s": "fast"}, "rate_deg_s"),
        ({"rate_bias_percent": -100.0}, "rate_bias_percent"),
        ({"revolutions": 0.0}, "revolutions"),
        ({"revolutions": float("inf")}, "revolutions"),
        ({"revolutions": 1e4}, "timestamps"),
        ({"harmonics": "1,3,0"}, "harmonics"),
        ({"harmonics": ((0, 1.0, 0.0),)}, "order"),
        ({"harmonics": ((1.5, 1.0, 0.0),)}, "order"),
        ({"harmonics": ((1, -1.0, 0.0),)}, "amplitude"),
        ({"harmonics": ((1, 1.0),)}, "harmonics[0]"),
        ({"harmonics": ((1, 1.0, float("nan")),)}, "phase"),
        ({"harmonics": ((9000, 0.1, 0.0),)}, "order"),
        ({"harmonics": ((8000, 30.0, 0.0),)}, "swap"),
        ({"graduation_noise_arcsec": -0.1}, "graduation_noise_arcsec"),
        ({"graduation_noise_arcsec": 40.0}, "swap"),
        ({"head_placement_arcsec": -1.0}, "head_placement_arcsec"),
        ({"head_placement_arcsec": 200.0}, "half a pitch"),
        ({"rate_fluctuation_percent": -0.1}, "rate_fluctuation_percent"),
        ({"rate_fluctuation_percent": 80.0}, "zero"),
        ({"fluctuation_hz": (8000.0,)}, "half the pulse rate"),
        ({"fluctuation_hz": (-1.0,)}, "fluctuation_hz[0]"),
        ({"fluctuation_hz": (2.0, 2.0)}, "twice"),
        ({"fluctuation_hz": ()}, "fluctuation_hz"),
        ({"fluctuation_hz": 3.0}, "fluctuation_hz"),
        ({"jitter_s": -1e-9}, "jitter_s"),
        ({"jitter_s": 1e-5}, "jitter_s"),
        ({"start_spread_s": -0.1}, "start_spread_s"),
        ({"start_spread_s": 1.8}, "start_spread_s"),
        ({"seed": -1}, "seed"),
        ({"seed": 1.5}, "seed"),
    ],
)
def test_bad_settings_raise_one_line(kwargs: dict[str, Any], word: str) -> None:
    with pytest.raises(ConfigError) as info:
        simulate_pulses(**kwargs)
    msg = str(info.value)
    assert word in msg and "\n" not in msg
