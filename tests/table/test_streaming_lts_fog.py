"""Chunked LTS and FOG calibrations: equal to the in-memory paths (≤ 1e-9) and to the twin's truth."""

from __future__ import annotations

import numpy as np
import pytest

import rotacal.table.streaming as streaming
from rotacal import sim
from rotacal.errors import CaptureError, ConfigError
from rotacal.io import write_capture
from rotacal.table import _stream_lts as lts
from rotacal.table import (
    calibrate_fog_motion,
    calibrate_fog_motion_chunked,
    calibrate_lts_motion,
    calibrate_lts_motion_chunked,
    fog_chunks_from_file,
    lts_chunks_from_file,
)

DISTORTED = sim.SineMotion(
    amplitude_deg=0.5,
    frequency_hz=2.0,
    harmonics={2: (0.010, 0.4), 3: (0.008, 1.1), 5: (0.002, 2.0)},
)
SET = {"set_amplitude_deg": 0.5, "set_frequency_hz": 2.0}


@pytest.fixture(scope="module")
def lts_capture():
    return sim.simulate_lts(DISTORTED, radius_mm=100.0, noise_mm=3e-5, seed=4).columns


@pytest.fixture(scope="module")
def fog_capture():
    return sim.simulate_fog(DISTORTED, snr_db=40.0, bias_deg_s=0.02, seed=5).columns


def chunked(columns, rows):
    """A chunk source over in-memory columns, ``rows`` rows per chunk."""

    def chunks():
        n = columns["time_s"].size
        for i in range(0, n, rows):
            yield {k: v[i : i + rows] for k, v in columns.items()}

    return chunks


def assert_same(r0, r, *, offset_abs=0.0):
    """Same reversals, the same JSON keys, the numbers equal to ≤ 1e-9 relative."""
    d0, d = r0.to_dict(), r.to_dict()
    assert d.keys() == d0.keys()
    np.testing.assert_allclose(r.reversal_times_s, r0.reversal_times_s, rtol=0, atol=1e-12)
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
        "position_error_max_deg",
        "position_error_rms_deg",
        "snr_db",
        "drift_deg_s",
        "rate_drift_deg_s2",
    ):
        if key in d0:
            assert d[key] == pytest.approx(d0[key], rel=1e-9, abs=1e-15), key
    # an offset near 0 (the FOG's is the mean of an angle less its mean: rounding around 0)
    # is compared on the scale of the motion
    assert r.offset_deg == pytest.approx(
        r0.offset_deg, rel=1e-9, abs=max(offset_abs, 1e-12 * r0.amplitude_deg)
    )
    for key in ("amplitude_error_percent", "frequency_error_percent"):
        if key in d0:  # differences of nearly equal numbers: compare on the scale of the value
            assert d[key] == pytest.approx(d0[key], abs=1e-9 * 100), key
    np.testing.assert_allclose(
        r.harmonic_amplitudes_deg, r0.harmonic_amplitudes_deg, rtol=0, atol=1e-9 * r0.amplitude_deg
    )
    # the residual comes from the normal equations (Σy² − …): ~1e-6 relative by cancellation,
    # and so do the standard uncertainties that scale with it
    assert r.residual_rms_deg == pytest.approx(r0.residual_rms_deg, rel=1e-5)
    for key in ("amplitude_deg_u", "frequency_hz_u", "thd_percent_u"):
        assert d[key] == pytest.approx(d0[key], rel=1e-5), key
    assert r.notes == r0.notes
    assert r.warnings == r0.warnings


def lts_in_memory(c, **kw):
    return calibrate_lts_motion(c["time_s"], c["displacement_mm"], radius_mm=100.0, **kw)


def fog_in_memory(c, **kw):
    return calibrate_fog_motion(c["time_s"], c["rate_deg_s"], **kw)


