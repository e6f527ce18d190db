"""Up/down counter readings: the register's wrap-around unwrapped, whole-array or in chunks.

A counter card (or a table controller) counts an encoder's edges in a register of b bits and the
DAQ logs the register. When the count passes the register's end it wraps: an unsigned register
goes 2^b − 1 → 0, a signed (two's complement) one 2^(b−1) − 1 → −2^(b−1). The true count is
recovered from the steps between successive readings taken modulo M = 2^b and folded into
[−M/2, M/2) — the same rule as phase unwrapping (Itoh 1982), on integers, so it is exact.

The rule holds only while the count moves by less than M/2 between two readings. A step whose
folded size reaches :data:`AMBIGUOUS_FRACTION`·M is refused (:class:`~rotacal.errors.CaptureError`
naming the sample): a lost stretch of samples or a glitch there could just as well be a wrap
the other way, and a wrong turn of the register is a wrong angle of 360·M/N degrees.

Register width without ``bits``: the smallest of 8, 16, 24, 32 and 64 bits whose range (signed
when any reading is negative, else unsigned) holds every reading (:func:`infer_register`). A wider
register whose counts stayed inside a narrower one's range never wraps in the record and so is
unwrapped alike; only steps of a quarter of the narrower register would be read differently, and
those are refused.

References
----------
K. Itoh (1982), Analysis of the phase unwrapping algorithm, Applied Optics 21(14):2470 (the
unwrapping rule); two's complement: IEEE Std 1754-1994 §2 (integer representation).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from rotacal.errors import CaptureError, ConfigError

__all__ = [
    "AMBIGUOUS_FRACTION",
    "REGISTER_BITS",
    "CounterUnwrapper",
    "counts_to_angle_deg",
    "infer_register",
    "unwrap_counts",
]

#: Register widths a counter may have (bits), in the order the inference tries them.
REGISTER_BITS = (8, 16, 24, 32, 64)
#: A folded step of at least this fraction of the register is ambiguous (refused).
AMBIGUOUS_FRACTION = 0.25
#: Readings unwrapped per block by :func:`unwrap_counts`.
_BLOCK = 1 << 18
#: Largest |count| a float64 column holds exactly (2^53).
_FLOAT_EXACT = float(2**53)


def _as_integers(count: np.ndarray, name: str, offset: int = 0) -> np.ndarray:
    """``count`` as int64, refusing non-finite, non-integer and (for floats) inexact values;
    unsigned 64-bit readings keep their bit pattern (two's complement view)."""
    c = np.asarray(count)
    if c.ndim != 1:
        raise CaptureError(f"column {name} must be 1-D")
    if c.dtype.kind == "u" and c.dtype.itemsize == 8:
        return c.view(np.int64)
    if c.dtype.kind in "iub":
        return c.astype(np.int64, copy=False)
    if c.dtype.kind != "f":
        raise CaptureError(f"column {name} holds {c.dtype} values, not counts")
    lo, hi = (float(np.min(c)), float(np.max(c))) if c.size else (0.0, 0.0)
    if not (np.isfinite(lo) and np.isfinite(hi)):  # NaN or inf somewhere: find it
        i = int(np.flatnonzero(~np.isfinite(c))[0])
        raise CaptureError(f"column {name} has a NaN or inf at sample {offset + i}")
    if max(abs(lo), abs(hi)) > _FLOAT_EXACT:
        i = int(np.flatnonzero(np.abs(c) > _FLOAT_EXACT)[0])
        raise CaptureError(
            f"column {name} holds {c[i]:.17g} at sample {offset + i}, beyond 2^53 where a "
            "floating-point column is no longer exact: store the counts as 64-bit integers "
            "(NPZ or HDF5)"
        )
    ci = c.astype(np.int64)
    if not np.array_equal(ci, c):
        i = int(np.flatnonzero(ci != c)[0])
        raise CaptureError(
            f"column {name} holds {c[i]!r} at sample {offset + i}: a counter's readings are whole "
            "numbers (is this an angle? then name the column angle_deg)"
        )
    return ci


def infer_register(count: np.ndarray, name: str = "count") -> tuple[int, bool]:
    """The counter's register ``(bits, signed)`` from its readings (module docstring's rule).

    Parameters
    ----------
    count : array of int or whole floats — the register's readings.
    name : the column's name, for messages.

    Returns
    -------
    (int, bool) — the smallest width of :data:`REGISTER_BITS` whose range holds every reading, and
    whether the register is signed (some reading is negative).
    """
    c = np.asarray(count)
    if c.size == 0:
        raise CaptureError(f"column {name} is empty")
    if c.dtype.kind == "u" and c.dtype.itemsize == 8:
        hi_u = int(c.max())
        return (64, False) if hi_u >= 2**63 else infer_register(c.view(np.int64), name)
    lo, hi = int(np.min(c)), int(np.max(c))
    signed = lo < 0
    for bits in REGISTER_BITS:
        low, high = _range(bits, signed)
        if low <= lo and hi <= high:
            return bits, signed
    raise CaptureError(f"column {name} spans {lo}..{hi}: wider than a 64-bit register")


def _range(bits: int, signed: bool) -> tuple[int, int]:
    """Smallest and largest reading of a register."""
    return (-(2 ** (bits - 1)), 2 ** (bits - 1) - 1) if signed else (0, 2**bits - 1)


def _check_register(bits: int, signed: bool | None) -> None:
    if bits not in REGISTER_BITS:
        valid = ", ".join(map(str, REGISTER_BITS))
        raise ConfigError(f"--counter-bits must be one of {valid}, got {bits}")
    if signed is not None and not isinstance(signed, bool):
        raise ConfigError(f"signed must be True, False or None, got {signed!r}")


@dataclasses.dataclass
class CounterUnwrapper:
    """Unwraps a counter's readings chunk by chunk with the last reading carried over.

    ``feed(chunk)`` returns the chunk's true counts (int64) — the first reading as the register
    holds it (signed registers read as two's complement), then every step folded into
    [−M/2, M/2) and summed. The concatenated output of successive calls equals
    :func:`unwrap_counts` of the whole record, for any chunking.

    Attributes
    ----------
    bits : int — register width (one of :data:`REGISTER_BITS`).
    signed : bool or None — whether the register is signed; None: signed when a reading is
        negative (decided on the first chunk; a later negative reading in an unsigned register
        is refused).
    name : str — the column's name, for messages.
    """

    bits: int
    signed: bool | None = None
    name: str = "count"
    _last_raw: int | None = dataclasses.field(default=None, init=False, repr=False)
    _last_true: int = dataclasses.field(default=0, init=False, repr=False)
    _seen: int = dataclasses.field(default=0, init=False, repr=False)

    def __post_init__(self) -> None:
        _check_register(self.bits, self.signed)

    def feed(self, chunk: np.ndarray) -> np.ndarray:
        """The true counts of the next readings (int64; see the class docstring)."""
        c = _as_integers(chunk, self.name, self._seen)
        if c.size == 0:
            return np.empty(0, dtype=np.int64)
        if self.signed is None:
            self.signed = bool(np.min(c) < 0)
        self._check_values(c)
        bits = self.bits
        prev = c[0] if self._last_raw is None else self._last_raw
        # in place, no temporaries: steps, folded into [−M/2, M/2), summed
        out = np.empty(c.size, dtype=np.int64)
        with np.errstate(over="ignore"):  # 64-bit steps wrap modulo 2^64: that is the fold
            np.subtract(c[1:], c[:-1], out=out[1:])
            out[0] = np.int64(c[0]) - np.int64(prev)
        if bits < 64:
            half = np.int64(1 << (bits - 1))
            out += half
            out &= np.int64((1 << bits) - 1)
            out -= half
        self._check_steps(out)
        start = self._first_true(int(c[0])) if self._last_raw is None else self._last_true
        np.cumsum(out, out=out)
        out += np.int64(start)
        self._last_raw = int(c[-1])
        self._last_true = int(out[-1])
        self._seen += c.size
        return out

    def _first_true(self, raw: int) -> int:
        """The first reading as a count: in a signed register, readings are two's complement."""
        if self.bits < 64 and self.signed and raw >= 2 ** (self.bits - 1):
            return raw - 2**self.bits
        return raw

    def _check_values(self, c: np.ndarray) -> None:
        if self.bits == 64:
            return
        low, high = _range(self.bits, bool(self.signed))
        if self.signed:  # a signed register logged as its unsigned bit pattern is fine too
            high = 2**self.bits - 1
        if low <= int(np.min(c)) and int(np.max(c)) <= high:  # two reductions, no mask
            return
        bad = np.flatnonzero((c < low) | (c > high))
        if bad.size:
            i = int(bad[0])
            kind = "signed" if self.signed else "unsigned"
            raise CaptureError(
                f"column {self.name} reads {int(c[i])} at sample {self._seen + i}, outside a "
                f"{self.bits}-bit {kind} register ({low}..{high}): give the right --counter-bits"
            )

    def _check_steps(self, steps: np.ndarray) -> None:
        limit = int(AMBIGUOUS_FRACTION * 2.0**self.bits)
        if self.bits == 64:
            return  # a quarter of 2^64 counts between two samples is not a motion
        if -limit < int(np.min(steps)) and int(np.max(steps)) < limit:
            return
        bad = np.flatnonzero(np.abs(steps) >= limit)
        if bad.size:
            i = int(bad[0])
            raise CaptureError(
                f"column {self.name} steps by {int(steps[i])} counts at sample {self._seen + i}, "
                f"{abs(int(steps[i])) / 2.0**self.bits:.0%} of the {self.bits}-bit register: "
                "whether the register wrapped there is ambiguous (samples lost, or a glitch); "
                "sample faster, or give the right --counter-bits"
            )


def unwrap_counts(
    count: np.ndarray, bits: int | None = None, signed: bool | None = None, *, name: str = "count"
) -> tuple[np.ndarray, int, bool]:
    """The true counts of a wrapping up/down counter (whole array).

    Parameters
    ----------
    count : array of int or whole floats — the register's readings in time order.
    bits : int, optional — register width (8, 16, 24, 32 or 64); None: :func:`infer_register`.
    signed : bool, optional — whether the register is signed (two's complement); None: signed
        when any reading is negative.
    name : the column's name, for messages.

    Returns
    -------
    (array of int64, int, bool) — the true counts (the first reading as read, then each step
    folded into [−2^(b−1), 2^(b−1)) and summed), the width used and whether it is signed.

    Raises
    ------
    CaptureError
        A reading outside the register, a non-integer or non-finite reading, or an ambiguous
        step (≥ :data:`AMBIGUOUS_FRACTION` of the register), each naming the sample.

    References
    ----------
    K. Itoh (1982), Applied Optics 21(14):2470 (unwrapping by folded differences).
    """
    if bits is None:
        bits, inferred_signed = infer_register(count, name)
        signed = inferred_signed if signed is None else signed
    c = np.asarray(count)
    u = CounterUnwrapper(int(bits), signed, name)
    if signed is None and c.size > _BLOCK:  # decided on the whole record, as documented
        u.signed = bool(np.min(c) < 0)
    out = np.empty(c.size, dtype=np.int64)
    for s in range(0, c.size, _BLOCK):  # in cache-sized blocks: no record-sized temporaries
        out[s : s + _BLOCK] = u.feed(c[s : s + _BLOCK])
    return out, u.bits, bool(u.signed)


def counts_to_angle_deg(count: np.ndarray, counts_per_rev: float) -> np.ndarray:
    """Angle (deg) of true counts: ``360·count/N`` for N counts per revolution."""
    if not (np.isfinite(counts_per_rev) and counts_per_rev > 0):
        raise ConfigError(f"--counts-per-rev must be positive, got {counts_per_rev}")
    return np.asarray(count, dtype=np.float64) * (360.0 / float(counts_per_rev))
