"""The rate analysis streamed from a file against the in-memory path, and the bounded budgets'
sufficient statistics against the whole-vector closed forms."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

import rotacal.uncertainty.summaries_peak as summaries_peak
from rotacal.cli import cli
from rotacal.errors import CaptureError, ConfigError
from rotacal.sim.pulses import simulate_pulses
from rotacal.table.rate import calibrate_rate
from rotacal.table.rate_file import calibrate_rate_file
from rotacal.uncertainty import Input
from rotacal.uncertainty.summaries import (
    CirculantError,
    CovarianceCorrection,
    FilteredWhite,
    SeriesStats,
    denoised,
    rms_budget,
)
from rotacal.uncertainty.summaries_peak import PeakCollector, WelchSums, denoised_at, welch_gain

M = 900


@pytest.fixture(scope="module")
def capture(tmp_path_factory):
    """One head of a twin (m = 900, 60 revolutions less 333 pulses), saved as NPZ, and the
    deviation self-calibrated from the whole two-head capture (another capture of the same
    encoder: it must be aligned)."""
    from rotacal.encoder.selfcal import self_calibrate

    cap = simulate_pulses(heads=2, pulses_per_rev=M, rate_deg_s=120.0, revolutions=60.0, seed=5)
    heads = [np.asarray(cap.columns["head_0"]), np.asarray(cap.columns["head_1"])]
    sc = self_calibrate(heads, pulses_per_rev=M)
    path = tmp_path_factory.mktemp("rate") / "one.npz"
    t = heads[0][333:]
    np.savez(path, head_0=t)
    return path, t, np.asarray(sc.deviation_arcsec)


def _assert_same(a, b, where=""):
    """Every JSON number equal to 1e-9 relative (strings and structure exactly)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), where
        for k in a:
            _assert_same(a[k], b[k], f"{where}.{k}")
    elif isinstance(a, list):
        assert len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _assert_same(x, y, f"{where}[{i}]")
    elif isinstance(a, float) and isinstance(b, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-300), where
    else:
        assert a == b, where


@pytest.mark.parametrize("chunk", [997, 7777])
@pytest.mark.parametrize("given", [False, True])
def test_streamed_file_equals_in_memory(capture, monkeypatch, chunk, given):
    """Chunks shorter than the jitter's 2m + 3 overlap (997) and longer (7777), neither a
    multiple of the average (a boundary inside a rate point) nor of any Allan cluster; Welch
    windows of 512 points so that the peak's filter crosses many: every JSON number to 1e-9.
    With a deviation from another capture, the alignment's own pass gives the same shift."""
    path, t, dev = capture
    monkeypatch.setattr(summaries_peak, "WINDOW", 512)
    kw = dict(pulses_per_rev=M, average=10, set_rate_deg_s=120.0, selfcal=dev if given else None)
    mem = calibrate_rate([t], **kw)
    streamed = calibrate_rate_file(path, chunk_rows=chunk, **kw)
    assert streamed.compensated is given
    assert streamed.deviation_shift_pulses == mem.deviation_shift_pulses == (333 if given else None)
    assert len(mem.rate_deg_s) > 5 * 512  # the filter's windows are crossed many times
    _assert_same(mem.to_dict(), streamed.to_dict())


def test_streamed_file_refuses_what_needs_every_head(tmp_path, capture):
    _, t, _ = capture
    path = tmp_path / "two.npz"
    np.savez(path, head_0=t, head_1=t + 1e-4)
    with pytest.raises(ConfigError, match="head_0"):
        calibrate_rate_file(path, pulses_per_rev=M, head=1)
    with pytest.raises(ConfigError, match="one head"):
        calibrate_rate_file(path, pulses_per_rev=M, head="all", compensate=False)


def test_streamed_file_names_a_missing_pulse_as_the_whole_train_does(tmp_path, capture):
    _, t, _ = capture
    path = tmp_path / "gap.npz"
    np.savez(path, head_0=np.delete(t, 30_000))
    with pytest.raises(CaptureError) as whole:
        calibrate_rate([np.delete(t, 30_000)], pulses_per_rev=M)
    assert "after pulse 29999 " in str(whole.value)
    with pytest.raises(CaptureError) as streamed:
        calibrate_rate_file(path, pulses_per_rev=M, chunk_rows=7777)
    assert "after pulse 29999 " in str(whole.value)
    assert "after pulse 29999 " in str(streamed.value)


def test_cli_streams_a_large_capture_by_itself(capture, tmp_path, monkeypatch):
    """Above the threshold the command takes the streamed path unasked; --in-memory forces
    the other; both write the same JSON numbers."""
    import rotacal.cli.pulses as pulses_cli
    import rotacal.table.rate_file as rate_file

    path, _, _ = capture
    calls = []
    real = rate_file.calibrate_rate_file
    monkeypatch.setattr(
        rate_file, "calibrate_rate_file", lambda *a, **k: calls.append(1) or real(*a, **k)
    )
    monkeypatch.setattr(pulses_cli, "_IN_MEMORY_MAX_PULSES", 1000)
    out = {}
    for flag in ("", "--in-memory"):
        dest = tmp_path / f"r{flag}.json"
        args = ["rate", str(path), "--pulses-per-rev", str(M), "--json", str(dest)]
        res = CliRunner().invoke(cli, args + ([flag] if flag else []), prog_name="rotacal")
        assert res.exit_code == 0, res.output
        out[flag] = json.loads(dest.read_text())
    assert len(calls) == 1
    assert out[""]["provenance"]["options"]["chunked"] is None  # chosen, not asked for
    for data in out.values():
        data.pop("provenance")
    _assert_same(out["--in-memory"], out[""])


