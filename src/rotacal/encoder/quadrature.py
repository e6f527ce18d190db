"""Demodulation of an optical shaft encoder's two analog quadrature signals into angle.

The chain follows Feng et al. 2023 (Sensors 23:4876, §3): the two signals are corrected for offset,
gain mismatch and phase error (Heydemann 1981), turned into a continuous phase, subdivided into
twelve subintervals per signal period (eqs. (3)–(4)), the subintervals holding a reversing moment
are recognised by the odd/even count of consecutive trend changes (eqs. (5)–(6)), the reversing
moment is pinned to one sample (eqs. (7)–(8)), and n whole motion periods are cut between 2n+1
reversals (§3.3).

Conventions (INTERFACE.md): ``a ≈ cos φ``, ``b ≈ sin φ``, ``φ = 2π·lines·θ/360`` with θ the table
angle in degrees; θ increases when ``a`` leads ``b`` by a quarter signal period (``b = sin φ``
reaches its peak a quarter period after ``a = cos φ`` while φ grows), and φ = arctan2(b, a).
Subinterval labels here increase with θ (label = k mod 12 + 1, k = ⌊φ/(π/6)⌋); the paper numbers
them the other way round for its own direction sign (its eq. (3)), which does not matter to the
algorithm: it only uses changes of trend.

Where rotacal departs from its sources in the subdivision (eqs. (3)–(4)):

- *From Ye et al. (2020)*, whose linearisation subdivision Feng et al. (2023) use for its twelve
  subintervals and for θ (§3.1, §3.3): rotacal does not linearise. It takes the phase
  ``φ = arctan2(v, u)`` of the Heydemann-corrected signals in float64 (the arctangent method the
  seed lists among the traditional ones), unwrapped by counting whole cycles; its error is the
  rounding of arctan2 and whatever the Heydemann model leaves, not the residual of a piecewise
  linearisation with its compensation (Ye et al. state < 3.2·10⁻⁵° of the 360° signal
  period). The twelve subintervals are the 30° sectors of that phase, ``k = ⌊φ/(π/6)⌋``, not
  sectors chosen by which signal (or phase-shifted copy) is in its linear section.
- *From Feng et al. (2023)*: (1) the labels count up with θ (their eq. (3) counts down for
  Sdir = 1); (2) k is a continuous count, not a label modulo 12, so a sample that jumps over
  subintervals (sampling too slow) is seen: a :class:`SubdivisionWarning` above one subinterval,
  an error from five (150°), where the paper assumes every subinterval is visited; (3) the
  signals are corrected (Heydemann 1981) before the subdivision, which the paper leaves to
  "preprocessing"; (4) for the reversing moments see :func:`find_reversals` (which visit holds
  the reversal, the cluster pruning by hysteresis and the window of eqs. (7)–(8)).

The steps live in modules along the data's path — :mod:`rotacal.encoder.heydemann` (checks and
correction), :mod:`rotacal.encoder.phase` (phase, angle, subintervals) and
:mod:`rotacal.encoder.reversals` (eqs. (5)–(8), §3.3) — and stay importable from here; this module
holds the whole chain. Everything is whole-array NumPy; the only Python loops run over reversals
(a few hundred).
:func:`demodulate` runs the correction, the phase and the subinterval transitions in one pass
over cache-sized blocks (:mod:`rotacal.encoder._kernel`; a Numba twin for long captures).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

# The chain's steps live in their own modules; their names stay importable from here.
from rotacal.encoder.heydemann import (  # noqa: F401  (re-exported)
    FULL_COVERAGE_FRACTION,
    MAX_AMPLITUDE_RATIO,
    MAX_CIRCLE_RESIDUAL,
    MAX_PHASE_ERROR_RAD,
    MIN_ARC_RAD,
    QuadratureCorrection,
    _apply,
    _check_pair,
    _check_pair_and_rails,
    _check_varies,
    _clipping,
    _fit,
    _rails_verdict,
    _stride_for,
    check_correction,
    correct_quadrature,
    fit_quadrature_correction,
)
from rotacal.encoder.phase import (  # noqa: F401  (re-exported)
    SUBINTERVALS_PER_PERIOD,
    PhaseState,
    _check_lines,
    _transitions,
    angle_deg,
    rotation_direction,
    subinterval_transitions,
    subintervals,
    unwrapped_phase,
)
from rotacal.encoder.reversals import (  # noqa: F401  (re-exported)
    ReversalPlan,
    Reversals,
    SubdivisionWarning,
    WindowSignals,
    _pinned,
    find_reversals,
    intercept_periods,
    plan_reversals,
    reversal_point_in_window,
    reversal_window,
    reversing_subintervals,
)
from rotacal.errors import CaptureError
from rotacal.results import Result
from rotacal.signal import check_sampling

__all__ = [
    "Demodulation",
    "HysteresisRule",
    "PhaseState",
    "QuadratureCorrection",
    "ReversalPlan",
    "Reversals",
    "SubdivisionWarning",
    "angle_deg",
    "correct_quadrature",
    "demodulate",
    "find_reversals",
    "fit_quadrature_correction",
    "hysteresis_stride",
    "intercept_periods",
    "plan_reversals",
    "reversal_point_in_window",
    "reversal_window",
    "reversing_subintervals",
    "rotation_direction",
    "subinterval_transitions",
    "subintervals",
    "unwrapped_phase",
]

FloatArray = NDArray[np.floating[Any]]
_TWO_PI = 2.0 * math.pi

#: Samples a hysteresis rule sees (every N // this-th sample of the capture, at least every one).
HYSTERESIS_POINTS = 20_000

#: ``(t, φ) → hysteresis in subintervals, or None for the default``: see :func:`demodulate`.
HysteresisRule = Callable[[FloatArray, FloatArray], "int | None"]


def hysteresis_stride(n_samples: int) -> int:
    """Stride of the samples a hysteresis rule sees: every N // 20 000-th (at least 1)."""
    return max(1, n_samples // HYSTERESIS_POINTS)


@dataclasses.dataclass(frozen=True)
class Demodulation(Result):
    """Angle of the table from a quadrature-encoder capture, with its reversing moments.

    Attributes
    ----------
    correction : QuadratureCorrection
        The signal correction that was applied.
    reversals : Reversals
        Reversing moments.
    lines : int
        Signal periods per revolution of the encoder.
    n_samples : int
        Samples in the capture.
    sample_rate_hz : float
        Mean sample rate (Hz).
    angle_min_deg, angle_max_deg : float
        Extremes of θ over the capture (deg, same origin as ``_angle_deg``).
    _angle_deg : ndarray
        θ of every sample (deg); its origin is the zero of the encoder's signal phase at the
        start of the capture (only the motion, not the absolute position, is meaningful).
    _time_s : ndarray
        The time stamps passed in (s).
    """

    correction: QuadratureCorrection
    reversals: Reversals
    lines: int
    n_samples: int
    sample_rate_hz: float
    angle_min_deg: float
    angle_max_deg: float
    _angle_deg: np.ndarray
    _time_s: np.ndarray

    @property
    def angle_deg(self) -> np.ndarray:
        """θ of every sample (deg)."""
        return self._angle_deg

    @property
    def time_s(self) -> np.ndarray:
        """Time of every sample (s)."""
        return self._time_s

    @property
    def reversal_times_s(self) -> np.ndarray:
        """Time of every reversing moment (s)."""
        return self.reversals.times_s

    def periods(self, n_periods: int | None = None) -> tuple[int, int, int]:
        """``(first, last, n)``: samples of n whole motion periods (:func:`intercept_periods`)."""
        return intercept_periods(self.reversals, n_periods)

    def segment(self, n_periods: int | None = None) -> tuple[np.ndarray, np.ndarray, int]:
        """Time (s) and θ (deg) of n whole motion periods, and n (views, not copies)."""
        first, last, n = self.periods(n_periods)
        return self._time_s[first : last + 1], self._angle_deg[first : last + 1], n


# --------------------------------------------------------------------------------------------
# the whole chain
# --------------------------------------------------------------------------------------------


def _check_time(t: ArrayLike, n: int) -> FloatArray:
    tt = np.asarray(t, dtype=np.float64)
    if tt.ndim != 1 or tt.size != n:
        raise CaptureError(
            f"column 'time_s' has shape {tt.shape} but 'a' and 'b' have {n} samples; "
            "they must be sampled together."
        )
    check_sampling(tt, "time_s")
    return tt


def demodulate(
    t: ArrayLike,
    a: ArrayLike,
    b: ArrayLike,
    lines: int,
    *,
    correction: QuadratureCorrection | None = None,
    hysteresis_subintervals: int | None = None,
    max_points: int = 1_000_000,
    allow_clipped: bool = False,
    hysteresis_from: HysteresisRule | None = None,
) -> Demodulation:
    """Angle and reversing moments from a quadrature-encoder capture, in one call.

    Checks the capture, fits the Heydemann correction (unless one is given), corrects the
    signals, unwraps the phase, finds the reversing moments and converts the phase to θ.

    Parameters
    ----------
    t : array_like
        Time stamps (s), strictly increasing.
    a, b : array_like
        Raw signals (any unit), ``a ≈ cos φ``, ``b ≈ sin φ``.
    lines : int
        Signal periods per revolution of the encoder.
    correction : QuadratureCorrection, optional
        Use this correction instead of fitting one (e.g. from a capture with more motion).
    hysteresis_subintervals : int, optional
        See :func:`find_reversals`.
    max_points : int
        Largest number of samples used in the correction fit.
    allow_clipped : bool
        Demodulate signals with samples at the rails anyway (their ``warnings`` say so); refused
        by default. Every sample of both channels is judged (:mod:`rotacal.signal.clipping`).
    hysteresis_from : callable, optional
        Without ``hysteresis_subintervals``: a rule ``(t, φ) → hysteresis or None`` called with
        every :func:`hysteresis_stride`-th sample's time (s) and phase (rad); None keeps the
        default (the chunked calibration applies the same rule to the same samples).

    Returns
    -------
    Demodulation
        Correction, reversals, θ per sample (deg) and the time stamps (s).

    Raises
    ------
    CaptureError
        Bad capture (lengths, NaN, values beyond float64's range, constant or copied signals,
        clipping, not quadrature, time stamps).
    ConfigError
        Bad ``lines`` or ``hysteresis_subintervals``.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1–3.3, eqs. (3)–(8);
    Heydemann 1981, Appl. Opt. 20:3382 (signal correction).
    """
    _check_lines(lines)
    aa, bb, rails = _check_pair_and_rails(a, b)
    tt = _check_time(t, aa.size)
    clipped = _rails_verdict(rails, allow_clipped)
    if correction is None:
        correction = _fit(aa, bb, max_points)
    else:
        stride = _stride_for(aa.size, max_points)
        _check_varies(aa[::stride], bb[::stride])
    # correction, phase and subinterval transitions in one pass (the signals u, v are not kept:
    # eqs. (7)–(8) correct the few samples of each reversal window again)
    from rotacal.encoder._kernel import phase_pass

    scale = 360.0 / (_TWO_PI * float(lines))
    # θ = φ·scale block by block in the pass, unless the hysteresis rule still needs φ
    rule = hysteresis_subintervals is None and hysteresis_from is not None
    run = phase_pass(aa, bb, correction, scale=None if rule else scale)
    theta = run.phase_rad
    if rule:
        assert hysteresis_from is not None
        step = hysteresis_stride(theta.size)
        hysteresis_subintervals = hysteresis_from(tt[::step], theta[::step])
        theta *= scale
    plan = plan_reversals(
        run.indices, run.k_after, run.k_first, hysteresis_subintervals=hysteresis_subintervals
    )
    corr = correction
    reversals = _pinned(plan, tt, lambda rows: correct_quadrature(aa[rows], bb[rows], corr))
    span = float(tt[-1] - tt[0])
    return Demodulation(
        correction=correction,
        reversals=reversals,
        lines=int(lines),
        n_samples=int(aa.size),
        sample_rate_hz=(aa.size - 1) / span,
        # the scaling is monotonic: the extremes of θ are the scaled extremes of φ
        angle_min_deg=run.phase_min_rad * scale,
        angle_max_deg=run.phase_max_rad * scale,
        _angle_deg=theta,
        _time_s=tt,
        warnings=clipped,
    )
