"""Continuous phase, angle and the 30° subintervals of the corrected quadrature signals.

The second step of the chain of :mod:`rotacal.encoder.quadrature`: ``φ = arctan2(v, u)``
unwrapped by an integer cycle count (chunk by chunk with carried state), ``θ = φ·360/(2π·lines)``
and the subinterval count ``k = ⌊φ/(π/6)⌋`` with its transitions (Feng et al. 2023, Sensors
23:4876, §3.1, eqs. (3)–(4)).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.errors import CaptureError, ConfigError

FloatArray = NDArray[np.floating[Any]]
_TWO_PI = 2.0 * math.pi

#: Subintervals per signal period (Feng et al. 2023, §3.1).
SUBINTERVALS_PER_PERIOD = 12
_SUB_RAD = 2.0 * math.pi / SUBINTERVALS_PER_PERIOD


@dataclasses.dataclass(frozen=True)
class PhaseState:
    """What :func:`unwrapped_phase` carries from one chunk to the next.

    Attributes
    ----------
    last_wrapped_rad : float
        Wrapped phase ``arctan2(v, u)`` of the last sample of the previous chunk (rad).
    cycles : int
        Signal periods counted up to that sample (its unwrapped phase is
        ``last_wrapped_rad + 2π·cycles``).
    """

    last_wrapped_rad: float
    cycles: int


# --------------------------------------------------------------------------------------------
# phase and angle
# --------------------------------------------------------------------------------------------


def unwrapped_phase(
    u: ArrayLike, v: ArrayLike, *, state: PhaseState | None = None, out: FloatArray | None = None
) -> tuple[FloatArray, PhaseState]:
    """Continuous signal phase φ from corrected quadrature signals, chunk by chunk if wanted.

    ``φ = arctan2(v, u) + 2π·c`` where the cycle count ``c`` steps by −1 where the wrapped phase
    jumps up by more than π and by +1 where it jumps down by more than π (the integer form of
    ``np.unwrap``, several times faster). Passing the returned state with the next chunk gives
    exactly the same values as processing the capture in one piece.

    Parameters
    ----------
    u, v : array_like
        Corrected signals ≈ (cos φ, sin φ) (dimensionless).
    state : PhaseState, optional
        State returned with the previous chunk; None for the first (or only) chunk.
    out : ndarray, optional
        Where to write φ (float64, the length of u): a caller's buffer or a slice of the
        capture's phase array, instead of a fresh array (the same numbers).

    Returns
    -------
    phase_rad : ndarray
        Unwrapped phase φ (rad).
    state : PhaseState
        To pass with the next chunk.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1 (arctangent subdivision of the OSE signal);
    Ye et al. 2020, IEEE Trans. Ind. Electron. 67:8778 (phase demodulation of sinusoidal encoders).
    """
    uu = np.asarray(u, dtype=np.float64)
    vv = np.asarray(v, dtype=np.float64)
    if uu.shape != vv.shape or uu.ndim != 1:
        raise CaptureError(
            f"u and v must be one-dimensional and of equal length, got {uu.shape} and {vv.shape}."
        )
    wrapped = np.arctan2(vv, uu)
    if wrapped.size == 0:
        return wrapped, state if state is not None else PhaseState(0.0, 0)
    steps = np.empty(wrapped.size, dtype=np.int8)
    if state is None:
        d = np.diff(wrapped)
        steps[0] = 0
        start_cycles = 0
    else:
        d = np.diff(wrapped, prepend=state.last_wrapped_rad)
        start_cycles = state.cycles
        d0 = d[0]
        steps[0] = int(d0 < -math.pi) - int(d0 > math.pi)
        d = d[1:]
    body = steps[1:]
    np.less(d, -math.pi, out=body.view(np.bool_))
    body -= d > math.pi
    cycles = np.cumsum(steps, dtype=np.int64)
    if start_cycles:
        cycles += start_cycles
    phase = np.multiply(cycles, _TWO_PI, out=out)
    phase += wrapped
    return phase, PhaseState(float(wrapped[-1]), int(cycles[-1]))


def angle_deg(phase_rad: ArrayLike, lines: int) -> FloatArray:
    """Table angle θ from the signal phase: ``θ = φ·360/(2π·lines)``.

    Parameters
    ----------
    phase_rad : array_like
        Unwrapped signal phase φ (rad).
    lines : int
        Signal periods per revolution (e.g. 36000 for a Heidenhain RON 886).

    Returns
    -------
    ndarray
        θ (deg).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.3 (angular displacement of every data point).
    """
    _check_lines(lines)
    return np.asarray(phase_rad, dtype=np.float64) * (360.0 / (_TWO_PI * float(lines)))


def _check_lines(lines: int) -> None:
    if isinstance(lines, bool) or not float(lines).is_integer() or lines < 1:
        raise ConfigError(f"lines={lines!r} must be a positive whole number of signal periods.")


def subintervals(phase_rad: ArrayLike) -> NDArray[np.int8]:
    """Subinterval label 1..12 of each sample: twelve subintervals of 30° per signal period.

    ``label = ⌊φ/(π/6)⌋ mod 12 + 1``; labels increase with θ (the paper's eqs. (3)–(4) number
    them the other way round for its direction sign; only changes of trend matter).

    Parameters
    ----------
    phase_rad : array_like
        Unwrapped (or wrapped) signal phase φ (rad).

    Returns
    -------
    ndarray of int8
        Labels 1..12.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1, eqs. (3)–(4).
    """
    k = np.floor(np.asarray(phase_rad, dtype=np.float64) * (1.0 / _SUB_RAD))
    return (np.mod(k, SUBINTERVALS_PER_PERIOD) + 1).astype(np.int8)


def _transitions(phase: FloatArray) -> tuple[NDArray[np.intp], FloatArray, FloatArray, float]:
    """Sample index of each subinterval transition, the count k after it, its step, and k[0]."""
    k = np.floor(phase * (1.0 / _SUB_RAD))
    idx = np.flatnonzero(k[1:] != k[:-1])
    idx += 1
    k_after = k[idx]
    dk = k_after - k[idx - 1]
    return idx, k_after, dk, float(k[0]) if k.size else 0.0


def rotation_direction(phase_rad: ArrayLike) -> tuple[NDArray[np.intp], NDArray[np.int8]]:
    """Direction of rotation at each subinterval transition.

    Parameters
    ----------
    phase_rad : array_like
        Unwrapped signal phase φ (rad).

    Returns
    -------
    indices : ndarray of int
        Sample index of each transition (first sample in the new subinterval).
    direction : ndarray of int8
        +1 where θ increases, −1 where it decreases (Sdir of the paper, with θ's sign).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1, eqs. (3)–(4).
    """
    idx, _, dk, _ = _transitions(np.asarray(phase_rad, dtype=np.float64))
    return idx, np.sign(dk).astype(np.int8)


def subinterval_transitions(
    phase_rad: ArrayLike, *, previous_k: float | None = None, offset: int = 0
) -> tuple[NDArray[np.intp], FloatArray, float, float]:
    """Subinterval transitions of one chunk of the phase, chunk-exact.

    ``k = ⌊φ/(π/6)⌋``; a transition is a sample whose k differs from the previous sample's.

    Parameters
    ----------
    phase_rad : array_like
        Unwrapped phase φ (rad) of the chunk (from :func:`unwrapped_phase` with carried state).
    previous_k : float, optional
        k of the sample before the chunk (None for the first chunk).
    offset : int
        Global sample index of the chunk's first sample.

    Returns
    -------
    indices : ndarray of int
        Global sample index of each transition (first sample in the new subinterval).
    k_after : ndarray of float
        k after each transition (whole numbers stored as float, as :func:`find_reversals` uses).
    k_first, k_last : float
        k of the chunk's first and last sample (pass ``k_last`` as ``previous_k`` with the next
        chunk); NaN for an empty chunk.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1, eqs. (3)–(4).
    """
    k = np.floor(np.asarray(phase_rad, dtype=np.float64) * (1.0 / _SUB_RAD))
    idx = np.flatnonzero(k[1:] != k[:-1])
    idx += 1
    if previous_k is not None and k.size and k[0] != previous_k:
        idx = np.concatenate(([0], idx))
    k_after = k[idx]
    idx += offset
    if k.size == 0:
        return idx, k_after, math.nan, math.nan
    return idx, k_after, float(k[0]), float(k[-1])
