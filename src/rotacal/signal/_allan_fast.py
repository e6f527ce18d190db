"""Sums of squared second differences at many cluster sizes (private kernel of ``allan``).

For a phase record ``x_0 … x_{N-1}`` the overlapping Allan variance at cluster size ``m`` needs

    S(m) = Σ_{i=0}^{L-1} (x_{i+2m} − 2·x_{i+m} + x_i)²,   L = N − 2m.

:func:`direct_sums` evaluates this literally, O(L) per ``m``. :func:`second_difference_sums`
returns it for *every* requested ``m`` in O(N log² N) total, exactly up to floating-point
rounding. The derivation (this module is its reference):

1. **Expansion.** With ``R(ℓ) = Σ_{i<N−ℓ} z_i z_{i+ℓ}`` (full-range lagged products),
   ``H(m) = Σ_{j<m} z_j z_{j+m}`` (the inner product of the two halves of the first 2m samples)
   and ``T(m)`` the same for the last 2m samples,

       S(m) = Σ_{i<L} z_i² + 4·Σ_{i<L} z_{i+m}² + Σ_{i<L} z_{i+2m}²
              − 4·(2R(m) − H(m) − T(m)) + 2·R(2m),

   because ``Σ_{i<L} z_i z_{i+m} = R(m) − T(m)``, ``Σ_{i<L} z_{i+m} z_{i+2m} = R(m) − H(m)`` and
   ``Σ_{i<L} z_i z_{i+2m} = R(2m)``. Squares come from prefix sums (built in blocks, so that
   they do not drift over the record); ``R`` for all lags from one batched FFT correlation over
   blocks (overlap-add of per-block spectra; for lags longer than a block, a partitioned
   correlation along the block index); ``H`` and ``T`` for all ``m`` from a divide and conquer
   of FFT correlations (the region ``j < m`` is a triangle in the (j, lag) plane: its lower half
   is one full block correlation, its two quarter triangles recurse), O(K log² K) for ``m < K``;
   its top levels at once from the spectra of 2·32 blocks (a triangular sum over the blocks,
   :func:`_head_block_products`). No transform is longer than a few 10⁵ points: longer ones
   stream the whole record through memory in each pass and run ~5× slower per point.

2. **Conditioning.** The expansion subtracts large sums; its rounding error is about
   ``ε·log N·Σz²`` against a result ``S(m)``. A straight line is annihilated by the second
   difference, so the global best line is removed first (caller). For red noise (flicker or
   random-walk rate) ``Σz²/S(m)`` still grows like a power of ``N/m``, so cluster sizes are
   processed in groups ``[M, 2^G·M)``: per group, ``x`` is replaced by ``z = x − g`` where ``g``
   is the continuous piecewise-linear interpolant of ``x`` at knots spaced ``B = 4·M_hi``. The
   second difference of ``g`` is a sum of non-overlapping tents ``Δ_k·h_m(i − q_k)`` at the knots
   (``Δ_k`` the slope change, ``h_m(j) = m − |j + m|`` on ``−2m < j < 0``), so

       S_x(m) = S_z(m) + 2·Σ_k Δ_k·Σ_i d_i(z)·h_m(i − q_k) + Σ_k Δ_k²·(2m³ + m)/3,

   where the middle sum needs only sums of ``z`` and ``t·z`` over windows around each knot
   (local prefix sums, O(1) per knot and ``m``). Within a group ``Σz²/S(m)`` is bounded by a
   constant that depends on ``B/m`` only, not on ``N``. A rate ramp makes ``x`` a parabola, whose
   bumps between knots break that bound: the best parabola is removed exactly first and its share
   added back in closed form (:func:`_without_parabola`, :class:`_RampTerms`).

3. **Guards.** Cluster sizes below ``DIRECT_BELOW`` and those with fewer than ``DIRECT_TAIL``
   terms (``m`` near ``N/2``, where ``S`` is a sum of few terms) are computed directly (cheap
   there). Every fast value carries a rounding-error estimate; any value whose estimate exceeds
   ``FAST_RTOL`` is recomputed directly, so a result is never silently imprecise.
"""

from __future__ import annotations

import math

import numpy as np

from rotacal._jit import use_numba
from rotacal.signal._phase import RUNNING_SUM_BLOCK, running_sum

