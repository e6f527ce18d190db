"""The exponential sums of the normal equations from block moments, at any frequency (private).

For block b with centre offset ``d_b = c_b − t_ref``, half-length h and the moments
``P_bl = Σ u^l``, ``Q_bl = Σ (y − y0)·u^l`` of :class:`~rotacal.signal._blocks.HarmonicFitAccumulator`,
the Taylor series of ``exp(j·k·ω·h·u)`` (coefficients ``c_kl = (j·k·ω·h)^l / l!``) gives

    S_p(k) = Σ_b e^{jkωd_b} Σ_l c_kl · [moment of (d_b + h·u)^p · u^l]
    Y_p(k) = Σ_b e^{jkωd_b} Σ_l c_kl · [y-moment of (d_b + h·u)^p · u^l]

(the sums S_p, Y_p of :mod:`rotacal.signal._normal`). The order of the sums is swapped: first
``A_p[k, l] = Σ_b e^{jkωd_b}·d_b^p·P_bl`` and ``B_p[k, l] = Σ_b e^{jkωd_b}·d_b^p·Q_bl``, one BLAS
product of the (2H+1 harmonics × blocks) exponentials with the (blocks × moments) moments per
chunk of blocks; then the few Taylor coefficients. The exponentials of a block are the powers of
``e^{jωd_b}`` (one complex exponential per block, not one per harmonic). A full block on the
sampling grid holds the same P row as every other full block, so its part of ``A_p`` is
``(Σ_b e^{jkωd_b}·d_b^p)·P̄_l``: the P moments are read only for the blocks cut by a chunk
boundary or off the grid. The cost is O(blocks·H·terms) per frequency, the same for 10 or
10,000 periods of the same block count; the block length sets the count.
"""

from __future__ import annotations

import math

import numpy as np

from rotacal.errors import CaptureError
from rotacal.signal._normal import SumsFn

#: Blocks per BLAS product (their exponentials, 2·(2H+1) rows of doubles, stay in the L2 cache).
SUM_ROWS = 2048
#: The exponential series is cut where its terms fall below this.
TRUNC = 1e-17


def taylor_terms(x: float, limit: int) -> int:
    """Smallest L with x^L/L! ≤ 1e-17 (the exponential series cut after L terms), or limit+1."""
    term = 1.0
    for ell in range(1, limit + 1):
        term *= x / ell
        if term <= TRUNC:
            return ell
    return limit + 1


def unit_powers(e1: np.ndarray, kmax: int) -> np.ndarray:
    """``e1**k`` for k = 0..kmax as columns, by repeated multiplication (error ~k·eps)."""
    out = np.empty((e1.size, kmax + 1), dtype=np.complex128)
    out[:, 0] = 1.0
    if kmax >= 1:
        out[:, 1] = e1
    for k in range(2, kmax + 1):
        np.multiply(out[:, k - 1], e1, out=out[:, k])
    return out


