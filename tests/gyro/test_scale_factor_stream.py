"""Gyro scale factor from a log read in chunks: the same result as in memory (≤ 1e-9 relative),
the same refusals, and point statistics that stay exact where plain sums lose their digits."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro import calibrate_scale_factor_chunked
from rotacal.gyro.scale_factor import calibrate_scale_factor
from rotacal.gyro.scale_factor_points import _group
from rotacal.gyro.scale_factor_stream import _RatePoints, scale_factor_chunks
from rotacal.sim.gyro_rates import simulate_gyro_rates

_TRIALS = 2000  # the Monte Carlo is the same code on the same point statistics: few trials do


def _differences(a, b, path=""):
    """Paths where two JSON trees differ by more than 1e-9 relative (NaN equals NaN)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys(), path
        return [d for k in a for d in _differences(a[k], b[k], f"{path}.{k}")]
    if isinstance(a, list | tuple):
        assert len(a) == len(b), path
        return [
            d
            for i, (x, y) in enumerate(zip(a, b, strict=True))
            for d in _differences(x, y, f"{path}[{i}]")
        ]
    if isinstance(a, float) and isinstance(b, float):
        if a == b or (math.isnan(a) and math.isnan(b)) or abs(a - b) <= 1e-9 * max(abs(a), abs(b)):
            return []
    elif a == b:
        return []
    return [(path, a, b)]


def _same_result(memory, streamed):
    """Streamed equals in memory to 1e-9 relative; the NL noise bias, a difference of two Monte
    Carlo means (which amplifies the rounding of the point means), to 1e-9 of the NL it corrects."""
    a, b = memory.to_dict(), streamed.to_dict()
    nl = abs(a["nonlinearity_percent_fs"])
    for key in ("nonlinearity_percent_fs_bias", "nonlinearity_percent_fs_bias_corrected"):
        x, y = a.pop(key), b.pop(key)  # None: NaN in the JSON
        assert (x is None and y is None) or abs(x - y) <= 1e-9 * nl, key
    for d in (a, b):  # the bias is quoted in the NL budget's notes: compare the rest of them
        budget = d.get("uncertainty_budgets", {}).get("nonlinearity_percent_fs")
        if budget:
            budget["notes"] = [n for n in budget["notes"] if "Bias from the noise" not in n]
    assert _differences(a, b) == []
    assert memory.warnings == streamed.warnings


def _both(rate, output, chunk_rows, **kw):
    kw.setdefault("mc_trials", _TRIALS)
    memory = calibrate_scale_factor(rate, output, **kw)
    streamed = calibrate_scale_factor_chunked(
        scale_factor_chunks(rate, output, chunk_rows=chunk_rows), **kw
    )
    return memory, streamed


def _twin(**kw):
    kw.setdefault("samples_per_point", 400)
    cap = simulate_gyro_rates(**kw)
    return cap.columns["rate_deg_s"], cap.columns["output"]


CASES = {
    "noisy": (lambda: _twin(seed=1), {}),
    "quantised flat points": (lambda: _twin(quantum=1e-2, seed=2), {}),
    "noise-free grid": (lambda: _twin(quantum=1e-3, noise_std=0.0, seed=3), {}),
    "one sample per point": (lambda: _twin(samples_per_point=1, seed=4), {}),
    "bandwidth and requirement": (
        lambda: _twin(seed=5),
        {"sample_rate_hz": 200.0, "bandwidth_hz": 7.0, "requirement": "fmvss126"},
    ),
    "unequal points": (
        lambda: _twin(samples_per_point=[3, 50, 7, 400, 1, 2, 90, 5, 8, 13, 21], seed=6),
        {},
    ),
}


@pytest.mark.parametrize("chunk_rows", [1, 97, 1_000_000])
@pytest.mark.parametrize("case", list(CASES))
def test_streamed_equals_in_memory(case, chunk_rows):
    make, kw = CASES[case]
    rate, output = make()
    if chunk_rows == 1 and rate.size > 1000:
        rate, output = rate[::4], output[::4]  # one row per chunk: keep it quick
    _same_result(*_both(rate, output, chunk_rows, **kw))