#: Cluster sizes below this are computed directly (O(N) each).
DIRECT_BELOW = 8
#: Cluster sizes with fewer than this many second differences are computed directly (O(L)).
DIRECT_TAIL = 256
#: Each group of the fast method spans this many octaves of cluster size.
GROUP_OCTAVES = 3
#: Leaf size of the divide and conquer for the head/tail products.
LEAF = 16
#: A fast value whose estimated relative rounding error exceeds this is recomputed directly.
FAST_RTOL = 1e-8
#: Largest number of complex FFT elements held at once (bounds the working memory).
_FFT_BATCH = 1 << 18
#: More lags than this (samples): :func:`_lagged_products_long`, with blocks of _LONG_BLOCK.
_LONG_ABOVE = 1 << 17
_LONG_BLOCK = 1 << 15
#: Records of at most this many lag blocks take one whole-record power spectrum instead.
_WHOLE_BLOCKS = 4
#: Chunk (samples) of the direct method: keeps its temporaries in cache.
_DIRECT_CHUNK = 1 << 14
_EPS = float(np.finfo(np.float64).eps)


# ------------------------------------------------------------------------------ direct method
def direct_sums(
    z: np.ndarray, ms: np.ndarray, *, firsts: np.ndarray | None = None, jit: bool | None = None
) -> np.ndarray:
    """``S(m)`` by the definition, O(N − 2m) per cluster size (chunked, whole-array).

    Parameters
    ----------
    z : phase samples (any unit u; a straight line may have been removed).
    ms : cluster sizes (samples), each with ``N − 2m ≥ 1``.
    firsts : the first term i of each sum (default 0): a record read in chunks sums only the
        second differences that end in the newest chunk.
    jit : run the Numba twin (:mod:`rotacal.signal._allan_jit`, ≤ 1e-12 relative from this
        path); ``None`` asks :func:`rotacal._jit.use_numba` with the record's length.

    Returns
    -------
    ndarray — ``S(m)`` in u².

    References
    ----------
    NIST SP 1065 (Riley 2008), eq. (11): the overlapping Allan variance from phase data.
    """
    if ms.size and use_numba(z.size, jit):
        from rotacal.signal._allan_jit import direct_sums_jit

        starts = np.zeros(ms.size, dtype=np.int64) if firsts is None else firsts
        return np.asarray(
            direct_sums_jit(
                np.ascontiguousarray(z, dtype=np.float64),
                ms.astype(np.int64),
                np.asarray(starts, dtype=np.int64),
            )
        )
    n = z.size
    out = np.empty(ms.size)
    buf = np.empty(min(_DIRECT_CHUNK, n))
    starts_at = [0] * ms.size if firsts is None else np.asarray(firsts).tolist()
    for k, m in enumerate(ms.tolist()):
        L = n - 2 * m
        acc = 0.0
        for s in range(starts_at[k], L, _DIRECT_CHUNK):
            e = min(L, s + _DIRECT_CHUNK)
            b = buf[: e - s]
            np.multiply(z[s + m : e + m], -2.0, out=b)
            b += z[s + 2 * m : e + 2 * m]
            b += z[s:e]
            np.multiply(b, b, out=b)
            acc += float(b.sum())  # pairwise summation; BLAS dot avoided (thread spin-up)
        out[k] = acc
    return out