# ---------------------------------------------------------------------- sufficient statistics
def _quadratic_whole(d, g):
    """dᵀGd with the Toeplitz G of first column g, element by element (the former closed form)."""
    r = np.array([np.dot(d[: d.size - k], d[k:]) for k in range(d.size)])
    return float(g[0] * r[0] + 2.0 * np.dot(g[1:], r[1:]))


def _trace_whole(g1, g2):
    n = g1.size
    return float(n * g1[0] * g2[0] + 2.0 * np.dot(n - np.arange(1, n), g1[1:] * g2[1:]))


def _sources(rng, period):
    c = rng.normal(size=period)
    c = np.fft.irfft(np.abs(np.fft.rfft(c)) ** 2, period) / period  # symmetric, PSD
    inp = Input(name="x", value=0.0, u=1.0, dof=30.0, unit="")
    return [
        FilteredWhite(inp, "noise", taps=np.array([-0.7, 0.7]), sigma=1.3),
        CirculantError(inp, "bound", autocov=c),
        CovarianceCorrection(inp, "noise", autocov=-0.2 * c),
        CirculantError(inp, "absent", autocov=0.5 * c),
    ]


@pytest.mark.parametrize(("n", "period"), [(1000, 90), (1000, 1000), (777, 1300), (2001, 7)])
def test_series_stats_give_the_closed_form(n, period):
    """The folded and lagged sums (chunk by chunk, then moved by a·d + b) give dᵀGd, tr(G₁G₂)
    and the whole rms budget of the length-N formulas (periods below, at and above N)."""
    from rotacal.uncertainty.summaries_rms import trace_product

    rng = np.random.default_rng(n + period)
    d = rng.normal(size=n) + np.sin(np.arange(n) / 17.0)
    sources = _sources(rng, period)
    st = SeriesStats.empty([period])
    a, b = 0.93, 0.21
    for part in np.array_split((d - b) / a, 7):
        st.update(part)
    st = st.affine(a, b)
    for s in sources:
        g = s.lags(n)
        assert st.quadratic(s) == pytest.approx(_quadratic_whole(d, g), rel=1e-10)
        for o in sources:
            assert trace_product(s, o, n) == pytest.approx(_trace_whole(g, o.lags(n)), rel=1e-10)
    whole = rms_budget("x", "", d, sources).budget
    streamed = rms_budget("x", "", st, sources).budget
    assert streamed.value == pytest.approx(math.sqrt(np.mean(d * d)), rel=1e-12)
    for key in ("u", "U", "dof_eff"):
        assert getattr(streamed, key) == pytest.approx(getattr(whole, key), rel=1e-10)


