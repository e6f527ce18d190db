"""Chunked (out-of-core) encoder calibration: equal to the in-memory path and to the twin's truth."""

from __future__ import annotations

import numpy as np
import pytest

import rotacal.table.streaming as streaming
from rotacal import _jit, sim
from rotacal.encoder import demodulate
from rotacal.errors import CaptureError, ConfigError
from rotacal.io import read_capture, write_capture
from rotacal.table import (
    calibrate_encoder_motion,
    calibrate_encoder_motion_chunked,
    encoder_chunks_from_file,
)

LINES = 36000
DISTORTED = sim.SineMotion(
    amplitude_deg=0.5,
    frequency_hz=2.0,
    harmonics={2: (0.010, 0.4), 3: (0.008, 1.1), 5: (0.002, 2.0)},
)
# A vibration near the reversals: candidates come in clusters (pruned to one reversal each).
SHAKY = sim.SineMotion(
    amplitude_deg=0.25, frequency_hz=3.0, vibration_deg=0.0015, vibration_hz=61.0
)


@pytest.fixture(scope="module")
def capture():
    cap = sim.simulate_encoder(
        DISTORTED,
        offset_a=0.03,
        offset_b=-0.02,
        amplitude_b=0.97,
        phase_error_rad=np.radians(1.5),
        noise_rms=0.004,
        adc_bits=16,
        seed=3,
    )
    return cap.columns


def chunked(columns, rows):
    """A chunk source over in-memory columns, ``rows`` rows per chunk."""

    def chunks():
        n = columns["a"].size
        for i in range(0, n, rows):
            yield {k: columns[k][i : i + rows] for k in ("time_s", "a", "b")}

    return chunks


def in_memory(columns, **kw):
    return calibrate_encoder_motion(columns["time_s"], columns["a"], columns["b"], **kw)


def assert_same(r0, r):
    """Same reversals to the sample, the same JSON keys, the numbers equal to rounding."""
    d0, d = r0.to_dict(), r.to_dict()
    assert d.keys() == d0.keys()
    assert np.array_equal(r.reversal_times_s, r0.reversal_times_s)
    assert (r.periods_used, r.samples_used, r.harmonics) == (
        r0.periods_used,
        r0.samples_used,
        r0.harmonics,
    )
    assert (r.analysis_start_s, r.analysis_stop_s) == (r0.analysis_start_s, r0.analysis_stop_s)
    for key in (
        "amplitude_deg",
        "frequency_hz",
        "angular_acceleration_amplitude_deg_s2",
        "thd_percent",
        "offset_deg",
        "set_amplitude_deg",
        "set_frequency_hz",
        "position_error_max_deg",
        "position_error_rms_deg",
    ):
        if key in d0:
            assert d[key] == pytest.approx(d0[key], rel=1e-9, abs=1e-15), key
    for key in ("amplitude_error_percent", "frequency_error_percent"):
        if key in d0:  # differences of nearly equal numbers: compare on the scale of the value
            assert d[key] == pytest.approx(d0[key], abs=1e-9 * 100), key
    np.testing.assert_allclose(
        r.harmonic_amplitudes_deg, r0.harmonic_amplitudes_deg, rtol=0, atol=1e-9 * r0.amplitude_deg
    )
    # the residual comes from the normal equations (Σy² − …): ~1e-6 relative by cancellation
    assert r.residual_rms_deg == pytest.approx(r0.residual_rms_deg, rel=1e-5)
    assert r.notes == r0.notes


