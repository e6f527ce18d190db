"""The per-sample encoder chain in one pass over cache-sized blocks (private).

Heydemann correction (Heydemann 1981, eqs. (1)–(2) solved for cos φ and sin φ), ``arctan2``, the
integer cycle count, the 30° subinterval count k = ⌊φ/(π/6)⌋ with its transitions (Feng et al.
2023, Sensors 23:4876, §3.1, eqs. (3)–(4)) and the extremes of φ, block by block with the state
carried, so the corrected signals never exist as whole arrays. Two twins give the same numbers:
the NumPy path composes :func:`correct_quadrature`, :func:`unwrapped_phase` and
:func:`subinterval_transitions` on each block (bit for bit what they give on the whole chunk);
the Numba path (:mod:`rotacal.encoder._kernel_jit`, for long captures) corrects each block in
one compiled pass, takes ``arctan2`` with NumPy (its SIMD ``arctan2`` beats a compiled loop's
libm call) and runs the state carried from sample to sample in one compiled loop: bit for bit
the same numbers.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rotacal._jit import use_numba
from rotacal.encoder.heydemann import QuadratureCorrection, check_correction, correct_quadrature
from rotacal.encoder.phase import PhaseState, subinterval_transitions, unwrapped_phase

#: Samples per block: the block's signals and phase stay in the CPU cache between the steps.
BLOCK = 1 << 15
_INV_SUB = 1.0 / (2.0 * math.pi / 12.0)


@dataclasses.dataclass(frozen=True)
class ChunkPhase:
    """What one pass over a chunk gives.

    Attributes
    ----------
    phase_rad : ndarray
        Unwrapped phase φ of every sample (rad), times ``scale`` when :func:`phase_pass` was
        given one.
    state : PhaseState
        To pass with the next chunk.
    indices : ndarray of int64
        Global sample index of each subinterval transition.
    k_after : ndarray of float
        k after each transition.
    k_first, k_last : float
        k of the chunk's first and last sample.
    phase_min_rad, phase_max_rad : float
        Extremes of φ over the chunk (rad).
    """

    phase_rad: np.ndarray
    state: PhaseState
    indices: np.ndarray
    k_after: np.ndarray
    k_first: float
    k_last: float
    phase_min_rad: float
    phase_max_rad: float


def phase_pass(
    a: np.ndarray,
    b: np.ndarray,
    correction: QuadratureCorrection,
    *,
    state: PhaseState | None = None,
    previous_k: float | None = None,
    offset: int = 0,
    jit: bool | None = None,
    scale: float | None = None,
) -> ChunkPhase:
    """Correct, unwrap and subdivide one chunk of raw signals, chunk-exact.

    Parameters
    ----------
    a, b : ndarray
        Raw signals of the chunk (float64, unit of the correction, e.g. V), at least 1 sample.
    correction : QuadratureCorrection
        Offsets and amplitudes (signal unit), phase error (rad).
    state : PhaseState, optional
        From the previous chunk (None for the first).
    previous_k : float, optional
        k of the sample before the chunk (None for the first chunk; with a ``state`` and no
        ``previous_k`` it is taken from the state).
    offset : int
        Global sample index of the chunk's first sample.
    jit : bool, optional
        Force the Numba twin (True) or the NumPy path (False); default by size.
    scale : float, optional
        Store φ·scale instead of φ (e.g. 360/(2π·lines): θ in deg), each block scaled while it
        is in the cache instead of in a pass of its own afterwards (the same numbers bit for
        bit). The extremes, the counts and the state stay those of φ (rad).

    Returns
    -------
    ChunkPhase

    References
    ----------
    Heydemann, P. L. M. 1981, Appl. Opt. 20:3382–3384, eqs. (1)–(2) solved for cos φ and sin φ;
    Feng et al. 2023, Sensors 23:4876, §3.1, eqs. (3)–(4) (arctangent subdivision, 30°
    subintervals).
    """
    check_correction(correction)
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    n = int(a.size)
    if state is None:
        previous_k = None
    elif previous_k is None:
        # k of the sample before the chunk, from its phase exactly as unwrapped_phase forms it
        previous_k = float(
            math.floor((state.cycles * (2.0 * math.pi) + state.last_wrapped_rad) * _INV_SUB)
        )
    if use_numba(n, jit):
        return _phase_jit(a, b, correction, state, previous_k, offset, scale)
    phase = np.empty(n, dtype=np.float64)
    idx: list[np.ndarray] = []
    k_after: list[np.ndarray] = []
    k_first = math.nan
    lo, hi = math.inf, -math.inf
    k_prev = previous_k
    for s in range(0, n, BLOCK):
        u, v = correct_quadrature(a[s : s + BLOCK], b[s : s + BLOCK], correction)
        # φ straight into its place in the output, scaled there once its counts are taken
        ph, state = unwrapped_phase(u, v, state=state, out=phase[s : s + BLOCK])
        i, k, k0, k_prev = subinterval_transitions(ph, previous_k=k_prev, offset=offset + s)
        if s == 0:
            k_first = k0
        idx.append(i.astype(np.int64, copy=False))
        k_after.append(k)
        lo = min(lo, float(ph.min()))
        hi = max(hi, float(ph.max()))
        if scale is not None:
            ph *= scale
    assert state is not None and k_prev is not None
    return ChunkPhase(
        phase, state, np.concatenate(idx), np.concatenate(k_after), k_first, k_prev, lo, hi
    )


def _phase_jit(
    a: np.ndarray,
    b: np.ndarray,
    c: QuadratureCorrection,
    state: PhaseState | None,
    previous_k: float | None,
    offset: int,
    scale: float | None,
) -> ChunkPhase:
    from rotacal.encoder._kernel_jit import correct_block, phase_block

    consts = np.array([2.0 * math.pi, _INV_SUB, math.pi])
    alpha = c.phase_error_rad  # the factors correct_quadrature multiplies by, formed alike
    coefs = np.array(
        [
            c.offset_a,
            c.offset_b,
            1.0 / c.amplitude_a,
            1.0 / (c.amplitude_b * math.cos(alpha)),
            math.tan(alpha),
        ]
    )
    u = np.empty(min(a.size, BLOCK))
    v = np.empty(u.size)
    has_prev = state is not None
    carry = np.array([0.0, 0.0, 0.0, math.inf, -math.inf])
    if state is not None and previous_k is not None:
        carry[:3] = (state.last_wrapped_rad, float(state.cycles), previous_k)
    n = a.size
    phase = np.empty(n, dtype=np.float64)
    # The kernel writes each block's transitions straight after the previous ones (no copy per
    # block, no concatenation), into arrays with room for a transition at every sample of the
    # block: a quarter of the samples to start with (a fast motion has fewer), doubled as needed.
    out_i = np.empty(min(n, n // 4 + BLOCK), dtype=np.int64)
    out_k = np.empty(out_i.size, dtype=np.float64)
    total = 0
    k_first = math.nan
    for s in range(0, n, BLOCK):
        e = min(n, s + BLOCK)
        if total + (e - s) > out_i.size:
            size = min(n, 2 * out_i.size)
            out_i = np.concatenate((out_i[:total], np.empty(size - total, dtype=np.int64)))
            out_k = np.concatenate((out_k[:total], np.empty(size - total)))
        correct_block(a[s:e], b[s:e], coefs, alpha != 0.0, u, v)
        wrapped = np.arctan2(v[: e - s], u[: e - s], out=u[: e - s])
        total += phase_block(
            wrapped,
            consts,
            carry,
            has_prev or s > 0,
            offset + s,
            phase[s:e],
            out_i[total:],
            out_k[total:],
        )
        if s == 0:
            k_first = float(np.floor(phase[0] * _INV_SUB))
        if scale is not None:
            phase[s:e] *= scale
    return ChunkPhase(
        phase,
        PhaseState(float(carry[0]), int(carry[1])),
        out_i[:total],
        out_k[:total],
        k_first,
        float(carry[2]),
        float(carry[3]),
        float(carry[4]),
    )