@pytest.mark.parametrize(
    ("rows", "gather"),
    [(997, 1000), (997, None), (65_537, 1000)],
    ids=["997-accumulated", "997-gathered", "65537-accumulated"],
)
def test_lts_chunked_equals_in_memory_and_truth(lts_capture, monkeypatch, rows, gather):
    if gather is not None:  # force the accumulated fit
        monkeypatch.setattr(streaming, "_GATHER_MAX_SAMPLES", gather)
    r0 = lts_in_memory(lts_capture, **SET)
    seen: list[int] = []
    r = calibrate_lts_motion_chunked(
        chunked(lts_capture, rows), radius_mm=100.0, progress=seen.append, **SET
    )
    assert_same(r0, r)
    assert seen == sorted(seen) and seen[-1] >= 5 * lts_capture["time_s"].size
    truth = DISTORTED.truth(r.analysis_start_s, r.analysis_stop_s)
    assert r.thd_percent == pytest.approx(truth["thd_percent"], abs=0.02)
    assert r.amplitude_deg == pytest.approx(truth["amplitude_deg"], rel=2e-4)
    assert r.frequency_hz == pytest.approx(truth["frequency_hz"], rel=1e-5)
    for key in ("t", "angle_deg", "t_used", "residual_deg", "position_error_deg"):
        np.testing.assert_allclose(r._plot[key], r0._plot[key], rtol=1e-9, atol=1e-12)


def test_lts_with_drift_through_an_npz_file(tmp_path, monkeypatch):
    drifting = sim.SineMotion(amplitude_deg=0.2, frequency_hz=1.0, drift_deg_s=0.05)
    c = sim.simulate_lts(drifting, radius_mm=100.0, noise_mm=3e-5, seed=9).columns
    path = write_capture(tmp_path / "lts.npz", c)
    monkeypatch.setattr(streaming, "_GATHER_MAX_SAMPLES", 1000)
    r0 = lts_in_memory(c, drift=True, **SET)
    source = lts_chunks_from_file(path, chunk_rows=7_001)
    r = calibrate_lts_motion_chunked(source, radius_mm=100.0, drift=True, **SET)
    assert_same(r0, r)
    assert r.drift_deg_s == pytest.approx(0.05, rel=1e-3)


def test_order_statistics_are_numpys_percentiles():
    rng = np.random.default_rng(1)
    # smooth values, and values on a coarse grid (many equal values around each rank)
    for x in (rng.normal(size=50_001), np.round(rng.normal(size=40_000), 1)):
        parts = np.array_split(x, 13)
        for q in (2.0, 50.0, 98.0):
            got = lts.percentile(
                x.size,
                q,
                lambda ranks, x=x, parts=parts: lts.order_statistics(
                    lambda: iter(parts), ranks, float(x.min()), float(x.max())
                ),
            )
            assert got == np.percentile(x, q)


