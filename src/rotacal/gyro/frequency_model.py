"""The second-order model of a gyro's dynamic response, fitted across frequencies.

A rate gyro's response to the table's rate is modelled as the unit-gain second-order low-pass

    H(s) = ωn² / (s² + 2ζωn·s + ωn²),   s = j·2πf,   ωn = 2π·fn,

optionally times a pure delay ``exp(−s·τ)`` (a digital gyro's group delay, or a constant time
skew between the reference and the DUT channels). The −3 dB bandwidth is where |H| = 1/√2 (half
power); for the model it has the closed form

    f_3dB = fn·√(c + √(c² + 1)),   c = 1 − 2ζ²

(|H|² = 1/((1 − x)² + 4ζ²x) with x = (f/fn)²; setting it to ½ gives x² − 2c·x − 1 = 0). The delay
changes the phase only, never the bandwidth.

The fit is weighted nonlinear least squares of the amplitude ratio and the phase at each
frequency (each residual divided by its standard uncertainty), by ``scipy.optimize.least_squares``
from the best point of a coarse grid. The covariance of the parameters is ``(JᵀJ)⁻¹`` at the
solution (GUM, JCGM 100:2008, §5.1 and annex H.3 for the least-squares case), multiplied by the
Birge ratio χ²/ν when that exceeds one (the points scatter more than their uncertainties say: the
spread, not the stated uncertainties, then sets the parameters' uncertainty). A time skew common
to every capture (a Type B input of the phase, the same at every frequency, hence fully
correlated), or a timebase error, is propagated into the parameters through their sensitivity to
it, ``(JᵀJ)⁻¹Jᵀ·g`` with g the change of the weighted data per unit of the input
(:class:`CommonInput`); the bandwidth's uncertainty
follows from the parameters' covariance by the first-order propagation of GUM §5.2.2.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import optimize

from rotacal.errors import CaptureError
from rotacal.uncertainty.quantiles import chi2_ppf

__all__ = [
    "CommonInput",
    "SecondOrderFit",
    "bandwidth_from_model",
    "fit_second_order",
    "second_order_response",
]

#: χ² beyond this quantile of its distribution reads as lack of fit (a warning).
LACK_OF_FIT_QUANTILE = 0.999
_TWO_PI = 2.0 * math.pi


def second_order_response(
    frequency_hz: Any, natural_frequency_hz: float, damping_ratio: float, delay_s: float = 0.0
) -> np.ndarray:
    """H(j·2πf) of the unit-gain second-order low-pass, times ``exp(−j·2πf·τ)``.

    Parameters
    ----------
    frequency_hz : array_like — f (Hz).
    natural_frequency_hz : float — fn = ωn/2π (Hz), > 0.
    damping_ratio : float — ζ (-), > 0.
    delay_s : float — pure delay τ (s).

    Returns
    -------
    numpy.ndarray of complex — H at each f (-).
    """
    x = np.asarray(frequency_hz, dtype=np.float64) / natural_frequency_hz
    h = 1.0 / (1.0 - x * x + 2j * damping_ratio * x)
    if delay_s:
        h = h * np.exp(-1j * _TWO_PI * np.asarray(frequency_hz, dtype=np.float64) * delay_s)
    return h


def _model_phase_deg(f: np.ndarray, fn: float, zeta: float, delay_s: float) -> np.ndarray:
    """Continuous phase of the model (deg): 0 → −180° for the low-pass, minus 360·f·τ."""
    x = f / fn
    return -np.degrees(np.arctan2(2.0 * zeta * x, 1.0 - x * x)) - 360.0 * f * delay_s


def bandwidth_from_model(natural_frequency_hz: float, damping_ratio: float) -> float:
    """The −3 dB (|H| = 1/√2) bandwidth of the second-order low-pass (Hz), closed form.

    ``f_3dB = fn·√(c + √(c² + 1))`` with ``c = 1 − 2ζ²`` (module docstring); ζ = 1/√2 gives fn.

    Parameters
    ----------
    natural_frequency_hz : float — fn (Hz).
    damping_ratio : float — ζ (-), ≥ 0.
    """
    c = 1.0 - 2.0 * damping_ratio**2
    return natural_frequency_hz * math.sqrt(c + math.sqrt(c * c + 1.0))


def _bandwidth_gradient(fn: float, zeta: float) -> np.ndarray:
    """(∂f_3dB/∂fn, ∂f_3dB/∂ζ) of :func:`bandwidth_from_model`."""
    c = 1.0 - 2.0 * zeta**2
    root = math.sqrt(c * c + 1.0)
    x = c + root
    dx_dzeta = -4.0 * zeta * (1.0 + c / root)
    return np.array([math.sqrt(x), fn * dx_dzeta / (2.0 * math.sqrt(x))])


@dataclasses.dataclass(frozen=True)
class CommonInput:
    """A Type B input common to every point (fully correlated across frequencies).

    Attributes
    ----------
    name : str — what it is, for messages.
    ratio_shift : array — change of each measured amplitude ratio per unit of the input (-).
    phase_shift_deg : array — change of each measured phase per unit of the input (deg).
    u : float — the input's standard uncertainty (its unit).
    parameter_relative_shift : array, optional — relative change of (fn, ζ[, τ]) per unit of the
        input that does not go through the points (a timebase error e scales every frequency by
        1 + e: fn by 1 + e, τ by 1/(1 + e), i.e. (1, 0, −1)).
    """

    name: str
    ratio_shift: np.ndarray
    phase_shift_deg: np.ndarray
    u: float
    parameter_relative_shift: np.ndarray | None = None


@dataclasses.dataclass(frozen=True)
class SecondOrderFit:
    """The fitted second-order model and its uncertainties.

    Attributes
    ----------
    natural_frequency_hz, natural_frequency_hz_u : fn and u(fn) (Hz).
    damping_ratio, damping_ratio_u : ζ and u(ζ) (-).
    bandwidth_hz, bandwidth_hz_u : −3 dB bandwidth of the fitted model and its u (Hz).
    delay_s, delay_s_u : the pure delay τ and u(τ) (s); None when no delay was fitted.
    covariance : covariance of (fn, ζ[, τ]) in Hz, -, s, all inputs included.
    chi_squared : Σ of the squared weighted residuals (Type A uncertainties only).
    degrees_of_freedom : 2·frequencies − parameters.
    birge_ratio : χ²/ν when it exceeded one and scaled the covariance, else 1.
    lack_of_fit : χ² beyond its 99.9 % quantile.
    """

    natural_frequency_hz: float
    natural_frequency_hz_u: float
    damping_ratio: float
    damping_ratio_u: float
    bandwidth_hz: float
    bandwidth_hz_u: float
    delay_s: float | None
    delay_s_u: float | None
    covariance: np.ndarray
    chi_squared: float
    degrees_of_freedom: int
    birge_ratio: float
    lack_of_fit: bool

    def response(self, frequency_hz: Any) -> np.ndarray:
        """The fitted H at ``frequency_hz`` (Hz), complex (-)."""
        return second_order_response(
            frequency_hz, self.natural_frequency_hz, self.damping_ratio, self.delay_s or 0.0
        )

    def phase_deg(self, frequency_hz: Any) -> np.ndarray:
        """The fitted model's continuous phase (deg) at ``frequency_hz`` (Hz)."""
        f = np.asarray(frequency_hz, dtype=np.float64)
        return _model_phase_deg(
            f, self.natural_frequency_hz, self.damping_ratio, self.delay_s or 0.0
        )


