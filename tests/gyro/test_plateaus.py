"""Plateaus of a continuous rate-table log (rotacal.gyro.plateaus, scale_factor_log): twin truth in,
truth out; the real xinli recordings concatenated into one log; the refusals."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from rotacal.errors import CaptureError
from rotacal.gyro.plateaus import find_plateaus
from rotacal.gyro.scale_factor_log import calibrate_scale_factor_log
from rotacal.sim import simulate_gyro_log

#: Boundaries must lie within two samples of the twin's truth: the ramp of 50 °/s² crosses the
#: detector's band (6σ + 0.001 °/s ≈ 0.12 °/s) within a few milliseconds, under one sample.
_EDGE_SAMPLES = 2


@functools.cache
def _twin(**kw):
    return simulate_gyro_log(**kw)


@pytest.mark.parametrize("kw", [{}, {"rate_noise_deg_s": 0.0}, {"lag_s": 0.5, "seed": 4}])
def test_twin_boundaries_and_line_come_out_within_their_tolerance(kw):
    cap = _twin(**kw)
    c, truth = cap.columns, cap.truth
    r = calibrate_scale_factor_log(c["time_s"], c["rate_deg_s"], c["output"])
    assert r.warnings == () and len(r.plateaus) == len(truth["plateaus"])
    tol = _EDGE_SAMPLES / truth["sensor"]["fs_hz"]
    for p, q in zip(r.plateaus, truth["plateaus"], strict=True):
        assert abs(p["start_s"] - r.settle_s - q["start_s"]) <= tol
        assert abs(p["end_s"] - q["end_s"]) <= tol
        assert (
            abs(p["rate_deg_s"] - q["rate_deg_s"]) < 5 * truth["sensor"]["rate_noise_deg_s"] + 1e-9
        )
    # the DUT's transient must be dropped: the settling read from the output covers the
    # lag's decay to 1e-4 of a step at least as far as the noise can see it
    assert r.settle_s >= 0.5 * truth["settle_time_s"]
    assert abs(r.scale_factor - truth["ls_scale_factor"]) <= 3 * r.scale_factor_u
    assert abs(r.bias - truth["ls_bias"]) <= 3 * r.bias_u
    lo, hi = r.nonlinearity_percent_fs_interval
    assert lo <= truth["nonlinearity_percent_fs"] <= hi


def test_without_settling_the_lag_biases_the_scale_factor():
    """The check above can fail: keeping each step's transient moves S by many u."""
    cap = _twin(lag_s=0.5, seed=4)
    c, truth = cap.columns, cap.truth
    r = calibrate_scale_factor_log(c["time_s"], c["rate_deg_s"], c["output"], settle_s=0.0)
    assert abs(r.scale_factor - truth["ls_scale_factor"]) > 5 * r.scale_factor_u


def test_chunked_fit_equals_the_in_memory_one():
    c = _twin().columns
    a, b = (
        calibrate_scale_factor_log(c["time_s"], c["rate_deg_s"], c["output"], chunked=k)
        for k in (False, True)
    )
    assert b.scale_factor == pytest.approx(a.scale_factor, rel=1e-9)
    assert b.bias == pytest.approx(a.bias, rel=1e-9)
    assert b.plateaus == a.plateaus


def test_too_noisy_and_too_short_plateaus_are_rejected_and_said():
    cap = _twin()
    t, rate, out = (cap.columns[k].copy() for k in ("time_s", "rate_deg_s", "output"))
    noisy, last = cap.truth["plateaus"][3], cap.truth["plateaus"][-1]
    inside = (t > noisy["start_s"] + 1) & (t < noisy["end_s"] - 1)
    rate[inside] += np.random.default_rng(5).normal(0, 0.2, inside.sum())
    keep = t < last["start_s"] + 8.0  # the last plateau cut to 8 s: too short once settled
    r = calibrate_scale_factor_log(t[keep], rate[keep], out[keep], settle_s=4.0)
    reasons = [p["reason"] for p in r.plateaus_rejected]
    assert len(reasons) == 2 and "too noisy" in reasons[0] and "too short" in reasons[1], reasons
    assert len(r.plateaus) == len(cap.truth["plateaus"]) - 2
    assert [w.split(" rejected, ")[1] for w in r.warnings] == reasons


