"""Heydemann correction of an encoder's two quadrature signals: checks, fit and application.

The first step of the chain of :mod:`rotacal.encoder.quadrature`: the raw signals are checked
(lengths, finite values, not constant, not copies, clipping) and corrected for offset, gain
mismatch and phase error (Heydemann 1981, Appl. Opt. 20:3382–3384) before the phase is taken.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result, with_warnings
from rotacal.signal._values import (
    check_magnitudes,
    check_not_constant,
    check_not_copies,
    in_working_range,
)
from rotacal.signal.clipping import (
    RailDetector,
    check_clipping,
    find_quadrature_clipping,
    quadrature_rail_detectors,
)

FloatArray = NDArray[np.floating[Any]]
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


def _check_pair_and_rails(
    a: ArrayLike, b: ArrayLike
) -> tuple[FloatArray, FloatArray, tuple[RailDetector, RailDetector]]:
    """:func:`_check_pair`'s checks and both channels' rail detectors in one reading of the
    pair: a channel whose detector saw only finite values inside the working range needs no
    pass of its own (:meth:`~rotacal.signal.clipping.RailDetector.in_working_range`; the
    others get :func:`_check_finite`, which names the fault). The same refusals, in the same
    order; judge the rails with :func:`_rails_verdict` when the other checks have passed."""
    aa = _as_signal(a, "a")
    bb = _as_signal(b, "b")
    if aa.size != bb.size:
        _check_pair(aa, bb)  # its one-line refusal
    detectors = quadrature_rail_detectors(aa, bb)
    for x, name, det in ((aa, "a", detectors[0]), (bb, "b", detectors[1])):
        if not det.in_working_range():
            _check_finite(x, name)
    return aa, bb, detectors


def _rails_verdict(
    detectors: tuple[RailDetector, RailDetector], allow_clipped: bool
) -> tuple[str, ...]:
    """:func:`_clipping`'s refusal or warnings from the detectors of
    :func:`_check_pair_and_rails`."""
    return check_clipping(
        {"a": detectors[0].result(), "b": detectors[1].result()}, allow_clipped=allow_clipped
    )


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
    found_a, found_b = find_quadrature_clipping(aa, bb)
    return check_clipping({"a": found_a, "b": found_b}, allow_clipped=allow_clipped)


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
    # contiguous copies: the strided samples are read several times below (bit for bit the same)
    a_s = np.ascontiguousarray(aa[::stride])
    b_s = np.ascontiguousarray(bb[::stride])
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
    aa, bb, rails = _check_pair_and_rails(a, b)
    clipped = _rails_verdict(rails, allow_clipped)
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
