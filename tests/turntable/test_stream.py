"""The Monte Carlo's counter-based stream (rotacal.turntable.stream, _mc_jit) against truth.

- the compiled Philox4x64-10 words equal NumPy's own ``Philox`` (an independent implementation);
- sin and cos of a turn equal the long-double values to 2.3e-16, and the compiled twin gives the
  NumPy one's bits;
- the fused compiled Monte Carlo equals the NumPy twin (ROTACAL_NUMBA=0) to the last bit on
  chains that exercise every branch of the recursion, on 1, 2 and 3 threads and any chunk size;
- its statistics are those of the PCG64 stream it replaces (a χ² homogeneity test of the
  histograms, the quantiles within each other's coverage intervals) and within the worst case;
- the PCG64 stream still gives the numbers of earlier versions.
"""

from __future__ import annotations

import dataclasses
import math
import types

import numpy as np
import pytest
from scipy.stats import chi2_contingency

from rotacal.errors import ConfigError
from rotacal.turntable import _mc_jit
from rotacal.turntable.allocation import allocate, monte_carlo_check, worst_case
from rotacal.turntable.config import load_turntable, seed_table_toml
from rotacal.turntable.draws import TopValues
from rotacal.turntable.model import Turntable, seed_table
from rotacal.turntable.seed001 import EQ16_DEG
from rotacal.turntable.stream import philox_key, turn_sin_cos


@pytest.fixture(scope="module")
def seed() -> Turntable:
    return seed_table()


@pytest.fixture(scope="module")
def alloc(seed: Turntable):
    return allocate(seed, math.radians(EQ16_DEG))


def _result(res) -> dict:
    out = res.to_dict()
    out.pop("draws_per_second")
    return out


@pytest.mark.parametrize("seed_value", [0, 2026, 2**63 + 5])
def test_compiled_philox_words_are_numpys(seed_value: int) -> None:
    key = philox_key(seed_value)
    reference = np.random.Philox(seed_value).random_raw(4 * 1_300)
    for first_block, n_blocks in ((0, 5), (1_037, 263)):  # from the start, and from within
        words = np.empty(4 * n_blocks, dtype=np.uint64)
        _mc_jit.philox_words(key, first_block, words, np.empty((4, n_blocks), dtype=np.uint64))
        expected = reference[4 * first_block : 4 * (first_block + n_blocks)]
        np.testing.assert_array_equal(words, expected)
    # and NumPy's doubles are (x >> 11)·2⁻⁵³ of those words
    doubles = np.random.Generator(np.random.Philox(seed_value)).random(8)
    np.testing.assert_array_equal(doubles, (reference[:8] >> np.uint64(11)) * 2.0**-53)


def test_sin_cos_of_a_turn_to_the_long_double_values() -> None:
    rng = np.random.default_rng(3)
    eighths = np.arange(9) / 8.0
    edges = np.concatenate([eighths, np.nextafter(eighths, 2.0), np.nextafter(eighths, -1.0)])
    u = np.concatenate([rng.random(200_000), edges[(edges >= 0) & (edges < 1)]])
    sin, cos = turn_sin_cos(u)
    angle = u.astype(np.longdouble) * np.longdouble("6.28318530717958647692528676655900577")
    assert np.max(np.abs(sin - np.sin(angle))) <= 2.3e-16
    assert np.max(np.abs(cos - np.cos(angle))) <= 2.3e-16
    assert turn_sin_cos(np.array([0.0]))[0][0] == 0.0 and turn_sin_cos(np.array([0.25]))[0][0] == 1
    sin_c, cos_c = np.empty_like(u), np.empty_like(u)
    _mc_jit.turn_sin_cos(u, sin_c, cos_c)
    np.testing.assert_array_equal(sin_c, sin)
    np.testing.assert_array_equal(cos_c, cos)


@pytest.mark.parametrize("signs", ["random", "positive"])
def test_same_numbers_on_any_thread_count_and_chunk(seed, alloc, signs, monkeypatch) -> None:
    over = {n: (None if v is None else 1.03 * v) for n, v in alloc.upper_bounds_rad.items()}
    over_alloc = dataclasses.replace(alloc, upper_bounds_rad=over)
    monkeypatch.setenv("ROTACAL_NUMBA", "1")
    calls: list[int] = []
    runs = 120_000
    a = monte_carlo_check(seed, over_alloc, runs=runs, seed=4, signs=signs, chunk=runs)
    b = monte_carlo_check(
        seed, over_alloc, runs=runs, seed=4, signs=signs, chunk=9_999, threads=3,
        progress=lambda done, total: calls.append(done),
    )  # fmt: skip
    monkeypatch.setenv("ROTACAL_NUMBA", "0")
    c = monte_carlo_check(seed, over_alloc, runs=runs, seed=4, signs=signs, chunk=50_000)
    assert _result(a) == _result(b) == _result(c)
    assert calls[-1] == runs and len(calls) == math.ceil(runs / 9_999)
    assert a.quantile_abs_rad is not None and a.stream == "philox"
    assert signs == "positive" or a.outside > 0


