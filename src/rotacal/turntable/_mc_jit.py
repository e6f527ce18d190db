"""The Monte Carlo check in one compiled pass (private; imports Numba: load it only through
:func:`rotacal.turntable.fast.compiled_monte_carlo`).

For each block of draws: the Philox4x64-10 words of the stream (:mod:`rotacal.turntable.stream`),
the errors χ and the sine and cosine of the angles from their uniforms, the recursion
D ← A_kᵀ·D·A_k·E_k of seed 001's eqs. (17)–(24) (the operations of
:func:`rotacal.turntable.matrices._fast_kernel` in its order, as the compiled kernel of
:mod:`rotacal.turntable.fast` does them), and the tallies: maxima, histograms, draws outside the
requirement, and the |Δ_j| above the least of the largest values kept so far (the candidates for
the 99.9 % quantile). Nothing the size of the chunk is made but those candidates.

Every draw's numbers come from its place in the stream, so a chunk may be cut into ranges run
on several threads (the kernel releases the GIL), each with its own tallies, merged afterwards:
maxima and integer counts do not depend on the order, so the result is the same on any number of
threads. Each loop over a block does one step for every draw of it without a branch, so the
compiler runs it on several draws at once (the 64-bit products of Philox as 32-bit halves).

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §3.2, eqs. (17)–(24); Salmon et al.
(2011), Proc. SC11, §3 (Philox4x64-10, its constants and rounds).
"""

from __future__ import annotations

import numba
import numpy as np

from rotacal.turntable.stream import _COS, _HALF_PI, _SIN

#: Draws per block: its words, errors, sines and D stay in the first two cache levels.
BLOCK = 256

_M0 = np.uint64(0xD2E7470EE14C6C93)
_M1 = np.uint64(0xCA5A826395121157)
_W0 = np.uint64(0x9E3779B97F4A7C15)
_W1 = np.uint64(0xBB67AE8584CAA73B)
_LOW = np.uint64(0xFFFFFFFF)
_SHIFT = np.uint64(32)
_TO_53 = np.uint64(11)
_2_TO_M53 = 1.0 / 9007199254740992.0
_S3, _S5, _S7, _S9, _S11, _S13, _S15, _S17 = _SIN
_C4, _C6, _C8, _C10, _C12, _C14, _C16 = _COS

_jit = numba.njit(cache=True, nogil=True, error_model="numpy")


@numba.njit(inline="always")
def _mulhi(a: np.uint64, b: np.uint64) -> np.uint64:
    """The high 64 bits of the 128-bit product a·b, from 32-bit halves."""
    a_lo = a & _LOW
    a_hi = a >> _SHIFT
    b_lo = b & _LOW
    b_hi = b >> _SHIFT
    low = a_lo * b_lo
    mid = a_hi * b_lo + (low >> _SHIFT)
    cross = a_lo * b_hi + (mid & _LOW)
    return a_hi * b_hi + (mid >> _SHIFT) + (cross >> _SHIFT)


@_jit
def philox_words(key: np.ndarray, first_block: int, words: np.ndarray, lanes: np.ndarray) -> None:
    """Words 4·first_block … of the stream keyed by ``key`` into ``words`` (its length a multiple
    of 4): Philox4x64-10 of the counters first_block + 1, … (Salmon et al. 2011, §3), word i of
    a block at 4·block + i. ``lanes`` is scratch of shape (4, len(words)/4)."""
    n = words.shape[0] // 4
    x0, x1, x2, x3 = lanes[0], lanes[1], lanes[2], lanes[3]
    for i in range(n):
        x0[i] = np.uint64(first_block + 1 + i)
        x1[i] = np.uint64(0)
        x2[i] = np.uint64(0)
        x3[i] = np.uint64(0)
    k0 = key[0]
    k1 = key[1]
    for _ in range(10):
        for i in range(n):
            a = x0[i]
            c = x2[i]
            x0[i] = _mulhi(_M1, c) ^ x1[i] ^ k0
            x1[i] = _M1 * c
            x2[i] = _mulhi(_M0, a) ^ x3[i] ^ k1
            x3[i] = _M0 * a
        k0 = k0 + _W0
        k1 = k1 + _W1
    for i in range(n):
        words[4 * i] = x0[i]
        words[4 * i + 1] = x1[i]
        words[4 * i + 2] = x2[i]
        words[4 * i + 3] = x3[i]


@numba.njit(inline="always")
def _uniform(word: np.uint64) -> float:
    """NumPy's double of a 64-bit word: (x >> 11)·2⁻⁵³ ∈ [0, 1)."""
    return float(word >> _TO_53) * _2_TO_M53


