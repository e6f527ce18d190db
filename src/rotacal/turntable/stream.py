"""The Monte Carlo's random draws as a counter-based stream, and the sine and cosine of a turn.

The Monte Carlo check (:func:`rotacal.turntable.montecarlo.monte_carlo_check`) draws one row of
``width`` uniforms per table (errors first, then angles). With the ``"philox"`` stream they are the
doubles of ``numpy.random.Generator(numpy.random.Philox(seed))``: NumPy's Philox4x64-10 keyed by
``SeedSequence(seed)``, the uint64 number s of the stream the output of block ⌊s/4⌋ (counter
⌊s/4⌋ + 1, as NumPy increments before it generates), word s mod 4, and the uniform
``(x >> 11)·2⁻⁵³``. Draw n takes numbers n·width … n·width + width − 1. Any draw's numbers can be
computed without the ones before (Salmon et al. 2011: a counter-based generator), so the compiled
path (:mod:`rotacal.turntable._mc_jit`) makes them block by block, on any number of threads, and
gets the numbers the NumPy path reads from NumPy's own generator: the result depends on the seed
only, not on chunk size, block size or thread count.

An angle φ = 2π·u uniform on [0, 2π) enters the model through cos φ and sin φ only.
:func:`turn_sin_cos` computes them from u without the C library: t = 4u and q = ⌊t + ½⌋ are
exact, so is f = t − q ∈ [−½, ½], and φ = (π/2)(q + f); sin and cos of x = (π/2)·f ∈ [−π/4, π/4]
come from their Taylor series (through x¹⁷ and x¹⁶: the first term left out is below 8.3·10⁻²⁰ and
2.0·10⁻¹⁸ for |x| ≤ π/4, far below half an ulp of the result, 5.6·10⁻¹⁷ near 1), and the quadrant
q mod 4 swaps them and sets their signs. The error is that of the rounding of x and of the
Horner sums: the tests find it within 2.3·10⁻¹⁶ of the exact sine and cosine of 2π·u (long
double reference). The compiled twin does the same operations in the same order (no fused
multiply-add), so both give the same bits.

References
----------
Salmon J. K., Moraes M. A., Dror R. O., Shaw D. E. (2011), "Parallel random numbers: as easy as
1, 2, 3", Proc. SC11, §3 (Philox4x64-10); NumPy ``numpy.random.Philox``; Abramowitz & Stegun
(1964) 4.3.65–4.3.66 (the Taylor series of sin and cos).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["STREAMS", "philox_key", "turn_sin_cos"]

#: The Monte Carlo's streams: ``"philox"`` (counter-based, the default) and ``"pcg64"`` (the
#: sequential ``Generator(PCG64(seed))`` of rotacal before it, kept to reproduce earlier results).
STREAMS = ("philox", "pcg64")

_HALF_PI = 0.5 * math.pi
#: Taylor coefficients (−1)^k/(2k+1)! of sin x for k = 1…8 and (−1)^k/(2k)! of cos x for k = 2…8.
_SIN = tuple((-1.0) ** k / math.factorial(2 * k + 1) for k in range(1, 9))
_COS = tuple((-1.0) ** k / math.factorial(2 * k) for k in range(2, 9))


def philox_key(seed: int) -> np.ndarray:
    """The two 64-bit words of the Philox key that ``numpy.random.Philox(seed)`` derives from
    ``SeedSequence(seed)`` (seed an integer ≥ 0): what the compiled stream is keyed with."""
    state = np.random.Philox(seed).state["state"]
    return np.asarray(state["key"], dtype=np.uint64).copy()


def turn_sin_cos(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """sin(2π·u) and cos(2π·u) of uniforms u ∈ [0, 1) (dimensionless; the angle is in rad).

    Exact reduction to x = (π/2)·f, |x| ≤ π/4, Taylor series of sin x (through x¹⁷) and cos x
    (through x¹⁶) by Horner's rule, then the quadrant (module docstring). Element-wise; the
    operations of the compiled twin ``rotacal.turntable._mc_jit.turn_sin_cos`` in its order.

    Parameters
    ----------
    u : ndarray
        Fractions of a turn in [0, 1).

    Returns
    -------
    (sin, cos) : ndarrays
        Of the angle 2π·u rad, within 2.3·10⁻¹⁶ of the exact values.
    """
    t = 4.0 * np.asarray(u, dtype=float)
    q = np.floor(t + 0.5)
    x = (t - q) * _HALF_PI
    x2 = x * x
    ps: np.ndarray | float = _SIN[7]
    for coefficient in _SIN[6::-1]:
        ps = coefficient + x2 * ps
    pc: np.ndarray | float = _COS[6]
    for coefficient in _COS[5::-1]:
        pc = coefficient + x2 * pc
    s = x + x * (x2 * ps)
    c = (1.0 - 0.5 * x2) + (x2 * x2) * pc
    quadrant = q.astype(np.int64) & 3
    swap = (quadrant & 1) == 1
    sin_sign = 1.0 - 2.0 * ((quadrant >> 1) & 1)
    cos_sign = 1.0 - 2.0 * (((quadrant + 1) >> 1) & 1)
    return sin_sign * np.where(swap, c, s), cos_sign * np.where(swap, s, c)