@pytest.mark.parametrize(
    ("rows", "gather"),
    [(997, 1000), (997, None), (65_537, 1000)],
    ids=["997-accumulated", "997-gathered", "65537-accumulated"],
)
def test_fog_chunked_equals_in_memory_and_truth(fog_capture, monkeypatch, rows, gather):
    if gather is not None:
        monkeypatch.setattr(streaming, "_GATHER_MAX_SAMPLES", gather)
    r0 = fog_in_memory(fog_capture, **SET)
    seen: list[int] = []
    r = calibrate_fog_motion_chunked(chunked(fog_capture, rows), progress=seen.append, **SET)
    assert_same(r0, r, offset_abs=1e-12 * r0.amplitude_deg)
    assert seen[-1] >= 4 * fog_capture["time_s"].size
    truth = DISTORTED.truth(r.analysis_start_s, r.analysis_stop_s)
    assert r.thd_percent == pytest.approx(truth["thd_percent"], abs=0.05)
    assert r.amplitude_deg == pytest.approx(truth["amplitude_deg"], rel=1e-3)
    assert r.frequency_hz == pytest.approx(truth["frequency_hz"], rel=1e-5)
    for key in ("t", "rate_deg_s", "t_used", "residual_deg_s", "position_error_deg"):
        np.testing.assert_allclose(r._plot[key], r0._plot[key], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(
        r._plot["angle_deg_integrated"], r0._plot["angle_deg_integrated"], rtol=0, atol=1e-12
    )


def test_fog_with_drift_through_an_npz_file(tmp_path, monkeypatch):
    c = sim.simulate_fog(DISTORTED, snr_db=40.0, bias_deg_s=0.1, bias_drift_deg_s2=0.01, seed=3)
    path = write_capture(tmp_path / "fog.npz", c.columns)
    monkeypatch.setattr(streaming, "_GATHER_MAX_SAMPLES", 1000)
    r0 = fog_in_memory(c.columns, drift=True)
    r = calibrate_fog_motion_chunked(fog_chunks_from_file(path, chunk_rows=5_003), drift=True)
    assert_same(r0, r, offset_abs=1e-12 * r0.amplitude_deg)
    assert r.rate_drift_deg_s2 == pytest.approx(0.01, rel=0.05)


def _with_nan(c, name):
    out = dict(c)
    out[name] = c[name].copy()
    out[name][[2 * 997 + 5, 30_000]] = np.nan
    return out


def _backwards(c, name):
    out = dict(c)
    out["time_s"] = c["time_s"].copy()
    out["time_s"][997 * 3] = out["time_s"][997 * 3 - 1] - 1e-6  # across a chunk boundary
    return out


def _gap(c, name):
    out = dict(c)
    out["time_s"] = c["time_s"].copy()
    out["time_s"][5000:] += 1.0
    return out


def _constant(c, name):
    out = dict(c)
    out[name] = np.full_like(c[name], 0.25)
    return out


def _clipped(c, name):
    out = dict(c)
    lim = 0.8 * np.max(np.abs(c[name]))
    out[name] = np.clip(c[name], -lim, lim)
    return out


def _short(c, name):
    return {k: v[:12] for k, v in c.items()}


def _too_few_reversals(c, name):
    keep = c["time_s"] < c["time_s"][0] + 0.6  # 1.2 periods of the 2 Hz motion
    return {k: v[keep] for k, v in c.items()}


@pytest.mark.parametrize(
    "spoil", [_with_nan, _backwards, _gap, _constant, _clipped, _short, _too_few_reversals]
)
@pytest.mark.parametrize("scheme", ["lts", "fog"])
def test_bad_captures_give_the_in_memory_error(lts_capture, fog_capture, spoil, scheme):
    if scheme == "lts":
        bad = spoil(lts_capture, "displacement_mm")
        memory, stream = lts_in_memory, calibrate_lts_motion_chunked
        kw = {"radius_mm": 100.0}
    else:
        bad = spoil(fog_capture, "rate_deg_s")
        memory, stream = fog_in_memory, calibrate_fog_motion_chunked
        kw = {}
    with pytest.raises(CaptureError) as mem:
        memory(bad)
    with pytest.raises(CaptureError) as chk:
        stream(chunked(bad, 997), **kw)
    assert str(chk.value) == str(mem.value)


def test_lts_beyond_the_radius_and_bad_settings(lts_capture):
    with pytest.raises(CaptureError) as mem:
        calibrate_lts_motion(lts_capture["time_s"], lts_capture["displacement_mm"], radius_mm=0.5)
    with pytest.raises(CaptureError) as chk:
        calibrate_lts_motion_chunked(chunked(lts_capture, 997), radius_mm=0.5)
    assert str(chk.value) == str(mem.value) and "more than R" in str(chk.value)
    with pytest.raises(ConfigError, match="radius"):
        calibrate_lts_motion_chunked(chunked(lts_capture, 997), radius_mm=-1.0)
    with pytest.raises(ConfigError, match="give both"):
        calibrate_lts_motion_chunked(chunked(lts_capture, 997), radius_mm=100.0, set_frequency_hz=2)
    with pytest.raises(ConfigError, match="lts_chunks_from_file"):
        calibrate_lts_motion_chunked(iter([lts_capture]), radius_mm=100.0)  # type: ignore[arg-type]


def test_chunks_missing_the_signal_are_refused(fog_capture):
    def missing():
        yield {"time_s": fog_capture["time_s"]}

    with pytest.raises(CaptureError, match=r"no column 'rate_deg_s'.*time_s and rate_deg_s"):
        calibrate_fog_motion_chunked(missing)


@pytest.mark.parametrize("scheme", ["lts", "fog"])
def test_the_cli_streams_a_large_capture_by_itself(
    lts_capture, fog_capture, tmp_path, monkeypatch, scheme
):
    """Above the in-memory limit (lowered here) the command streams; same JSON as --in-memory;
    a fault names the file."""
    import json

    from click.testing import CliRunner

    import rotacal.cli.motion as cli_motion
    from rotacal.cli import cli

    cap = lts_capture if scheme == "lts" else fog_capture
    path = write_capture(tmp_path / f"{scheme}.npz", cap)
    args = [
        "motion",
        scheme,
        str(path),
        "--json",
        "-",
        *(["--radius-mm", "100"] * (scheme == "lts")),
    ]

    def run(*more):
        r = CliRunner().invoke(cli, [*args, *more], prog_name="rotacal")
        assert r.exit_code == 0, r.output
        return json.loads(r.stdout)

    whole = run("--in-memory")
    calls = []
    real = (
        streaming.calibrate_lts_motion_chunked
        if scheme == "lts"
        else streaming.calibrate_fog_motion_chunked
    )
    name = real.__name__
    monkeypatch.setattr(f"rotacal.table.{name}", lambda *a, **k: calls.append(1) or real(*a, **k))
    monkeypatch.setattr(cli_motion, "_IN_MEMORY_MAX_SAMPLES", 1000)
    streamed = run()
    assert calls == [1]
    assert streamed["reversal_times_s"] == pytest.approx(whole["reversal_times_s"], abs=1e-12)
    assert streamed["thd_percent"] == pytest.approx(whole["thd_percent"], rel=1e-9)
    bad = dict(cap)
    bad["time_s"] = cap["time_s"].copy()
    bad["time_s"][5000:] += 1.0
    bad_path = write_capture(tmp_path / "gap.npz", bad)
    r = CliRunner().invoke(cli, ["motion", scheme, str(bad_path), *args[3:]], prog_name="rotacal")
    assert r.exit_code != 0 and "gap.npz" in r.stderr and "gap" in r.stderr


SLOW = sim.SineMotion(amplitude_deg=0.5, frequency_hz=0.5, harmonics={2: (0.010, 0.4)})


@pytest.mark.parametrize("rows", [997, 65_537])
@pytest.mark.parametrize("scheme", ["lts", "fog"])
def test_long_blocks_of_a_slow_motion_equal_in_memory(monkeypatch, scheme, rows):
    """0.5 Hz at 10 kHz: the chunked fits use their own long blocks (block_length ≥ 64),
    each add ending on a block boundary; the result is still the in-memory one."""
    from rotacal.table import _stream_fit

    monkeypatch.setattr(streaming, "_GATHER_MAX_SAMPLES", 1000)
    assert _stream_fit.block_length(0.5, 10, 1e-4) >= 64
    if scheme == "lts":
        c = sim.simulate_lts(SLOW, radius_mm=100.0, fs_hz=10_000.0, duration_s=9.0, seed=2).columns
        r0 = lts_in_memory(c, **SET)
        r = calibrate_lts_motion_chunked(chunked(c, rows), radius_mm=100.0, **SET)
        assert_same(r0, r)
    else:
        c = sim.simulate_fog(SLOW, snr_db=40.0, fs_hz=10_000.0, duration_s=9.0, seed=2).columns
        r0 = fog_in_memory(c, **SET)
        r = calibrate_fog_motion_chunked(chunked(c, rows), **SET)
        assert_same(r0, r, offset_abs=1e-12 * r0.amplitude_deg)
    truth = SLOW.truth(r.analysis_start_s, r.analysis_stop_s)
    assert r.amplitude_deg == pytest.approx(truth["amplitude_deg"], rel=1e-3)


def test_block_aligned_adds_give_the_one_add_fit():
    """accumulate's block-aligned adds (any chunking) = one add of every sample."""
    from rotacal.signal import fit_harmonics
    from rotacal.table import _stream_fit

    t = np.arange(200_003) * 1e-4
    y = SLOW.angle_deg(t) + np.random.default_rng(0).normal(0.0, 1e-4, t.size)
    m = _stream_fit.block_length(0.5, 10, 1e-4)
    acc = _stream_fit.accumulator(0.5, 10, 1e-4)
    pieces = ((0, t[i : i + 7_919], y[i : i + 7_919]) for i in range(0, t.size, 7_919))
    _stream_fit.accumulate([(acc, None)], pieces, m)
    got = acc.fit(0.5, 10, True, max_iter=50, rtol=1e-12)
    want = fit_harmonics(t, y, frequency_hz=0.5, harmonics=10)
    assert got.frequency_hz == pytest.approx(want.frequency_hz, rel=1e-12)
    np.testing.assert_allclose(got.amplitudes, want.amplitudes, rtol=0, atol=1e-11)
