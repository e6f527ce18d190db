"""Clipped captures of the sinusoidal-motion schemes: refused with the share the twin clipped,
analysed only with allow_clipped (and then said in ``warnings``); unclipped twins say nothing."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from rotacal import sim
from rotacal.errors import CaptureError
from rotacal.table import (
    calibrate_encoder_motion,
    calibrate_encoder_motion_chunked,
    calibrate_fog_motion,
    calibrate_lts_motion,
)

AMPLITUDE_DEG = 0.5
RADIUS_MM = 100.0


def _share(message: str) -> float:
    """The share of clipped samples the message states (fraction)."""
    m = re.search(r"clipped \(a saturated sensor or ADC\): ([0-9.]+) %", message)
    assert m is not None, message
    return float(m.group(1)) / 100


def _lts(level: float | None, seed: int = 0):
    d_amp = RADIUS_MM * math.tan(math.radians(AMPLITUDE_DEG))
    rng = None if level is None else level * d_amp
    return sim.simulate("lts", amplitude_deg=AMPLITUDE_DEG, range_mm=rng, seed=seed)


def _fog(level: float | None, seed: int = 0):
    rate_amp = 2 * math.pi * 2.0 * AMPLITUDE_DEG  # the default 2 Hz motion
    rng = None if level is None else level * rate_amp
    return sim.simulate("fog", amplitude_deg=AMPLITUDE_DEG, snr_db=10.0, range_deg_s=rng, seed=seed)


def _run_lts(cap, **kw):
    c = cap.columns
    return calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=RADIUS_MM, **kw)


def _run_fog(cap, **kw):
    return calibrate_fog_motion(cap.columns["time_s"], cap.columns["rate_deg_s"], **kw)


@pytest.mark.parametrize(
    ("make", "run", "column", "level"),
    [
        (_lts, _run_lts, "displacement_mm", 0.70),
        (_lts, _run_lts, "displacement_mm", 0.95),
        (_fog, _run_fog, "rate_deg_s", 0.26),
        (_fog, _run_fog, "rate_deg_s", 0.90),
    ],
)
def test_a_clipped_sensor_is_refused_then_allowed_with_a_warning(make, run, column, level):
    cap = make(level)
    truth_share = cap.truth["sensor"]["clipped_samples"] / len(cap)
    assert truth_share > 0.05
    with pytest.raises(CaptureError) as exc:
        run(cap)
    msg = str(exc.value)
    assert f"column '{column}'" in msg and "--allow-clipped" in msg and "\n" not in msg
    assert _share(msg) == pytest.approx(truth_share, abs=0.001)
    r = run(cap, allow_clipped=True)
    # a flattened peak is also motion the harmonics do not explain (motion_plausibility)
    (clipping,) = [w for w in r.warnings if not w.startswith("lack of fit:")]
    assert f"'{column}'" in clipping
    assert _share(clipping) == pytest.approx(truth_share, abs=0.001)
    assert r.to_dict()["warnings"] == list(r.warnings)
    # what the refusal prevents: the amplitude of a clipped record is far off the truth
    assert abs(r.amplitude_deg / cap.truth["amplitude_deg"] - 1) > 0.01


@pytest.mark.parametrize(("make", "run"), [(_lts, _run_lts), (_fog, _run_fog)])
@pytest.mark.parametrize("seed", range(3))
def test_unclipped_twins_pass_without_a_warning(make, run, seed):
    r = run(make(None, seed))
    assert r.warnings == ()
    assert "warnings" in r.to_dict() and r.to_dict()["warnings"] == []


def _encoder(amplitude_a: float = 1.0, amplitude_b: float = 1.0, seed: int = 0):
    """A 16-bit ADC of range ±1.25: an amplitude of 1.3 puts the channel at the rails."""
    return sim.simulate(
        "encoder",
        amplitude_deg=AMPLITUDE_DEG,
        adc_bits=16,
        noise_rms=0.002,
        amplitude_a=amplitude_a,
        amplitude_b=amplitude_b,
        seed=seed,
    )


def _chunks(columns, rows):
    def chunks():
        for i in range(0, columns["a"].size, rows):
            yield {k: columns[k][i : i + rows] for k in ("time_s", "a", "b")}

    return chunks


@pytest.mark.parametrize("channel", ["a", "b"])
def test_an_encoder_channel_at_the_adc_rails_is_refused_in_memory_and_chunked(channel):
    cap = _encoder(**{f"amplitude_{channel}": 1.3})
    c = cap.columns
    truth_share = cap.truth["sensor"]["clipped_samples"][channel] / len(cap)
    with pytest.raises(CaptureError) as mem:
        calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000)
    with pytest.raises(CaptureError) as chk:
        calibrate_encoder_motion_chunked(_chunks(c, 7777), lines=36000)
    assert str(mem.value) == str(chk.value)
    assert f"column '{channel}' is clipped" in str(mem.value)
    # the rail code also holds the honest samples of the last half LSB below the range
    assert _share(str(mem.value)) == pytest.approx(truth_share, abs=0.002)
    r_mem = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000, allow_clipped=True)
    r_chk = calibrate_encoder_motion_chunked(_chunks(c, 7777), lines=36000, allow_clipped=True)
    assert r_mem.warnings == r_chk.warnings and len(r_mem.warnings) == 1
    assert f"'{channel}'" in r_mem.warnings[0]


def test_an_unclipped_encoder_says_nothing_in_memory_and_chunked():
    c = _encoder(seed=4).columns
    assert calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000).warnings == ()
    assert calibrate_encoder_motion_chunked(_chunks(c, 5000), lines=36000).warnings == ()


def test_an_encoder_stopping_where_a_channel_peaks_is_not_clipped():
    """0.5° is 50 lines: the table stops (stagnates) where a = cos φ peaks, b stands still."""
    cap = sim.simulate(
        "encoder", amplitude_deg=AMPLITUDE_DEG, adc_bits=12, stagnation_s=0.05, seed=1
    )
    c = cap.columns
    assert np.mean(c["a"] == c["a"].max()) > 0.1  # a sits at its top code a tenth of the time
    r = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=36000)
    assert r.warnings == ()