# ------------------------------------------------------------------------------ FFT helpers
def _lagged_products(z: np.ndarray, lag_max: int) -> np.ndarray:
    """``R(ℓ) = Σ_{i<N−ℓ} z_i z_{i+ℓ}`` for ``ℓ = 0 … lag_max − 1``.

    Blocks of length ``P ≥ lag_max`` are transformed once (length 2P, zero padded); the spectrum
    of block ``b`` followed by block ``b + 1`` is ``U_b + (−1)^k U_{b+1}``, and the per-block
    correlation spectra are summed before one inverse transform. A record shorter than one
    block takes its power spectrum instead (one forward, one inverse transform); lags longer
    than ``_LONG_ABOVE`` go by :func:`_lagged_products_long` (blocks shorter than the lags).
    """
    import scipy.fft as sfft  # imported where used: the rate analysis never is (0.1 s)

    n = z.size
    if lag_max > _LONG_ABOVE and n > _WHOLE_BLOCKS * _LONG_BLOCK:
        return _lagged_products_long(z, lag_max, _LONG_BLOCK)
    p = sfft.next_fast_len(max(lag_max, 4096), real=True)
    nb = -(-n // p)
    if nb <= _WHOLE_BLOCKS:
        # few blocks: the power spectrum of the whole record, zero padded past n + lag_max, costs
        # fewer transform points than the 2·nb·p of the blocks (4× fewer at nb = 2)
        spec = sfft.rfft(z, n=sfft.next_fast_len(n + lag_max, real=True))
        re, im = spec.real, spec.imag  # |U|² in the spectrum's own memory (no temporaries)
        np.square(re, out=re)
        np.square(im, out=im)
        re += im
        im[:] = 0.0
        whole: np.ndarray = sfft.irfft(spec, n=2 * (spec.size - 1))
        return whole[:lag_max]  # a view: the caller reads a few lags and lets it go
    sign = np.ones(p + 1)
    sign[1::2] = -1.0
    acc = np.zeros(p + 1, dtype=np.complex128)
    rows = max(1, _FFT_BATCH // (p + 1))
    prev: np.ndarray | None = None  # spectrum of the first block of the current batch
    for s in range(nb - 1, -1, -rows):  # walk backwards so block b + 1 is always known
        lo = max(0, s - rows + 1)
        if (s + 1) * p <= n:  # whole blocks: a view of the record, no padded copy of it
            batch = z[lo * p : (s + 1) * p].reshape(s + 1 - lo, p)
        else:
            batch = np.zeros((s + 1 - lo, p))
            batch.ravel()[: n - lo * p] = z[lo * p :]
        spec = sfft.rfft(batch, n=2 * p, axis=1)
        nxt = np.empty_like(spec)
        nxt[:-1] = spec[1:]
        nxt[-1] = prev if prev is not None else 0.0
        nxt *= sign
        nxt += spec
        prev = spec[0].copy()
        np.conjugate(spec, out=spec)
        acc += np.einsum("ij,ij->j", spec, nxt)
    r: np.ndarray = sfft.irfft(acc, n=2 * p)[:lag_max]
    return r


def _lagged_products_long(z: np.ndarray, lag_max: int, p: int) -> np.ndarray:
    """``R(ℓ)`` for ``ℓ < lag_max`` of a long record with lags longer than one block of ``p``.

    Uniformly partitioned correlation, transforms of ``2p`` points only: with ``U_b`` the
    spectrum (length 2p) of block ``b`` and ``W_c = U_c + (−1)^k·U_{c+1}`` that of the window
    ``[cp, cp + 2p)``, the lag block ``d`` of ``R`` is ``irfft(Σ_b conj(U_b)·W_{b+d})[:p]``
    (no wrap-around: ``i + r < 2p``). Bin by bin, that sum over the blocks is a correlation along
    the block index, taken by FFTs of length ``Q ≥ n_b + n_d`` along it (no wrap-around either:
    ``b + d + 1 < Q``). As ``W`` is ``U`` plus ``U`` shifted by one block, its transform along
    the blocks is ``Û(f)·(1 + (−1)^k·e^{2πif/Q})``, so one forward transform serves both:
    ``C = ifft(|Û|²·(1 + (−1)^k·e^{2πif/Q}))``, in chunks of bins, each chunk's result written
    over its own bins of the block spectra. Memory: the spectra (16 bytes a sample) and the
    result, with cache-sized temporaries, where a whole-record transform holds several
    record-sized buffers (and streams through each of them ~24 times).
    """
    import scipy.fft as sfft

    n = z.size
    nb = -(-n // p)
    nd = -(-lag_max // p)
    bins = p + 1
    spec = np.empty((nb, bins), dtype=np.complex128)
    step = max(1, _FFT_BATCH // bins)
    full = n // p
    for b0 in range(0, nb, step):
        b1 = min(nb, b0 + step)
        if b1 <= full:
            batch = z[b0 * p : b1 * p].reshape(b1 - b0, p)
        else:
            batch = np.zeros((b1 - b0, p))
            batch.ravel()[: n - b0 * p] = z[b0 * p :]
        spec[b0:b1] = sfft.rfft(batch, n=2 * p, axis=1)
    q = sfft.next_fast_len(nb + nd)
    width = 2 * max(1, _FFT_BATCH // (2 * q))  # even: each chunk starts on an even bin
    shift = np.exp(2j * np.pi * np.arange(q) / q)
    factor = np.empty((q, width), dtype=np.complex128)
    factor[:, 0::2] = (1.0 + shift)[:, None]  # (−1)^k = +1
    factor[:, 1::2] = (1.0 - shift)[:, None]  # (−1)^k = −1
    for k0 in range(0, bins, width):
        k1 = min(bins, k0 + width)
        fu = sfft.fft(spec[:, k0:k1], n=q, axis=0)
        power = fu.real * fu.real
        power += fu.imag * fu.imag
        np.multiply(power, factor[:, : k1 - k0], out=fu)
        spec[:nd, k0:k1] = sfft.ifft(fu, axis=0, overwrite_x=True)[:nd]
    out = np.empty(nd * p)
    rows = max(1, _FFT_BATCH // bins)
    for d0 in range(0, nd, rows):
        d1 = min(nd, d0 + rows)
        out[d0 * p : d1 * p] = sfft.irfft(spec[d0:d1], n=2 * p, axis=1)[:, :p].ravel()
    return out[:lag_max]


def _correlate_rows(u: np.ndarray, v: np.ndarray, n: int, nout: int) -> np.ndarray:
    """``c[t, l] = Σ_r Σ_j u[r, t, j]·v[r, t, j + l]`` for ``l < nout`` by length-``n`` FFTs.

    ``u`` and ``v`` have shape (signals, rows, ·); the signals' spectra are summed.
    """
    import scipy.fft as sfft

    ns, nr = u.shape[0], u.shape[1]
    out = np.empty((nr, nout))
    step = max(1, _FFT_BATCH // (ns * (n // 2 + 1)))
    for s in range(0, nr, step):
        e = min(nr, s + step)
        acc: np.ndarray | None = None
        for r in range(ns):
            su = sfft.rfft(u[r, s:e], n=n, axis=1)
            sv = sfft.rfft(v[r, s:e], n=n, axis=1)
            np.conjugate(su, out=su)
            su *= sv
            if acc is None:
                acc = su
            else:
                acc += su
        assert acc is not None
        out[s:e] = sfft.irfft(acc, n=n, axis=1)[:, :nout]
    return out


def _smooth_size(k: int) -> tuple[int, int]:
    """The smallest ``leaf·2^j ≥ k`` with a smooth ``leaf`` in ``[LEAF, 2·LEAF)`` (fast FFTs)."""
    best = (0, 0)
    for leaf in _LEAVES:
        j = max(0, math.ceil(math.log2(max(k, 1) / leaf)))
        size = leaf << j
        if best[0] == 0 or size < best[0]:
            best = (size, leaf)
    return best


_LEAVES = (16, 18, 20, 24, 25, 27, 30)
#: Levels of the divide and conquer taken at once by block spectra: at most this many ...
TOP_LEVELS = 5
#: ... and only while the blocks keep at least this many samples.
TOP_BLOCK = 1 << 17


def _top_levels(k: int, leaf: int) -> int:
    """How many top levels of :func:`_half_products` (size ``k``) :func:`_head_block_products`
    takes: the block ``k >> top`` stays a multiple of the leaf and ≥ :data:`TOP_BLOCK`."""
    top = 0
    while top < TOP_LEVELS and (k >> (top + 1)) >= max(TOP_BLOCK, leaf):
        top += 1
    return top


def _head_block_products(zs: np.ndarray, p: int, nq: int, chunk: int = 2048) -> np.ndarray:
    """``t[qp + r] = Σ_rows Σ_{j<qp} zs[row, j]·zs[row, j + qp + r]`` for ``q < nq``, ``r < p``:
    the part of the head products ``H(m) = Σ_{j<m} z_j z_{j+m}`` (``m = qp + r``) whose first
    index lies in a whole block before ``m``'s own block — what the top ``log2(nq)`` levels of
    :func:`_half_products` compute, without transforms as long as the record (a real FFT of
    10⁷ points streams memory in each of its ~24 passes; blocks of ``2p`` points stay cached).

    Uniformly partitioned correlation: with ``V_c`` the spectrum (length 2p) of block ``c`` of
    ``p`` samples, ``W_c = V_c + (−1)^k·V_{c+1}`` is that of the window ``[cp, cp + 2p)`` (the
    second block is shifted by half the length), and ``irfft(conj(V_b)·W_{b+q})[r]`` is
    ``Σ_{i<p} zs[bp + i]·zs[(b + q)p + i + r]`` for ``r < p`` without wrap-around (``i + r <
    2p``). The block ``q`` of ``t`` is therefore ``irfft(Σ_{b<q} conj(V_b)·W_{b+q})[:p]``: a
    triangular sum over the blocks, bin by bin, in chunks of ``chunk`` bins (cache-sized);
    O(nq·N/2) complex products against O(N log N) per level it replaces. ``zs`` has at least
    ``2·nq·p`` columns (any unit u; result u²).
    """
    import scipy.fft as sfft

    ns = zs.shape[0]
    bins = p + 1
    sign = np.ones(bins)
    sign[1::2] = -1.0
    acc = np.zeros((nq, bins), dtype=np.complex128)
    spec = np.empty((2 * nq, bins), dtype=np.complex128)  # one buffer for the rows in turn
    step = max(1, _FFT_BATCH // bins)  # transforms in batches: small temporaries, reused
    for r in range(ns):
        blocks = zs[r, : 2 * nq * p].reshape(2 * nq, p)
        for b0 in range(0, 2 * nq, step):
            spec[b0 : b0 + step] = sfft.rfft(blocks[b0 : b0 + step], n=2 * p, axis=1)
        for k0 in range(0, bins, chunk):
            k1 = min(bins, k0 + chunk)
            v = spec[:, k0:k1]
            w = v[1:] * sign[k0:k1]
            w += v[:-1]
            u = np.conjugate(v[:nq])
            a = acc[:, k0:k1]
            for q in range(1, nq):
                a[q] += np.einsum("bk,bk->k", u[:q], w[q : 2 * q])
    del spec
    out = np.empty(nq * p)
    rows_per = max(1, _FFT_BATCH // p)
    for q0 in range(0, nq, rows_per):
        q1 = min(nq, q0 + rows_per)
        out[q0 * p : q1 * p] = sfft.irfft(acc[q0:q1], n=2 * p, axis=1)[:, :p].ravel()
    return out


def _half_products(zs: np.ndarray, k: int, leaf: int, jit: bool = False) -> np.ndarray:
    """``H[m] = Σ_rows Σ_{j<m} zs[r, j]·zs[r, j + m]`` for ``m < k`` (``k = leaf·2^j``).

    ``zs`` has one signal per row (the head, and the reversed tail, of the record) and at least
    ``2k + k/2`` columns (zero padded). Node ``t`` of size ``s`` covers ``m ∈ [t·s, (t + 1)·s)``
    with ``j`` offset ``t·s`` and partner offset ``2t·s``; the upper half of its ``m`` range takes
    the full correlation of its first ``s/2`` samples, the rest recurses (two children of size
    ``s/2``) down to leaves that are summed directly. The rows' correlation spectra are added
    before the inverse transform.
    """
    ns = zs.shape[0]
    h = np.zeros(k)
    s = k
    top = _top_levels(k, leaf)
    if top:  # the first top levels at once from block spectra (no record-long transforms)
        s = k >> top
        h += _head_block_products(zs, s, 1 << top)
    while s > leaf:
        half = s // 2
        nodes = k // s
        u = zs[:, :k].reshape(ns, nodes, s)[:, :, :half]
        v = zs[:, half : half + 2 * k].reshape(ns, nodes, 2 * s)[:, :, :s]
        h.reshape(nodes, s)[:, half:] += _correlate_rows(u, v, s, half)
        s = half
    if jit:  # the leaves by the Numba twin: the same terms in the same order, no temporaries
        from rotacal.signal._allan_jit import leaf_products_jit

        h += leaf_products_jit(np.ascontiguousarray(zs), k, leaf)
        return h
    nodes = k // leaf
    u = zs[:, :k].reshape(ns, nodes, leaf)
    v = zs[:, : 2 * k].reshape(ns, nodes, 2 * leaf)
    hl = np.zeros((ns, nodes, leaf))
    for j in range(leaf - 1):
        hl[:, :, j + 1 :] += u[:, :, j : j + 1] * v[:, :, 2 * j + 1 : j + leaf]
    h += hl.sum(axis=0).reshape(k)
    return h


# ------------------------------------------------------------------------------ one group
def _group_sums(
    x: np.ndarray, ms: np.ndarray, m_hi: int, jit: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """``S(m)`` and a rounding-magnitude estimate for cluster sizes ``ms`` (all ``< m_hi``)."""
    n = x.size
    seg = 4 * m_hi
    last_knot = n - 1 - 2 * m_hi
    knots = np.arange(seg, last_knot + 1, seg, dtype=np.int64)
    if knots.size:
        nodes = np.concatenate(([0], knots, [n - 1]))
        vals = x[nodes]
        slopes = np.diff(vals) / np.diff(nodes)
        delta = np.diff(slopes)
        z = np.interp(np.arange(n, dtype=np.float64), nodes.astype(np.float64), vals)
        np.subtract(x, z, out=z)  # x − g, in the interpolant's memory
    else:
        delta = np.zeros(0)
        z = x
    L = n - 2 * ms
    # squares
    c2, _ = _prefix_sums(z, square=True)
    sq = c2[L] + 4.0 * (c2[ms + L] - c2[ms]) + (c2[n] - c2[2 * ms])
    # full-range lagged products up to lag 2·m_hi
    r = _lagged_products(z, 2 * m_hi)
    # head and tail half products (their sum), H(m) + T(m)
    k, leaf = _smooth_size(m_hi)
    width = min(2 * k, n)
    zs = np.zeros((2, 2 * k + k // 2 + leaf))
    zs[0, :width] = z[:width]
    zs[1, :width] = z[::-1][:width]
    ht = _half_products(zs, k, leaf, jit)
    s = sq - 4.0 * (2.0 * r[ms] - ht[ms]) + 2.0 * r[2 * ms]
    mag = np.full(ms.size, c2[n])
    if delta.size:
        cross, tents = _knot_terms(z, knots, delta, ms, m_hi)
        s += 2.0 * cross + tents
        mag += 2.0 * np.abs(cross) + tents + sq
    return s, mag


def _knot_terms(
    z: np.ndarray, knots: np.ndarray, delta: np.ndarray, ms: np.ndarray, m_hi: int
) -> tuple[np.ndarray, np.ndarray]:
    """``Σ_k Δ_k Σ_i d_i(z)·h_m(i − q_k)`` and ``Σ_k Δ_k²·(2m³ + m)/3`` for each ``m``.

    With local coordinates ``t = u + c`` around each knot (``c = 2·m_hi``; the windows
    ``[q_k − c, q_k + c)`` tile the record because the knots are ``2c`` apart), the knot sum of
    ``Σ_u (α + β·u)·z_{q_k+u}`` over ``u ∈ [a, b]`` needs only the prefix sums ``D0``, ``D1`` of
    ``y_t = Σ_k Δ_k·z_{q_k−c+t}`` and ``t·y_t``: O(N) once, then O(1) per ``m``.
    """
    c = 2 * m_hi
    w = 2 * c
    start = int(knots[0]) - c
    zw = z[start : start + knots.size * w].reshape(knots.size, w)
    y = np.einsum("k,kt->t", delta, zw)
    d0, _ = _prefix_sums(y)
    d1, _ = _prefix_sums(y * np.arange(w, dtype=np.float64))
    mm = ms.astype(np.int64)
    cross = np.zeros(ms.size)
    for mult, sh in ((1.0, 0), (-2.0, 1), (1.0, 2)):
        sv = sh * mm
        # W_s = Σ_{u=s−2m}^{s−m} (u − s + 2m)·z_{q+u} + Σ_{u=s−m+1}^{s} (s − u)·z_{q+u}
        for a, b, alpha, beta in (
            (sv - 2 * mm, sv - mm, 2 * mm - sv, 1.0),
            (sv - mm + 1, sv, sv, -1.0),
        ):
            lo = a + c
            hi = b + c + 1
            cross += mult * ((alpha - beta * c) * (d0[hi] - d0[lo]) + beta * (d1[hi] - d1[lo]))
    msf = ms.astype(np.float64)
    tents = float(np.einsum("k,k->", delta, delta)) * (2.0 * msf**3 + msf) / 3.0
    return cross, tents


# ------------------------------------------------------------------------------ public kernel
def second_difference_sums(
    z: np.ndarray, ms: np.ndarray, *, jit: bool | None = None
) -> tuple[np.ndarray, int]:
    """``S(m)`` for the sorted unique cluster sizes ``ms`` (``1 ≤ m``, ``N − 2m ≥ 1``).

    Parameters
    ----------
    z : phase samples (unit u) with the best straight line already removed.
    ms : sorted unique cluster sizes (samples).
    jit : the direct sums by their Numba twin (see :func:`direct_sums`); being cheaper, it also
        takes the groups of cluster sizes where it costs less than the fast method.

    Returns
    -------
    (sums, n_direct) — ``S(m)`` in u², and how many of them were computed directly.

    References
    ----------
    NIST SP 1065 (Riley 2008), eq. (11) (the sum evaluated); the O(N log² N) evaluation is
    derived in this module's docstring (expansion, divide and conquer, local detrending).
    Measured against the literal sum: ≤ 5e-10 relative for white/flicker/random-walk FM, white
    PM and a dominant rate ramp (tests/signal/test_allan.py); against the literal sum in long
    double on the same phase ≤ 1e-12 for white FM and ramps, ≤ 3e-11 for random-walk FM, and
    ≤ 1e-12 at spot-checked m of the 10⁷-sample gyro record of ``benchmarks/bench_allan.py``
    (white + random-walk rate noise), with and without its rate ramp.
    """
    n = z.size
    jit = use_numba(n, jit)
    # the Numba twin of the direct sum is ~8× faster: more cluster sizes are cheaper directly
    direct_cost = 1.0 / _JIT_DIRECT_SPEEDUP if jit else 1.0
    out = np.empty(ms.size)
    direct = (ms < DIRECT_BELOW) | (n - 2 * ms < DIRECT_TAIL)
    nlog = math.log2(max(n, 2))
    parabola: tuple[np.ndarray, _RampTerms | None] | None = None  # made for the first fast group
    for lo, hi in _groups(n, int(ms[-1])):
        sel = np.flatnonzero(~direct & (ms >= lo) & (ms < hi))
        if not sel.size:
            continue
        group = ms[sel]
        m_hi = int(group[-1]) + 1
        cost_direct = direct_cost * float(np.sum(n - 2 * group))
        cost_fast = _FAST_COST * n * (1.0 + math.log2(m_hi) ** 2 * m_hi / n)
        if cost_direct <= cost_fast:
            direct[sel] = True
            continue
        if parabola is None:
            w, curvature = _without_parabola(z)
            parabola = (w, _RampTerms(w, curvature, nlog) if curvature else None)
        w, ramp = parabola
        s, mag = _group_sums(w, group, m_hi, jit)
        if ramp is not None:
            ramp.add_to(group, s, mag)
        bad = ~(s > 0) | (_ERR_FACTOR * _EPS * nlog * mag > FAST_RTOL * s)
        out[sel] = s
        direct[sel[bad]] = True
    idx = np.flatnonzero(direct)
    if idx.size:
        out[idx] = direct_sums(z, ms[idx], jit=jit)
    return out, int(idx.size)


def _without_parabola(z: np.ndarray) -> tuple[np.ndarray, float]:
    """``w = z − a·T`` with ``T_k = (k − c)² − t̄`` (``c = N // 2``, ``t̄`` the mean of the
    squares rounded to an integer) and the fitted curvature ``a``
    rounded so that every ``a·T_k`` is exact; returns ``(w, 2a)``, ``2a`` being the second
    difference of ``a·T`` per m² (0.0 and ``z`` itself when ``T`` leaves no bits for ``a``).

    A rate ramp makes the phase a parabola, which the piecewise-linear detrending of each group
    leaves as bumps of height ``a·B²/4``: ``Σz²/S(m)`` then grows like ``(B/m)⁴`` and the guard
    sends thousands of cluster sizes to the direct method. Because ``a·T_k`` is exact (``a`` has
    at most ``53 − bits(T_max)`` significant bits, ``T_k`` is an integer below ``2^bits``), the
    only rounding is that of ``z − a·T``, ≤ ε/2·|w_k| per point, far below the direct method's
    own ε·|z_k|; and ``x_{i+2m} − 2x_{i+m} + x_i`` of ``a·T`` is exactly ``2a·m²``.
    """
    n = z.size
    c = n // 2
    t_max = max(c, n - 1 - c) ** 2
    bits = 53 - t_max.bit_length()
    if bits < 1:
        return z, 0.0
    u = np.arange(n, dtype=np.float64)
    u -= c
    u /= max(c, 1)  # in [−1, 1]: a well-conditioned least-squares fit of 1, u, u²
    u2 = u * u
    powers = [float(n), float(np.sum(u)), float(np.sum(u2)), float(np.dot(u, u2))]
    powers.append(float(np.dot(u2, u2)))
    gram = np.array([powers[0:3], powers[1:4], powers[2:5]])
    rhs = np.array([float(np.sum(z)), float(np.dot(u, z)), float(np.dot(u2, z))])
    coef = float(np.linalg.solve(gram, rhs)[2]) / float(max(c, 1)) ** 2
    del u, u2
    if not (math.isfinite(coef) and coef != 0.0):
        return z, 0.0
    mant, expo = math.frexp(coef)
    a = math.ldexp(round(math.ldexp(mant, bits)), expo - bits)
    if a == 0.0:
        return z, 0.0
    t = np.arange(-c, n - c, dtype=np.float64)
    np.multiply(t, t, out=t)  # exact integers below 2^53
    t -= float(round(float(np.mean(t))))  # keeps w small; still exact integers, |T − t̄| < T_max
    t *= a  # exact: a has at most 53 − bits(T_max) significant bits
    np.subtract(z, t, out=t)
    return t, 2.0 * a


def _prefix_sums(v: np.ndarray, *, square: bool = False) -> tuple[np.ndarray, float]:
    """Prefix sums ``P[i] = Σ_{j<i} v_j`` (or of ``v_j²``; ``P[0] = 0``, ``N + 1`` values) and
    the largest block sum of ``|v|`` (of ``v²``), built in blocks of ``b`` samples
    (:func:`~rotacal.signal._phase.running_sum`: a running sum within each block, the blocks'
    (pairwise) totals added in long double). Each ``P[i]`` is then
    off by at most ``u·(b·max_block Σ|v| + |P[i]|)`` (u = ε/2), where one running sum over the
    record drifts by up to ``u·i·max|P|``: for the squares of a 10⁷-sample phase that drift
    alone cost S(m) ~1e-10 relative (their differences are much smaller than their sums).
    """
    n = v.size
    prefix = np.empty(n + 1)
    prefix[0] = 0.0
    body = prefix[1:]
    if square:
        np.square(v, out=body)
    else:
        body[:] = v
    magnitudes = body if square else np.abs(body)
    block_abs = float(np.max(np.add.reduceat(magnitudes, np.arange(0, n, RUNNING_SUM_BLOCK))))
    running_sum(body)
    return prefix, block_abs


class _RampTerms:
    """The exact parabola's share of ``S(m)``: with ``d_i(x) = d_i(w) + 2a·m²``,

        S_x(m) = S_w(m) + 2·(2a·m²)·D_w(m) + L·(2a·m²)²,

    ``D_w(m) = Σ_{i<L} d_i(w)``, which telescopes to window sums at the ends of the record:
    ``Σ w[N−m, N) − Σ w[N−2m, N−m) − Σ w[m, 2m) + Σ w[0, m)``, taken from prefix sums of ``w``
    built in blocks (a running sum within each block, the blocks' totals summed in long double),
    so that each prefix sum is off by at most ``u·(b·max_block Σ|w| + |P|)`` (u = ε/2, b the
    block; :func:`_prefix_sums`): that bound enters each value's error magnitude.
    """

    def __init__(self, w: np.ndarray, curvature: float, nlog: float) -> None:
        self.curvature = curvature
        b = RUNNING_SUM_BLOCK
        self.prefix, block_abs = _prefix_sums(w)
        u = 0.5 * _EPS
        # D_w is 8 prefix sums with ± signs; the bound in units of the guard's magnitude
        err_d = 8.0 * u * (b * block_abs + 2.0 * float(np.max(np.abs(self.prefix))))
        self.d_err = err_d / (_ERR_FACTOR * _EPS * nlog)

    def add_to(self, ms: np.ndarray, s: np.ndarray, mag: np.ndarray) -> None:
        """Add the parabola's terms to the group's sums ``s`` and magnitudes ``mag``."""
        p = self.prefix
        n = p.size - 1
        d = (p[n] - p[n - ms]) - (p[n - ms] - p[n - 2 * ms]) - (p[2 * ms] - p[ms]) + p[ms]
        step = self.curvature * ms.astype(np.float64) ** 2  # d_i of the parabola, 2a·m²
        cross = 2.0 * step * d
        tail = (n - 2 * ms) * step * step
        s += cross + tail
        mag += np.abs(cross) + tail + 2.0 * np.abs(step) * self.d_err


#: Rounding error of a fast value ≈ this × ε × log2(N) × magnitude of its terms (measured ≤ 135).
_ERR_FACTOR = 64.0
#: Cost of one fast group in units of one direct pass over N samples (measured, rough).
_FAST_COST = 25.0
#: Speed of the Numba direct sum against the NumPy one (measured ~9× at 10⁷ samples).
_JIT_DIRECT_SPEEDUP = 8.0


def _groups(n: int, m_max: int) -> list[tuple[int, int]]:
    """Cluster-size groups ``[lo, hi)``; all sizes too large for interior knots form the last."""
    groups = []
    lo = DIRECT_BELOW
    while lo <= m_max:
        hi = lo << GROUP_OCTAVES
        if 4 * hi > n - 1 - 2 * hi:  # no interior knot: the global line, one group to the end
            groups.append((lo, m_max + 1))
            break
        groups.append((lo, hi))
        lo = hi
    return groups
