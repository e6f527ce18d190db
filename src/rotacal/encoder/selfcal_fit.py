"""The fit of a multi-head self-calibration: each head's line shift, the information every
Fourier order carries, and the generalised least-squares solution per order (Kokuyama et al. 2015,
§3; Masuda & Kajitani 1993), with the local rate that turns head delays into angles."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

__all__ = ["head_shifts", "noise_gain", "undetectable_orders"]

#: Half-width (pulses) of the window that gives the local rate used to turn delays into angles.
RATE_WINDOW = 32
#: Information (relative to n, what equally spaced heads give every detectable order) below which
#: a Fourier order counts as undetectable: its noise would be amplified more than tenfold.
_UNDETECTABLE_TOL = 1e-2
#: Revolutions whose spectra are formed and fitted at once: the temporaries stay a few of them,
#: where the whole record's spectra and residuals were each as large as its head differences.
FIT_REVOLUTIONS = 8


def head_shifts(heads: int, pulses_per_rev: int, rotation: str = "forward") -> NDArray[np.int64]:
    """Line shift of each head against head 0: s_i = round(i·m/n) (negated for reverse rotation).

    Heads must sit within half a pitch of their nominal i·360/n positions.
    """
    i = np.arange(heads)
    s = np.rint(i * pulses_per_rev / heads).astype(np.int64)
    return s if rotation == "forward" else (-s) % pulses_per_rev


def _information(shifts: NDArray[np.int64], m: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-order GLS weights g_i = exp(2πi q s_i/m) − 1 (heads 1 … n−1) and the information.

    Kept for the last two line shifts asked for: a fit block by block of revolutions asks for
    the same ones every block (read-only arrays, shared)."""
    key = (np.asarray(shifts, dtype=np.int64).tobytes(), int(m))
    found = _INFORMATION.get(key)
    if found is None:
        found = _information_of(np.asarray(shifts, dtype=np.int64), int(m))
        for arr in found:
            arr.flags.writeable = False
        if len(_INFORMATION) >= 2:  # the two senses of rotation; a large m makes them big
            _INFORMATION.pop(next(iter(_INFORMATION)))
        _INFORMATION[key] = found
    return found


_INFORMATION: dict[tuple[bytes, int], tuple[np.ndarray, np.ndarray]] = {}


