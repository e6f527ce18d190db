"""Counter unwrap: every register width, signed and unsigned, chunked = whole, refusals, real data."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from rotacal.errors import CaptureError, ConfigError
from rotacal.signal.counter import (
    REGISTER_BITS,
    CounterUnwrapper,
    counts_to_angle_deg,
    infer_register,
    unwrap_counts,
)


def _walk(bits: int, n: int = 20_000, seed: int = 0) -> np.ndarray:
    """A true count that sweeps through several register lengths (for b ≤ 16) and back, its
    steps below a tenth of the register; independent of the method: integer random walk."""
    rng = np.random.default_rng(seed)
    top = min(2 ** (bits - 4), 5_000)
    steps = rng.integers(-top // 3, top + 1, n)
    steps[n // 2 :] *= -1  # turn back: wraps in both directions
    return np.cumsum(steps).astype(np.int64) + 123


def _register(true: np.ndarray, bits: int, signed: bool) -> np.ndarray:
    if bits == 64:
        return true
    m = 1 << bits
    return ((true + m // 2) % m - m // 2) if signed else true % m


@pytest.mark.parametrize("bits", REGISTER_BITS)
@pytest.mark.parametrize("signed", [False, True])
def test_wrap_at_every_width(bits, signed):
    true = _walk(bits, seed=bits)
    reg = _register(true, bits, signed)
    if bits <= 16:
        assert np.count_nonzero(np.diff(reg) != np.diff(true)) > 10  # the record does wrap
    out, used_bits, used_signed = unwrap_counts(reg, bits, signed)
    assert used_bits == bits and used_signed == signed
    np.testing.assert_array_equal(out - out[0], true - true[0])
    # streamed in uneven chunks with the last reading carried: identical
    u = CounterUnwrapper(bits, signed)
    cuts = [0, 1, 7, 4_000, 4_001, 13_333, true.size]
    chunked = np.concatenate([u.feed(reg[a:b]) for a, b in itertools.pairwise(cuts)])
    np.testing.assert_array_equal(chunked, out)


def test_a_signed_register_logged_as_its_bit_pattern_and_as_floats():
    true = _walk(16)
    pattern = true % 65536  # what a logger that reads the register as unsigned writes
    out, _, _ = unwrap_counts(pattern.astype(np.float64), 16, True)
    np.testing.assert_array_equal(out - out[0], true - true[0])


def test_unsigned_64_bit_bit_patterns_wrap_too():
    true = np.arange(-50, 50, dtype=np.int64) * 7 + (2**63 - 200)  # passes 2^63 - 1
    reg = (true.astype(object) % 2**64).astype(np.uint64)  # an unsigned 64-bit register
    out, bits, signed = unwrap_counts(reg)
    assert (bits, signed) == (64, False)
    np.testing.assert_array_equal(np.diff(out), np.full(99, 7))


def test_register_inference_rule():
    assert infer_register(np.array([0, 200])) == (8, False)
    assert infer_register(np.array([0, 256])) == (16, False)
    assert infer_register(np.array([-1, 100])) == (8, True)
    assert infer_register(np.array([-129, 0])) == (16, True)
    assert infer_register(np.array([0, 2**24 - 1])) == (24, False)
    assert infer_register(np.array([0, 2**24])) == (32, False)
    assert infer_register(np.array([-(2**40), 0])) == (64, True)


def test_refusals_name_the_sample():
    with pytest.raises(CaptureError, match=r"sample 3.*ambiguous"):
        unwrap_counts(np.array([0, 10, 20, 90, 100]), 8, False)  # a step of 70 of 256
    with pytest.raises(CaptureError, match=r"sample 2.*whole numbers"):
        unwrap_counts(np.array([0.0, 1.0, 1.5]), 16)
    with pytest.raises(CaptureError, match="NaN or inf at sample 1"):
        unwrap_counts(np.array([0.0, np.nan]), 16)
    with pytest.raises(CaptureError, match="outside a 8-bit unsigned register"):
        unwrap_counts(np.array([0, 300]), 8, False)
    with pytest.raises(CaptureError, match="beyond 2\\^53"):
        unwrap_counts(np.array([0.0, 2.0**60]), 64)
    with pytest.raises(ConfigError, match="--counter-bits"):
        unwrap_counts(np.array([0, 1]), 12)
    with pytest.raises(ConfigError, match="--counts-per-rev"):
        counts_to_angle_deg(np.array([1]), 0)


def test_real_sample_counter_wrapped_into_16_bits(shared_data):
    """xinli's logger counts +10 per sample (README); m30_3turn's counter passes 6·65536, so a
    16-bit register wraps there (and an 8-bit one every 26 samples): the unwrap gives the logged
    counter back exactly."""
    path = shared_data("xinli_turntable", "data", "m30_3turn.dat")
    counter = np.loadtxt(path, usecols=1).astype(np.int64)
    assert infer_register(counter) == (24, False)
    for bits in (8, 16):
        wrapped = counter % (1 << bits)
        assert np.count_nonzero(np.diff(wrapped) < 0) >= 1
        out, _, _ = unwrap_counts(wrapped, bits, False)
        np.testing.assert_array_equal(out - out[0], counter - counter[0])