def test_new_stream_has_the_old_streams_statistics(seed, alloc, monkeypatch) -> None:
    """Same distribution: the histograms pass a χ² homogeneity test, each stream's 99.9 %
    quantile lies in the other's 95 % interval (widened by its own), and no draw of either
    exceeds the full model's worst case."""
    monkeypatch.setenv("ROTACAL_NUMBA", "1")
    runs = 250_000
    new = monte_carlo_check(seed, alloc, runs=runs, seed=21)
    old = monte_carlo_check(seed, alloc, runs=runs, seed=21, stream="pcg64")
    assert old.stream == "pcg64" and new.max_abs_rad != old.max_abs_rad  # other draws
    wc = worst_case(
        seed, alloc.upper_bounds_rad, alloc.requirement_rad, lower_bounds=alloc.lower_bounds_rad
    )
    for c in ("psi", "theta", "gamma"):
        counts = np.array([new.histograms[c]["counts"], old.histograms[c]["counts"]])
        counts = counts[:, counts.sum(axis=0) > 0]
        assert chi2_contingency(counts).pvalue > 1e-3, c
        assert new.quantile_abs_rad is not None and old.quantile_abs_rad is not None
        q_new, lo_new, hi_new = new.quantile_abs_rad[c]
        q_old, lo_old, hi_old = old.quantile_abs_rad[c]
        assert lo_old - (hi_new - lo_new) <= q_new <= hi_old + (hi_new - lo_new), c
        assert lo_new - (hi_old - lo_old) <= q_old <= hi_new + (hi_old - lo_old), c
        for res in (new, old):
            assert res.max_abs_rad[c] <= wc[c]["full_rad"] * (1 + 1e-12)
    # a wrong law would fail the χ² test: the histogram of θ with positive signs only
    positive = monte_carlo_check(seed, alloc, runs=runs, seed=21, signs="positive")
    counts = np.array([positive.histograms["theta"]["counts"], old.histograms["theta"]["counts"]])
    counts = counts[:, counts.sum(axis=0) > 0]
    assert chi2_contingency(counts).pvalue < 1e-6


def test_pcg64_stream_gives_the_numbers_of_earlier_versions(seed, monkeypatch) -> None:
    """rotacal before the Philox stream gave these for 20 000 draws of seed 3 (both paths)."""
    names = seed.angular_error_names
    bounds = types.SimpleNamespace(
        upper_bounds_rad={n: 1e-4 * (1 + i) for i, n in enumerate(names)},
        lower_bounds_rad=dict.fromkeys(names, 2e-5),
        requirement_rad=dict.fromkeys(("psi", "theta", "gamma"), 5e-4),
    )
    for flag in ("0", "1"):
        monkeypatch.setenv("ROTACAL_NUMBA", flag)
        res = monte_carlo_check(seed, bounds, runs=20_000, seed=3, stream="pcg64")
        assert res.max_abs_rad == {
            "psi": 0.0017519088903007506,
            "theta": 0.000592197750270303,
            "gamma": 0.001575587729747811,
        }
        assert res.outside == 13216
        assert res.histograms["psi"]["counts"][:12] == [
            151, 161, 164, 182, 164, 188, 159, 170, 151, 170, 198, 180
        ]  # fmt: skip
        assert res.quantile_abs_rad is not None
        assert res.quantile_abs_rad["theta"] == (
            0.0005826306556644027,
            0.0005804070710843435,
            0.0005857410413873699,
        )


@pytest.mark.parametrize(
    ("kwargs", "fragment"),
    [
        ({"stream": "mt19937"}, "stream must be 'philox' or 'pcg64', got 'mt19937'"),
        ({"threads": 0}, "threads must be an integer ≥ 1, got 0"),
        ({"threads": 1.0}, "threads must be an integer ≥ 1, got 1.0"),
    ],
)
def test_stream_and_threads_are_checked(seed, alloc, kwargs, fragment) -> None:
    with pytest.raises(ConfigError, match=fragment):
        monte_carlo_check(seed, alloc, runs=10, **kwargs)


def test_top_values_from_candidates_equal_those_from_chunks() -> None:
    rng = np.random.default_rng(8)
    chunks = [rng.random((n, 3)) for n in (50, 700, 1, 400)]
    whole, parts = TopValues(120, 3), TopValues(120, 3)
    assert np.all(parts.floor() == -np.inf) and np.all(TopValues(0, 3).floor() == np.inf)
    for chunk in chunks:
        whole.add(chunk)
        floor = parts.floor()
        parts.add_columns([chunk[:, j][chunk[:, j] > floor[j]] for j in range(3)])
    np.testing.assert_array_equal(np.sort(whole.values, axis=0), np.sort(parts.values, axis=0))
    every = np.concatenate(chunks)
    np.testing.assert_array_equal(np.sort(parts.values, axis=0), np.sort(every, axis=0)[-120:])


def test_config_chooses_the_stream() -> None:
    text = seed_table_toml().replace('signs = "random"', 'signs = "random"\nstream = "pcg64"')
    assert load_turntable(text).settings["monte_carlo"]["stream"] == "pcg64"
    assert "stream" not in seed_table().settings["monte_carlo"]  # the default: philox
