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

Everything is whole-array NumPy; the only Python loops run over reversals (a few hundred).
:func:`demodulate` runs the correction, the phase and the subinterval transitions in one pass
over cache-sized blocks (:mod:`rotacal.encoder._kernel`; a Numba twin for long captures).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result, with_warnings
from rotacal.signal import check_sampling
from rotacal.signal._values import (
    check_magnitudes,
    check_not_constant,
    check_not_copies,
    in_working_range,
)
from rotacal.signal.clipping import check_clipping, find_clipping

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

#: Subintervals per signal period (Feng et al. 2023, §3.1).
SUBINTERVALS_PER_PERIOD = 12
_SUB_RAD = 2.0 * math.pi / SUBINTERVALS_PER_PERIOD
_TWO_PI = 2.0 * math.pi

#: The Heydemann ellipse is trusted only when the data cover at least this much of the period.
FULL_COVERAGE_FRACTION = 0.8
#: Below this arc (rad) not even the offsets can be estimated.
MIN_ARC_RAD = math.pi / 4
#: Phase errors beyond this (rad) mean the signals are not in quadrature.
MAX_PHASE_ERROR_RAD = math.radians(45.0)
#: A partial arc is accepted only if a circle fits it to this rms radial residual (relative).
MAX_CIRCLE_RESIDUAL = 0.1
#: Amplitude ratios outside [1/x, x] mean the signals are not a usable quadrature pair.
MAX_AMPLITUDE_RATIO = 5.0

_MIN_SAMPLES = 16
_CHUNK = 1 << 18
_COVERAGE_BINS = 720


#: Largest phase step (in 30° subintervals) between samples that is still demodulated.
_MAX_SAFE_STEP = 5


#: Samples a hysteresis rule sees (every N // this-th sample of the capture, at least every one).
HYSTERESIS_POINTS = 20_000

#: ``(t, φ) → hysteresis in subintervals, or None for the default``: see :func:`demodulate`.
HysteresisRule = Callable[[FloatArray, FloatArray], "int | None"]