@numba.njit(inline="always")
def _turn_sin_cos(u: float) -> tuple[float, float]:
    """sin(2πu), cos(2πu): the operations of :func:`rotacal.turntable.stream.turn_sin_cos`."""
    t = 4.0 * u
    q = np.floor(t + 0.5)
    x = (t - q) * _HALF_PI
    x2 = x * x
    ps = _S3 + x2 * (
        _S5 + x2 * (_S7 + x2 * (_S9 + x2 * (_S11 + x2 * (_S13 + x2 * (_S15 + x2 * _S17)))))
    )
    pc = _C4 + x2 * (_C6 + x2 * (_C8 + x2 * (_C10 + x2 * (_C12 + x2 * (_C14 + x2 * _C16)))))
    s = x + x * (x2 * ps)
    c = (1.0 - 0.5 * x2) + (x2 * x2) * pc
    quadrant = np.int64(q) & 3
    sin_sign = 1.0 - 2.0 * ((quadrant >> 1) & 1)
    cos_sign = 1.0 - 2.0 * (((quadrant + 1) >> 1) & 1)
    if quadrant & 1:
        return sin_sign * c, cos_sign * s
    return sin_sign * s, cos_sign * c


@_jit
def turn_sin_cos(u: np.ndarray, sin: np.ndarray, cos: np.ndarray) -> None:
    """sin(2πu) and cos(2πu) of each u into ``sin`` and ``cos`` (the compiled twin of
    :func:`rotacal.turntable.stream.turn_sin_cos`)."""
    for r in range(u.shape[0]):
        sin[r], cos[r] = _turn_sin_cos(u[r])


@numba.njit(inline="always")
def _conjugate(d: np.ndarray, ax: int, cos: np.ndarray, sin: np.ndarray, m: int) -> None:
    """D ← Aᵀ·D·A for a rotation about axis ``ax``: columns i, j of every row (D·A), then rows
    i, j of every column, each pair (a, b) becoming (a·c + b·s, b·c − a·s)."""
    i = (ax + 1) % 3
    j = (ax + 2) % 3
    for p in range(6):
        if p < 3:
            a = d[3 * p + i]
            b = d[3 * p + j]
        else:
            a = d[3 * i + p - 3]
            b = d[3 * j + p - 3]
        for r in range(m):
            x = a[r]
            y = b[r]
            a[r] = x * cos[r] + y * sin[r]
            b[r] = y * cos[r] - x * sin[r]


@numba.njit(inline="always")
def _apply_errors(d: np.ndarray, e: np.ndarray, started: bool, final: bool, m: int) -> None:
    """D ← D·(I + skew(e)), or D = I + skew(e) for the first link with errors; after the last
    link (``final``) only the entries (0, 2), (1, 0), (2, 1) of eq. (24)."""
    ex = e[0]
    ey = e[1]
    ez = e[2]
    if not started:
        for r in range(m):
            d[0, r] = 1.0
            d[1, r] = 0.0 - ez[r]
            d[2, r] = ey[r]
            d[3, r] = ez[r]
            d[4, r] = 1.0
            d[5, r] = 0.0 - ex[r]
            d[6, r] = 0.0 - ey[r]
            d[7, r] = ex[r]
            d[8, r] = 1.0
    elif final:
        for r in range(m):
            d[2, r] = d[2, r] + (d[0, r] * ey[r] - d[1, r] * ex[r])
            d[3, r] = d[3, r] + (d[4, r] * ez[r] - d[5, r] * ey[r])
            d[7, r] = d[7, r] + (d[8, r] * ex[r] - d[6, r] * ez[r])
    else:
        for p in range(3):
            a0 = d[3 * p]
            a1 = d[3 * p + 1]
            a2 = d[3 * p + 2]
            for r in range(m):
                x0 = a0[r]
                x1 = a1[r]
                x2 = a2[r]
                a0[r] = x0 + (x1 * ez[r] - x2 * ey[r])
                a1[r] = x1 + (x2 * ex[r] - x0 * ez[r])
                a2[r] = x2 + (x0 * ey[r] - x1 * ex[r])