def test_welch_filter_is_the_whole_vector_filter_up_to_one_window():
    rng = np.random.default_rng(3)
    d = np.cumsum(rng.normal(size=3000)) * 0.01 + rng.normal(size=3000)
    g = np.zeros(3000)
    g[0] = 1.0
    w = WelchSums(d.size)
    w.update(d)
    noise = np.full(d.size // 2 + 1, float(d.size))  # E|X_q|² of unit white noise
    pos = np.array([5, 1500, 2999])
    (mine,) = denoised_at(d, pos, [welch_gain(w.power(), noise)])
    np.testing.assert_allclose(mine, denoised(d, g)[pos], rtol=1e-12)


def test_peak_collector_equals_the_array_filter_across_windows(monkeypatch):
    """Chunks of 333 against windows of 256: the candidates and their filtered values."""
    monkeypatch.setattr(summaries_peak, "WINDOW", 256)
    rng = np.random.default_rng(4)
    d = np.sin(np.arange(5000) / 40.0) + 0.05 * rng.normal(size=5000)
    welch = WelchSums(d.size)
    for part in np.array_split(d, 15):
        welch.update(part)
    gain = welch_gain(welch.power(), np.full(129, 0.05**2 * 256))
    collector = PeakCollector(d.size, 0.97, [gain])
    for start in range(0, d.size, 333):
        collector.update(d[start : start + 333])
    got = collector.result()
    pos = np.flatnonzero(np.abs(d) >= 0.97)
    np.testing.assert_array_equal(got.pos, pos)
    np.testing.assert_array_equal(got.base, d[pos])
    np.testing.assert_allclose(got.denoised[0], denoised_at(d, pos, [gain])[0], rtol=1e-12)
    assert got.plain == float(np.max(np.abs(d)))


@pytest.mark.parametrize("chunk", [997, 4321])
@pytest.mark.parametrize("same_line", [True, False])
def test_compiled_per_pulse_loops_equal_the_numpy_ones(capture, same_line, chunk):
    """The Numba twins of the jitter sums and the rate points: ≤ 1e-12 relative, any chunking
    (chunks shorter and longer than the jitter's 2m + 3 pulses carried)."""
    pytest.importorskip("numba")
    from rotacal.table.rate_jitter import JitterSums
    from rotacal.table.rate_stream import _RatePoints

    _, t, dev = capture
    t = t if same_line else t[: 2 * M]  # under two revolutions: the filter along the pulses
    out = {}
    for jit in (False, True):
        sums = JitterSums(t.size, M, jit=jit)
        points = _RatePoints(M, 10, dev, 17, jit)
        parts = []
        for start in range(0, t.size, chunk):
            part = t[start : start + chunk]
            sums.update(part)
            nom, ang = points.angles(part)
            parts.append(points.push(part, ang, nom))
        out[jit] = (sums.result(), [np.concatenate([p[i] for p in parts]) for i in range(3)])
    assert out[True][0] == pytest.approx(out[False][0], rel=1e-12)
    for compiled, plain in zip(out[True][1], out[False][1], strict=True):
        np.testing.assert_allclose(compiled, plain, rtol=1e-12)


def test_monte_carlo_batches_draw_the_same_rows():
    """Batches of trials (the peak's memory bound) give the rows of one whole draw."""
    from rotacal.uncertainty.summaries import iter_statistic_samples, statistic_samples

    rng = np.random.default_rng(8)
    sources = _sources(rng, 60)
    pos = np.array([3, 4, 5, 70, 71, 400, 999], dtype=np.int64)
    whole = statistic_samples(pos, 1000, sources, trials=50, seed=3)
    parts = list(iter_statistic_samples(pos, 1000, sources, trials=50, seed=3, batch=7))
    assert len(parts) == 8
    for group in ("noise", "other"):
        np.testing.assert_allclose(
            np.concatenate([x[group] for x in parts]), whole[group], rtol=1e-12, atol=1e-15
        )


def test_streamed_self_calibrated_rate_equals_in_memory(tmp_path):
    """Several heads and nothing given: the capture self-calibrates in chunks (one reader per
    head, a head starting later) and the rate of head 0 streams after it — every JSON number of
    the in-memory calibrate_rate to 1e-9, the self-calibration's own covariance term included."""
    cap = simulate_pulses(heads=3, pulses_per_rev=M, rate_deg_s=120.0, revolutions=12.0, seed=9)
    heads = [np.asarray(cap.columns[f"head_{i}"]) for i in range(3)]
    heads[2] = heads[2][50:]  # ragged: head 2 starts 50 pulses late
    path = tmp_path / "three.npz"
    np.savez(path, **{f"head_{i}": h for i, h in enumerate(heads)})
    kw = dict(pulses_per_rev=M, average=10, set_rate_deg_s=120.0)
    mem = calibrate_rate(heads, **kw)
    streamed = calibrate_rate_file(path, chunk_rows=1234, **kw)
    assert streamed.selfcal is not None and mem.selfcal is not None
    assert any("self-calibrated from this capture" in n for n in streamed.notes)
    _assert_same(mem.to_dict(), streamed.to_dict())
    with pytest.raises(ConfigError, match="head_0"):
        calibrate_rate_file(path, head=1, **kw)


def test_cli_streams_a_capture_to_self_calibrate_by_itself(tmp_path, monkeypatch):
    """Several heads above the self-calibration's threshold: `rotacal rate` streams both the
    self-calibration and the rate unasked, and writes --in-memory's numbers."""
    import rotacal.cli.pulses as pulses_cli
    import rotacal.encoder.selfcal_stream as selfcal_stream

    cap = simulate_pulses(heads=2, pulses_per_rev=M, rate_deg_s=120.0, revolutions=6.0, seed=4)
    path = tmp_path / "two.npz"
    np.savez(path, **{k: np.asarray(v) for k, v in cap.columns.items() if k.startswith("head_")})
    monkeypatch.setattr(pulses_cli, "_SELFCAL_IN_MEMORY_MAX", 1000)
    calls = []
    real = selfcal_stream.self_calibrate_chunked
    monkeypatch.setattr(
        selfcal_stream, "self_calibrate_chunked", lambda *a, **k: calls.append(1) or real(*a, **k)
    )
    out = {}
    for flag in ("", "--in-memory"):
        dest = tmp_path / f"r{flag}.json"
        args = ["rate", str(path), "--pulses-per-rev", str(M), "--json", str(dest)]
        res = CliRunner().invoke(cli, args + ([flag] if flag else []), prog_name="rotacal")
        assert res.exit_code == 0, res.output
        out[flag] = json.loads(dest.read_text())
    assert len(calls) == 1  # the chunked self-calibration ran once: for the unasked stream
    for data in out.values():
        data.pop("provenance")
    assert out[""]["compensated"] is True
    _assert_same(out["--in-memory"], out[""])
