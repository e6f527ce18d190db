"""Sensor models, the dispatcher, writing, and the Table 1 scenarios."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import rotacal.io
from rotacal.errors import ConfigError
from rotacal.sim import (
    SimCapture,
    SineMotion,
    simulate,
    simulate_encoder,
    simulate_fog,
    simulate_lts,
    table1_scenarios,
)

MOTION = SineMotion(0.1, 5.0, harmonics={3: (0.04, 0.5)}, stagnation_s=0.0005, creep_deg=0.0002)


def test_encoder_clean_phase_equals_angle() -> None:
    lines = 36000
    cap = simulate_encoder(MOTION, lines=lines, fs_hz=50_000.0)
    t, a, b = cap.columns["time_s"], cap.columns["a"], cap.columns["b"]
    assert list(cap.columns) == ["time_s", "a", "b"]
    phi = 2 * math.pi * lines * MOTION.angle_deg(t) / 360.0
    err = np.angle(np.exp(1j * (np.arctan2(b, a) - phi)))  # difference mod 2π
    assert np.max(np.abs(err)) < 1e-9
    # θ increases when a leads b: on a rising stretch, the demodulated phase increases
    up = MOTION.rate_deg_s(t) > 0
    dphi = np.diff(np.unwrap(np.arctan2(b, a)))
    assert np.all(dphi[up[:-1] & up[1:]] > 0)
    tr = cap.truth
    assert tr["sensor"]["lines"] == lines and tr["kind"] == "encoder"
    assert tr["t_start_s"] == 0.0 and tr["t_stop_s"] == pytest.approx(t[-1])
    json.dumps(tr, allow_nan=False)


def test_encoder_imperfections_and_adc() -> None:
    cap = simulate_encoder(
        MOTION, offset_a=0.1, offset_b=-0.05, amplitude_a=1.1, amplitude_b=0.9,
        phase_error_rad=0.02, adc_bits=12, adc_range=(-1.25, 1.25),
    )  # fmt: skip
    t = cap.columns["time_s"]
    phi = 2 * math.pi * 36000 * MOTION.angle_deg(t) / 360.0
    lsb = 2.5 / 4096
    np.testing.assert_allclose(cap.columns["a"], 0.1 + 1.1 * np.cos(phi), atol=lsb / 2 + 1e-12)
    np.testing.assert_allclose(
        cap.columns["b"], -0.05 + 0.9 * np.sin(phi + 0.02), atol=lsb / 2 + 1e-12
    )
    # values on the mid-rise code grid
    codes = (cap.columns["a"] + 1.25) / lsb - 0.5
    np.testing.assert_allclose(codes, np.round(codes), atol=1e-6)
    # clipping at the range
    clip = simulate_encoder(MOTION, amplitude_a=1.5, adc_bits=16)
    assert clip.columns["a"].max() < 1.25 and clip.columns["a"].max() > 1.2499
    assert clip.truth["sensor"]["clipped_samples"]["a"] > 0


def test_lts_inverts_to_angle() -> None:
    cap = simulate_lts(MOTION, radius_mm=80.0, noise_mm=0.0)
    t, d = cap.columns["time_s"], cap.columns["displacement_mm"]
    np.testing.assert_allclose(np.degrees(np.arctan(d / 80.0)), MOTION.angle_deg(t), atol=1e-14)
    noisy = simulate_lts(MOTION, noise_mm=3e-5, zero_offset_mm=0.01, seed=3)
    resid = noisy.columns["displacement_mm"] - d * 100 / 80 - 0.01
    assert np.std(resid) == pytest.approx(3e-5, rel=0.05)


@pytest.mark.parametrize("snr", [-3.0, 7.7, 20.0])
def test_fog_realised_snr_matches_request(snr: float) -> None:
    m = SineMotion(0.1, 5.0, harmonics={3: (0.05, 0.2)})
    cap = simulate_fog(m, snr_db=snr, bias_deg_s=0.3, fs_hz=2000.0, duration_s=100.0, seed=5)
    t, r = cap.columns["time_s"], cap.columns["rate_deg_s"]
    clean = m.rate_deg_s(t)
    noise = r - clean - 0.3
    realised = 10 * math.log10(np.mean((clean - clean.mean()) ** 2) / np.mean(noise**2))
    assert realised == pytest.approx(snr, abs=0.3)
    assert cap.truth["sensor"]["snr_db"] == pytest.approx(snr, abs=1e-9)
    assert cap.truth["sensor"]["snr_db_realised"] == pytest.approx(realised, abs=1e-9)


def test_fog_noise_free_is_the_rate() -> None:
    cap = simulate_fog(MOTION, bias_deg_s=-0.2)
    t = cap.columns["time_s"]
    np.testing.assert_allclose(cap.columns["rate_deg_s"], MOTION.rate_deg_s(t) - 0.2, atol=0)


def test_fog_bias_drift_is_a_ramp_from_the_first_sample() -> None:
    cap = simulate_fog(MOTION, bias_deg_s=-0.2, bias_drift_deg_s2=0.003, start_s=1.5)
    t = cap.columns["time_s"]
    want = MOTION.rate_deg_s(t) - 0.2 + 0.003 * (t - 1.5)
    np.testing.assert_allclose(cap.columns["rate_deg_s"], want, rtol=0, atol=1e-13)
    assert cap.truth["sensor"]["bias_drift_deg_s2"] == 0.003


@pytest.mark.parametrize(
    ("kind", "opts", "col"),
    [
        ("encoder", {"noise_rms": 0.01}, "a"),
        ("lts", {"noise_mm": 1e-4}, "displacement_mm"),
        ("fog", {"noise_deg_s": 0.5}, "rate_deg_s"),
    ],
)
def test_seeds_reproducible(kind: str, opts: dict, col: str) -> None:
    c1 = simulate(kind, motion=MOTION, seed=7, **opts)
    c2 = simulate(kind, motion=MOTION, seed=7, **opts)
    c3 = simulate(kind, motion=MOTION, seed=8, **opts)
    for name in c1.columns:
        np.testing.assert_array_equal(c1.columns[name], c2.columns[name])
    assert not np.array_equal(c1.columns[col], c3.columns[col])
    assert c1.truth == c2.truth


def test_default_duration_not_at_reversals() -> None:
    cap = simulate("lts", amplitude_deg=0.2, frequency_hz=4.0)
    t = cap.columns["time_s"]
    assert t[-1] == pytest.approx(6.125 / 4.0, abs=2 / 10_000.0)
    rev = np.asarray(cap.truth["reversal_times_s"])
    assert rev.size == 12
    assert min(rev[0] - t[0], t[-1] - rev[-1]) > 0.1 / 4.0
    assert cap.truth["motion"]["amplitude_deg"] == 0.2


def test_bad_options_raise_one_line_config_errors() -> None:
    cases = [
        lambda: simulate("pulsar", motion=MOTION),
        lambda: simulate_encoder(MOTION, fs_hz=2000.0),
        lambda: simulate("encoder", motion=MOTION, bogus=1),
        lambda: simulate("lts", amplitude_deg=-0.1),
        lambda: simulate_fog(MOTION, snr_db=5.0, noise_deg_s=0.1),
        lambda: simulate_lts(MOTION, radius_mm=0.0),
        lambda: simulate_encoder(MOTION, adc_bits=40),
    ]
    for make in cases:
        with pytest.raises(ConfigError) as e:
            make()
        assert "\n" not in str(e.value)
    with pytest.raises(ConfigError, match=r"known kinds: .*encoder, .*fog, .*lts"):
        simulate("pulsar")
    with pytest.raises(ConfigError, match="raise fs_hz above"):
        simulate_encoder(MOTION, fs_hz=2000.0)


def test_encoder_phase_step_limit_is_pi_over_6() -> None:
    m = SineMotion(1.0, 1.0)  # peak rate 2π °/s → φ rate 2π·36000·2π/360 rad/s
    phi_rate = 2 * math.pi * 36000 * 2 * math.pi / 360
    fs_min = phi_rate / (math.pi / 6)
    simulate_encoder(m, fs_hz=fs_min * 1.01, duration_s=0.3)
    with pytest.raises(ConfigError):
        simulate_encoder(m, fs_hz=fs_min * 0.99, duration_s=0.3)


def test_write_writes_capture_and_truth_together(tmp_path: Path) -> None:
    cap = simulate_fog(MOTION, noise_deg_s=0.1, duration_s=0.5)
    out = cap.write(tmp_path / "fog.npz")
    assert out == tmp_path / "fog.npz"
    back = rotacal.io.read_capture(out)
    for name, values in cap.columns.items():
        assert np.array_equal(back[name], values)
    truth = json.loads((tmp_path / "fog.npz.truth.json").read_text())
    assert truth["thd_percent"] == pytest.approx(cap.truth["thd_percent"], rel=1e-15)
    assert truth["sensor"]["noise_deg_s"] == 0.1
    with pytest.raises(ConfigError, match="exists"):
        cap.write(tmp_path / "fog.npz")
    cap.write(tmp_path / "fog.npz", overwrite=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fog.npz", "fog.npz.truth.json"]


def test_write_is_both_or_neither(tmp_path: Path) -> None:
    """A truth file in the way: the capture is not written either (and no temporary is left)."""
    cap = SimCapture("fog", {"time_s": np.arange(3.0), "rate_deg_s": np.zeros(3)}, {"k": 1})
    (tmp_path / "x.csv.truth.json").write_text("keep")
    with pytest.raises(ConfigError, match=r"x\.csv\.truth\.json already exists"):
        cap.write(tmp_path / "x.csv")
    assert [p.name for p in tmp_path.iterdir()] == ["x.csv.truth.json"]
    assert (tmp_path / "x.csv.truth.json").read_text() == "keep"


def test_table1_scenarios() -> None:
    sc = table1_scenarios()
    assert [(s["amplitude_deg"], s["frequency_hz"]) for s in sc] == [
        (0.025, 10.0), (0.1, 5.0), (0.25, 3.0), (0.5, 2.0), (5.0, 0.5),
    ]  # fmt: skip
    targets = [4.49, 5.42, 2.79, 1.38, 0.21]
    for s, target in zip(sc, targets, strict=True):
        m = s["motion"]
        assert s["target_thd_percent"] == target
        assert m.truth(0.0, m.period_s)["thd_percent"] == pytest.approx(target, abs=0.005)
        assert m.stagnation_s > 0 and m.creep_deg > 0
        assert "fog" in s["paper_sensors"]
        for kind, opts in s["sensors"].items():
            n = round(opts["duration_s"] * opts["fs_hz"])
            assert n <= 2_000_000, (s["name"], kind)
        assert s["sensors"]["encoder"]["lines"] == 36000
        assert s["sensors"]["lts"]["radius_mm"] == 100.0
    assert sc[0]["paper_sensors"] == ("lts", "fog")
    # the FOG noise density gives ≈ 7.7 dB at 0.1°/5 Hz and a much lower SNR at 0.025°/10 Hz
    snr = [
        simulate("fog", motion=s["motion"], **s["sensors"]["fog"]).truth["sensor"]["snr_db"]
        for s in sc
    ]
    assert snr[1] == pytest.approx(7.7, abs=0.1)
    assert snr[0] < snr[1] - 4
    assert snr == sorted(snr)