@pytest.mark.parametrize(
    ("rows", "gather"),
    [(997, 1000), (997, None), (65_537, 1000), (1_000_000, None)],
    ids=["997-accumulated", "997-gathered", "65537-accumulated", "one-chunk"],
)
def test_chunked_equals_in_memory_and_truth(capture, monkeypatch, rows, gather):
    if gather is not None:  # force the accumulated fit (the capture's span is ~1.3e5 samples)
        monkeypatch.setattr(streaming, "_GATHER_MAX_SAMPLES", gather)
    kw = {"lines": LINES, "set_amplitude_deg": 0.5, "set_frequency_hz": 2.0}
    r0 = in_memory(capture, **kw)
    seen: list[int] = []
    r = calibrate_encoder_motion_chunked(chunked(capture, rows), progress=seen.append, **kw)
    assert_same(r0, r)
    assert seen == sorted(seen) and seen[-1] >= 4 * capture["a"].size
    truth = DISTORTED.truth(r.analysis_start_s, r.analysis_stop_s)
    assert r.thd_percent == pytest.approx(truth["thd_percent"], abs=0.02)
    assert r.amplitude_deg == pytest.approx(truth["amplitude_deg"], rel=2e-4)
    assert r.frequency_hz == pytest.approx(truth["frequency_hz"], rel=1e-5)
    # the plot copies are those of the in-memory path
    for key in ("t", "angle_deg", "t_used", "residual_deg", "position_error_deg"):
        np.testing.assert_allclose(r._plot[key], r0._plot[key], rtol=1e-9, atol=1e-12)


def test_reversing_subintervals_straddle_chunk_boundaries(capture):
    """With 997-row chunks some windows of eqs. (7)-(8) are read from two chunks."""
    t, a, b = capture["time_s"], capture["a"], capture["b"]
    demod = demodulate(t, a, b, LINES)
    # independent of the streaming code: the windows [Sub-, Sub+] of the in-memory reversals
    idx = demod.reversals.indices
    k = np.floor(demod.angle_deg * LINES / 30.0)  # subinterval count k = floor(phi / (pi/6))
    straddle = 0
    for i in idx:
        lo, hi = i, i
        while lo > 0 and k[lo - 1] == k[i]:
            lo -= 1
        while hi < k.size - 1 and k[hi + 1] == k[i]:
            hi += 1
        straddle += (lo - 1) // 997 != (hi + 1) // 997
    assert straddle >= 3


def test_clusters_of_candidates_across_chunks():
    cap = sim.simulate_encoder(SHAKY, noise_rms=0.002, seed=2)
    c = cap.columns
    r0 = in_memory(c, lines=LINES)
    r = calibrate_encoder_motion_chunked(chunked(c, 997), lines=LINES)
    assert_same(r0, r)
    t = c["time_s"]
    truth = np.asarray(SHAKY.truth(t[0], t[-1])["reversal_times_s"])
    assert r.reversal_times_s.size == truth.size
    assert np.max(np.abs(r.reversal_times_s - truth)) < 3e-3


def test_through_an_npz_file(capture, tmp_path):
    path = write_capture(tmp_path / "enc.npz", capture)
    cap = read_capture(path, columns=["time_s", "a", "b"])
    r0 = in_memory(cap.columns, lines=LINES, harmonics=6)
    source = encoder_chunks_from_file(path, chunk_rows=20_011)
    r = calibrate_encoder_motion_chunked(source, lines=LINES, harmonics=6)
    assert_same(r0, r)


def test_through_an_hdf5_group_with_a_column_mapping(capture, tmp_path):
    cols = {"t": capture["time_s"], "ch_a": capture["a"], "ch_b": capture["b"]}
    path = write_capture(tmp_path / "enc.h5", cols, group="run1")
    r0 = in_memory(capture, lines=LINES)
    source = encoder_chunks_from_file(
        path, mapping={"t": "time_s", "ch_a": "a", "ch_b": "b"}, group="run1", chunk_rows=30_000
    )
    assert_same(r0, calibrate_encoder_motion_chunked(source, lines=LINES))


def test_nan_in_the_third_chunk_of_a_file_names_the_global_row(capture, tmp_path):
    bad = dict(capture)
    bad["b"] = capture["b"].copy()
    bad["b"][2 * 1000 + 17] = np.nan
    path = write_capture(tmp_path / "nan.npz", bad)
    with pytest.raises(CaptureError, match=r"row 2017\b"):
        calibrate_encoder_motion_chunked(
            encoder_chunks_from_file(path, chunk_rows=1000), lines=LINES
        )


