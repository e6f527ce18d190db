"""Numba twin of :func:`rotacal.signal._residual.residual_sums` (private; imports Numba).

Imported only when a record is long enough (:func:`rotacal._jit.use_numba`); compiled on first
use and cached on disk. Per sample: θ = ω·(t − t_ref) as the NumPy path forms it; cos θ and sin θ
exactly every :data:`_RESYNC` samples and in between by rotating the previous pair through
δ = θᵢ − θᵢ₋₁ (exact by Sterbenz's lemma while θ keeps its sign within a factor 2), with cos δ and
sin δ from their Taylor series to δ⁹ (the next term below 3·10⁻¹⁷ for |δ| ≤ 0.1 rad; a larger
step takes the exact functions); the harmonics by the angle-addition recurrence; the terms added
in the NumPy path's order. The rotation rounds by about an ulp per step, so the residual sums
agree with the NumPy path's to ≤ 1e-12 relative, not to the bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: Samples between exact cos/sin (the rotation's rounding walks ~√n ulps in between).
_RESYNC = 64
#: Partial sums of this many samples keep the rounding of the long sum small.
_PART = 4096
#: Largest step δ (rad) rotated with the Taylor series.
_MAX_STEP = 0.1
#: Samples per block of the harmonics' vectorised loops (their arrays stay in the L1/L2 cache).
_BLOCK = 1024
#: All bits of a float64 but its sign.
_MAGNITUDE = np.int64(0x7FFFFFFFFFFFFFFF)


@njit(cache=True, nogil=True, inline="always")
def _cos_sin(theta: float, theta_prev: float, c1: float, s1: float, exact: bool) -> tuple:
    """cos θ and sin θ: exact, or the previous pair rotated through δ = θ − θ_prev."""
    d = theta - theta_prev
    if exact or abs(d) > _MAX_STEP:
        return math.cos(theta), math.sin(theta)
    d2 = d * d
    cd = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0)))
    sd = d * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0))))
    return c1 * cd - s1 * sd, s1 * cd + c1 * sd


@njit(cache=True, nogil=True)
def residual_sums_jit(
    t: np.ndarray,
    y: np.ndarray,
    t_ref: float,
    omega: float,
    consts: np.ndarray,
    ca: np.ndarray,
    cb: np.ndarray,
    drifts: np.ndarray,
) -> np.ndarray:  # pragma: no cover - compiled
    """Residual sums of squares of one or two models (rows of ``ca``/``cb``) over the samples
    (row 0 of the result) and the residuals' sums with τ = t − t_ref (row 1).

    With one model the second row repeats the first (its sum is dropped). Blocks of
    :data:`_BLOCK` samples: cos θ, sin θ sample by sample, then each harmonic for the whole
    block (a loop over samples without dependences, which the compiler vectorises), then the
    residuals summed in sample order.
    """
    n = t.size
    nh = ca.shape[1]
    two = consts.size > 1
    j = 1 if two else 0
    ca0, cb0, ca1, cb1 = ca[0], cb[0], ca[j], cb[j]
    const0, const1 = consts[0], consts[j]
    drift0, drift1 = drifts[0], drifts[j]
    c1 = np.empty(_BLOCK)
    s1 = np.empty(_BLOCK)
    ch = np.empty(_BLOCK)
    sh = np.empty(_BLOCK)
    tau = np.empty(_BLOCK)
    m0 = np.empty(_BLOCK)
    m1 = np.empty(_BLOCK)
    out0 = 0.0
    out1 = 0.0
    part0 = 0.0
    part1 = 0.0
    tau0 = 0.0
    tau1 = 0.0
    c_prev = 1.0
    s_prev = 0.0
    theta_prev = 0.0
    for s in range(0, n, _BLOCK):
        size = min(n - s, _BLOCK)
        for q in range(size):
            i = s + q
            tq = t[i] - t_ref
            theta = omega * tq
            c_prev, s_prev = _cos_sin(theta, theta_prev, c_prev, s_prev, i % _RESYNC == 0)
            theta_prev = theta
            tau[q] = tq
            c1[q] = c_prev
            s1[q] = s_prev
            ch[q] = c_prev
            sh[q] = s_prev
            m0[q] = const0
            m1[q] = const1
        for k in range(nh):
            a0 = ca0[k]
            b0 = cb0[k]
            a1 = ca1[k]
            b1 = cb1[k]
            rotate = k > 0
            for q in range(size):
                cq = ch[q]
                sq = sh[q]
                if rotate:
                    cq, sq = cq * c1[q] - sq * s1[q], sq * c1[q] + cq * s1[q]
                    ch[q] = cq
                    sh[q] = sq
                m0[q] = m0[q] + a0 * cq
                m0[q] = m0[q] + b0 * sq
                m1[q] = m1[q] + a1 * cq
                m1[q] = m1[q] + b1 * sq
        for q in range(size):
            i = s + q
            if i % _PART == 0:
                out0 += part0
                out1 += part1
                part0 = 0.0
                part1 = 0.0
            v0 = m0[q]
            v1 = m1[q]
            if drift0 != 0.0:
                v0 = v0 + drift0 * tau[q]
            if drift1 != 0.0:
                v1 = v1 + drift1 * tau[q]
            r0 = y[i] - v0
            r1 = y[i] - v1
            part0 += r0 * r0
            part1 += r1 * r1
            tau0 += r0 * tau[q]
            tau1 += r1 * tau[q]
    out = np.empty((2, consts.size))
    out[0, 0] = out0 + part0
    out[1, 0] = tau0
    if two:
        out[0, 1] = out1 + part1
        out[1, 1] = tau1
    return out


@njit(cache=True, nogil=True, fastmath={"contract"})
def _add_harmonic(
    model: np.ndarray,
    slope: np.ndarray,
    crow: np.ndarray,
    srow: np.ndarray,
    al: float,
    be: float,
    h: float,
    size: int,
) -> None:  # pragma: no cover - compiled
    """``model += α·cos + β·sin`` and ``slope += h·(β·cos − α·sin)`` over one block (a loop
    without dependences: vectorised, with fused multiply-adds)."""
    hal = h * al
    hbe = h * be
    for q in range(size):
        c = crow[q]
        sn = srow[q]
        model[q] += al * c + be * sn
        slope[q] += hbe * c - hal * sn


@njit(cache=True, nogil=True)
def _block_rss(
    y: np.ndarray, model: np.ndarray, tau: np.ndarray
) -> tuple:  # pragma: no cover - compiled
    """``Σ (y − model)²`` and ``Σ (y − model)·τ`` over ``y.size`` samples, each in four
    interleaved partial sums (a vectorised loop; no less accurate than one running sum), kept
    in registers."""
    r0 = r1 = r2 = r3 = 0.0
    t0 = t1 = t2 = t3 = 0.0
    size = y.size
    full = size - size % 4
    for q in range(0, full, 4):
        d0 = y[q] - model[q]
        d1 = y[q + 1] - model[q + 1]
        d2 = y[q + 2] - model[q + 2]
        d3 = y[q + 3] - model[q + 3]
        r0 += d0 * d0
        r1 += d1 * d1
        r2 += d2 * d2
        r3 += d3 * d3
        t0 += d0 * tau[q]
        t1 += d1 * tau[q + 1]
        t2 += d2 * tau[q + 2]
        t3 += d3 * tau[q + 3]
    for q in range(full, size):
        d0 = y[q] - model[q]
        r0 += d0 * d0
        t0 += d0 * tau[q]
    return (r0 + r1) + (r2 + r3), (t0 + t1) + (t2 + t3)


@njit(cache=True, nogil=True)
def _largest_magnitude_bits(bits: np.ndarray, size: int) -> np.int64:  # pragma: no cover
    """The bits of the largest |x| of the first ``size`` floats whose bits are ``bits`` (int64):
    without their sign bit the bits of non-negative floats order as the floats do, and an
    integer max is vectorised (a floating-point one is not). Compare with a bound's bits."""
    worst = np.int64(0)
    for q in range(size):
        worst = max(worst, bits[q] & _MAGNITUDE)
    return worst