def test_interleaved_rows_noisy_set_rates_and_a_large_offset():
    # rows of the points mixed (a pooled log), set rates jittering within the tolerance, and an
    # output offset 10⁶ times its noise: the grouping, the block noise and the quantum follow
    rng = np.random.default_rng(7)
    rate, output = _twin(seed=7)
    order = rng.permutation(rate.size)
    rate = rate[order] + rng.uniform(-4e-4, 4e-4, rate.size)
    output = output[order] + 1000.0
    memory, streamed = _both(rate, output, 331, sample_rate_hz=100.0, bandwidth_hz=10.0)
    assert any("were merged into one point" in n for n in memory.notes)
    _same_result(memory, streamed)


def test_left_out_outputs_take_a_third_pass_for_the_quantum():
    rate, output = _twin(quantum=1e-3, seed=8, samples_per_point=[60_000] + [300] * 10)
    output = output.copy()
    output[[5, 17, 60_001, 60_900]] = np.nan  # the big point's stride now counts 59 998 samples
    passes = []
    source = scale_factor_chunks(rate, output, chunk_rows=50_000)

    def counted(columns):
        passes.append(tuple(columns))
        return source(columns)

    memory = calibrate_scale_factor(rate, output, nan_policy="omit", mc_trials=_TRIALS)
    streamed = calibrate_scale_factor_chunked(counted, nan_policy="omit", mc_trials=_TRIALS)
    assert len(passes) == 3 and passes[0] == ("rate_deg_s",)
    _same_result(memory, streamed)
    assert streamed.output_quantum == pytest.approx(1e-3, rel=1e-9)


@pytest.mark.parametrize(
    ("saturation", "quantum"), [((1.3, 3.7), None), ((1.3, 3.7), 0.001), ((1.2505, 3.8), None)]
)
def test_clipping_is_found_and_allowed_the_same_way(saturation, quantum):
    rate, output = _twin(saturation=saturation, quantum=quantum, seed=3, samples_per_point=2000)
    with pytest.raises(CaptureError) as memory:
        calibrate_scale_factor(rate, output, mc_trials=_TRIALS)
    with pytest.raises(CaptureError) as streamed:
        calibrate_scale_factor_chunked(scale_factor_chunks(rate, output, chunk_rows=777))
    assert str(streamed.value) == str(memory.value)
    assert "is clipped" in str(memory.value)
    _same_result(*_both(rate, output, 777, allow_clipped=True))


def test_a_flat_point_at_the_extreme_and_rest_at_the_extreme():
    # the grouped rule's two branches: a point all at the column's maximum while the others show
    # their noise (a rail); and the same level at rest (zero set rate), which is not one
    rng = np.random.default_rng(11)
    rates = np.repeat(np.arange(-50.0, 51.0, 10.0), 300)
    output = np.round(0.01 * rates + rng.normal(0.0, 2e-3, rates.size), 3)
    top = output.max() + 0.05
    output[rates == 50.0] = top
    for rest_too in (False, True):
        o = output.copy()
        if rest_too:
            o[np.flatnonzero(rates == 0.0)[:3]] = top
        try:
            memory = calibrate_scale_factor(rates, o, mc_trials=_TRIALS)
        except CaptureError as e:
            with pytest.raises(CaptureError) as streamed:
                calibrate_scale_factor_chunked(scale_factor_chunks(rates, o, chunk_rows=500))
            assert str(streamed.value) == str(e)
            assert not rest_too and "is clipped" in str(e)
        else:
            assert rest_too
            streamed = calibrate_scale_factor_chunked(
                scale_factor_chunks(rates, o, chunk_rows=500), mc_trials=_TRIALS
            )
            _same_result(memory, streamed)