def test_nan_in_memory_chunks_gives_the_in_memory_message(capture):
    bad = dict(capture)
    bad["b"] = capture["b"].copy()
    bad["b"][[2 * 997 + 5, 50_000]] = np.nan
    with pytest.raises(CaptureError) as mem:
        in_memory(bad, lines=LINES)
    with pytest.raises(CaptureError) as chk:
        calibrate_encoder_motion_chunked(chunked(bad, 997), lines=LINES)
    assert str(chk.value) == str(mem.value)
    assert "2 non-finite values" in str(chk.value) and "sample 1999" in str(chk.value)


def test_time_going_backwards_across_a_chunk_boundary(capture, tmp_path):
    bad = dict(capture)
    t = capture["time_s"].copy()
    t[3000] = t[2999] - 1e-6  # the first row of the 4th chunk goes back in time
    bad["time_s"] = t
    with pytest.raises(CaptureError) as mem:
        in_memory(bad, lines=LINES)
    path = write_capture(tmp_path / "back.npz", bad)
    with pytest.raises(CaptureError) as chk:
        calibrate_encoder_motion_chunked(
            encoder_chunks_from_file(path, chunk_rows=1000), lines=LINES
        )
    assert str(chk.value) == str(mem.value)
    assert "at sample 3000" in str(chk.value)


def _clipped(capture):
    out = dict(capture)
    out["a"] = np.clip(capture["a"], -0.8, 0.8)
    return out


def _not_quadrature(capture):
    out = dict(capture)
    out["b"] = capture["a"].copy()
    return out


def _too_short(capture):
    n = 20_000  # 0.4 s of a 2 Hz motion: fewer than 3 reversals
    return {k: v[:n] for k, v in capture.items()}


@pytest.mark.parametrize(
    ("spoil", "word"),
    [(_clipped, "clipped"), (_not_quadrature, "quadrature"), (_too_short, "reversing")],
)
def test_bad_captures_give_the_in_memory_error(capture, spoil, word):
    bad = spoil(capture)
    with pytest.raises(CaptureError) as mem:
        in_memory(bad, lines=LINES)
    with pytest.raises(CaptureError) as chk:
        calibrate_encoder_motion_chunked(chunked(bad, 997), lines=LINES)
    assert str(chk.value) == str(mem.value)
    assert word in str(chk.value)


def test_chunk_sources_that_cannot_work_are_refused(capture):
    with pytest.raises(ConfigError, match="callable"):
        calibrate_encoder_motion_chunked(iter([capture]), lines=LINES)  # type: ignore[arg-type]
    calls = []

    def changing():  # a different chunking on every pass
        calls.append(1)
        return chunked(capture, 1000 + len(calls))()

    with pytest.raises(CaptureError, match="same"):
        calibrate_encoder_motion_chunked(changing, lines=LINES)

    def missing():
        yield {"time_s": capture["time_s"], "a": capture["a"]}

    with pytest.raises(CaptureError, match="no column 'b'"):
        calibrate_encoder_motion_chunked(missing, lines=LINES)
    with pytest.raises(ConfigError, match="give both"):
        calibrate_encoder_motion_chunked(chunked(capture, 997), lines=LINES, set_amplitude_deg=0.5)
    with pytest.raises(ConfigError, match="chunk_rows"):
        encoder_chunks_from_file("x.npz", chunk_rows=0)


def test_chunked_with_the_numba_pass_equals_in_memory_without(capture, monkeypatch):
    kw = {"lines": LINES, "set_amplitude_deg": 0.5, "set_frequency_hz": 2.0}
    monkeypatch.setenv("ROTACAL_NUMBA", "0")
    r0 = in_memory(capture, **kw)
    monkeypatch.delenv("ROTACAL_NUMBA")
    monkeypatch.setattr(_jit, "MIN_SAMPLES", 0)  # the Numba twin for every pass of the capture
    assert _jit.use_numba(capture["a"].size)
    r = calibrate_encoder_motion_chunked(chunked(capture, 65_537), **kw)
    assert_same(r0, r)
    truth = DISTORTED.truth(r.analysis_start_s, r.analysis_stop_s)
    assert r.thd_percent == pytest.approx(truth["thd_percent"], abs=0.02)
