"""The chunked self-calibration against the in-memory one (the reference): every number of the
JSON equal to 1e-9 relative, with chunks, blocks and revolutions whose boundaries disagree, ragged
heads, and the same refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

import rotacal.encoder.selfcal_stream as stream
from rotacal.encoder import self_calibrate, self_calibrate_chunked
from rotacal.errors import CaptureError
from rotacal.sim.pulses import simulate_pulses

#: Chunk lengths per head: none divides the pulses per revolution or the blocks.
_SIZES = (97, 131, 1000, 53, 389, 64, 7)


def _chunked(heads, sizes=_SIZES):
    def make():
        return [
            [h[k : k + sizes[i % len(sizes)]] for k in range(0, h.size, sizes[i % len(sizes)])]
            for i, h in enumerate(heads)
        ]

    return make


def _leaves(d, path=""):
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _leaves(v, f"{path}/{k}")
    elif isinstance(d, list):
        for i, v in enumerate(d):
            yield from _leaves(v, f"{path}[{i}]")
    else:
        yield path, d


def _assert_same(ref, got):
    a, b = dict(_leaves(ref.to_dict())), dict(_leaves(got.to_dict()))
    assert a.keys() == b.keys()
    scale = float(np.max(np.abs(ref.deviation_arcsec)))
    for key, x in a.items():
        y = b[key]
        if isinstance(x, float) and isinstance(y, float):
            # curve points cross zero and undetectable orders are zero: 1e-9 of the curve's
            # size there, relative elsewhere
            curve = "deviation_arcsec[" in key or "harmonic_amplitudes_arcsec[" in key
            tol = 1e-9 * (scale if curve else abs(x))
            assert abs(x - y) <= tol + 1e-300, (key, x, y)
        else:
            assert x == y, (key, x, y)
    np.testing.assert_allclose(
        got.per_revolution_arcsec, ref.per_revolution_arcsec, atol=1e-9 * scale
    )


@pytest.fixture(scope="module")
def ragged():
    """5 heads on 360 lines, 7.6 revolutions; head 2 starts 40 pulses late, head 3 stops early."""
    cap = simulate_pulses(heads=5, pulses_per_rev=360, revolutions=7.6, seed=3)
    heads = [np.asarray(cap.columns[f"head_{i}"]) for i in range(5)]
    heads[2] = heads[2][40:]
    heads[3] = heads[3][:-100]
    return heads


@pytest.mark.parametrize("block", [1, 500, 1 << 18])
def test_equals_the_in_memory_result(ragged, block):
    ref = self_calibrate(ragged, pulses_per_rev=360)
    got = self_calibrate_chunked(_chunked(ragged), pulses_per_rev=360, block_pulses=block)
    assert any("head_2 starts" in n for n in got.notes)
    assert any("head_3 stops" in n for n in got.notes)
    assert ref.revolutions_used == 7 and ref.deviation_pp_arcsec > 1.0
    _assert_same(ref, got)


def test_reverse_numbering_and_forced_sense():
    cap = simulate_pulses(heads=6, pulses_per_rev=600, revolutions=4.4, seed=2)
    heads = [np.asarray(cap.columns[f"head_{i}"]) for i in range(6)]
    heads = [heads[0], *heads[1:][::-1]]
    for rotation in ("auto", "forward"):
        ref = self_calibrate(heads, pulses_per_rev=600, rotation=rotation)
        got = self_calibrate_chunked(
            _chunked(heads), pulses_per_rev=600, rotation=rotation, block_pulses=1300
        )
        _assert_same(ref, got)
    assert got.rotation == "forward" and ref.rotation == "forward"


def test_two_heads_and_one_revolution():
    cap = simulate_pulses(heads=2, pulses_per_rev=500, revolutions=1.4, seed=6)
    heads = [np.asarray(cap.columns[f"head_{i}"]) for i in range(2)]
    ref = self_calibrate(heads, pulses_per_rev=500)
    got = self_calibrate_chunked(_chunked(heads), pulses_per_rev=500)
    assert ref.revolutions_used == 1 and ref.repeatability_rms_arcsec is None
    _assert_same(ref, got)


def test_a_second_fit_when_the_record_places_a_head_on_another_line(ragged, monkeypatch):
    """The first block's line shifts are provisional: wrong ones are refitted, not kept."""
    calls = []
    real = stream._data_shifts

    def first_wrong(heads, m, rotation, mean):
        s = real(heads, m, rotation, mean)
        calls.append(rotation)
        if len(calls) <= 2:  # the provisional shifts of both senses
            s = s.copy()
            s[1] = (s[1] + 1) % m
        return s

    monkeypatch.setattr(stream, "_data_shifts", first_wrong)
    ref = self_calibrate(ragged, pulses_per_rev=360)
    got = self_calibrate_chunked(_chunked(ragged), pulses_per_rev=360, block_pulses=400)
    assert len(calls) > 4  # a second fitting pass ran
    _assert_same(ref, got)


