"""Numba twin of :func:`rotacal.signal.clipping.find_quadrature_clipping`'s pass over the samples
(private; imports Numba).

Imported only for long captures (:func:`rotacal._jit.use_numba`), compiled on first use and cached
on disk. The NumPy detector reads each piece of a channel in several passes (its range, the
samples at each extreme, the next value inward, the runs of equal samples) and makes boolean and
index arrays for them; this kernel reads both channels once, block by block: one vectorised loop
gives each block's extremes of both channels (by integer order keys, which also show a value that
is not finite) and how many samples repeat their predecessor, and only the rare blocks that can
change an extreme's state (their extreme reaches the next value inward) or that hold a run are
scanned sample by sample. The state it leaves is the one
:class:`~rotacal.signal.clipping.RailDetector` reaches on the same column (the same extremes,
counts, first rows, companion spans and runs: see that class for why they do not depend on where
pieces are cut), so the verdicts and messages are the same. (Differences no verdict sees: a
run of a single sample counts 0 here, 1 there, and every rule reads a run as at least 1; an
extreme at zero where the block holds both −0 and +0 is +0 here, either one there.)
Measured on 10⁷ samples of both channels: ~6.5 ms CPU against ~13.5 ms for the NumPy detectors.
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Samples per block (both channels' blocks stay in the L1 cache between the loops).
_BLOCK = 2048
#: All bits of a float64 but its sign (the order keys of :func:`_block_summary`).
_MASK = np.int64(0x7FFFFFFFFFFFFFFF)
#: Columns of a side's state: value, count, first row, next value, next count, companion's
#: low and high over the rows at the extreme, longest run at it (values as sign·x).
SIDE_FIELDS = 8
#: Columns of a channel's state after its two sides: longest run elsewhere, the open run's value
#: and length.
ELSEWHERE, OPEN_VALUE, OPEN_LEN = 2 * SIDE_FIELDS, 2 * SIDE_FIELDS + 1, 2 * SIDE_FIELDS + 2
STATE_FIELDS = 2 * SIDE_FIELDS + 3


@njit(cache=True, nogil=True)
def _block_summary(
    ia: np.ndarray, ib: np.ndarray, a: np.ndarray, b: np.ndarray, keys: np.ndarray
) -> tuple:  # pragma: no cover - compiled
    """One block of both channels (views) in one vectorised loop: the order keys of their
    extremes into ``keys`` (low and high of a, of b) and how many samples of a and of b equal
    the one before them.

    ``ia``, ``ib`` are the blocks' bits as int64. A float's bits ``v`` become the integer key
    ``v ^ ((v >> 63) & 0x7FF…F)``, which orders finite values as floats do, −0 just below +0,
    ±inf beyond them and NaN beyond ±inf: an integer min/max (which the compiler vectorises;
    a floating-point one it does not) finds the extremes, and a non-finite value shows as a
    non-finite extreme.
    """
    v = ia[0]
    lo_a = hi_a = v ^ ((v >> 63) & _MASK)
    v = ib[0]
    lo_b = hi_b = v ^ ((v >> 63) & _MASK)
    rep_a = 0
    rep_b = 0
    for i in range(1, ia.size):
        v = ia[i]
        key = v ^ ((v >> 63) & _MASK)
        lo_a = min(lo_a, key)
        hi_a = max(hi_a, key)
        v = ib[i]
        key = v ^ ((v >> 63) & _MASK)
        lo_b = min(lo_b, key)
        hi_b = max(hi_b, key)
        rep_a += a[i] == a[i - 1]
        rep_b += b[i] == b[i - 1]
    for j, key in enumerate((lo_a, hi_a, lo_b, hi_b)):
        keys[j] = key ^ ((key >> 63) & _MASK)  # the key's own inverse: the float's bits
    return rep_a, rep_b


@njit(cache=True, nogil=True)
def _side_block(
    x: np.ndarray, c: np.ndarray, s: int, e: int, sign: float, top: float, st: np.ndarray, o: int
) -> None:  # pragma: no cover - compiled
    """One block's extreme ``top`` (as sign·x) folded into the side at column ``o``: its count,
    first row, the next value inward with its count and the companion's span at it, merged as
    :meth:`rotacal.signal.clipping._Side.merge` merges a piece's (a run at an extreme that is
    passed counts elsewhere)."""
    if top < st[o + 3]:
        return  # below both of the two largest values so far: nothing to add
    k = 0
    first = -1
    second = -np.inf
    k2 = 0
    c_lo = np.inf
    c_hi = -np.inf
    for i in range(s, e):
        w = sign * x[i]
        if w == top:
            k += 1
            if first < 0:
                first = i
            c_lo = min(c_lo, c[i])
            c_hi = max(c_hi, c[i])
        elif w > second:
            second = w
            k2 = 1
        elif w == second:
            k2 += 1
    value = st[o]
    if top > value:
        if second > value:
            st[o + 3] = second
            st[o + 4] = k2
        elif second == value:
            st[o + 3] = second
            st[o + 4] = k2 + st[o + 1]
        else:
            st[o + 3] = value
            st[o + 4] = st[o + 1]
        st[ELSEWHERE] = max(st[ELSEWHERE], st[o + 7])
        st[o + 7] = 0.0
        st[o] = top
        st[o + 1] = k
        st[o + 2] = first
        st[o + 5] = c_lo
        st[o + 6] = c_hi
    elif top == value:
        st[o + 1] += k
        st[o + 5] = min(st[o + 5], c_lo)
        st[o + 6] = max(st[o + 6], c_hi)
        if second > st[o + 3]:
            st[o + 3] = second
            st[o + 4] = k2
        elif second == st[o + 3]:
            st[o + 4] += k2
    elif top > st[o + 3]:
        st[o + 3] = top
        st[o + 4] = k
    elif top == st[o + 3]:
        st[o + 4] += k


@njit(cache=True, nogil=True)
def _runs_block(
    x: np.ndarray, s: int, e: int, repeats: bool, st: np.ndarray
) -> None:  # pragma: no cover - compiled
    """The block's runs of equal samples: a run closes (and counts when ≥ 2 long) where the value
    changes; the last one stays open for the next block."""

    def classify(value: float, length: float) -> None:
        # a closed run of ≥ 2 samples: at an extreme, or elsewhere
        at_hi = value == st[0]
        at_lo = value == -st[SIDE_FIELDS]
        if at_hi:
            st[7] = max(st[7], length)
        if at_lo:
            st[SIDE_FIELDS + 7] = max(st[SIDE_FIELDS + 7], length)
        if not (at_hi or at_lo):
            st[ELSEWHERE] = max(st[ELSEWHERE], length)

    value = st[OPEN_VALUE]
    length = st[OPEN_LEN]
    if not repeats and not (length > 0 and x[s] == value):
        if length > 1:  # no run inside the block nor across its start: only the open one closes
            classify(value, length)
        st[OPEN_VALUE] = x[e - 1]
        st[OPEN_LEN] = 1.0
        return
    for i in range(s, e):
        v = x[i]
        if length > 0 and v == value:
            length += 1
        else:
            if length > 1:
                classify(value, length)
            value = v
            length = 1.0
    st[OPEN_VALUE] = value
    st[OPEN_LEN] = length


@njit(cache=True, nogil=True)
def quadrature_rails(
    a: np.ndarray, b: np.ndarray, st: np.ndarray, ranges: np.ndarray
) -> bool:  # pragma: no cover - compiled
    """Both channels' rail state into ``st`` (2 × :data:`STATE_FIELDS`, row 0 for ``a`` with
    ``b`` as its companion, row 1 the other way round) and their ranges into ``ranges`` (low
    and high of a, of b; start at (inf, −inf)); False (the state left incomplete) as soon as a
    value is not finite — the NumPy detector then judges the columns.

    ``st`` must come initialised: each side's value and next value −inf, counts 0, first −1,
    companion span (inf, −inf), runs 0; the open run's length 0.
    """
    n = a.size
    ia = a.view(np.int64)
    ib = b.view(np.int64)
    bits = np.empty(4, dtype=np.int64)
    extremes = bits.view(np.float64)
    for s in range(0, n, _BLOCK):
        e = min(n, s + _BLOCK)
        rep_a, rep_b = _block_summary(ia[s:e], ib[s:e], a[s:e], b[s:e], bits)
        lo_a, hi_a, lo_b, hi_b = extremes[0], extremes[1], extremes[2], extremes[3]
        if not (
            np.isfinite(lo_a) and np.isfinite(hi_a) and np.isfinite(lo_b) and np.isfinite(hi_b)
        ):
            return False
        for ch in range(2):
            x = a if ch == 0 else b
            c = b if ch == 0 else a
            row = st[ch]
            lo = lo_a if ch == 0 else lo_b
            hi = hi_a if ch == 0 else hi_b
            _side_block(x, c, s, e, 1.0, hi, row, 0)
            _side_block(x, c, s, e, -1.0, -lo, row, SIDE_FIELDS)
            repeats = (rep_a if ch == 0 else rep_b) > 0
            _runs_block(x, s, e, repeats, row)
        ranges[0] = min(ranges[0], lo_a)
        ranges[1] = max(ranges[1], hi_a)
        ranges[2] = min(ranges[2], lo_b)
        ranges[3] = max(ranges[3], hi_b)
    return True
