"""The phase a stability deviation is computed from: the rate's integral (or the phase given)
with what the deviation cannot see removed, so that its differences lose no digits.

Every deviation of the Allan family is a sum of squared differences of the phase that annihilate
a straight line (the Hadamard's third differences annihilate a parabola too). Removing such a
component changes no deviation in exact arithmetic; in floating point it keeps the phase's
magnitude — and with it the rounding of every stored value, |x|·2⁻⁵³ — at the size of the noise.
That matters most for a rate ramp: its phase is a parabola that reaches R·N²/2 (5·10⁹ °·samples
for a 100 °/s ramp over 10⁸ samples, i.e. 5·10⁻⁷ of rounding on each value).
"""

from __future__ import annotations

import numpy as np

__all__ = ["RUNNING_SUM_BLOCK", "phase_record", "running_sum"]

#: Block of :func:`running_sum` (samples): a running sum restarts at each.
RUNNING_SUM_BLOCK = 4096


def running_sum(values: np.ndarray, start: float = 0.0) -> np.ndarray:
    """Replace ``values`` (1-D, float64, contiguous) in place by ``start`` plus its running sum,
    and return it.

    In blocks of :data:`RUNNING_SUM_BLOCK`: a running sum within each block, the blocks' totals
    summed in long double and added to each block. One running sum over the record rounds each
    addition at the size of the sum so far — errors that pile up systematically along a ramp's
    parabola (9e-10 of an ADEV and 1.9e-9 of an HDEV at 10⁸ samples of a 100 °/s ramp); here
    each value is off by at most
    u·(b·block Σ|v| + |value|) (u = ε/2, b the block; in practice about ε·(block Σ|v| +
    |value|), 100× less than one running sum's drift on a ramp: tested), at 1.3× the cost of
    ``np.cumsum``.
    """
    if values.ndim != 1 or not values.flags.c_contiguous:  # reshape would copy: nothing written
        raise ValueError("running_sum needs a contiguous 1-D array")
    b = RUNNING_SUM_BLOCK
    full = values.size // b
    blocks = values[: full * b].reshape(full, b)
    rest = values[full * b :]
    totals = np.empty(full + (rest.size > 0))
    totals[:full] = blocks.sum(axis=1)
    if rest.size:
        totals[-1] = rest.sum()
    offsets = np.empty(totals.size, dtype=np.longdouble)
    offsets[0] = 0.0
    np.cumsum(totals[:-1].astype(np.longdouble), out=offsets[1:])
    offsets += start
    starts = offsets.astype(np.float64)
    np.cumsum(blocks, axis=1, out=blocks)
    blocks += starts[:full, None]
    if rest.size:
        np.cumsum(rest, out=rest)
        rest += starts[-1]
    return values


def _centred_index(n: int) -> np.ndarray:
    """k − (n − 1)/2 for k = 0 … n − 1: orthogonal to a constant (and k² to k)."""
    k = np.arange(n, dtype=np.float64)
    k -= 0.5 * (n - 1)
    return k


def _subtract_line(values: np.ndarray) -> np.ndarray:
    """Subtract from ``values``, in place, its least-squares straight line over the sample index
    (its mean and its slope), and return it."""
    k = _centred_index(values.size)
    slope = float(np.einsum("i,i->", k, values)) / float(np.einsum("i,i->", k, k))
    values -= float(np.mean(values))
    k *= slope
    values -= k
    return values


def phase_record(
    y: np.ndarray, fs: float, data_type: str, *, ramp_blind: bool = False
) -> np.ndarray:
    """The phase (in the rate's unit × s) of a rate or phase record, less what the deviation
    cannot see.

    Parameters
    ----------
    y : ndarray — the record, 1-D: a rate (u) or a phase (u·s).
    fs : float — sampling rate (Hz).
    data_type : "rate" (the phase is its running integral, x_0 = 0, N + 1 points) or "phase".
    ramp_blind : bool — the deviation annihilates a parabola in the phase (the Hadamard, NIST
        SP 1065 eq. (18)): the best straight line of the rate (a phase record's first
        differences) is removed before it is integrated.

    Returns
    -------
    ndarray — the phase with its best straight line removed (and, if ``ramp_blind``, a parabola:
    the one of the rate's best line).
    """
    if data_type == "phase" and not ramp_blind:
        x = y - float(np.mean(y))
    else:
        # a phase record's parabola is its first differences' ramp: the difference of two
        # neighbours within a factor of two is exact (Sterbenz's lemma), and the ramp is then
        # removed at the differences' own size, not at the parabola's
        x = np.empty(y.size + (data_type == "rate"))
        x[0] = 0.0
        rate = x[1:]  # integrated in place: x_i = Σ_{k<i} rate_k
        if data_type == "phase":
            np.subtract(y[1:], y[:-1], out=rate)
        else:
            rate[:] = y
        if ramp_blind:
            _subtract_line(rate)
        else:
            rate -= float(np.mean(rate))
        running_sum(rate)
        if data_type == "rate":
            x /= fs
    return _subtract_line(x)
