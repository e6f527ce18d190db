"""Residual sums of squares of fitted harmonic series over the samples, in one pass (private).

When the normal equations cannot resolve a fit's residual (``yᵀy − bᵀp`` is rounding), it is
summed from the samples. Several models at one frequency (the fit and its drift check) share the
cosines and sines, so they are summed together, over cache-sized chunks (NumPy) or sample by
sample (the Numba twin in :mod:`rotacal.signal._residual_jit`, for long records).
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from rotacal._jit import use_numba
from rotacal._threads import blas_one_thread
from rotacal.signal._result import harmonic_series_many

#: Samples per chunk of the NumPy path: the cosines, sines and model of a chunk stay in cache.
_CHUNK = 1 << 14
#: Samples per block of the uniform-grid path (both twins): the table of cos(hφ), sin(hφ).
GRID_BLOCK = 1024
#: Blocks per matrix product of the NumPy grid path.
_GRID_GROUP = 64
#: From this many samples on, the NumPy grid path sums the second half of the record on a second
#: thread (where the machine has two cores): the same sums, in about half the wall time.
SPLIT_SAMPLES = 1 << 21
#: On a uniform grid a sample's angle may differ from its table angle by at most this (rad)
#: over H: the first-order correction then leaves (H·δ)²/2 ≤ 5e-17 of a harmonic's amplitude.
_GRID_DELTA = 1e-8


def residual_sums(
    t: np.ndarray,
    y: np.ndarray,
    t_ref: float,
    frequency_hz: float,
    models: Sequence[tuple[float, np.ndarray, np.ndarray, float]],
    *,
    jit: bool | None = None,
) -> list[float]:
    """``Σ (y − model)²`` for each model ``const + Σ_h a_h cos(hωτ) + b_h sin(hωτ) + D·τ``.

    Parameters
    ----------
    t : ndarray
        Sample times (s).
    y : ndarray
        Samples (unit of y).
    t_ref : float
        Reference time τ = 0 of the models (s).
    frequency_hz : float
        Fundamental f (Hz); ω = 2πf.
    models : sequence of (const, a, b, D)
        Offset (unit of y), cosine and sine coefficients of harmonics 1..H (unit of y) and drift
        D (unit of y per s).
    jit : bool, optional
        Force the Numba twin (True) or the NumPy path (False); default: by the record's size
        (:func:`rotacal._jit.use_numba`).

    Returns
    -------
    list of float
        One residual sum of squares per model (unit of y squared).

    References
    ----------
    IEEE Std 1057-2017, §4.1.3 (the residual of the sine fits, from which s² = RSS/(N − p));
    Feng et al. 2023, Sensors 23:4876, eq. (9) (the multi-harmonic model).
    """
    return _sums(t, y, t_ref, frequency_hz, models, jit)[0]


def residual_tau_sums(
    t: np.ndarray,
    y: np.ndarray,
    t_ref: float,
    frequency_hz: float,
    model: tuple[float, np.ndarray, np.ndarray, float],
    *,
    jit: bool | None = None,
) -> tuple[float, float]:
    """``Σ r²`` and ``Σ r·τ`` of one model's residual ``r = y − model`` (τ = t − t_ref, s).

    The second sum is the residual's product with a drift column τ: with it a fit's residual
    gives that of the same fit with the column added, without a second pass over the samples
    (:meth:`~rotacal.signal._blocks.HarmonicFitAccumulator.fit`). Arguments as
    :func:`residual_sums`; returns (unit of y squared, unit of y times s).
    """
    rss, rtau = _sums(t, y, t_ref, frequency_hz, [model], jit)
    return rss[0], rtau[0]


def _sums(
    t: np.ndarray,
    y: np.ndarray,
    t_ref: float,
    frequency_hz: float,
    models: Sequence[tuple[float, np.ndarray, np.ndarray, float]],
    jit: bool | None,
) -> tuple[list[float], list[float]]:
    """``Σ r²`` and ``Σ r·τ`` of each model (:func:`residual_sums`, :func:`residual_tau_sums`)."""
    omega = 2.0 * math.pi * frequency_hz
    consts = np.array([float(m[0]) for m in models])
    ca = np.array([np.asarray(m[1], dtype=np.float64) for m in models])
    cb = np.array([np.asarray(m[2], dtype=np.float64) for m in models])
    drifts = np.array([float(m[3]) for m in models])
    dt = (float(t[-1]) - float(t[0])) / (t.size - 1) if t.size > 1 else 0.0
    tol = _GRID_DELTA / max(ca.shape[1], 1)
    if len(models) <= 2 and use_numba(t.size, jit):
        from rotacal.signal._residual_jit import residual_sums_grid, residual_sums_jit

        if dt > 0:  # on a uniform grid: the table of cos/sin (falls back when off the grid)
            out, on_grid = residual_sums_grid(
                t, y, float(t_ref), omega, dt, tol, consts, ca, cb, drifts
            )
            if on_grid:
                return [float(x) for x in out[0]], [float(x) for x in out[1]]
        out = residual_sums_jit(t, y, float(t_ref), omega, consts, ca, cb, drifts)
        return [float(x) for x in out[0]], [float(x) for x in out[1]]
    if dt > 0:
        grid = grid_residual_sums(t, y, float(t_ref), omega, dt, tol, consts, ca, cb, drifts)
        if grid is not None:
            return grid
    sums = [0.0] * len(models)
    tau_sums = [0.0] * len(models)
    series = [(np.asarray(ca_i), np.asarray(cb_i), const) for const, ca_i, cb_i, _ in models]
    for s in range(0, t.size, _CHUNK):
        tau = t[s : s + _CHUNK] - t_ref
        ys = y[s : s + _CHUNK]
        for i, model in enumerate(harmonic_series_many(omega * tau, series)):
            drift = models[i][3]
            if drift:
                model += drift * tau
            r = ys - model
            sums[i] += float(r @ r)
            tau_sums[i] += float(r @ tau)
    return sums, tau_sums


def grid_residual_sums(
    t: np.ndarray,
    y: np.ndarray,
    t_ref: float,
    omega: float,
    dt: float,
    tol: float,
    consts: np.ndarray,
    ca: np.ndarray,
    cb: np.ndarray,
    drifts: np.ndarray,
) -> tuple[list[float], list[float]] | None:
    """The residual sums (``Σ r²`` and ``Σ r·τ`` of each model) of samples on a uniform grid of step ``dt`` (s) by matrix products.

    The NumPy twin of :func:`rotacal.signal._residual_jit.residual_sums_grid` (same angles,
    same tables): in a block of :data:`GRID_BLOCK` samples from θ_s, sample q lies at
    θ_s + φ_q + δ_q (φ_q = q·ω·dt); each model's harmonics are ``α_h cos hφ_q + β_h sin hφ_q``
    (angle addition: α_h = a_h cos hθ_s + b_h sin hθ_s, β_h = b_h cos hθ_s − a_h sin hθ_s) plus
    ``δ_q·Σ_h h(β_h cos hφ_q − α_h sin hφ_q)``, for :data:`_GRID_GROUP` blocks at once as one
    product of their coefficients with the table. None when some |δ| exceeds ``tol`` (rad):
    the samples are not on the grid.
    """
    n = t.size
    nm, nh = ca.shape
    harm = np.arange(1, nh + 1, dtype=np.float64)
    phi = np.arange(GRID_BLOCK) * (omega * dt)
    ang = np.outer(harm, phi)
    table = np.vstack([np.cos(ang), np.sin(ang)])  # (2H, GRID_BLOCK)
    step = GRID_BLOCK * _GRID_GROUP

    def steps_sums(first: int, stop: int) -> list[tuple[np.ndarray, np.ndarray]] | None:
        """``Σ r²`` and ``Σ r·τ`` of each model over each part of the steps from sample
        ``first`` (a multiple of ``step``) to ``stop``, in sample order; None off the grid."""
        out = []
        for s in range(first, stop, step):
            e = min(n, s + step)
            full = (e - s) // GRID_BLOCK
            parts = [(s, full, GRID_BLOCK)] if full else []
            if s + full * GRID_BLOCK < e:
                parts.append((s + full * GRID_BLOCK, 1, e - s - full * GRID_BLOCK))
            for start, nb, size in parts:
                tau = t[start : start + nb * size].reshape(nb, size) - t_ref
                theta = omega * tau
                theta_s = theta[:, :1]
                delta = (theta - theta_s) - phi[None, :size]
                if not np.abs(delta).max() <= tol:
                    return None
                h_theta = theta_s * harm[None, :]
                c_h, s_h = np.cos(h_theta), np.sin(h_theta)
                ys = y[start : start + nb * size].reshape(nb, size)
                # every model's values and first-order terms in one product with the table
                # (one BLAS thread: on these small products more threads only spin)
                al = ca[:, None, :] * c_h + cb[:, None, :] * s_h  # (models, blocks, H)
                be = cb[:, None, :] * c_h - ca[:, None, :] * s_h
                coef = np.concatenate(
                    [np.concatenate([al, be], axis=2), np.concatenate([harm * be, -harm * al], 2)]
                ).reshape(2 * nm * nb, 2 * nh)
                prod = coef @ table[:, :size]
                rr, rt = np.empty(nm), np.empty(nm)
                for j in range(nm):
                    model = prod[j * nb : (j + 1) * nb]
                    model += delta * prod[(nm + j) * nb : (nm + j + 1) * nb]
                    model += consts[j]
                    if drifts[j]:
                        model += drifts[j] * tau
                    r = np.subtract(ys, model, out=model).reshape(-1)
                    rr[j] = float(r @ r)
                    rt[j] = float(r @ tau.reshape(-1))
                out.append((rr, rt))
        return out

    with blas_one_thread():
        if n < SPLIT_SAMPLES or (os.cpu_count() or 1) < 2:
            pieces = [steps_sums(0, n)]
        else:
            # the second half on a second core (NumPy and BLAS release the GIL); the parts'
            # sums are added below in sample order, so the result is that of one thread's pass
            half = (n // 2) // step * step
            with ThreadPoolExecutor(1) as pool:
                later = pool.submit(steps_sums, half, n)
                pieces = [steps_sums(0, half), later.result()]
    sums = np.zeros(nm)
    tau_sums = np.zeros(nm)
    for piece in pieces:
        if piece is None:
            return None
        for rr, rt in piece:
            sums += rr
            tau_sums += rt
    return [float(x) for x in sums], [float(x) for x in tau_sums]