@pytest.fixture(scope="module")
def small():
    cap = simulate_pulses(heads=6, pulses_per_rev=3000, revolutions=2.5, seed=1)
    return [np.asarray(cap.columns[f"head_{i}"]) for i in range(6)]


def _gap(h):
    h[4] = np.delete(h[4], [1000, 1001, 1002])


def _extra(h):
    t = h[0]
    h[0] = np.insert(t, 700, 0.5 * (t[699] + t[700]))


def _swap(h):
    h[1] = h[1].copy()
    h[1][[10, 11]] = h[1][[11, 10]]


def _nan(h):
    h[3] = h[3].copy()
    h[3][7] = np.nan


def _copy(h):
    h[2] = h[0] + 1e-4


def _other_scale(h):
    t = h[3]
    h[3] = np.sort(np.concatenate((t, 0.5 * (t[1:] + t[:-1]))))[: t.size]


def _short(h):
    h[5] = h[5][:1200]


@pytest.mark.parametrize(
    ("spoil", "match"),
    [
        (_gap, r"head_4.*3 pulse\(s\) missing after pulse 999"),
        (_extra, r"head_0.*extra pulse"),
        (_swap, r"head_1.*not strictly increasing at pulse 11"),
        (_nan, r"head_3.*NaN or inf at pulse 7"),
        (_copy, r"head_2' is a copy of head_0"),
        (_other_scale, r"head_3"),
        (_short, r"cover only .* less than one revolution.*head_5 stops"),
    ],
)
def test_the_same_refusals(small, spoil, match):
    heads = list(small)
    spoil(heads)
    with pytest.raises(CaptureError, match=match):
        self_calibrate(heads, pulses_per_rev=3000)
    with pytest.raises(CaptureError, match=match):
        self_calibrate_chunked(_chunked(heads), pulses_per_rev=3000)


@pytest.mark.parametrize("wrong", [6000, 1500, 3001])
def test_a_wrong_count_is_refused_alike(small, wrong):
    with pytest.raises(CaptureError, match="3000 pulses"):
        self_calibrate_chunked(_chunked(small, (4096,)), pulses_per_rev=wrong)


def test_progress_reaches_twice_the_time_stamps(ragged):
    seen = []
    self_calibrate_chunked(_chunked(ragged), pulses_per_rev=360, progress=seen.append)
    total = sum(h.size for h in ragged)
    assert seen == sorted(seen) and total <= seen[-1] <= 2 * total
    assert math.isclose(seen[-1], total + 5 * (ragged[0].size - 40 - 1), rel_tol=0.05)


@pytest.mark.parametrize("pulses", [50, 129, 130, 5000])
@pytest.mark.parametrize("size", [1, 63, 64, 1000])
def test_the_train_check_judges_every_interval_by_the_in_memory_local_period(
    monkeypatch, pulses, size
):
    """The same period at every interval, bit for bit, whatever the chunks (the refusals at
    1.5 and 0.75 periods then fall alike)."""
    from rotacal.encoder.pulse_stream import TrainCheck
    from rotacal.encoder.pulses import _local_period

    rng = np.random.default_rng(pulses + size)
    dt = (
        1e-3 * (1 + 0.2 * np.sin(np.arange(pulses - 1) / 300)) * (1 + 0.01 * rng.random(pulses - 1))
    )
    t = np.concatenate(([0.5], 0.5 + np.cumsum(dt)))
    seen = []
    monkeypatch.setattr(
        TrainCheck, "_refuse", lambda self, ratio, tt, i0: seen.append(ratio.copy())
    )
    check = TrainCheck("head_0")
    for k in range(0, t.size, size):
        check.feed(t[k : k + size])
    check.finish()
    expected = np.diff(t) / _local_period(np.diff(t))
    np.testing.assert_array_equal(np.concatenate(seen), expected)


def test_block_medians_are_numpys_medians_bit_for_bit():
    from rotacal.encoder.pulses import block_medians

    rng = np.random.default_rng(5)
    for scale in (1e-6, 1.0, 1e3):
        x = scale * rng.random(64 * 40) + 1e-3 * rng.integers(0, 3, 64 * 40)  # ties too
        np.testing.assert_array_equal(block_medians(x), np.median(x.reshape(-1, 64), axis=1))