@numba.njit(inline="always")
def chain_block(
    cos: np.ndarray,
    sin: np.ndarray,
    chi: np.ndarray,
    axis: np.ndarray,
    angle: np.ndarray,
    start: np.ndarray,
    error: np.ndarray,
    error_axis: np.ndarray,
    last: int,
    d: np.ndarray,
    e: np.ndarray,
    m: int,
) -> bool:
    """The recursion for m draws: ``cos``/``sin`` (n_angles, ≥ m) of the angles that matter,
    ``chi`` (n_angular, ≥ m) rad; D (nine rows) left in ``d``. False when no link has errors
    (ΔR = I)."""
    started = False
    for k in range(axis.shape[0]):
        if axis[k] >= 0 and started:
            _conjugate(d, axis[k], cos[angle[k]], sin[angle[k]], m)
        if start[k + 1] == start[k]:
            continue
        for a in range(3):
            for r in range(m):
                e[a, r] = 0.0
        for q in range(start[k], start[k + 1]):
            acc = e[error_axis[q]]
            column = chi[error[q]]
            for r in range(m):
                acc[r] = acc[r] + column[r]
        _apply_errors(d, e, started, k == last, m)
        started = True
    return started


@_jit
def orientation_kernel(
    angles: np.ndarray,
    chi: np.ndarray,
    axis: np.ndarray,
    angle: np.ndarray,
    start: np.ndarray,
    error: np.ndarray,
    error_axis: np.ndarray,
    last_link: np.ndarray,
    out: np.ndarray,
) -> None:
    """(Δψ, Δθ, Δγ) into ``out`` (N, 3) rad for ``angles`` (N, n_angles) and ``chi``
    (N, n_angular) rad, block by block; cos and sin by the C library, of the angles that
    conjugate a D other than I only."""
    n = angles.shape[0]
    n_angles = angles.shape[1]
    d = np.empty((9, BLOCK))
    e = np.empty((3, BLOCK))
    cos = np.empty((n_angles, BLOCK))
    sin = np.empty((n_angles, BLOCK))
    chi_t = np.empty((chi.shape[1], BLOCK))
    needed = _needed_angles(axis, angle, start, n_angles)
    for lo in range(0, n, BLOCK):
        m = min(BLOCK, n - lo)
        for k in range(n_angles):
            if needed[k]:
                for r in range(m):
                    phi = angles[lo + r, k]
                    cos[k, r] = np.cos(phi)
                    sin[k, r] = np.sin(phi)
        for i in range(chi.shape[1]):
            for r in range(m):
                chi_t[i, r] = chi[lo + r, i]
        started = chain_block(cos, sin, chi_t, axis, angle, start, error, error_axis,
                              last_link[0], d, e, m)  # fmt: skip
        for r in range(m):
            out[lo + r, 0] = d[2, r] if started else 0.0
            out[lo + r, 1] = d[3, r] if started else 0.0
            out[lo + r, 2] = d[7, r] if started else 0.0


@numba.njit(inline="always")
def _needed_angles(axis: np.ndarray, angle: np.ndarray, start: np.ndarray, n: int) -> np.ndarray:
    """Which angles conjugate a D other than I (the others cancel exactly)."""
    needed = np.zeros(n, dtype=np.bool_)
    seen_error = False
    for k in range(axis.shape[0]):
        if axis[k] >= 0 and seen_error:
            needed[angle[k]] = True
        if start[k + 1] > start[k]:
            seen_error = True
    return needed


@numba.njit(inline="always")
def _tally_draw(
    psi: float,
    theta: float,
    gamma: float,
    requirement: np.ndarray,
    bins_per_rad: np.ndarray,
    floor: np.ndarray,
    max_abs: np.ndarray,
    counts: np.ndarray,
    candidates: np.ndarray,
    found: np.ndarray,
) -> int:
    """One draw's (Δψ, Δθ, Δγ) (rad) into the running max |Δ_j|, the histograms over ±I_j of the
    components within it (+I_j in the last bin), and the candidates |Δ_j| > floor[j]; 1 when some
    |Δ_j| > I_j, else 0."""
    bins = counts.shape[1]
    out = 0
    for j in range(3):
        value = psi if j == 0 else (theta if j == 1 else gamma)
        size = np.abs(value)
        if size > max_abs[j]:
            max_abs[j] = size
        if size > floor[j]:
            candidates[j, found[j]] = size
            found[j] += 1
        if size > requirement[j]:
            out = 1
            continue
        index = int(np.floor((value + requirement[j]) * bins_per_rad[j]))
        counts[j, min(index, bins - 1)] += 1
    return out


@_jit
def tally(
    d: np.ndarray,
    requirement: np.ndarray,
    bins_per_rad: np.ndarray,
    max_abs: np.ndarray,
    counts: np.ndarray,
) -> int:
    """The PCG64 path's tallies of a chunk of (Δψ, Δθ, Δγ) rows (rad): running max |Δ_j| (in
    ``max_abs``), histograms over ±I_j of the components within it (in ``counts``), and the
    number of draws with some |Δ_j| > I_j (returned)."""
    no_floor = np.full(3, np.inf)
    no_candidates = np.empty((3, 0))
    found = np.zeros(3, dtype=np.int64)
    outside = 0
    for row in range(d.shape[0]):
        outside += _tally_draw(d[row, 0], d[row, 1], d[row, 2], requirement, bins_per_rad,
                               no_floor, max_abs, counts, no_candidates, found)  # fmt: skip
    return outside


