"""Brent's root finder, step for step as SciPy's ``brentq`` (private).

``scipy.optimize`` takes ~0.15 s to import (with scipy.sparse and scipy.linalg), which the budget
of every sinusoidal-motion calibration paid for four root searches. This is the same algorithm
as SciPy's C ``brentq`` (``scipy/optimize/Zeros/brentq.c``, C. Harris), the same operations in the
same order, so the roots are the same to the last bit (a test compares the two on many
functions). Reference: R. P. Brent, *Algorithms for Minimization without Derivatives* (1973),
ch. 4.
"""

from __future__ import annotations

import math
from collections.abc import Callable

#: SciPy's defaults: at most 100 iterations, rtol no finer than 4·eps.
MAX_ITER = 100
MIN_RTOL = 4.0 * 2.220446049250313e-16


def brentq(
    f: Callable[[float], float],
    a: float,
    b: float,
    xtol: float = 2e-12,
    rtol: float = MIN_RTOL,
    maxiter: int = MAX_ITER,
) -> float:
    """A root of ``f`` in [a, b] (``f(a)`` and ``f(b)`` of opposite signs), to within
    ``xtol + rtol·|x|`` (units of x). Raises ValueError for a bracket without a sign change
    or bad tolerances, RuntimeError when ``maxiter`` iterations do not converge (as SciPy)."""
    if not xtol > 0:
        raise ValueError(f"xtol too small ({xtol:g} <= 0)")
    if not rtol >= MIN_RTOL:
        raise ValueError(f"rtol too small ({rtol:g} < {MIN_RTOL:g})")
    xpre, xcur = float(a), float(b)
    xblk = fblk = spre = scur = 0.0
    fpre = float(f(xpre))
    fcur = float(f(xcur))
    if fpre == 0:
        return xpre
    if fcur == 0:
        return xcur
    if math.copysign(1.0, fpre) == math.copysign(1.0, fcur):
        raise ValueError("f(a) and f(b) must have different signs")
    for _ in range(maxiter):
        if fpre != 0 and fcur != 0 and math.copysign(1.0, fpre) != math.copysign(1.0, fcur):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # extrapolate (inverse quadratic)
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):  # a good short step
                spre, scur = scur, stry
            else:  # bisect
                spre = scur = sbis
        else:  # bisect
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = float(f(xcur))
    raise RuntimeError(f"brentq: no convergence after {maxiter} iterations")