def hysteresis_stride(n_samples: int) -> int:
    """Stride of the samples a hysteresis rule sees: every N // 20 000-th (at least 1)."""
    return max(1, n_samples // HYSTERESIS_POINTS)


class SubdivisionWarning(UserWarning):
    """The sampling is too slow for the 12-fold subdivision (subintervals were skipped)."""


# --------------------------------------------------------------------------------------------
# results
# --------------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class QuadratureCorrection(Result):
    """Offsets, amplitudes and phase error of the two signals (Heydemann 1981 model).

    Model: ``a = offset_a + amplitude_a·cos φ``,
    ``b = offset_b + amplitude_b·sin(φ + phase_error_rad)``.

    Attributes
    ----------
    offset_a, offset_b : float
        Offsets p, q in the unit of the signals (e.g. V).
    amplitude_a, amplitude_b : float
        Amplitudes R_a, R_b in the unit of the signals.
    phase_error_rad : float
        Phase error α of ``b`` (rad); 0 for perfect quadrature.
    method : str
        ``"heydemann"`` (full ellipse), ``"offsets only (partial period)"`` (circle fit: amplitude
        ratio 1 and phase 0 assumed), or ``"given"``/``"none"`` for corrections made by hand.
    coverage_rad : float
        How much of the signal period the data cover (rad); 2π is the full ellipse.
    points_used : int
        Number of samples that entered the fit.
    """

    offset_a: float
    offset_b: float
    amplitude_a: float
    amplitude_b: float
    phase_error_rad: float
    method: str
    coverage_rad: float
    points_used: int = 0

    @property
    def amplitude_ratio(self) -> float:
        """R_b / R_a (dimensionless)."""
        return self.amplitude_b / self.amplitude_a

    @classmethod
    def identity(cls) -> QuadratureCorrection:
        """No correction: offsets 0, amplitudes 1, phase error 0."""
        return cls(0.0, 0.0, 1.0, 1.0, 0.0, "none", float("nan"), 0)


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


@dataclasses.dataclass(frozen=True)
class Reversals(Result):
    """Reversing moments of the motion (Feng et al. 2023, §3.1–3.2).

    Attributes
    ----------
    indices : ndarray of int
        Sample index of each reversing moment (Chp of eqs. (7)–(8)).
    times_s : ndarray of float
        Time of each reversing moment (s).
    kinds : ndarray of int
        +1 for a maximum of θ, −1 for a minimum; they alternate.
    candidates : int
        Reversals found by the odd/even rule (eqs. (5)–(6)) before cluster pruning.
    hysteresis_subintervals : int
        Excursion (in subintervals) below which neighbouring candidates were treated as one cluster.
    transitions : int
        Subinterval transitions in the capture.
    skipped_transitions : int
        Transitions that jumped over one subinterval or more (sampling too slow for the
        subdivision).
    max_step_subintervals : int
        Largest jump between two samples (subintervals); 1 is the normal value.
    """

    indices: np.ndarray
    times_s: np.ndarray
    kinds: np.ndarray
    candidates: int
    hysteresis_subintervals: int
    transitions: int = 0
    skipped_transitions: int = 0
    max_step_subintervals: int = 0

    def __len__(self) -> int:
        return int(self.indices.size)


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
# input checks
# --------------------------------------------------------------------------------------------


def _as_signal(x: ArrayLike, name: str) -> FloatArray:
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim != 1:
        raise CaptureError(f"column '{name}' must be one-dimensional, got shape {arr.shape}.")
    if arr.size < _MIN_SAMPLES:
        raise CaptureError(
            f"column '{name}' has {arr.size} samples; at least {_MIN_SAMPLES} are needed."
        )
    return arr


def _check_finite(x: FloatArray, name: str) -> None:
    # One cheap pass (a sum of squares); only if it is out of range do we look for the culprits.
    if in_working_range(x):
        return
    bad = np.flatnonzero(~np.isfinite(x))
    if bad.size:
        raise CaptureError(
            f"column '{name}' has {bad.size} non-finite values (NaN or inf), the first at sample "
            f"{int(bad[0])}; remove or interpolate them before demodulating."
        )
    check_magnitudes(name, x, what="an encoder signal")


def _check_pair(a: ArrayLike, b: ArrayLike) -> tuple[FloatArray, FloatArray]:
    aa = _as_signal(a, "a")
    bb = _as_signal(b, "b")
    if aa.size != bb.size:
        raise CaptureError(
            f"columns 'a' and 'b' differ in length ({aa.size} and {bb.size} samples); "
            "they must be sampled together."
        )
    _check_finite(aa, "a")
    _check_finite(bb, "b")
    return aa, bb


def _check_varies(a: FloatArray, b: FloatArray) -> None:
    """Refuse a constant signal, or b an exact copy of a (or of −a): no phase can be demodulated."""
    check_not_constant("a", a, "it carries no encoder signal")
    check_not_constant("b", b, "it carries no encoder signal")
    check_not_copies(
        {"a": a, "b": b}, "a and b must be the two quadrature channels of the encoder (cos and sin)"
    )


def _clipping(aa: FloatArray, bb: FloatArray, allow_clipped: bool) -> tuple[str, ...]:
    """Refuse a channel at the rails (or return the warnings when allowed): the one detector,
    each channel judged with the other as its companion (a table at rest where a channel peaks
    is not a rail)."""
    return check_clipping(
        {
            "a": find_clipping(aa, "a", companion=bb),
            "b": find_clipping(bb, "b", companion=aa),
        },
        allow_clipped=allow_clipped,
    )


def _stride_for(n: int, max_points: int) -> int:
    if max_points < _MIN_SAMPLES:
        raise ConfigError(f"max_points={max_points} is too small; use at least {_MIN_SAMPLES}.")
    return max(1, -(-n // max_points))


# --------------------------------------------------------------------------------------------
# Heydemann correction
# --------------------------------------------------------------------------------------------


def _coverage(u: FloatArray, v: FloatArray) -> float:
    """Arc of the period covered by the points (rad): 2π minus the largest empty angular gap."""
    psi = np.arctan2(v, u)
    bins = np.floor((psi + math.pi) * (_COVERAGE_BINS / _TWO_PI)).astype(np.intp)
    np.clip(bins, 0, _COVERAGE_BINS - 1, out=bins)
    occupied = np.flatnonzero(np.bincount(bins, minlength=_COVERAGE_BINS))
    if occupied.size == 0:
        return 0.0
    gaps = np.diff(np.concatenate((occupied, [occupied[0] + _COVERAGE_BINS]))) - 1
    return float(_TWO_PI * (1.0 - gaps.max() / _COVERAGE_BINS))


def _normal_equations(x: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Normal equations of the conic A x² + B y² + C xy + D x + E y = 1, accumulated in chunks."""
    m = np.zeros((5, 5))
    r = np.zeros(5)
    for s in range(0, x.size, _CHUNK):
        xs = x[s : s + _CHUNK]
        ys = y[s : s + _CHUNK]
        design = np.stack((xs * xs, ys * ys, xs * ys, xs, ys), axis=1)
        m += design.T @ design
        r += design.sum(axis=0)
    return m, r


def _conic_to_ellipse(c: FloatArray) -> tuple[float, float, float, float, float] | None:
    """Centre, amplitudes and phase error from the conic coefficients (None if not an ellipse)."""
    big_a, big_b, big_c, d, e = (float(z) for z in c)
    disc = 4.0 * big_a * big_b - big_c * big_c
    if not (big_a > 0.0 and big_b > 0.0 and disc > 0.0):
        return None
    p = (big_c * e - 2.0 * big_b * d) / disc
    q = (big_c * d - 2.0 * big_a * e) / disc
    g = 1.0 + big_a * p * p + big_b * q * q + big_c * p * q
    if g <= 0.0:
        return None
    sin_alpha = -big_c / (2.0 * math.sqrt(big_a * big_b))
    cos_alpha = math.sqrt(max(0.0, 1.0 - sin_alpha * sin_alpha))
    if cos_alpha <= 1e-9:
        return None
    ra = math.sqrt(g / big_a) / cos_alpha
    rb = math.sqrt(g / big_b) / cos_alpha
    return p, q, ra, rb, math.asin(sin_alpha)


def _apply(
    a: FloatArray, b: FloatArray, p: float, q: float, ra: float, rb: float, alpha: float
) -> tuple[FloatArray, FloatArray]:
    u = a - p
    u *= 1.0 / ra
    v = b - q
    v *= 1.0 / (rb * math.cos(alpha))
    if alpha != 0.0:
        v -= u * math.tan(alpha)
    return u, v


def _fit(aa: FloatArray, bb: FloatArray, max_points: int) -> QuadratureCorrection:
    stride = _stride_for(aa.size, max_points)
    a_s = aa[::stride]
    b_s = bb[::stride]
    _check_varies(a_s, b_s)
    ma, mb = float(a_s.mean()), float(b_s.mean())
    sa, sb = float(a_s.std()), float(b_s.std())
    for s, name in ((sa, "a"), (sb, "b")):
        if not s > 0.0:
            raise CaptureError(f"column '{name}' is constant; it carries no encoder signal.")
    x = (a_s - ma) / sa
    y = (b_s - mb) / sb
    n_used = int(x.size)

    # 1. Heydemann: linear least squares on the conic, parameters from its coefficients.
    m, r = _normal_equations(x, y)
    ellipse = None
    if np.linalg.cond(m) < 1e13:
        ellipse = _conic_to_ellipse(np.linalg.solve(m, r))
    if ellipse is not None:
        p, q, ra, rb, alpha = ellipse
        ratio = (rb * sb) / (ra * sa)
        sane = abs(alpha) <= MAX_PHASE_ERROR_RAD and 1 / MAX_AMPLITUDE_RATIO < ratio
        sane = sane and ratio < MAX_AMPLITUDE_RATIO
        coverage = _coverage(*_apply(x, y, p, q, ra, rb, alpha))
        if sane and coverage >= FULL_COVERAGE_FRACTION * _TWO_PI:
            return QuadratureCorrection(
                offset_a=ma + sa * p,
                offset_b=mb + sb * q,
                amplitude_a=sa * ra,
                amplitude_b=sb * rb,
                phase_error_rad=alpha,
                method="heydemann",
                coverage_rad=coverage,
                points_used=n_used,
            )

    # 2. Circle (amplitude ratio 1, phase error 0 kept nominal): x² + y² = D x + E y + F, with the
    #    same scale on both axes so that the circle stays a circle in the signals' own unit.
    s = max(sa, sb)
    xc = (a_s - ma) / s
    yc = (b_s - mb) / s
    design = np.stack((xc, yc, np.ones_like(xc)), axis=1)
    mc = design.T @ design
    rc = design.T @ (xc * xc + yc * yc)
    circle_ok = False
    coverage_c = 0.0
    pc = qc = rad = 0.0
    if np.linalg.cond(mc) < 1e13:
        d, e, f = np.linalg.solve(mc, rc)
        pc, qc = float(d) / 2.0, float(e) / 2.0
        r2 = float(f) + pc * pc + qc * qc
        if r2 > 0.0:
            rad = math.sqrt(r2)
            coverage_c = _coverage(xc - pc, yc - qc)
            radial = np.hypot(xc - pc, yc - qc) - rad
            circle_ok = float(np.sqrt(np.mean(radial * radial))) < MAX_CIRCLE_RESIDUAL * rad
    if coverage_c >= FULL_COVERAGE_FRACTION * _TWO_PI:
        # The data go all round, yet no sane ellipse fits them: not a quadrature pair.
        detail = ""
        if ellipse is not None:
            ratio = (ellipse[3] * sb) / (ellipse[2] * sa)
            detail = (
                f" (fitted phase error {math.degrees(ellipse[4]):.1f}°, "
                f"amplitude ratio b/a {ratio:.3g})"
            )
        raise CaptureError(
            "columns 'a' and 'b' are not in quadrature" + detail + "; check that they are the "
            "two channels of the same encoder (cos and sin), not one channel twice or a ≈ ±b."
        )
    if circle_ok and coverage_c >= MIN_ARC_RAD:
        return QuadratureCorrection(
            offset_a=ma + s * pc,
            offset_b=mb + s * qc,
            amplitude_a=s * rad,
            amplitude_b=s * rad,
            phase_error_rad=0.0,
            method="offsets only (partial period)",
            coverage_rad=coverage_c,
            points_used=n_used,
        )
    raise CaptureError(
        "columns 'a' and 'b' do not trace an arc of an ellipse: either they are not in quadrature "
        "(a ≈ ±b) or the motion covers less than 1/8 of a signal period; check the columns, or "
        "fit the correction on a capture with more motion (--correction-from in the CLI, "
        "correction= in Python)."
    )


def fit_quadrature_correction(
    a: ArrayLike, b: ArrayLike, *, max_points: int = 1_000_000, allow_clipped: bool = False
) -> QuadratureCorrection:
    """Fit offsets, amplitudes and phase error of two quadrature signals (Heydemann correction).

    A linear least-squares fit of the conic ``A a² + B b² + C ab + D a + E b = 1`` (on centred,
    scaled signals; normal equations accumulated in chunks) gives the ellipse the signals trace;
    offsets, amplitudes and phase error follow in closed form. At most ``max_points`` samples are
    used, on an even stride over the whole capture.

    When the data cover less than 80 % of the signal period the ellipse is ill-determined; the fit
    then keeps the nominal amplitude ratio 1 and phase error 0 and fits a circle, which still gives
    the offsets (``method="offsets only (partial period)"``). Below 1/8 of a period nothing can be
    fitted and a :class:`~rotacal.errors.CaptureError` asks for a correction from another capture.

    Parameters
    ----------
    a, b : array_like
        The two signals (any unit, e.g. V), ``a ≈ cos φ``, ``b ≈ sin φ``.
    max_points : int
        Largest number of samples used in the fit.
    allow_clipped : bool
        Fit signals with samples at the rails (:mod:`rotacal.signal.clipping`) anyway, saying so
        in the result's ``warnings``; refused by default (a clipped arc biases the ellipse).

    Returns
    -------
    QuadratureCorrection
        Offsets and amplitudes in the unit of the signals, phase error in rad.

    Raises
    ------
    CaptureError
        Different lengths, non-finite values, values beyond float64's working range (|x| > 1e100,
        or a column all below 1e-100), constant signals, b a copy of a (or of −a), clipped
        signals, signals that are not in quadrature (phase error beyond 45° or amplitude ratio
        beyond 5), or too short an arc.

    References
    ----------
    Heydemann, P. L. M. 1981, Determination and correction of quadrature fringe measurement errors
    in interferometers, Appl. Opt. 20:3382–3384, eqs. (1)–(6).
    Feng et al. 2023, Sensors 23:4876, §3 (signal preprocessing before the subdivision).
    """
    aa, bb = _check_pair(a, b)
    clipped = _clipping(aa, bb, allow_clipped)
    return with_warnings(_fit(aa, bb, max_points), clipped)


def correct_quadrature(
    a: ArrayLike, b: ArrayLike, correction: QuadratureCorrection
) -> tuple[FloatArray, FloatArray]:
    """Turn the raw signals into ``(u, v) ≈ (cos φ, sin φ)``.

    ``u = (a − p)/R_a``, ``v = ((b − q)/R_b − u·sin α)/cos α``.

    Parameters
    ----------
    a, b : array_like
        Raw signals (unit of the correction, e.g. V).
    correction : QuadratureCorrection
        Offsets and amplitudes (signal unit), phase error (rad).

    Returns
    -------
    u, v : ndarray
        Corrected signals (dimensionless, unit circle).

    References
    ----------
    Heydemann, P. L. M. 1981, Appl. Opt. 20:3382–3384, eqs. (1)–(2) solved for cos φ and sin φ.
    """
    aa = np.asarray(a, dtype=np.float64)
    bb = np.asarray(b, dtype=np.float64)
    if aa.shape != bb.shape:
        raise CaptureError(
            f"columns 'a' and 'b' differ in shape ({aa.shape} and {bb.shape}); "
            "they must be sampled together."
        )
    c = check_correction(correction)
    return _apply(aa, bb, c.offset_a, c.offset_b, c.amplitude_a, c.amplitude_b, c.phase_error_rad)


def check_correction(c: QuadratureCorrection) -> QuadratureCorrection:
    """Refuse a correction that cannot be applied (amplitudes ≤ 0, |phase error| ≥ π/2)."""
    if not (c.amplitude_a > 0 and c.amplitude_b > 0 and abs(c.phase_error_rad) < math.pi / 2):
        raise ConfigError(
            f"correction has amplitudes {c.amplitude_a:g}, {c.amplitude_b:g} and phase error "
            f"{c.phase_error_rad:g} rad; amplitudes must be > 0 and |phase error| < π/2."
        )
    return c


# --------------------------------------------------------------------------------------------
# phase and angle
# --------------------------------------------------------------------------------------------


def unwrapped_phase(
    u: ArrayLike, v: ArrayLike, *, state: PhaseState | None = None
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
    phase = cycles * _TWO_PI
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


# --------------------------------------------------------------------------------------------
# reversals
# --------------------------------------------------------------------------------------------


def _odd_runs(direction: NDArray[np.int8]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """First transition and length of each run of an odd number of consecutive trend changes."""
    change = direction[1:] != direction[:-1]  # change[j-1]: transition j turns the trend
    padded = np.concatenate(([False], change, [False]))
    edges = np.flatnonzero(padded[1:] != padded[:-1])
    starts = edges[0::2]
    lengths = edges[1::2] - starts
    odd = (lengths % 2) == 1
    return starts[odd] + 1, lengths[odd]


def _no_reversals(hyst: int, n_trans: int, skipped: int, max_step: int) -> ReversalPlan:
    """The plan of a capture in which no reversing moment was found."""
    no_windows = np.empty((0, 2), dtype=np.intp)
    return ReversalPlan(
        no_windows,
        no_windows.copy(),
        np.empty(0, dtype=np.int8),
        0,
        hyst,
        n_trans,
        skipped,
        max_step,
    )


def _candidates(
    k_after: FloatArray, dk: FloatArray
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.int8], FloatArray]:
    """Reversal candidates of eqs. (5)–(6): runs of an odd number of consecutive trend changes.

    Transition j leads from subinterval visit j to visit j+1; visit m ≥ 1 holds the count
    ``k_after[m-1]``. A trend change at transition j makes visit j a turning visit, so a run of L
    changes starting at transition j0 has the turning visits j0 .. j0+L-1.

    Returns the first transition j0 and length L of each odd run, its kind (+1: a maximum of θ,
    the direction before the run was increasing) and its level (the extreme k of its turning
    visits: the highest for a maximum, the lowest for a minimum).
    """
    direction = np.sign(dk).astype(np.int8)
    first_change, run_len = _odd_runs(direction)
    if first_change.size == 0:
        return first_change, run_len, np.empty(0, dtype=np.int8), np.empty(0)
    kinds = direction[first_change - 1]
    seg = np.empty(2 * first_change.size, dtype=np.intp)
    seg[0::2] = first_change - 1
    seg[1::2] = first_change - 1 + run_len
    hi = np.maximum.reduceat(k_after, seg)[0::2]
    lo = np.minimum.reduceat(k_after, seg)[0::2]
    return first_change, run_len, kinds, np.where(kinds > 0, hi, lo)


def reversing_subintervals(
    phase_rad: ArrayLike,
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.int8]]:
    """The subintervals holding a reversing moment, exactly as the paper identifies them.

    Runs of an even number of consecutive trend changes hold no reversal (eq. (5)); a run of an
    odd number holds one, in its middle subinterval visit (eq. (6): in {4,5,6,7,8,7,8,7,6,5} the
    second 7). No cluster pruning is applied here (see :func:`find_reversals`).

    Parameters
    ----------
    phase_rad : array_like
        Unwrapped signal phase φ (rad).

    Returns
    -------
    sub_minus, sub_plus : ndarray of int
        First and last sample index (inclusive) of each reversing subinterval visit.
    kinds : ndarray of int8
        +1 where the reversal is a maximum of θ, −1 a minimum.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1, eqs. (5)–(6).
    """
    idx, k_after, dk, _ = _transitions(np.asarray(phase_rad, dtype=np.float64))
    if idx.size < 2:
        empty = np.empty(0, dtype=np.intp)
        return empty, empty.copy(), np.empty(0, dtype=np.int8)
    first_change, run_len, kinds, _ = _candidates(k_after, dk)
    middle = first_change + (run_len - 1) // 2
    return idx[middle - 1], idx[middle] - 1, kinds


#: ``(lo, hi) → (u, v)`` of samples lo..hi (inclusive): the corrected signals of a window.
WindowSignals = Callable[[int, int], tuple[FloatArray, FloatArray]]


def _reversal_point(signals: WindowSignals, n: int, first: int, last: int) -> int:
    """Chp of eqs. (7)–(8): the extreme sample of the faster-changing signal in [Sub⁻, Sub⁺]."""
    if last <= first:
        return first
    lo, hi = reversal_window(first, last, n)
    return lo + reversal_point_in_window(*signals(lo, hi))


def _pinned(plan: ReversalPlan, t: FloatArray, signals: WindowSignals) -> Reversals:
    """The reversals of a plan, each pinned to its Chp (eqs. (7)–(8)) with its time (s)."""
    chp = [_reversal_point(signals, t.size, int(f), int(last)) for f, last in plan.windows.tolist()]
    indices = plan.indices(chp)
    return Reversals(
        indices=indices,
        times_s=t[indices],
        kinds=plan.kinds,
        candidates=plan.candidates,
        hysteresis_subintervals=plan.hysteresis_subintervals,
        transitions=plan.transitions,
        skipped_transitions=plan.skipped_transitions,
        max_step_subintervals=plan.max_step_subintervals,
    )


def reversal_window(first: int, last: int, n_samples: int) -> tuple[int, int]:
    """Samples that eqs. (7)–(8) read for the reversing subinterval visit ``[first, last]``.

    rotacal takes the sums of eqs. (7)–(8) with the samples just outside [Sub⁻, Sub⁺] as
    endpoints (both lie in the subinterval the motion came from and returned to), so that the
    sign of q stays right when [Sub⁻, Sub⁺] spans several visits of the extreme subinterval.

    Parameters
    ----------
    first, last : int
        Sub⁻ and Sub⁺, first and last sample index (inclusive) of the visit.
    n_samples : int
        Samples in the capture.

    Returns
    -------
    lo, hi : int
        First and last sample index (inclusive) to read; ``lo == hi == first`` when the visit is
        a single sample (its Chp is that sample, nothing needs reading).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.2, eqs. (7)–(8).
    """
    if last <= first:
        return first, first
    return max(first - 1, 0), min(last + 1, n_samples - 1)


def reversal_point_in_window(u_window: ArrayLike, v_window: ArrayLike) -> int:
    """Chp of eqs. (7)–(8) within the samples of :func:`reversal_window`, as an offset.

    ``qu = Σ u − n·(u_first + u_last)/2`` and likewise ``qv``; the signal with the larger |q|
    changes most; Chp is its maximum if q > 0, its minimum if q < 0 (the middle sample if q = 0).

    Parameters
    ----------
    u_window, v_window : array_like
        Corrected signals (dimensionless) at samples ``lo .. hi`` of :func:`reversal_window`.

    Returns
    -------
    int
        Chp − lo (samples).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.2, eqs. (7)–(8).
    """
    us = np.asarray(u_window, dtype=np.float64)
    vs = np.asarray(v_window, dtype=np.float64)
    if us.size < 2:
        return 0
    qu = float(np.sum(us)) - us.size * 0.5 * (us[0] + us[-1])
    qv = float(np.sum(vs)) - vs.size * 0.5 * (vs[0] + vs[-1])
    seg, q = (us, qu) if abs(qu) >= abs(qv) else (vs, qv)
    if q > 0:
        return int(np.argmax(seg))
    if q < 0:
        return int(np.argmin(seg))
    return (us.size - 1) // 2


@dataclasses.dataclass(frozen=True)
class ReversalPlan:
    """Reversing moments found from the subinterval transitions, before their precise point.

    Everything of :func:`find_reversals` except eqs. (7)–(8), which need the signals: a chunked
    caller reads the samples of each window in a later pass over the capture.

    Attributes
    ----------
    windows : ndarray of int, shape (m, 2)
        ``[Sub⁻, Sub⁺]`` (sample indices, inclusive) of each reversing subinterval visit whose
        Chp is needed; see :func:`reversal_window` for the samples to read.
    pairs : ndarray of int, shape (r, 2)
        Rows of ``windows`` for each reversal: its index is ``(chp[p0] + chp[p1]) // 2``
        (``p0 == p1`` for a reversal that is a single candidate).
    kinds : ndarray of int8
        +1 for a maximum of θ, −1 for a minimum.
    candidates, hysteresis_subintervals, transitions, skipped_transitions, max_step_subintervals
        As in :class:`Reversals`.
    """

    windows: np.ndarray
    pairs: np.ndarray
    kinds: np.ndarray
    candidates: int
    hysteresis_subintervals: int
    transitions: int
    skipped_transitions: int
    max_step_subintervals: int

    def indices(self, chp: ArrayLike) -> NDArray[np.intp]:
        """Sample index of each reversal from the Chp (sample index) of every window."""
        c = np.asarray(chp, dtype=np.intp)
        if self.pairs.shape[0] == 0:
            return np.empty(0, dtype=np.intp)
        return (c[self.pairs[:, 0]] + c[self.pairs[:, 1]]) // 2


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


def plan_reversals(
    transition_indices: ArrayLike,
    k_after: ArrayLike,
    k_start: float,
    *,
    hysteresis_subintervals: int | None = None,
    stacklevel: int = 2,
) -> ReversalPlan:
    """Reversing moments from the list of subinterval transitions (steps 1–3 of find_reversals).

    Parameters
    ----------
    transition_indices : array_like of int
        Sample index of every transition of the capture, increasing.
    k_after : array_like
        Subinterval count k after each transition.
    k_start : float
        k of the capture's first sample.
    hysteresis_subintervals : int, optional
        See :func:`find_reversals`.
    stacklevel : int
        Passed to :func:`warnings.warn` for the :class:`SubdivisionWarning`.

    Returns
    -------
    ReversalPlan
        Windows whose Chp (eqs. (7)–(8)) is still to be found, and how they make reversals.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1 eqs. (3)–(6).
    """
    idx = np.asarray(transition_indices, dtype=np.intp)
    ka = np.asarray(k_after, dtype=np.float64)
    k0 = float(k_start)
    if hysteresis_subintervals is not None and (
        isinstance(hysteresis_subintervals, bool)
        or int(hysteresis_subintervals) != hysteresis_subintervals
        or hysteresis_subintervals < 1
    ):
        raise ConfigError(
            f"hysteresis_subintervals={hysteresis_subintervals!r} must be a whole number ≥ 1."
        )
    n_trans = int(idx.size)
    dk = np.diff(ka, prepend=k0) if n_trans else np.empty(0)
    step = np.abs(dk)
    skipped = int(np.count_nonzero(step > 1.0))
    max_step = int(step.max()) if n_trans else 0
    if max_step >= _MAX_SAFE_STEP:
        # A jump of 5 subintervals is 150° of the signal period: one more and the unwrapping
        # cannot tell forward from backward, so the angle would be silently wrong.
        raise CaptureError(
            f"the encoder phase jumps by up to {30 * max_step}° of a signal period between two "
            "samples: the capture is sampled too slowly for the motion (or too noisy) to be "
            "demodulated — sample faster (at least 12 samples per signal period at the highest "
            "rate)."
        )
    if skipped:
        warnings.warn(
            f"{skipped} of {n_trans} subinterval transitions skipped subintervals (largest jump "
            f"{max_step} of 12 per signal period): the sampling is too slow for the subdivision"
            + ("; above 5 the phase unwrapping itself is ambiguous." if max_step > 5 else "."),
            SubdivisionWarning,
            stacklevel=stacklevel,
        )
    if n_trans:
        k_lo = min(k0, float(ka.min()))
        k_hi = max(k0, float(ka.max()))
    else:
        k_lo = k_hi = k0
    if hysteresis_subintervals is None:
        hyst = max(2, round(0.1 * (k_hi - k_lo)))
    else:
        hyst = int(hysteresis_subintervals)

    if n_trans < 2:
        return _no_reversals(hyst, n_trans, skipped, max_step)
    first_change, run_len, kinds, level = _candidates(ka, dk)
    n_cand = int(first_change.size)
    if n_cand == 0:
        return _no_reversals(hyst, n_trans, skipped, max_step)

    # rotacal's extension: clusters of candidates closer than the hysteresis.
    linked = np.abs(np.diff(level)) < hyst
    cluster_start = np.flatnonzero(np.concatenate(([True], ~linked)))
    cluster_size = np.diff(np.append(cluster_start, n_cand))
    keep = cluster_size % 2 == 1
    rev_kinds = kinds[cluster_start[keep]].astype(np.int8)

    def window(c: int) -> tuple[int, int]:
        j0 = int(first_change[c])
        levels = ka[j0 - 1 : j0 - 1 + int(run_len[c])]
        at_extreme = np.flatnonzero(levels == level[c])
        return int(idx[j0 - 1 + int(at_extreme[0])]), int(idx[j0 + int(at_extreme[-1])]) - 1

    windows: list[tuple[int, int]] = []
    pairs = np.empty((int(np.count_nonzero(keep)), 2), dtype=np.intp)
    for i, (start, size) in enumerate(
        zip(cluster_start[keep].tolist(), cluster_size[keep].tolist(), strict=True)
    ):
        windows.append(window(start))
        if size == 1:
            pairs[i] = len(windows) - 1
        else:
            # A cluster straddles the reversal symmetrically: take the middle of its
            # outermost extremes (both of the cluster's kind).
            windows.append(window(start + size - 1))
            pairs[i] = (len(windows) - 2, len(windows) - 1)
    return ReversalPlan(
        windows=np.asarray(windows, dtype=np.intp).reshape(-1, 2),
        pairs=pairs,
        kinds=rev_kinds,
        candidates=n_cand,
        hysteresis_subintervals=hyst,
        transitions=n_trans,
        skipped_transitions=skipped,
        max_step_subintervals=max_step,
    )


def find_reversals(
    t: ArrayLike,
    u: ArrayLike,
    v: ArrayLike,
    phase_rad: ArrayLike,
    *,
    hysteresis_subintervals: int | None = None,
) -> Reversals:
    """Reversing moments of the motion, each pinned to one sample.

    1. Subinterval count ``k = ⌊φ/(π/6)⌋``; a transition is a sample where k changes, its
       direction the sign of the change (eqs. (3)–(4)).
    2. A trend change is a transition whose direction differs from the previous one. A run of an
       even number of consecutive trend changes holds no reversal (eq. (5)); an odd run holds one
       (eq. (6)): a *candidate*, a maximum of θ if the direction before the run was increasing,
       else a minimum. Its *level* is the extreme k of the run's turning visits (the highest for
       a maximum, the lowest for a minimum).
    3. *rotacal's extension* (not in the paper): a vibration superposed on the motion near a
       reversal moves it back and forth by more than one subinterval, so the candidates of step 2
       come in extra max/min pairs. Neighbouring candidates (which alternate max/min) whose levels
       differ by less than ``hysteresis_subintervals`` are linked into a cluster; a cluster of an
       odd number of candidates is one reversal, of the kind of its first candidate, an even
       number none.
    4. Where the reversal lies: for a single candidate, the window ``[Sub⁻, Sub⁺]`` runs from the
       first to the last of its turning visits that sit at its level (in eq. (6)'s
       {4,5,6,7,8,7,8,7,6,5} that is 8-7-8, the two visits of 8 and the 7 between them); for a
       cluster, the windows of its first and last candidate (both of the cluster's kind).
    5. In each window the sums ``qu``, ``qv`` of eqs. (7)–(8), with the samples just outside
       ``[Sub⁻, Sub⁺]`` as endpoints (:func:`reversal_window`), pick the signal that changes
       most; Chp is its minimum if q < 0 and its maximum if q > 0. Within a run of trend changes
       k alternates between two neighbouring levels, so a window spans at most 60° of φ, over
       which at least one signal is monotonic in φ (the one that changes most, unless the other
       is near its own extreme), and then its extreme is that of φ. The
       sign of q is set against the endpoints, which lie in the neighbouring level: when most of
       a long window sits in that level too, q can point to the dip instead (2 of 977 reversals
       of a noisy synthetic capture with a vibration faster than the motion). A single
       candidate's reversing moment is its Chp; a cluster's is the sample midway between the
       Chp of its first and last candidate (the cluster straddles the reversal symmetrically).

    How this differs from the paper's literal rule, also with the pruning off: the paper takes
    the *middle* turning visit of an odd run as the reversing subinterval (eq. (6): the second
    7) and searches eqs. (7)–(8) between that visit's own endpoints; rotacal searches the visits
    at the run's extreme level, where θ is extreme (in the example the paper's 7 lies in the dip
    between the two visits of 8), with one sample more on each side (:func:`reversal_window`).
    :func:`reversing_subintervals` gives the paper's middle visits exactly.

    The hysteresis. Neighbouring candidates always differ by at least 2 subintervals (between a
    maximum and the next minimum the motion goes down twice in a row), so a hysteresis of 1 or 2
    links none: every candidate of step 2 is a reversal, which is the paper's odd/even rule of
    eqs. (5)–(6) — with the reversing point of steps 4–5, not the paper's. The default is not
    that rule: it is 10 % of the span of k over the capture (at least 2), which prunes vibration
    pairs up to a tenth of the stroke. A table that drifts spans more than it swings, so the
    sinusoidal-motion calibration with ``drift=True`` passes 10 % of the span without the drift
    (:func:`demodulate`'s ``hysteresis_from``).

    Parameters
    ----------
    t : array_like
        Time of each sample (s).
    u, v : array_like
        Corrected signals ≈ (cos φ, sin φ) (dimensionless).
    phase_rad : array_like
        Unwrapped phase φ (rad) from :func:`unwrapped_phase`.
    hysteresis_subintervals : int, optional
        Smallest difference in level (30° subintervals of the signal period) between a maximum
        and a neighbouring minimum that keeps them apart (step 3); 1 or 2 turns the pruning off.
        Default: 10 % of the peak-to-peak of k, at least 2.

    Returns
    -------
    Reversals
        Sample indices, times (s) and kinds (+1 maximum of θ, −1 minimum).

    Warns
    -----
    SubdivisionWarning
        When k jumps by more than one subinterval between samples (sampling too slow for the
        subdivision); directions stay valid while jumps are below 6 subintervals (π).

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.1 eqs. (3)–(6) and §3.2 eqs. (7)–(8).
    """
    tt = np.asarray(t, dtype=np.float64)
    uu = np.asarray(u, dtype=np.float64)
    vv = np.asarray(v, dtype=np.float64)
    phase = np.asarray(phase_rad, dtype=np.float64)
    if not (tt.shape == uu.shape == vv.shape == phase.shape) or phase.ndim != 1:
        raise CaptureError(
            "t, u, v and phase_rad must be one-dimensional and of equal length, got "
            f"{tt.shape}, {uu.shape}, {vv.shape} and {phase.shape}."
        )
    idx, k_after, _, k0 = _transitions(phase)
    plan = plan_reversals(
        idx, k_after, k0, hysteresis_subintervals=hysteresis_subintervals, stacklevel=3
    )
    return _pinned(plan, tt, lambda lo, hi: (uu[lo : hi + 1], vv[lo : hi + 1]))


def intercept_periods(reversals: Reversals, n_periods: int | None = None) -> tuple[int, int, int]:
    """Sample range of n whole motion periods, bounded by 2n+1 reversing moments.

    The first ``2n+1`` reversals are used; the range runs from the first of them to the last,
    inclusive.

    Parameters
    ----------
    reversals : Reversals
        From :func:`find_reversals`.
    n_periods : int, optional
        Number of motion periods wanted; None takes as many as the capture holds.

    Returns
    -------
    first, last, n : int
        First and last (inclusive) sample index, and the number of periods n.

    Raises
    ------
    CaptureError
        Fewer than 2n+1 reversals (fewer than 3 when ``n_periods`` is None).
    ConfigError
        ``n_periods`` below 1.

    References
    ----------
    Feng et al. 2023, Sensors 23:4876, §3.3.
    """
    count = len(reversals.indices)
    available = (count - 1) // 2 if count else 0
    if n_periods is not None:
        if isinstance(n_periods, bool) or int(n_periods) != n_periods or n_periods < 1:
            raise ConfigError(f"n_periods={n_periods!r} must be a whole number ≥ 1.")
        n = int(n_periods)
    else:
        n = max(available, 1)
    if n > available:
        raise CaptureError(
            f"the capture holds {count} reversing moments, enough for {available} whole motion "
            f"periods, but {n} were asked for ({2 * n + 1} reversals needed); record a longer "
            "capture or ask for fewer periods."
        )
    return int(reversals.indices[0]), int(reversals.indices[2 * n]), n


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
    aa, bb = _check_pair(a, b)
    tt = _check_time(t, aa.size)
    clipped = _clipping(aa, bb, allow_clipped)
    if correction is None:
        correction = _fit(aa, bb, max_points)
    else:
        stride = _stride_for(aa.size, max_points)
        _check_varies(aa[::stride], bb[::stride])
    # correction, phase and subinterval transitions in one pass (the signals u, v are not kept:
    # eqs. (7)–(8) correct the few samples of each reversal window again)
    from rotacal.encoder._kernel import phase_pass

    run = phase_pass(aa, bb, correction)
    phase = run.phase_rad
    if hysteresis_subintervals is None and hysteresis_from is not None:
        step = hysteresis_stride(phase.size)
        hysteresis_subintervals = hysteresis_from(tt[::step], phase[::step])
    plan = plan_reversals(
        run.indices, run.k_after, run.k_first, hysteresis_subintervals=hysteresis_subintervals
    )
    corr = correction
    reversals = _pinned(
        plan, tt, lambda lo, hi: correct_quadrature(aa[lo : hi + 1], bb[lo : hi + 1], corr)
    )
    scale = 360.0 / (_TWO_PI * float(lines))
    theta = phase
    theta *= scale
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