@_jit
def pcg64_draws(
    u: np.ndarray,
    lower: np.ndarray,
    width: np.ndarray,
    random_signs: bool,
    chi: np.ndarray,
    angles: np.ndarray,
) -> None:
    """The PCG64 path's χ_i = s_i·(LB_i + (UB_i − LB_i)·|v|) with v = 2u − 1 (random signs) or
    LB_i + width·u, and φ = 2π·u, from the row of uniforms u = (errors…, angles…) of each draw
    (rad)."""
    n_err = chi.shape[1]
    two_pi = 2.0 * np.pi
    for row in range(u.shape[0]):
        for i in range(n_err):
            if random_signs:
                v = 2.0 * u[row, i] - 1.0
                chi[row, i] = np.copysign(lower[i] + width[i] * np.abs(v), v)
            else:
                chi[row, i] = lower[i] + width[i] * u[row, i]
        for k in range(angles.shape[1]):
            angles[row, k] = two_pi * u[row, n_err + k]


@_jit
def monte_carlo_chunk(
    key: np.ndarray,
    first: int,
    m: int,
    n_angles: int,
    lower: np.ndarray,
    width: np.ndarray,
    random_signs: bool,
    axis: np.ndarray,
    angle: np.ndarray,
    start: np.ndarray,
    error: np.ndarray,
    error_axis: np.ndarray,
    last_link: np.ndarray,
    requirement: np.ndarray,
    bins_per_rad: np.ndarray,
    floor: np.ndarray,
    max_abs: np.ndarray,
    counts: np.ndarray,
    candidates: np.ndarray,
    found: np.ndarray,
) -> int:
    """Draws ``first`` … ``first + m − 1`` of the stream keyed by ``key``: their maxima and
    histograms merged into ``max_abs`` (3,) and ``counts`` (3, bins); every |Δ_j| > floor[j] (rad)
    into ``candidates[j, :found[j]]`` (``candidates`` (3, ≥ m)). Returns the draws with some
    |Δ_j| > requirement[j]. χ_i = ±(LB_i + width_i·|2u − 1|) (random signs) or LB_i + width_i·u;
    φ = 2π·u. Releases the GIL: ranges of a chunk may run on several threads."""
    n_err = lower.shape[0]
    row = n_err + n_angles
    needed = _needed_angles(axis, angle, start, n_angles)
    last = last_link[0]
    n_words = (BLOCK * row) // 4 * 4 + 8
    words = np.empty(n_words, dtype=np.uint64)
    lanes = np.empty((4, n_words // 4), dtype=np.uint64)
    chi = np.empty((n_err, BLOCK))
    cos = np.empty((n_angles, BLOCK))
    sin = np.empty((n_angles, BLOCK))
    d = np.empty((9, BLOCK))
    e = np.empty((3, BLOCK))
    n_found = np.zeros(3, dtype=np.int64)
    outside = 0
    for lo in range(0, m, BLOCK):
        mb = min(BLOCK, m - lo)
        first_word = (first + lo) * row
        first_block = first_word // 4
        n_blocks = ((first + lo + mb) * row + 3) // 4 - first_block
        philox_words(key, first_block, words[: 4 * n_blocks], lanes)
        offset = first_word - 4 * first_block
        for i in range(n_err):
            lo_i = lower[i]
            width_i = width[i]
            for r in range(mb):
                u = _uniform(words[offset + r * row + i])
                if random_signs:
                    v = 2.0 * u - 1.0
                    chi[i, r] = np.copysign(lo_i + width_i * np.abs(v), v)
                else:
                    chi[i, r] = lo_i + width_i * u
        for k in range(n_angles):
            if needed[k]:
                for r in range(mb):
                    sin[k, r], cos[k, r] = _turn_sin_cos(
                        _uniform(words[offset + r * row + n_err + k])
                    )
        started = chain_block(cos, sin, chi, axis, angle, start, error, error_axis, last, d, e, mb)
        for r in range(mb):
            if started:
                outside += _tally_draw(d[2, r], d[3, r], d[7, r], requirement, bins_per_rad,
                                       floor, max_abs, counts, candidates, n_found)  # fmt: skip
            else:
                outside += _tally_draw(0.0, 0.0, 0.0, requirement, bins_per_rad, floor,
                                       max_abs, counts, candidates, n_found)  # fmt: skip
    for j in range(3):
        found[j] = n_found[j]
    return outside
