"""Monotone piecewise cubic (PCHIP) interpolation, operation for operation as SciPy's (private).

``scipy.interpolate`` costs ~0.2 s to import (it pulls in scipy.optimize and scipy.sparse); the
reversal-time budget of every sinusoidal-motion calibration paid it to interpolate one table of
45 points. This is SciPy's ``PchipInterpolator`` (Fritsch & Carlson 1980, SIAM J. Numer. Anal.
17(2); end slopes by Moler, *Numerical Computing with MATLAB* §3.6) and ``PPoly`` evaluation,
the same arithmetic in the same order, so the values equal SciPy's bit for bit (a test compares
them). Only what the table needs: 1-D, strictly increasing x, evaluation inside [x₀, x_last].
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def _edge_slope(h0: float, h1: float, m0: float, m1: float) -> float:
    """The one-sided three-point end slope, kept shape-preserving (Moler's pchiptx)."""
    d = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    if np.sign(d) != np.sign(m0):
        return 0.0
    if np.sign(m0) != np.sign(m1) and abs(d) > 3.0 * abs(m0):
        return 3.0 * m0
    return float(d)


def pchip(x: np.ndarray, y: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """The PCHIP interpolant of (x, y) (x strictly increasing, ≥ 3 points), as a function of
    an array of points inside [x[0], x[-1]] (units of x in, of y out)."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    hk = x[1:] - x[:-1]
    mk = (y[1:] - y[:-1]) / hk
    smk = np.sign(mk)
    flat = (smk[1:] != smk[:-1]) | (mk[1:] == 0) | (mk[:-1] == 0)
    w1 = 2 * hk[1:] + hk[:-1]
    w2 = hk[1:] + 2 * hk[:-1]
    with np.errstate(divide="ignore", invalid="ignore"):
        whmean = (w1 / mk[:-1] + w2 / mk[1:]) / (w1 + w2)
    dk = np.zeros_like(y)
    dk[1:-1][~flat] = 1.0 / whmean[~flat]
    dk[0] = _edge_slope(hk[0], hk[1], mk[0], mk[1])
    dk[-1] = _edge_slope(hk[-1], hk[-2], mk[-1], mk[-2])
    # CubicHermiteSpline's coefficients, highest power first
    dx = np.diff(x)
    slope = np.diff(y) / dx
    t = (dk[:-1] + dk[1:] - 2 * slope) / dx
    c = np.stack((t / dx, (slope - dk[:-1]) / dx - t, dk[:-1], y[:-1]))

    def evaluate(points: np.ndarray) -> np.ndarray:
        # PPoly: the interval with x[i] <= p < x[i+1] (the last one for p = x[-1]), then
        # c3 + c2·s + c1·s² + c0·s³ summed in that order, the powers by repeated products
        p = np.asarray(points, dtype=np.float64)
        i = np.clip(np.searchsorted(x, p, side="right") - 1, 0, x.size - 2)
        s = p - x[i]
        res = 0.0 + c[3, i]
        z = s
        res = res + c[2, i] * z
        z = z * s
        res = res + c[1, i] * z
        z = z * s
        return res + c[0, i] * z

    return evaluate