def test_point_statistics_keep_their_digits_on_a_large_offset():
    # 2·10⁵ samples of 10⁸ + noise of 10⁻³ in chunks of 1000: the merged means and standard
    # deviations against exact rational arithmetic (a plain sum of squares would lose them all)
    rng = np.random.default_rng(5)
    rate = np.repeat([-10.0, 10.0], 100_000)
    output = 1e8 + 0.5 * rate + rng.normal(0.0, 1e-3, rate.size)
    r = calibrate_scale_factor_chunked(
        scale_factor_chunks(rate, output, chunk_rows=1000), mc_trials=_TRIALS
    )
    # every output lies in one binade, [2²⁶, 2²⁷): each is an integer multiple of its ulp 2⁻²⁶,
    # so Python's integers hold the values, their sum and their squares exactly (as Fractions
    # would, 20× faster)
    assert np.all((output >= 2.0**26) & (output < 2.0**27))
    for point, sel in zip(r.points, (rate < 0, rate > 0), strict=True):
        ints = [int(v) for v in (output[sel] * 2.0**26).tolist()]
        n, total = len(ints), sum(ints)
        mean = Fraction(total, n * 2**26)
        var = Fraction(n * sum(i * i for i in ints) - total * total, n * (n - 1) * 2**52)
        assert point.mean == pytest.approx(float(mean), rel=1e-15)
        assert point.std == pytest.approx(math.sqrt(var), rel=1e-9)


@pytest.mark.parametrize("chunk_rows", [1, 3, 50, 10_000])
@pytest.mark.parametrize("tol", [0.0, 1e-3, 0.5])
def test_rate_points_merged_over_chunks_are_the_single_linkage_of_the_whole(tol, chunk_rows):
    rng = np.random.default_rng(int(tol * 1000) + chunk_rows)
    rate = np.concatenate(
        [rng.choice([-20.0, -10.0, 0.0, 10.0, 20.0], 3000), rng.uniform(-30, 30, 300)]
    )
    rate = rate[rng.permutation(rate.size)]
    _, means, spread = _group(rate, tol)
    points = _RatePoints(tol)
    for s in range(0, rate.size, chunk_rows):
        points.add(rate[s : s + chunk_rows])
    np.testing.assert_array_equal(points.hi - points.lo, spread)
    assert points.rows.sum() == rate.size and points.lo.size == means.size


def _message(run):
    with pytest.raises((CaptureError, ConfigError)) as exc:
        run()
    return str(exc.value)


def test_refusals_say_the_same_as_in_memory():
    rate, out = _twin(samples_per_point=20, seed=1)
    cases = []
    o = out.copy()
    o[rate == 40.0] = np.nan
    cases.append((rate, o, {}))  # a point without samples
    o = out.copy()
    o[[3, 77]] = np.nan
    cases.append((rate, o, {}))  # non-finite outputs
    rr = rate.copy()
    rr[[5, 9]] = np.inf
    cases.append((rr, out, {}))  # non-finite set rates
    cases.append((rate, np.ones_like(out), {}))  # a flat output
    cases.append((rate, rate.copy(), {}))  # the output copies the rate
    cases.append((rate, -rate, {}))
    cases.append((np.full(10, 50.0), np.arange(10.0), {}))  # one rate
    cases.append((rate, out * 1e300, {}))  # beyond float64's working range
    cases.append((rate, out, {"sample_rate_hz": 100.0, "bandwidth_hz": 1.0}))  # blocks too long
    cases.append((rate, out, {"nan_policy": "drop"}))
    cases.append((rate[:0], out[:0], {}))
    for r, o, kw in cases:
        memory = _message(lambda r=r, o=o, kw=kw: calibrate_scale_factor(r, o, **kw))
        streamed = _message(
            lambda r=r, o=o, kw=kw: calibrate_scale_factor_chunked(
                scale_factor_chunks(r, o, chunk_rows=33), **kw
            )
        )
        assert streamed == memory


def test_a_capture_that_changes_between_passes_is_refused():
    rate, out = _twin(samples_per_point=20, seed=1)
    calls = []

    def growing(columns):
        calls.append(columns)
        n = rate.size - 20 * (len(calls) > 1)
        yield {c: {"rate_deg_s": rate, "output": out}[c][:n] for c in columns}

    with pytest.raises(CaptureError, match="changed between the passes"):
        calibrate_scale_factor_chunked(growing)
    with pytest.raises(ConfigError, match="unknown option 'mc_trails'"):
        calibrate_scale_factor_chunked(scale_factor_chunks(rate, out), mc_trails=2000)
    with pytest.raises(ConfigError, match="callable"):
        calibrate_scale_factor_chunked([rate, out])  # type: ignore[arg-type]