def _information_of(shifts: NDArray[np.int64], m: int) -> tuple[np.ndarray, np.ndarray]:
    q = np.arange(m // 2 + 1)
    g = np.exp(2j * np.pi * np.outer(shifts[1:], q) / m) - 1.0
    n = shifts.size
    info = np.sum(np.abs(g) ** 2, axis=0) - np.abs(np.sum(g, axis=0)) ** 2 / n
    return g, info


def undetectable_orders(
    heads: int, pulses_per_rev: int, shifts: NDArray[np.int64] | None = None
) -> list[int]:
    """Fourier orders 1 … m/2 of the deviation that the heads cannot measure.

    For n equally spaced heads on m lines, m divisible by n, these are the multiples of n (seed
    004, §3: "the n-th and its multiple Fourier components … cannot be extracted in principle").
    With other line shifts (``shifts``, one per head, 0 for head 0) an order counts as undetectable
    when the heads carry less than 1 % of the usual information on it (noise gain above 10).
    """
    if shifts is None:
        shifts = head_shifts(heads, pulses_per_rev)
    _, info = _information(shifts, pulses_per_rev)
    bad = info <= _UNDETECTABLE_TOL * heads
    bad[0] = False
    return [int(q) for q in np.flatnonzero(bad)]


def noise_gain(shifts: ArrayLike, pulses_per_rev: int, head: int) -> NDArray[np.complex128]:
    """How one head's own angle noise enters the self-calibrated curve, order by order.

    The fit per order is â(q) = [Σ g_i*·D_i − (Σ g_i*)(Σ D_i)/n]/I(q); head 0's noise N₀ enters
    every D_i with −1, head k's N_k enters D_k with +1 at the head-0 pulse it pairs with, i.e. at
    the line it reads shifted by s_k. So a head's noise at the line it reads appears in the curve
    at that line with the gain κ(q) = −Σ g_i*/(n·I) (head 0) or (g_k* − Σ g_i*/n)/I·e^(2πiqs_k/m)
    (head k) — 1/n at every detectable order for equally spaced heads — averaged over the
    revolutions. A rate from the same head, compensated with this curve, therefore carries that
    head's timing noise twice, partly cancelling.

    Parameters
    ----------
    shifts : array_like of int
        The heads' line shifts s_i (``SelfCalibration.head_line_shifts``).
    pulses_per_rev : int
        m.
    head : int
        The head whose noise is followed.

    Returns
    -------
    ndarray of complex, shape (m//2 + 1,)
        κ(q); 0 at order 0 and at the undetectable orders (set to zero by the fit).

    References
    ----------
    Kokuyama et al. (2015) §3; the fit of :func:`self_calibrate` (generalised least squares
    per order, noise shared through head 0).
    """
    s = np.asarray(shifts, dtype=np.int64)
    m = int(pulses_per_rev)
    g, info = _information(s, m)
    n = s.size
    ok = info > _UNDETECTABLE_TOL * n
    ok[0] = False
    total = np.conj(np.sum(g, axis=0))
    if head == 0:
        num = -total / n
    else:
        q = np.arange(m // 2 + 1)
        num = (np.conj(g[head - 1]) - total / n) * np.exp(2j * np.pi * q * s[head] / m)
    out = np.zeros(m // 2 + 1, dtype=np.complex128)
    out[ok] = num[ok] / info[ok]
    return out


def _gls(diff_spec: np.ndarray, shifts: NDArray[np.int64], m: int) -> tuple[np.ndarray, np.ndarray]:
    """Solve D̂_i(q) = a(q)·g_i(q) for a(q) per order, noise shared through head 0.

    The head differences D_i = e_i − e_0 have covariance σ²(I + 11ᵀ); its inverse is
    (I − 11ᵀ/n)/σ², which gives a(q) = [Σ g_i* D_i − (Σ g_i*)(Σ D_i)/n] / [Σ|g_i|² − |Σ g_i|²/n].
    """
    g, info = _information(shifts, m)
    n = shifts.size
    gc = np.conj(g)
    num = (
        np.einsum("iq,...iq->...q", gc, diff_spec)
        - np.sum(gc, axis=0) * np.sum(diff_spec, axis=-2) / n
    )
    ok = info > _UNDETECTABLE_TOL * n
    a = np.zeros((*diff_spec.shape[:-2], g.shape[1]), dtype=complex)
    a[..., ok] = num[..., ok] / info[ok]
    resid = a[..., None, :] * g
    np.subtract(diff_spec, resid, out=resid)  # in place: one array of the spectra's size less
    return a, resid


def _local_rate_deg_s(mean_times: FloatArray, pitch_deg: float) -> FloatArray:
    """Rate at every paired pulse from the head-averaged times over ±RATE_WINDOW pulses."""
    n = mean_times.size
    w = min(RATE_WINDOW, max(1, (n - 1) // 2))
    rate = np.empty(n)
    inner = slice(w, n - w)
    rate[inner] = 2 * w * pitch_deg / (mean_times[2 * w :] - mean_times[: n - 2 * w])
    rate[:w] = rate[w]
    rate[n - w :] = rate[n - w - 1]
    return rate


def _data_shifts(
    heads: int, m: int, rotation: str, mean_offsets_arcsec: FloatArray
) -> NDArray[np.int64]:
    """Line shift of each head from the data: the nominal position plus the measured offset.

    The mean angle between head 0's pulse j and head i's paired pulse is s_i·Δθ − h_i, so with h_i
    within half a pitch of its nominal ±i·360/n the line shift is the whole number of pitches in
    (±i·360/n + mean offset). This decides the line even when i·m/n ends in about one half.
    """
    pitch_arcsec = 360.0 / m * 3600.0
    sign = 1.0 if rotation == "forward" else -1.0
    nominal = sign * np.arange(1, heads) * 360.0 / heads * 3600.0
    s = np.rint((nominal + mean_offsets_arcsec) / pitch_arcsec).astype(np.int64) % m
    return np.concatenate(([0], s)).astype(np.int64)


def _parseval_ss(resid: np.ndarray, m: int) -> float:
    """Sum of squares in the sample domain of residual rfft spectra (last axis: orders)."""
    w = np.full(resid.shape[-1], 2.0)
    w[0] = 1.0
    if m % 2 == 0:
        w[-1] = 1.0
    return float(np.sum(w * np.abs(resid) ** 2)) / m


def fit_revolutions(
    used: FloatArray, shifts_by_sense: dict[str, NDArray[np.int64]], m: int
) -> dict[str, tuple[np.ndarray, float, NDArray[np.int64]]]:
    """The fit of every revolution for each candidate sense, block by block of revolutions.

    Parameters
    ----------
    used : ndarray, shape (R, n − 1, m), arcsec
        Head differences of heads 1 … n−1 against head 0 over R whole revolutions.
    shifts_by_sense : dict of str to ndarray of int
        The heads' line shifts s_i under each sense of rotation tried.
    m : int
        Pulses per revolution.

    Returns
    -------
    dict of sense to (a, ss, shifts)
        a: the fitted rfft orders of each revolution's curve, shape (R, m//2 + 1); ss: the sum of
        squares of what the fit leaves in the head differences (arcsec², added exactly over the
        blocks); the shifts.

    References
    ----------
    Kokuyama et al. (2015) §3 (the equal-division-averaged method); :func:`_gls`.
    """
    revs = used.shape[0]
    fitted = {s: np.empty((revs, m // 2 + 1), dtype=complex) for s in shifts_by_sense}
    parts: dict[str, list[float]] = {s: [] for s in shifts_by_sense}
    for r0 in range(0, revs, FIT_REVOLUTIONS):
        block = used[r0 : r0 + FIT_REVOLUTIONS]
        spec = np.fft.rfft(block - block.mean(axis=2, keepdims=True), axis=-1)
        for sense, shifts in shifts_by_sense.items():
            a, resid = _gls(spec, shifts, m)
            fitted[sense][r0 : r0 + FIT_REVOLUTIONS] = a
            parts[sense].append(_parseval_ss(resid, m))
    return {s: (fitted[s], math.fsum(parts[s]), shifts_by_sense[s]) for s in shifts_by_sense}
