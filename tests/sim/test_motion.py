"""SineMotion: the true motion and its truth, against closed forms and independent computations."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from rotacal.errors import ConfigError
from rotacal.sim import SineMotion

HARM = {2: (0.02, 1.0), 3: (0.05, 0.3), 5: (0.01, -2.0)}


def distorted(**kw: object) -> SineMotion:
    opts: dict = dict(
        amplitude_deg=0.3,
        frequency_hz=2.0,
        harmonics=HARM,
        stagnation_s=0.004,
        backlash_deg=0.003,
        creep_deg=0.0006,
    )
    opts.update(kw)
    return SineMotion(**opts)


def test_pure_harmonics_truth_equals_closed_form() -> None:
    a, f, ph = 0.7, 3.0, 0.4
    m = SineMotion(a, f, harmonics=HARM, phase_rad=ph, offset_deg=0.05)
    tr = m.truth(0.0, 2.0, harmonics=10)
    closed_thd = math.sqrt(sum(r * r for r, _ in HARM.values())) * 100.0
    assert tr["thd_percent"] == pytest.approx(closed_thd, rel=1e-12)
    assert tr["amplitude_deg"] == pytest.approx(a, rel=1e-13)
    expect = np.zeros(10)
    expect[0] = a
    for h, (r, _) in HARM.items():
        expect[h - 1] = a * r
    np.testing.assert_allclose(tr["harmonic_amplitudes_deg"], expect, rtol=0, atol=1e-14)
    # phases of A_h·sin(h(ωt + φ) + ψ_h) at t = 0: h·φ + ψ_h
    assert tr["harmonic_phases_rad"][0] == pytest.approx(ph, abs=1e-12)
    for h, (_, psi) in HARM.items():
        want = (h * ph + psi + math.pi) % (2 * math.pi) - math.pi
        assert tr["harmonic_phases_rad"][h - 1] == pytest.approx(want, abs=1e-10)
    assert tr["mean_deg"] == pytest.approx(0.05, abs=1e-14)
    w = 2 * math.pi * f
    assert tr["angular_acceleration_amplitude_deg_s2"] == pytest.approx(a * w * w, rel=1e-13)
    json.dumps(tr, allow_nan=False)  # plain JSON values only


def test_fft_truth_of_distorted_motion_is_stable_in_m() -> None:
    m = distorted()
    a14 = m.harmonic_truth(10, points=2**14)["amplitudes_deg"]
    a16 = m.harmonic_truth(10, points=2**16)["amplitudes_deg"]
    np.testing.assert_allclose(a14, a16, rtol=0, atol=1e-9 * m.amplitude_deg)
    # the distortion does move the fundamental and the THD away from the commanded values
    tr = m.truth(0.0, 1.0)
    assert abs(tr["amplitude_deg"] / m.amplitude_deg - 1) > 1e-3
    assert abs(tr["thd_percent"] - math.sqrt(sum(r * r for r, _ in HARM.values())) * 100) > 0.1


@pytest.mark.parametrize("phase", [0.0, 0.9, -2.5])
def test_reversals_of_pure_sine_at_quarter_periods(phase: float) -> None:
    f = 1.7
    m = SineMotion(0.2, f, phase_rad=phase)
    t0, t1 = 0.13, 4.0
    got = np.asarray(m.truth(t0, t1)["reversal_times_s"])
    w = 2 * math.pi * f
    k = np.arange(-5, 40)
    want = (math.pi / 2 + k * math.pi - phase) / w
    want = want[(want >= t0) & (want <= t1)]
    assert got.size == want.size
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


def test_stagnation_dwells_centred_on_quarter_periods() -> None:
    f, a, st = 2.0, 0.5, 0.01
    m = SineMotion(a, f, stagnation_s=st)
    T = 1 / f
    # flat at ±A for the dwell, centred on T/4 and 3T/4
    tq = np.linspace(T / 4 - 0.49 * st, T / 4 + 0.49 * st, 101)
    np.testing.assert_array_equal(m.angle_deg(tq), np.full(tq.size, a))
    np.testing.assert_array_equal(m.rate_deg_s(tq), 0.0)
    assert m.angle_deg(np.array([T / 4 + 0.51 * st]))[0] < a
    assert m.angle_deg(np.array([3 * T / 4]))[0] == pytest.approx(-a, abs=1e-15)
    # between dwells the phase runs faster: θ = A·sin(k·(ωt − π/2) + π/2) after the first dwell
    w = 2 * math.pi * f
    k = 2 * math.pi / (2 * math.pi - 2 * w * st)
    t = np.linspace(T / 4 + st / 2, 3 * T / 4 - st / 2, 200)
    want = a * np.sin(math.pi / 2 + k * (w * (t - T / 4) - w * st / 2))
    np.testing.assert_allclose(m.angle_deg(t), want, rtol=0, atol=1e-13)
    rev = np.asarray(m.truth(0.0, 2.0)["reversal_times_s"])
    np.testing.assert_allclose(rev, T / 4 + np.arange(rev.size) * T / 2, rtol=0, atol=1e-12)


def test_rate_equals_finite_difference_of_angle_smooth() -> None:
    m = SineMotion(0.3, 2.0, harmonics=HARM, vibration_deg=0.001, vibration_hz=37.0)
    t = np.linspace(0.1, 1.3, 20001)
    h = 1e-6
    fd = (m.angle_deg(t + h) - m.angle_deg(t - h)) / (2 * h)
    r = m.rate_deg_s(t)
    np.testing.assert_allclose(fd, r, rtol=0, atol=1e-7 * np.max(np.abs(r)))


def test_rate_integrates_to_angle_with_all_effects() -> None:
    m = distorted(vibration_deg=0.001, vibration_hz=37.0)
    t = np.linspace(0.1, 2.0, 400001)
    th = m.angle_deg(t)
    integ = cumulative_trapezoid(m.rate_deg_s(t), t, initial=0.0)
    np.testing.assert_allclose(integ, th - th[0], rtol=0, atol=1e-5)
    # and the finite difference agrees except on the few samples next to a velocity jump
    fd = np.gradient(th, t)
    bad = np.abs(fd - m.rate_deg_s(t)) > 1e-4 * np.max(np.abs(fd))
    assert np.count_nonzero(bad) < 40


def test_motion_is_exactly_periodic() -> None:
    m = distorted()
    t = np.linspace(0.0, 0.5, 5001)
    np.testing.assert_allclose(m.angle_deg(t + 10 * m.period_s), m.angle_deg(t), rtol=0, atol=1e-13)


def test_backlash_flat_for_dead_band_after_each_reversal() -> None:
    a, f, b = 0.4, 2.0, 0.01
    m = SineMotion(a, f, backlash_deg=b)
    w = 2 * math.pi * f
    T = 1 / f
    dwell = math.acos(1 - b / a) / w  # time for the command to travel the dead band
    for tr, y_flat in ((T / 4, a - b / 2), (3 * T / 4, -a + b / 2)):
        for per in (0, 3):
            t0 = tr + per * T
            t = np.linspace(t0 + 1e-9, t0 + dwell * (1 - 1e-9), 500)
            np.testing.assert_allclose(m.angle_deg(t), y_flat, rtol=0, atol=1e-15)
            np.testing.assert_array_equal(m.rate_deg_s(t), 0.0)
            after = m.angle_deg(np.array([t0 + dwell * 1.01]))[0]
            assert abs(after - y_flat) > 1e-7
            before = m.angle_deg(np.array([t0 - 1e-3]))[0]
            assert abs(before - y_flat) > 1e-7
    # the truth reversal is the middle of the flat part
    rev = np.asarray(m.truth(0.0, T)["reversal_times_s"])
    np.testing.assert_allclose(rev, [T / 4 + dwell / 2, 3 * T / 4 + dwell / 2], atol=1e-11)


def test_creep_is_the_documented_lag() -> None:
    a, f, c = 0.4, 2.0, 0.002
    x = 0.04
    m0 = SineMotion(a, f)
    m = SineMotion(a, f, creep_deg=c, creep_time_s=x)
    T = 1 / f
    t = np.linspace(0, T, 20001)
    diff = m.angle_deg(t) - m0.angle_deg(t)
    want = np.zeros_like(t)
    for te, direction in ((T / 4, -1.0), (3 * T / 4, 1.0)):
        tau = t - te
        inside = (tau >= 0) & (tau < x)
        want[inside] = -direction * c * np.sin(math.pi * tau[inside] / x) ** 2
    np.testing.assert_allclose(diff, want, rtol=0, atol=1e-15)
    # mild creep adds no reversal
    assert len(m.truth(0, 3)["reversal_times_s"]) == len(m0.truth(0, 3)["reversal_times_s"])


def test_vibration_excluded_from_truth() -> None:
    base = distorted()
    vib = distorted(vibration_deg=0.002, vibration_hz=41.0)
    # vibration makes the full velocity reverse many more times ...
    t = np.linspace(0, 3, 300001)
    r = vib.rate_deg_s(t)
    assert np.count_nonzero(np.diff(np.sign(r))) > 20
    # ... but the truth is that of the vibration-free motion
    tb, tv = base.truth(0.0, 3.0), vib.truth(0.0, 3.0)
    assert len(tv["reversal_times_s"]) == len(tb["reversal_times_s"]) == 12
    assert tv["reversal_times_s"] == tb["reversal_times_s"]
    assert tv["harmonic_amplitudes_deg"] == tb["harmonic_amplitudes_deg"]


@pytest.mark.parametrize(
    ("kwargs", "word"),
    [
        ({"amplitude_deg": -1.0, "frequency_hz": 1.0}, "amplitude_deg"),
        ({"amplitude_deg": 1.0, "frequency_hz": 0.0}, "frequency_hz"),
        ({"amplitude_deg": 1.0, "frequency_hz": 1.0, "harmonics": {1: (0.1, 0)}}, "harmonic"),
        ({"amplitude_deg": 1.0, "frequency_hz": 1.0, "harmonics": {3: (-0.1, 0)}}, "harmonic"),
        ({"amplitude_deg": 1.0, "frequency_hz": 1.0, "stagnation_s": 0.3}, "stagnation_s"),
        ({"amplitude_deg": 1.0, "frequency_hz": 1.0, "backlash_deg": 1.5}, "backlash_deg"),
        ({"amplitude_deg": 1.0, "frequency_hz": 1.0, "creep_deg": -1}, "creep_deg"),
        ({"amplitude_deg": 1.0, "frequency_hz": 1.0, "vibration_deg": 0.1}, "vibration_hz"),
        ({"amplitude_deg": 1.0, "frequency_hz": 1.0, "drift_deg_s": math.inf}, "drift_deg_s"),
        (
            {"amplitude_deg": 1.0, "frequency_hz": 1.0, "creep_deg": 0.01, "creep_time_s": 0.7},
            "creep_time_s",
        ),
    ],
)
def test_bad_motion_settings(kwargs: dict, word: str) -> None:
    with pytest.raises(ConfigError) as e:
        SineMotion(**kwargs)
    assert word in str(e.value)
    assert "\n" not in str(e.value)


def test_large_creep_overruns_and_truth_follows() -> None:
    a, f, x = 0.1, 5.0, 0.02
    limit = a * (2 * math.pi * f) ** 2 * x**2 / (2 * math.pi**2)
    m = SineMotion(a, f, creep_deg=5 * limit, creep_time_s=x)
    T = 1 / f
    rev = np.asarray(m.truth(0.0, T)["reversal_times_s"])
    assert rev.size == 2
    assert np.all(rev > np.array([T / 4, 3 * T / 4]) + 1e-4)  # later than the command's
    r = m.rate_deg_s(np.concatenate([rev - 1e-6, rev + 1e-6]))
    assert np.all(r[:2] * r[2:] < 0)  # the velocity changes sign there


def test_drift_adds_a_ramp_that_the_harmonic_truth_leaves_out() -> None:
    d = 0.004
    base = distorted()
    m = distorted(drift_deg_s=d)
    t = np.linspace(-0.3, 3.1, 40001)
    np.testing.assert_allclose(m.angle_deg(t) - base.angle_deg(t), d * t, rtol=0, atol=1e-15)
    np.testing.assert_allclose(m.rate_deg_s(t) - base.rate_deg_s(t), d, rtol=0, atol=1e-13)
    tr, tb = m.truth(0.0, 3.0), base.truth(0.0, 3.0)
    assert tr["harmonic_amplitudes_deg"] == tb["harmonic_amplitudes_deg"]
    assert tr["thd_percent"] == tb["thd_percent"]
    assert tr["drift_deg_s"] == d and tb["drift_deg_s"] == 0.0
    assert tr["motion"]["drift_deg_s"] == d
    json.dumps(tr, allow_nan=False)


def test_reversals_of_a_drifting_sine_follow_the_closed_form() -> None:
    """θ = A·sin(ωt) + d·t reverses where cos(ωt) = −d/(Aω): the maxima come earlier and the
    minima later than the quarter periods, the swings no longer half a period apart."""
    a, f, d = 0.2, 1.7, 0.5
    m = SineMotion(a, f, drift_deg_s=d)
    w = 2 * math.pi * f
    c = math.acos(-d / (a * w))
    k = np.arange(-3, 12)
    want = np.sort(np.concatenate([(c + 2 * math.pi * k) / w, (-c + 2 * math.pi * k) / w]))
    want = want[(want >= 0.0) & (want <= 4.0)]
    got = np.asarray(m.truth(0.0, 4.0)["reversal_times_s"])
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    assert not np.allclose(np.diff(got), 0.5 / f, atol=1e-3)


def test_drift_faster_than_the_motion_leaves_no_reversal() -> None:
    m = SineMotion(0.1, 2.0, drift_deg_s=1.3 * 0.1 * 2 * math.pi * 2.0)
    assert m.truth(0.0, 3.0)["reversal_times_s"] == []