def _residuals(
    p: np.ndarray,
    f: np.ndarray,
    ratio: np.ndarray,
    u_ratio: np.ndarray,
    phase: np.ndarray,
    u_phase: np.ndarray,
) -> np.ndarray:
    fn, zeta = p[0], p[1]
    tau = p[2] if p.size > 2 else 0.0
    x = f / fn
    mag = 1.0 / np.sqrt((1.0 - x * x) ** 2 + (2.0 * zeta * x) ** 2)
    ph = _model_phase_deg(f, fn, zeta, tau)
    return np.concatenate(((mag - ratio) / u_ratio, (ph - phase) / u_phase))


def _start(f: np.ndarray, args: tuple[np.ndarray, ...], delay: bool) -> np.ndarray:
    """The best (fn, ζ) of a coarse logarithmic grid (τ starts at 0): the fit's start."""
    fn, zeta = np.meshgrid(
        np.geomspace(f.min() / 4.0, f.max() * 20.0, 80), np.geomspace(0.02, 5.0, 24)
    )
    ratio, u_ratio, phase, u_phase = args
    x = f / fn.reshape(-1, 1)
    z = zeta.reshape(-1, 1)
    mag = 1.0 / np.sqrt((1.0 - x * x) ** 2 + (2.0 * z * x) ** 2)
    ph = -np.degrees(np.arctan2(2.0 * z * x, 1.0 - x * x))
    cost = np.sum(((mag - ratio) / u_ratio) ** 2 + ((ph - phase) / u_phase) ** 2, axis=1)
    best = int(np.argmin(cost))
    start = [float(fn.ravel()[best]), float(zeta.ravel()[best])]
    return np.array([*start, 0.0] if delay else start)