@njit(cache=True, nogil=True)
def _grid_model(
    model: np.ndarray,
    slope: np.ndarray,
    cq: np.ndarray,
    sq: np.ndarray,
    const: float,
    ca: np.ndarray,
    cb: np.ndarray,
    drift: float,
    theta_s: float,
    delta: np.ndarray,
    tau: np.ndarray,
    size: int,
) -> None:  # pragma: no cover - compiled
    """One model over one block of the grid (see :func:`residual_sums_grid`) into ``model``."""
    for q in range(size):
        model[q] = const
        slope[q] = 0.0
    for h in range(ca.size):
        ch = math.cos((h + 1) * theta_s)
        sh = math.sin((h + 1) * theta_s)
        al = ca[h] * ch + cb[h] * sh
        be = cb[h] * ch - ca[h] * sh
        _add_harmonic(model, slope, cq[h], sq[h], al, be, float(h + 1), size)
    for q in range(size):
        model[q] += delta[q] * slope[q] + drift * tau[q]


@njit(cache=True, nogil=True)
def residual_sums_grid(
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
) -> tuple:  # pragma: no cover - compiled
    """:func:`residual_sums_jit` for samples on a uniform grid of step ``dt`` (s), without the
    sample-to-sample dependence of the rotation.

    Within a block of :data:`_BLOCK` samples (:data:`rotacal.signal._residual.GRID_BLOCK`) starting at θ_s = ω·(t_s − t_ref), sample q has
    θ = θ_s + φ_q + δ with φ_q = q·ω·dt: cos(hφ_q), sin(hφ_q) come from a table made once
    (exact ``cos``/``sin``), cos(hθ_s), sin(hθ_s) exactly once per block, so the model is
    ``Σ_h α_h·cos(hφ_q) + β_h·sin(hφ_q)`` (α_h = a_h cos hθ_s + b_h sin hθ_s, β_h = b_h cos hθ_s −
    a_h sin hθ_s; angle addition) plus the first-order term in δ (θ as the NumPy path forms
    it, less its table angle: rounding of t, ~1e-12 rad), ``δ·Σ_h h·(β_h cos hφ_q − α_h sin hφ_q)``.
    The loops over a block's samples are free of dependences (vectorised). Returns the sums
    (row 0: ``Σ r²``, row 1: ``Σ r·τ`` of each model) and True, or False when some |δ| exceeds ``tol`` (the samples are not on the
    grid: the caller uses :func:`residual_sums_jit`); ``tol`` is that bound (rad). The NumPy
    twin is :func:`rotacal.signal._residual.grid_residual_sums`.
    """
    n = t.size
    nh = ca.shape[1]
    nm = consts.size
    cq = np.empty((nh, _BLOCK))
    sq = np.empty((nh, _BLOCK))
    wdt = omega * dt
    for h in range(nh):
        for q in range(_BLOCK):
            ang = (h + 1) * (q * wdt)
            cq[h, q] = math.cos(ang)
            sq[h, q] = math.sin(ang)
    delta = np.empty(_BLOCK)
    delta_bits = delta.view(np.int64)
    tol_bits = np.array([tol]).view(np.int64)[0]
    tau = np.empty(_BLOCK)
    slope = np.empty(_BLOCK)
    model = np.empty((nm, _BLOCK))
    out = np.zeros((2, nm))
    part = np.zeros(nm)
    for s in range(0, n, _BLOCK):
        size = min(n - s, _BLOCK)
        theta_s = omega * (t[s] - t_ref)
        ts = t[s : s + size]
        for q in range(size):
            tq = ts[q] - t_ref
            tau[q] = tq
            delta[q] = (omega * tq - theta_s) - q * wdt
        if _largest_magnitude_bits(delta_bits, size) > tol_bits:
            return out, False
        for j in range(nm):
            _grid_model(
                model[j],
                slope,
                cq,
                sq,
                consts[j],
                ca[j],
                cb[j],
                drifts[j],
                theta_s,
                delta,
                tau,
                size,
            )
        if s % _PART == 0:
            for j in range(nm):
                out[0, j] += part[j]
                part[j] = 0.0
        for j in range(nm):
            rss, rtau = _block_rss(y[s : s + size], model[j], tau)
            part[j] += rss
            out[1, j] += rtau
    for j in range(nm):
        out[0, j] += part[j]
    return out, True
