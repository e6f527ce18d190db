"""The exponential sums of the normal equations straight from a uniformly sampled record (private).

For a fast signal (thousands of periods in the record) the blocks of
:class:`~rotacal.signal._blocks.HarmonicFitAccumulator` hold only a few samples each, fewer than
their moments, and their count grows with the number of periods. A record held in memory on a
uniform grid is then summed directly at each trial frequency. It is cut into segments of
``SEG_SAMPLES`` samples; with the segment centres' offsets ``d_s = c_s − t_ref`` and the in-segment
offsets ``o_i = (i − (M−1)/2)·Δt``, the same for every segment on the grid,

    Y_p(k) = Σ_s e^{jkωd_s} Σ_i (y_si − y0)·(d_s + o_i)^p·e^{jkωo_i}        (p = 0, 1)
    S_p(k) = Σ_s e^{jkωd_s} Σ_i (d_s + o_i)^p·e^{jkωo_i}                    (p = 0, 1, 2)

(the sums S_p, Y_p of :mod:`rotacal.signal._normal`). The in-segment exponentials
``W_ik = e^{jkωo_i}`` are evaluated one by one (M·(2H+1) per frequency; no series, so no limit on
the phase within a segment); the inner y-sums of a run of segments are one BLAS product of the
(segments × M) centred samples with ``[W, o·W]``, the inner S-sums are ``Σ_i o_i^p W_ik`` for every
segment alike. The cost is O(N·H) per frequency whatever the number of periods. Samples after the
last whole segment are summed one by one.
"""

from __future__ import annotations

import math

import numpy as np

from rotacal.errors import CaptureError
from rotacal.signal._blocks_sums import unit_powers
from rotacal.signal._normal import SumsFn

SQUARES_OVERFLOW = "y holds values too large to square in float64; rescale the signal."

#: Samples per segment (the BLAS product's inner dimension).
SEG_SAMPLES = 256
#: Segments per BLAS product (64k samples: their centred copy, 512 kB, stays in the L2 cache).
SEG_ROWS = 256


def centred_square_sum(y: np.ndarray, y0: float) -> float:
    """``Σ (y − y0)²`` in runs of 64k samples (no record-long temporary); refuses a record whose
    squares overflow float64 (``y`` is finite)."""
    s2 = 0.0
    step = SEG_SAMPLES * SEG_ROWS
    buf = np.empty(min(step, y.size))
    for r in range(0, y.size, step):
        c = np.subtract(y[r : r + step], y0, out=buf[: min(step, y.size - r)])
        s2 += float(c @ c)
    if not math.isfinite(s2):
        raise CaptureError(SQUARES_OVERFLOW)
    return s2


def grid_sums(y: np.ndarray, y0: float, tau0_s: float, dt_s: float, nh: int) -> SumsFn:
    """A sums provider (:class:`~rotacal.signal._normal.SumsFn`) for
    :func:`~rotacal.signal._normal.solve_normal` over the samples ``y`` at ``τ_i = tau0_s + i·dt_s``.

    Parameters
    ----------
    y : ndarray
        The samples (finite), held by reference (not copied).
    y0 : float
        Centring constant subtracted from y (unit of y).
    tau0_s : float
        Time of the first sample relative to t_ref (s).
    dt_s : float
        Sampling interval (s).
    nh : int
        Harmonics H.

    References
    ----------
    IEEE Std 1057-2017, §4.1.3 (multi-harmonic least squares); Feng et al. 2023, Sensors
    23:4876, eq. (9).
    """
    n = y.size
    m = SEG_SAMPLES
    nseg = n // m
    kmax = 2 * nh
    ny = nh + 1
    ks = np.arange(kmax + 1, dtype=np.float64)
    o = (np.arange(m) - 0.5 * (m - 1)) * dt_s
    dvec = tau0_s + (np.arange(nseg) * m + 0.5 * (m - 1)) * dt_s
    tail_tau = tau0_s + np.arange(nseg * m, n) * dt_s
    tail_y = y[nseg * m :] - y0

    def sums(omega: float, deriv: bool, y_deriv: bool = True) -> tuple[np.ndarray, np.ndarray]:
        n_p = 3 if deriv else 1
        n_y = 2 if deriv and y_deriv else 1
        w = np.exp(1j * omega * np.outer(o, ks))  # (M, 2H+1)
        w_p = [w.sum(axis=0)] + [(o**p) @ w for p in range(1, n_p)]
        cols = [w[:, :ny].real, w[:, :ny].imag]
        if n_y == 2:
            ow = o[:, None] * w[:, :ny]
            cols += [ow.real, ow.imag]
        wcat = np.ascontiguousarray(np.hstack(cols))  # (M, 2·n_y·(H+1)) real
        t_seg = np.zeros((n_p, kmax + 1), dtype=np.complex128)  # Σ_s e^{jkωd_s}·d_s^p
        yv = np.zeros((n_y, ny), dtype=np.complex128)
        buf = np.empty((min(SEG_ROWS, nseg), m))
        z = np.empty((buf.shape[0], wcat.shape[1]))
        for r in range(0, nseg, SEG_ROWS):
            e = min(nseg, r + SEG_ROWS)
            c = e - r
            d = dvec[r:e]
            ex = unit_powers(np.exp(1j * omega * d), kmax)  # (c, 2H+1)
            blk = np.subtract(y[r * m : e * m].reshape(c, m), y0, out=buf[:c])
            zc = np.matmul(blk, wcat, out=z[:c])
            z0 = zc[:, :ny] + 1j * zc[:, ny : 2 * ny]
            exy = ex[:, :ny]
            yv[0] += np.sum(exy * z0, axis=0)
            t_seg[0] += ex.sum(axis=0)
            if n_y == 2:
                z1 = zc[:, 2 * ny : 3 * ny] + 1j * zc[:, 3 * ny :]
                yv[1] += np.sum(exy * (d[:, None] * z0 + z1), axis=0)
            if deriv:
                t_seg[1] += d @ ex
                t_seg[2] += (d * d) @ ex
        s = np.empty((n_p, kmax + 1), dtype=np.complex128)
        s[0] = t_seg[0] * w_p[0]
        if deriv:
            s[1] = t_seg[1] * w_p[0] + t_seg[0] * w_p[1]
            s[2] = t_seg[2] * w_p[0] + 2.0 * t_seg[1] * w_p[1] + t_seg[0] * w_p[2]
        if tail_tau.size:
            et = np.exp(1j * omega * np.outer(tail_tau, ks))
            for p in range(n_p):
                s[p] += (tail_tau**p) @ et
            for p in range(n_y):
                yv[p] += (tail_y * tail_tau**p) @ et[:, :ny]
        return s, yv

    return sums
