"""The Monte Carlo's orientation-error kernel: every draw through the chain in one pass.

:meth:`rotacal.turntable.model.Turntable.fast_orientation_error` evaluates ΔR = R_dᵀ·R_t
(seed 001, eqs. (17)–(24)) by the recursion D ← A_kᵀ·D·A_k·E_k of :func:`_fast_kernel
<rotacal.turntable.model._fast_kernel>`. That kernel runs on whole arrays, one NumPy operation per
entry product (about 75 for the seed table), so every draw's numbers go through memory 75 times.
Here the same recursion runs draw by draw in compiled code (Numba): the nine entries of D stay in
registers, cos and sin of an angle are taken only where D is no longer the identity (as there),
and each draw costs its arithmetic only.

The operations are those of ``_fast_kernel`` in the same order. Where that kernel skips a
constant (a product with an exact 0 or 1, a sum with an exact 0), the compiled one does the
operation, whose result is the same number (x·1 = x, x + 0 = x, 0·x = ±0 added to y is y for
finite x); only the sign of an exact zero may differ. cos and sin are the C library's, as
NumPy's are on this platform; the tests compare the two paths draw by draw.

Numba compiles the kernel on first use (cached on disk); without Numba, or with the environment
variable ``ROTACAL_NUMBA=0``, the NumPy path is used.

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §3.2, eqs. (17)–(24), Table 3.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

__all__ = ["chain_arrays", "compiled_kernel", "numba_enabled"]


def numba_enabled() -> bool:
    """Whether the compiled kernel is to be used: Numba importable and ``ROTACAL_NUMBA`` not 0."""
    if os.environ.get("ROTACAL_NUMBA", "1").strip() == "0":
        return False
    return _numba_available()


@functools.cache
def _numba_available() -> bool:
    try:
        import numba  # noqa: F401
    except ImportError:  # pragma: no cover - numba is a dependency
        return False
    return True


def chain_arrays(links: Sequence[Any]) -> tuple[np.ndarray, ...]:
    """The chain as the integer arrays the compiled kernel reads.

    Parameters
    ----------
    links : sequence of _LinkPlan
        The table's link plans (axis index or −1, angle index or −1, (error index, axis index)
        rotations).

    Returns
    -------
    (axis, angle, rotation_start, rotation_error, rotation_axis, last)
        Per link its axis and angle index; its rotations are rows rotation_start[k] to
        rotation_start[k + 1] of (rotation_error, rotation_axis); ``last`` (a 1-element array) is
        the link after which only the three entries of eq. (24) are needed, or −1.
    """
    axis = np.array([plan.axis for plan in links], dtype=np.int64)
    angle = np.array([plan.angle for plan in links], dtype=np.int64)
    start = np.zeros(len(links) + 1, dtype=np.int64)
    start[1:] = np.cumsum([len(plan.rotations) for plan in links])
    pairs = [pair for plan in links for pair in plan.rotations]
    error = np.array([i for i, _ in pairs], dtype=np.int64)
    error_axis = np.array([a for _, a in pairs], dtype=np.int64)
    last = len(links) - 1
    while last >= 0 and not links[last].rotations:
        last -= 1
    if any(plan.axis >= 0 for plan in links[last + 1 :]):
        last = -1
    return axis, angle, start, error, error_axis, np.array([last], dtype=np.int64)


@functools.cache
def compiled_kernel() -> Callable[..., None]:
    """The Numba kernel ``kernel(angles, chi, *chain_arrays(links), out)``, compiled on first use.

    ``angles`` (N, n_angles) rad, ``chi`` (N, n_angular) rad, ``out`` (N, 3) receives (Δψ, Δθ, Δγ)
    in rad (seed 001, eqs. (17)–(24)).
    """
    import numba

    return numba.njit(cache=True, nogil=True, error_model="numpy")(_kernel)


def _kernel(
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
    """D ← A_kᵀ·D·A_k·E_k draw by draw, the operations of ``_fast_kernel`` in its order."""
    n_links = axis.shape[0]
    last = last_link[0]
    d = np.empty(9)
    e = np.empty(3)
    for row in range(angles.shape[0]):
        started = False
        for k in range(n_links):
            ax = axis[k]
            if ax >= 0 and started:
                phi = angles[row, angle[k]]
                c = np.cos(phi)
                s = np.sin(phi)
                i = (ax + 1) % 3
                j = (ax + 2) % 3
                for r in range(3):  # M = D·A: columns i, j mix
                    di = d[3 * r + i]
                    dj = d[3 * r + j]
                    d[3 * r + i] = di * c + dj * s
                    d[3 * r + j] = dj * c - di * s
                for col in range(3):  # Aᵀ·M: rows i, j mix
                    mi = d[3 * i + col]
                    mj = d[3 * j + col]
                    d[3 * i + col] = mi * c + mj * s
                    d[3 * j + col] = mj * c - mi * s
            if start[k + 1] == start[k]:
                continue
            e[0] = 0.0
            e[1] = 0.0
            e[2] = 0.0
            for q in range(start[k], start[k + 1]):
                e[error_axis[q]] = e[error_axis[q]] + chi[row, error[q]]
            ex = e[0]
            ey = e[1]
            ez = e[2]
            if not started:
                d[0] = 1.0
                d[1] = 0.0 - ez
                d[2] = ey
                d[3] = ez
                d[4] = 1.0
                d[5] = 0.0 - ex
                d[6] = 0.0 - ey
                d[7] = ex
                d[8] = 1.0
                started = True
                continue
            # D·(I + skew(e)): (D·K)[r] = (D[r,1]ez − D[r,2]ey, D[r,2]ex − D[r,0]ez, D[r,0]ey − D[r,1]ex)
            if k == last:
                d[2] = d[2] + (d[0] * ey - d[1] * ex)
                d[3] = d[3] + (d[4] * ez - d[5] * ey)
                d[7] = d[7] + (d[8] * ex - d[6] * ez)
                continue
            for r in range(3):
                d0 = d[3 * r]
                d1 = d[3 * r + 1]
                d2 = d[3 * r + 2]
                d[3 * r] = d0 + (d1 * ez - d2 * ey)
                d[3 * r + 1] = d1 + (d2 * ex - d0 * ez)
                d[3 * r + 2] = d2 + (d0 * ey - d1 * ex)
        if started:
            out[row, 0] = d[2]
            out[row, 1] = d[3]
            out[row, 2] = d[7]
        else:
            out[row, 0] = 0.0
            out[row, 1] = 0.0
            out[row, 2] = 0.0