def test_a_steadier_plateau_is_not_rejected_as_noisy():
    cap = _twin()
    c = cap.columns
    r = find_plateaus(c["time_s"], c["rate_deg_s"], c["output"], settle_s=2.0)
    assert r.rejected == () and r.settle_source == "given" and r.settle_s == 2.0


def _refused(t, rate, *needles):
    with pytest.raises(CaptureError) as e:
        calibrate_scale_factor_log(t, rate, 0.01 * rate + 1.0)
    msg = str(e.value)
    assert "\n" not in msg
    for n in needles:
        assert n in msg, msg


def test_logs_without_two_plateaus_are_refused():
    t = np.arange(6000) * 0.01
    _refused(t, 20 * np.sin(2 * np.pi * 0.2 * t), "never settles")  # sinusoidal table
    _refused(t, 0.5 * t, "never settles")  # one long ramp
    _refused(t, np.full(t.size, 10.0), "one plateau rate")
    _refused(t[::-1], np.repeat([10.0, 20.0], 3000), "time_s does not increase at row 1")
    bad = np.repeat([10.0, 20.0], 3000)
    bad[7] = np.nan
    _refused(t, bad, "rate_deg_s holds nan at row 7")


def test_xinli_files_concatenated_give_their_plateaus_and_published_scale_factor(shared_data):
    """README of the xinli recordings: an 11-point line gives S ≈ 1.000199 (the 0 °/s point of
    the turn runs does not move the slope of rates symmetric about 0)."""
    data = shared_data("xinli_turntable") / "data"
    outs, rates = [], []
    for r in (10, 30, 60, 90, 120):
        for pre, sign in (("p", 1), ("m", -1)):
            x = np.loadtxt(data / f"{pre}{r}.dat", usecols=(4,))
            outs.append(x)
            rates.append(np.full(x.size, sign * r, dtype=float))
    y = np.concatenate(outs)
    t = np.arange(y.size) * 0.1  # the counter's period, one log
    res = calibrate_scale_factor_log(t, np.concatenate(rates), y)
    edges = np.cumsum([0, *(o.size for o in outs)])
    assert len(res.plateaus) == len(outs) and res.plateaus_rejected == ()
    for p, a, b, rate in zip(res.plateaus, edges[:-1], edges[1:], rates, strict=True):
        assert p["start_s"] == pytest.approx(a * 0.1 + res.settle_s, abs=1e-9)
        assert p["end_s"] == pytest.approx((b - 1) * 0.1, abs=1e-9)
        assert p["rate_deg_s"] == rate[0]
    assert res.scale_factor == pytest.approx(1.000199, abs=3e-6)


def test_a_drifting_plateau_is_rejected_as_not_steady():
    cap = _twin()
    t, rate, out = (cap.columns[k].copy() for k in ("time_s", "rate_deg_s", "output"))
    p = cap.truth["plateaus"][5]
    inside = (t >= p["start_s"]) & (t <= p["end_s"])
    # 0.09 °/s over 30 s: a creep within the noise's reach (σ 0.02 °/s), not a step
    rate[inside] += 0.003 * (t[inside] - p["start_s"])
    r = find_plateaus(t, rate, out)
    assert [q.reason.split(":")[0] for q in r.rejected] == ["not steady"]
    assert r.rejected[0].rate_deg_s == pytest.approx(p["rate_deg_s"], abs=0.1)


def test_each_plateau_states_its_mean_temperature():
    c = _twin().columns
    temperature = 20.0 + c["time_s"] / 100.0  # 1 °C per 100 s
    r = calibrate_scale_factor_log(
        c["time_s"], c["rate_deg_s"], c["output"], temperature_c=temperature
    )
    for p in r.plateaus:
        assert p["temperature_c"] == pytest.approx(
            20.0 + (p["start_s"] + p["end_s"]) / 200.0, abs=1e-3
        )
