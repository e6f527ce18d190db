"""Slow drift in a sinusoidal-motion calibration (Feng et al. 2023): fitted on request, flagged otherwise.

A table that turns slowly on top of its sinusoidal motion, θ(t) = p(t) + d·t with p periodic,
does not fit the IEEE 1057 model of eq. (1)'s sine fit: over n whole periods the ramp d·τ
projects onto the sine terms as ``b_h = −2d·(−1)^{hn}/(2πhf)`` and reads as harmonic distortion
(0.01° over a 0.1° motion's record is ~0.4 % of THD), and a ramp much larger than the motion leaves
a residual so large that the frequency refinement circles its minimum. ``drift=True`` (``--drift``)
adds the linear term to the fit (:func:`~rotacal.signal.fit_harmonics`), so everything taken
from the fit — harmonics, THD and its Monte Carlo budget, amplitude, frequency, the curvature at
the reversals — is that of the periodic part; the position error of eq. (2) is taken on the
angle with the fitted drift removed. The reversing moments stay those of the table's real
motion, drift included (where its rate is zero): with a steady drift a maximum and the next
minimum are no longer half a period apart, but successive maxima still are one period apart, so
2n+1 reversals still bound n whole periods (§3.3). What changes is how they are found when the
drift is large against the stroke: the encoder's hysteresis is taken without the drift
(:func:`drift_free_hysteresis`) and the LTS's trigger follows it (:func:`prefit_drift`).

What drift means per scheme:

- **OSE and LTS** measure θ itself: the linear term of the angle fit is the drift, reported as
  ``drift_deg_s`` (deg/s) with its standard uncertainty ``drift_deg_s_u``.
- **FOG** measures θ̇ = p′(t) + d: a steady table drift is a constant of the rate, which eq. (9)'s
  D0 already takes (the FOG's THD never counted it as distortion, and eq. (12)'s D0·t is exactly
  the linear term of the integrated angle). A rate record cannot tell it from the gyro's bias:
  D0 = bias + d. What a rate fit cannot absorb, and what then reads as distortion, is a rate
  offset that changes over the record — a bias drifting with temperature, or a table drift that
  speeds up. So the FOG's ``drift=True`` adds the same linear term to *its* fitted signal, the
  rate: ``D0 + D1·(t − t_ref)``. It reports ``drift_deg_s`` = D0 (the angle's drift plus the gyro's
  bias, which only a separate bias measurement can split) and ``rate_drift_deg_s2`` = D1, each
  with ``_u``; the reversing moments are the zeros of the fitted rate without D0 + D1·τ and the
  position error integrates the rate less D0 + D1·τ.

The drift's standard uncertainty has two parts (:func:`drift_u`). The fit's own (white noise of
the residual) and the projection onto the linear term of whatever periodic content the fit leaves
beyond its highest harmonic N_H: over n whole periods a component of rms s_h at harmonic h > N_H
has ⟨r, τ⟩ of rms N·s_h/(hω), which moves D by that times (ΦᵀΦ)⁻¹_DD; with the whole residual s
taken at h = N_H + 1 this is ``u_p = N·u_fit²/((N_H + 1)·ω·s)`` (≈ 3sω/((N_H + 1)n²π²) for n ≥ 3).
A residual of pure noise makes u_p an overstatement (by √(3N)/((N_H + 1)nπ) at most); one of
unmodelled harmonics — stagnation, creep, a table's friction at its reversals — makes it the
term that counts: on the twin's Table 1 motions the fit's own u alone missed the true drift by
up to 7 u. D0 of the FOG is orthogonal to every harmonic over whole periods and has the fit's u.

Without ``drift`` the fit also solves, at its final frequency, the model with the linear term
(:class:`~rotacal.signal.DriftCheck`: one more linear solve, no pass over the samples for long
records). A warning says so when that drift is significant — at least ``DRIFT_SIGNIFICANCE``
times its standard uncertainty — and matters — fitting it would move the THD or the amplitude by
more than the standard uncertainty the result states for it. Both are needed: unmodelled periodic
content above the highest harmonic can make a tiny drift "significant" against white noise on a
long record without moving any result, and on a short noisy record a large-looking shift can be
noise.

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Sensors 23:4876, eqs. (1), (2), (9)–(14).
IEEE Std 1057-2017, §4.1.3 (sine fitting; the linear term is rotacal's extension).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from rotacal.encoder import HysteresisRule
from rotacal.errors import CaptureError
from rotacal.signal import SineFit, displacement_amplitudes_from_rate, fit_harmonics
from rotacal.uncertainty import UncertaintyBudget

__all__ = [
    "DRIFT_SIGNIFICANCE",
    "detrended_angle",
    "drift_fields",
    "drift_free_hysteresis",
    "drift_note",
    "drift_u",
    "drift_warnings",
    "explained_fit",
    "fit_motion",
    "prefit_drift",
    "unfitted_drift_warning",
]

#: A drift counts as seen when it is at least this many standard uncertainties from zero.
DRIFT_SIGNIFICANCE = 5.0


#: Changes of THD (pp) and relative amplitude below which fitting a drift moves only rounding.
_ROUNDING_THD_PP = 1e-9
_ROUNDING_RELATIVE = 1e-11


def fit_motion(
    t: np.ndarray, y: np.ndarray, f0: float, harmonics: int, drift: bool, rate: bool = False
) -> SineFit:
    """The analysis fit of n whole periods (frequency refined from ``f0``, Hz): with the linear
    term when ``drift``, else with its :class:`~rotacal.signal.DriftCheck` (and
    :func:`explained_fit`'s error when only the fit with the term converges)."""

    def fit(with_term: bool) -> SineFit:
        return fit_harmonics(
            t, y, frequency_hz=f0, harmonics=harmonics, drift=with_term, drift_check=not with_term
        )

    return explained_fit(fit, drift, rate)


def explained_fit(fit: Callable[[bool], SineFit], drift: bool, rate: bool = False) -> SineFit:
    """``fit(drift)``; when a fit without the linear term fails and one with it converges, a
    :class:`~rotacal.errors.CaptureError` that names the drift and asks for --drift.

    A drift the model lacks can make the fit fail, not only distort it: over one or two periods
    the ramp pulls the frequency away and the refinement diverges. ``rate``: y is a rate (the
    FOG), whose linear term is the rate's drift (deg/s²).
    """
    try:
        return fit(drift)
    except CaptureError as exc:
        if drift:
            raise
        try:
            with_term = fit(True)
        except CaptureError:
            raise exc from None
        what = "the rate drifts by {:.3g} deg/s²" if rate else "the table drifts by {:.3g} deg/s"
        raise CaptureError(
            f"{str(exc).split(';')[0]}, but with a linear drift term the fit converges: "
            f"{what.format(with_term.drift)} over the analysed periods — rerun with --drift"
        ) from None


def drift_u(fit: SineFit, drift_u_fit: float, residual_rms: float) -> float:
    """Standard uncertainty of a fitted linear term: the fit's own and the periodic residual's.

    Parameters
    ----------
    fit : SineFit — gives N, N_H and f.
    drift_u_fit : float — u of D from the fit's covariance (unit of y per s).
    residual_rms : float — rms of the residual of the fit with the linear term (unit of y).

    Returns
    -------
    float — ``√(u_fit² + u_p²)``, ``u_p = N·u_fit²/((N_H + 1)·2πf·s)`` (module docstring).
    """
    n = fit.n_samples
    s = residual_rms * math.sqrt(n / max(n - fit.n_parameters, 1))
    if not s > 0:
        return float(drift_u_fit)
    u_p = n * drift_u_fit**2 / ((fit.harmonics + 1) * 2.0 * math.pi * fit.frequency_hz * s)
    return math.hypot(drift_u_fit, u_p)


def drift_fields(scheme: str, fit: SineFit) -> dict[str, Any]:
    """The MotionResult fields of a fit with drift (empty for a fit without).

    OSE/LTS: ``drift_deg_s``, ``drift_deg_s_u`` (deg/s) = D of the angle fit. FOG: ``drift_deg_s``,
    ``drift_deg_s_u`` = the rate offset D0 (deg/s; the table's drift plus the gyro's bias) and
    ``rate_drift_deg_s2``, ``rate_drift_deg_s2_u`` = D1 (deg/s²). The u of D and D1 are
    :func:`drift_u`; that of D0 is the fit's.
    """
    if fit.drift is None:
        return {}
    u = drift_u(fit, float(fit.drift_u or 0.0), fit.residual_rms)
    if scheme == "fog":
        return {
            "drift_deg_s": float(fit.offset),
            "drift_deg_s_u": float(fit.offset_u),
            "rate_drift_deg_s2": float(fit.drift),
            "rate_drift_deg_s2_u": u,
        }
    return {"drift_deg_s": float(fit.drift), "drift_deg_s_u": u}


def drift_note(scheme: str, fit: SineFit) -> str | None:
    """The result's note on a fitted drift (None without one)."""
    if fit.drift is None:
        return None
    if scheme == "fog":
        return (
            "drift fitted (--drift): the rate offset D0 (drift_deg_s) is the table's drift plus "
            "the gyro's bias, which a rate record cannot split; it changes by "
            f"D1 = {fit.drift:.4g} deg/s per second; both removed from the motion"
        )
    return f"drift fitted (--drift): {fit.drift:.6g} deg/s, removed from the motion"


def detrended_angle(fit: SineFit, t: np.ndarray, angle_deg: np.ndarray) -> np.ndarray:
    """The angle less the fitted drift ``D·(t − t_ref)`` (itself for a fit without drift)."""
    if fit.drift is None:
        return angle_deg
    return np.asarray(angle_deg - fit.drift * (np.asarray(t) - fit.t_ref_s))


def prefit_drift(t: np.ndarray, x: np.ndarray, harmonics: int) -> float:
    """Drift (unit of x per s) of a whole capture, before its reversals are known.

    A straight line is taken off first, so that a drift larger than the motion cannot hide the
    motion's line from the frequency estimate; the multi-harmonic fit with the linear term then
    gives the rest of the drift (the line's slope is biased by the partial period at the ends).
    """
    tau = t - 0.5 * (t[0] + t[-1])
    slope = float(np.dot(tau, x - x.mean()) / np.dot(tau, tau))
    # block moments: one pass, then every iteration is cheap (the QR solver redoes N×(2H+2))
    fit = fit_harmonics(t, x - slope * tau, harmonics=harmonics, drift=True, method="blocks")
    assert fit.drift is not None
    return slope + fit.drift


def drift_free_hysteresis() -> HysteresisRule:
    """The encoder's reversal hysteresis with ``drift=True``: 10 % of the span of k (30°
    subintervals of the signal period) once the drift is taken off, at least 2.

    The default of :func:`~rotacal.encoder.find_reversals` is 10 % of the whole span of k, which
    for a table that drifts grows with the drift until it swallows real swings (2° of drift over
    a 0.2° stroke: every reversal merged). The rule sees every N // 20 000-th sample
    (:func:`~rotacal.encoder.demodulate`'s ``hysteresis_from``) and takes the drift off with a
    straight line fitted to them: a tenth of the stroke in whole subintervals needs no more (the
    line's slope is pulled by the partial periods at the ends, which moves the span by a part of
    the stroke, not by the drift), and it costs one pass over 20 000 samples.
    """

    def rule(t: np.ndarray, phase_rad: np.ndarray) -> int | None:
        if t.size < 2:
            return None
        tau = t - t.mean()
        slope = float(np.dot(tau, phase_rad - phase_rad.mean()) / np.dot(tau, tau))
        k = (phase_rad - slope * tau) * (6.0 / math.pi)
        return max(2, round(0.1 * float(np.ptp(k))))

    return rule


def _displacement(scheme: str, amplitudes: np.ndarray, frequency_hz: float) -> np.ndarray:
    if scheme == "fog":
        return displacement_amplitudes_from_rate(amplitudes, frequency_hz)
    return np.asarray(amplitudes)


def _thd(a: np.ndarray) -> float:
    return 100.0 * math.sqrt(float(a[1:] @ a[1:])) / float(a[0])


def drift_warnings(
    scheme: str, fit: SineFit, budgets: Mapping[str, UncertaintyBudget], span_s: float
) -> list[str]:
    """The :func:`unfitted_drift_warning` of a result (its THD and amplitude budgets), if any."""
    amp = budgets["amplitude_deg"]
    line = unfitted_drift_warning(
        scheme,
        fit,
        thd_percent_u=budgets["thd_percent"].u,
        amplitude_relative_u=amp.u / amp.value,
        span_s=float(span_s),
    )
    return [] if line is None else [line]


def unfitted_drift_warning(
    scheme: str,
    fit: SineFit,
    *,
    thd_percent_u: float,
    amplitude_relative_u: float,
    span_s: float,
) -> str | None:
    """The warning line for a drift seen in a fit without drift that matters, else None.

    Parameters
    ----------
    scheme : ``"encoder"``, ``"lts"`` or ``"fog"``.
    fit : SineFit — the fit without drift, with its ``drift_check``.
    thd_percent_u : float, pp — the THD's stated standard uncertainty.
    amplitude_relative_u : float — the amplitude's stated relative standard uncertainty.
    span_s : float, s — the analysed span.
    """
    check = fit.drift_check
    if check is None or not check.drift_u > 0:
        return None
    significance = abs(check.drift) / drift_u(fit, check.drift_u, check.residual_rms)
    if not significance >= DRIFT_SIGNIFICANCE:
        return None
    f = fit.frequency_hz
    a_now = _displacement(scheme, fit.amplitudes, f)
    a_drift = _displacement(scheme, check.amplitudes, f)
    d_thd = _thd(a_drift) - _thd(a_now)
    d_amp = float(a_drift[0] / a_now[0] - 1.0)
    # a noise-free capture has u ≈ 0: moves at the rounding level of the sums are no drift
    if not (
        abs(d_thd) > max(thd_percent_u, _ROUNDING_THD_PP)
        or abs(d_amp) > max(amplitude_relative_u, _ROUNDING_RELATIVE)
    ):
        return None
    moves = (
        f"fitting it moves the THD by {d_thd:+.3g} pp (its u is {thd_percent_u:.2g} pp) and the "
        f"amplitude by {100 * d_amp:+.3g} % (u {100 * amplitude_relative_u:.2g} %)"
    )
    if scheme == "fog":
        return (
            f"the rate drifts by {check.drift:.3g} deg/s² ({check.drift * span_s:.3g} deg/s over "
            f"the {span_s:.4g} s analysed, {significance:.0f} times its u), which the fit did not "
            f"model; {moves} — rerun with --drift"
        )
    return (
        f"the angle drifts by {check.drift:.3g} deg/s ({check.drift * span_s:.3g}° over the "
        f"{span_s:.4g} s analysed, {significance:.0f} times its u), which the fit did not model; "
        f"{moves} — rerun with --drift"
    )