def _powers_split(
    e1: np.ndarray,
    nh: int,
    kmax: int,
    work: np.ndarray | None = None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Rows ``Re e1^k`` and ``Im e1^k``, ordered [Re 0..nh, Im 0..nh, Re nh+1..kmax, Im nh+1..kmax]
    (the rows the y-sums need come first); powers by repeated multiplication (error ~k·eps).
    ``work`` (complex, ≥ (kmax+1) × size) and ``out`` (real, ≥ 2(kmax+1) × size) are reused
    buffers when given (a chunk's arrays of a few hundred kB each, allocated once per sum)."""
    size = e1.size
    pw = np.empty((kmax + 1, size), dtype=np.complex128) if work is None else work[: kmax + 1]
    if pw.shape[1] != size:
        pw = pw[:, :size]
    pw[0] = 1.0
    if kmax >= 1:
        pw[1] = e1
    for k in range(2, kmax + 1):
        np.multiply(pw[k - 1], e1, out=pw[k])
    if out is None:
        out = np.empty((2 * (kmax + 1), size))
    else:
        out = out[: 2 * (kmax + 1), :size]
    ny = nh + 1
    out[:ny] = pw[:ny].real
    out[ny : 2 * ny] = pw[:ny].imag
    out[2 * ny : 2 * ny + kmax + 1 - ny] = pw[ny:].real
    out[2 * ny + kmax + 1 - ny :] = pw[ny:].imag
    return out


def _complex_rows(x: np.ndarray, nh: int, kmax: int) -> np.ndarray:
    """Undo the row order of :func:`_powers_split` on a product: (2(kmax+1), …) → (kmax+1, …)."""
    ny = nh + 1
    re = np.concatenate((x[:ny], x[2 * ny : 2 * ny + kmax + 1 - ny]))
    im = np.concatenate((x[ny : 2 * ny], x[2 * ny + kmax + 1 - ny :]))
    return re + 1j * im


def grid_power_sums(
    omega: float, d_first: float, d_last: float, block_s: float, count: int, kmax: int, n_p: int
) -> np.ndarray:
    """``Σ_b e^{jkωd_b}·d_b^p`` (k = 0..kmax, p < n_p ≤ 3) over ``count`` blocks at
    ``d_b = d_first + b·T`` (T = ``block_s``, s; ``d_last`` the last), in closed form.

    About the middle block, d_b = d_c + e·T with e symmetric (half-integers for an even count),
    ``Σ_e e^{jeθ} = D(θ) = sin(Jθ/2)/sin(θ/2)`` (the Dirichlet kernel, θ = kωT, J = count), and
    ``Σ_e e·e^{jeθ} = −j·D′(θ)``, ``Σ_e e²·e^{jeθ} = −D″(θ)`` from its derivatives; k = 0 takes
    the power sums J, 0 and J(J²−1)/12. Each is a few products of sines and cosines instead of
    a sum over the blocks; θ stays in (0, 2π) (the block plan keeps 2H·ω·T/2 below ~2 rad),
    where the terms do not cancel beyond a factor ~2/(Jθ).
    """
    jj = float(count)
    d_c = 0.5 * (d_first + d_last)
    ks = np.arange(kmax + 1, dtype=np.float64)
    theta = ks * (omega * block_s)
    half = 0.5 * theta[1:]
    sig, kap = np.sin(half), np.cos(half)
    big = jj * half
    s_a, c_a = np.sin(big), np.cos(big)
    d0 = np.empty(kmax + 1)
    d1 = np.empty(kmax + 1)  # D′
    d2 = np.empty(kmax + 1)  # D″
    d0[0], d1[0], d2[0] = jj, 0.0, -jj * (jj * jj - 1.0) / 12.0
    d0[1:] = s_a / sig
    num = 0.5 * jj * c_a * sig - 0.5 * s_a * kap
    d1[1:] = num / (sig * sig)
    d2[1:] = (0.25 * (1.0 - jj * jj) * s_a * sig * sig - 0.5 * jj * kap * c_a * sig
              + 0.5 * s_a * kap * kap) / sig**3  # fmt: skip
    rot = np.exp(1j * ks * (omega * d_c))
    e0 = d0.astype(np.complex128)
    e1 = -1j * d1
    e2 = -d2.astype(np.complex128)
    out = np.empty((kmax + 1, n_p), dtype=np.complex128)
    out[:, 0] = rot * e0
    if n_p > 1:
        out[:, 1] = rot * (d_c * e0 + block_s * e1)
        out[:, 2] = rot * (d_c * d_c * e0 + 2.0 * d_c * block_s * e1 + block_s * block_s * e2)
    return out


def block_sums(
    merged: tuple[np.ndarray, np.ndarray | None, np.ndarray],
    p_full: np.ndarray,
    grid_offset_s: float,
    block_s: float,
    nh: int,
    n_moments: int,
    block_samples: int,
) -> SumsFn:
    """A sums provider ``(ω, with_derivative[, y_derivative]) → (S, Y)`` for
    :func:`~rotacal.signal._normal.solve_normal` (:class:`~rotacal.signal._normal.SumsFn`).

    Parameters
    ----------
    merged : (j, P, Q)
        Block index, P and Q moments (k = 0..n_moments+1) of every block, j increasing; P None
        for a run of full blocks on the grid (each block's P row is ``p_full``).
    p_full : ndarray
        The P row of a full block on the grid.
    grid_offset_s : float
        Start of block 0 minus t_ref (s).
    block_s : float
        Block duration T_b (s).
    nh : int
        Harmonics H.
    n_moments, block_samples : int
        Moments available (Taylor terms) and samples per block (for the message).

    References
    ----------
    IEEE Std 1057-2017, §4.1.3 (multi-harmonic least squares); Feng et al. 2023, Sensors
    23:4876, eq. (9).
    """
    j, p, q = merged
    half = 0.5 * block_s
    dvec = grid_offset_s + (j + 0.5) * block_s
    kmax = 2 * nh
    # blocks whose P row is that of a full block (bit for bit) share it: only their weights count
    if p is None:  # a run of full blocks on the grid (no P rows stored)
        p = np.broadcast_to(p_full, q.shape)
        full = np.ones(j.size, dtype=bool)
    else:
        full = np.all(p == p_full, axis=1)
    part = np.flatnonzero(~full)
    d_part = dvec[part]
    p_part = p[part]
    wfull = np.where(full, 1.0, 0.0)
    # closed form for the full blocks' weights: blocks contiguous and most of them full (the
    # others are subtracted from the closed form: few, so nothing large cancels)
    closed_ok = j.size > 1 and int(j[-1]) - int(j[0]) + 1 == j.size and 4 * part.size <= j.size

    def sums(omega: float, deriv: bool, y_deriv: bool = True) -> tuple[np.ndarray, np.ndarray]:
        x = kmax * abs(omega) * half
        nterm = taylor_terms(x, n_moments)
        if nterm > n_moments:
            f = abs(omega) / (2.0 * math.pi)
            raise CaptureError(
                f"harmonic {kmax} of {f:.6g} Hz turns by {x:.3g} rad within one block of "
                f"{block_samples} samples, too much for the {n_moments} stored moments; create "
                f"the HarmonicFitAccumulator with frequency_hz≈{f:.6g} and harmonics={nh}."
            )
        nty = min(nterm, taylor_terms(nh * abs(omega) * half, n_moments))
        n_p = 3 if deriv else 1
        n_y = 2 if deriv and y_deriv else 1
        ny2 = 2 * (nh + 1)
        # weights of the full blocks' common P row (d^p) and the y-moments (Q, d·Q)
        t_full = np.zeros((2 * (kmax + 1), n_p))
        b_y = np.zeros((ny2, n_y * (nty + 1)))
        a_part = np.zeros((2 * (kmax + 1), n_p * (nterm + 2)))
        # the full blocks' weights in closed form (grid_power_sums): then the y-sums alone
        # read every block, and only for the harmonics 0..H
        closed = closed_ok and omega != 0.0
        kmax_rows = nh if closed else kmax
        # a chunk's work arrays, allocated once (fresh ones at every chunk cost more than the
        # arithmetic: their pages are faulted in again and again)
        rows = min(SUM_ROWS, j.size)
        nq = nty + 1
        jw = 1j * omega
        arg = np.empty(rows, dtype=np.complex128)
        work = np.empty((kmax_rows + 1, rows), dtype=np.complex128)
        ex_buf = np.empty((2 * (kmax_rows + 1), rows))
        qr_buf = np.empty((rows, n_y * nq))
        prod = np.empty((ny2, n_y * nq))
        for r in range(0, j.size, SUM_ROWS):
            d = dvec[r : r + SUM_ROWS]
            c = d.size
            e1 = np.exp(np.multiply(jw, d, out=arg[:c]), out=arg[:c])
            ex = _powers_split(e1, nh, kmax_rows, work, ex_buf)
            if not closed:
                w = wfull[r : r + SUM_ROWS]
                g = np.empty((c, n_p))
                g[:, 0] = w
                if deriv:
                    np.multiply(w, d, out=g[:, 1])
                    np.multiply(g[:, 1], d, out=g[:, 2])
                t_full += ex @ g
            qs = q[r : r + SUM_ROWS, :nq]
            if n_y == 2:
                qr = qr_buf[:c]
                qr[:, :nq] = qs
                np.multiply(d[:, None], qs, out=qr[:, nq:])
            else:
                qr = qs
            b_y += np.matmul(ex[:ny2], qr, out=prod)
        if part.size:
            ex = _powers_split(np.exp(1j * omega * d_part), nh, kmax)
            cols = [p_part[:, : nterm + 2]]
            if deriv:
                cols += [d_part[:, None] * cols[0], (d_part * d_part)[:, None] * cols[0]]
            a_part += ex @ np.concatenate(cols, axis=1)
        if closed:
            t_c = grid_power_sums(omega, dvec[0], dvec[-1], block_s, j.size, kmax, n_p)
            if part.size:  # less the blocks that are not full (their own P is in a_part)
                g = np.ones((d_part.size, n_p))
                if deriv:
                    g[:, 1] = d_part
                    g[:, 2] = d_part * d_part
                t_c -= _complex_rows(ex @ g, nh, kmax)
        else:
            t_c = _complex_rows(t_full, nh, kmax)  # (kmax+1, n_p)
        # A_p[k, l] = (full blocks' weight)·P̄_l + the other blocks' own P
        a_c = _complex_rows(a_part, nh, kmax).reshape(kmax + 1, n_p, nterm + 2)
        a_c += t_c[:, :, None] * p_full[None, None, : nterm + 2]
        b_c = (b_y[: nh + 1] + 1j * b_y[nh + 1 :]).reshape(nh + 1, n_y, nty + 1)
        ks = np.arange(kmax + 1)
        ell = np.arange(nterm)
        fact = np.array([math.factorial(int(i)) for i in ell], dtype=np.float64)
        cm = (1j * omega * half * ks[:, None]) ** ell[None, :] / fact[None, :]
        cy = cm[: nh + 1, :nty]
        s = np.empty((n_p, kmax + 1), dtype=np.complex128)
        a0 = a_c[:, 0]
        s[0] = np.sum(cm * a0[:, :nterm], axis=1)
        yv = np.empty((n_y, nh + 1), dtype=np.complex128)
        yv[0] = np.sum(cy * b_c[:, 0, :nty], axis=1)
        if deriv:
            a1 = a_c[:, 1]
            a2 = a_c[:, 2]
            s[1] = np.sum(cm * (a1[:, :nterm] + half * a0[:, 1 : nterm + 1]), axis=1)
            s[2] = np.sum(
                cm
                * (
                    a2[:, :nterm]
                    + 2.0 * half * a1[:, 1 : nterm + 1]
                    + half * half * a0[:, 2 : nterm + 2]
                ),
                axis=1,
            )
        if n_y == 2:
            b0 = b_c[:, 0]
            b1 = b_c[:, 1]
            yv[1] = np.sum(cy * (b1[:, :nty] + half * b0[:, 1 : nty + 1]), axis=1)
        return s, yv

    return sums