def fit_second_order(
    frequency_hz: Any,
    amplitude_ratio: Any,
    amplitude_ratio_u: Any,
    phase_deg: Any,
    phase_deg_u: Any,
    *,
    delay: bool = False,
    common: Sequence[CommonInput] = (),
) -> SecondOrderFit:
    """Weighted least-squares fit of H(s) = ωn²/(s² + 2ζωn s + ωn²) [· e^(−sτ)] to measured points.

    Parameters
    ----------
    frequency_hz : array_like — f of each point (Hz), distinct.
    amplitude_ratio, amplitude_ratio_u : array_like — |H| measured and its standard uncertainty
        (-), Type A (the sine fits').
    phase_deg, phase_deg_u : array_like — arg H measured, continuous across f (deg), and its
        standard uncertainty (deg) without the common time skew.
    delay : bool — fit the pure delay τ as a third parameter.
    common : sequence of CommonInput — Type B inputs that move every point together (a time skew
        between the channels, a timebase error), propagated into the parameters.

    Returns
    -------
    SecondOrderFit

    Raises
    ------
    CaptureError
        Fewer frequencies than parameters, or points that do not determine the parameters.

    References
    ----------
    JCGM 100:2008 (GUM) §5.1–5.2 and annex H.3 (least-squares fit, propagation); the model is
    the standard second-order system (e.g. IEEE Std 1431-2004's dynamic response of a CVG).
    """
    f = np.asarray(frequency_hz, dtype=np.float64)
    args = tuple(
        np.asarray(v, dtype=np.float64)
        for v in (amplitude_ratio, amplitude_ratio_u, phase_deg, phase_deg_u)
    )
    n_par = 3 if delay else 2
    if f.size < n_par:
        raise CaptureError(
            f"{f.size} frequenc{'y' if f.size == 1 else 'ies'} for a model of {n_par} parameters "
            f"(natural frequency, damping{', delay' if delay else ''}): give captures at "
            f"{n_par} or more frequencies"
        )
    if not (
        all(np.all(np.isfinite(a)) for a in args) and np.all(args[1] > 0) and np.all(args[3] > 0)
    ):
        raise CaptureError("a point's amplitude ratio, phase or uncertainty is not finite or ≤ 0")
    p0 = _start(f, args, delay)
    lower = [f.min() * 1e-3, 1e-4] + ([-np.inf] if delay else [])
    upper = [f.max() * 1e3, 1e3] + ([np.inf] if delay else [])
    sol = optimize.least_squares(
        _residuals,
        p0,
        args=(f, *args),
        bounds=(lower, upper),
        x_scale="jac",
        xtol=1e-14,
        ftol=1e-14,
        gtol=1e-14,
        max_nfev=2000,
    )
    j = sol.jac
    jtj = j.T @ j
    if np.linalg.matrix_rank(jtj) < n_par or np.linalg.cond(jtj) > 1e14:
        raise CaptureError(
            "the frequencies measured do not determine the natural frequency and damping: "
            "add captures near and above the DUT's bandwidth"
        )
    cov_a = np.linalg.inv(jtj)
    chi2 = float(np.sum(sol.fun**2))
    dof = 2 * f.size - n_par
    birge = chi2 / dof if dof > 0 and chi2 > dof else 1.0
    cov = cov_a * birge
    for c in common:
        # the optimum moves by (JᵀJ)⁻¹Jᵀ·(δy/u) when the data move by δy (the weighted
        # residuals are (model − y)/u), plus what the input does to the parameters directly
        g = np.concatenate((c.ratio_shift / args[1], c.phase_shift_deg / args[3]))
        sens = cov_a @ (j.T @ g)
        if c.parameter_relative_shift is not None:
            sens = sens + sol.x * np.asarray(c.parameter_relative_shift, dtype=float)[:n_par]
        cov = cov + np.outer(sens, sens) * c.u**2
    fn, zeta = float(sol.x[0]), float(sol.x[1])
    grad = _bandwidth_gradient(fn, zeta)
    sub = cov[:2, :2]
    lack = dof > 0 and chi2 > chi2_ppf(LACK_OF_FIT_QUANTILE, dof)
    return SecondOrderFit(
        natural_frequency_hz=fn,
        natural_frequency_hz_u=math.sqrt(cov[0, 0]),
        damping_ratio=zeta,
        damping_ratio_u=math.sqrt(cov[1, 1]),
        bandwidth_hz=bandwidth_from_model(fn, zeta),
        bandwidth_hz_u=math.sqrt(max(float(grad @ sub @ grad), 0.0)),
        delay_s=float(sol.x[2]) if delay else None,
        delay_s_u=math.sqrt(cov[2, 2]) if delay else None,
        covariance=cov,
        chi_squared=chi2,
        degrees_of_freedom=dof,
        birge_ratio=birge,
        lack_of_fit=bool(lack),
    )
