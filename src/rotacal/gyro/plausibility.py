"""Plausibility checks of the gyro calibrations: signs, sizes and fits a working gyro does not give.

Each function returns warning lines (what was seen, the number, the likely cause, what to check)
for the result's ``warnings``; an empty list when all is plausible. The shared statistics are in
:mod:`rotacal.signal.plausibility`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rotacal.signal.plausibility import (
    chi_square_test,
    lack_of_fit_warning,
    replicate_lack_of_fit,
)

__all__ = [
    "FALLING_SLOPE",
    "NONLINEARITY_LIMIT_PERCENT_FS",
    "REST_LIMIT",
    "SCATTER_LIMIT_PERCENT_FS",
    "allan_warnings",
    "multiposition_warnings",
    "negative_diagonal_warnings",
    "rotation_warnings",
    "scale_factor_warnings",
    "triad_fit_warnings",
]

#: Nonlinearity beyond which the straight line is no calibration of a working gyro (%FS).
NONLINEARITY_LIMIT_PERCENT_FS = 10.0
#: Rate at a rotation section's first or last sample, relative to its peak, beyond which the
#: section does not start or end at rest.
REST_LIMIT = 0.05
#: Log-log slope of σ(τ) at the longest τ below which the Allan deviation still falls (white
#: rate noise is −½, a flat bias-instability floor 0).
FALLING_SLOPE = -0.25
#: rms scatter of the rate points about a smooth cubic below which a lack of fit is too small to
#: matter (%FS): a tenth of the 0.5 %FS nonlinearity limits of yaw-rate sensors. The points' Type
#: A u (s/√n) assumes independent samples and is small for a correlated (real) gyro output: the
#: real XinLi rate table's 11 points scatter 22 u but 0.016 %FS about the cubic.
SCATTER_LIMIT_PERCENT_FS = 0.05
#: Degree of the smooth curve the scale-factor points must follow (S(1 + k₂Ω + k₃Ω²)).
_SMOOTH_DEGREE = 3

_AXES = "xyz"


def negative_diagonal_warnings(kmat: np.ndarray, columns: Sequence[str], check: str) -> list[str]:
    """One line per negative diagonal element of K (u = K·ω + b): output i falls as the DUT turns
    positively about its own axis i.

    Parameters
    ----------
    kmat : ndarray (3, 3)
        Scale/misalignment matrix (output unit per °/s).
    columns : sequence of 3 str
        The output columns, for the message.
    check : str
        What the user should check, for the message.
    """
    out = []
    for i, k_ii in enumerate(np.diag(np.asarray(kmat, dtype=float))):
        if k_ii < 0:
            out.append(
                f"K_{_AXES[i]}{_AXES[i]} = {k_ii:.6g} is negative: {columns[i]} falls while the "
                f"DUT turns positively about {_AXES[i]} (right-hand rule) — its axis is mounted "
                f"reversed or {check}"
            )
    return out


def triad_fit_warnings(
    fit_residual: np.ndarray,
    groups: np.ndarray,
    keep: np.ndarray,
    columns: Sequence[str],
    quanta: Sequence[float] = (0.0, 0.0, 0.0),
) -> list[str]:
    """The lack-of-fit F test of u = K·ω + b, per output, on the rows kept.

    Parameters
    ----------
    fit_residual : ndarray (n, 3)
        Output minus fitted K·ω + b (output unit).
    groups : ndarray (n,) of int
        The rate point of each row.
    keep : ndarray (n, 3) of bool
        Rows kept by the outlier rejection, per output.
    columns : sequence of 3 str
        The output columns, for the message.
    quanta : sequence of 3 float
        Output step of each channel (0 when not quantised): its rounding q²/12 biases each point
        mean beyond the repeats' scatter.

    References
    ----------
    NIST/SEMATECH e-Handbook of Statistical Methods (2012), §4.4.4.3; the robot-manipulator study (2023) (the model).
    """
    out = []
    for c in range(3):
        kc = keep[:, c]
        test = replicate_lack_of_fit(fit_residual[kc, c], groups[kc], 4, quanta[c] ** 2 / 12.0)
        line = lack_of_fit_warning(
            f"u = K·ω + b for {columns[c]}",
            test,
            "the point means scatter about the plane more than their repeats do — a nonlinear or "
            "rate-dependent output, a set rate the table did not reach, or drift between the "
            "points; check the rate points of that output",
        )
        if line is not None:
            out.append(line)
    return out


def scale_factor_warnings(
    *,
    scale_factor: float,
    nonlinearity_percent_fs: float,
    rates_deg_s: np.ndarray,
    residuals: np.ndarray,
    point_u: np.ndarray | None,
    full_scale_deg_s: float,
    output_unit: str,
    quantum: float | None = None,
) -> list[str]:
    """Warnings of a single-axis scale-factor test (Kokuyama et al. 2015, §4).

    * a negative scale factor (the output falls as the rate rises);
    * a nonlinearity beyond :data:`NONLINEARITY_LIMIT_PERCENT_FS`;
    * lack of fit: the point residuals about the line scatter about a smooth cubic (the
      nonlinearity a gyro has) more than the points' Type A uncertainties explain — the χ² test
      of :func:`rotacal.signal.plausibility.chi_square_test`, ν = points − 4 — by more than
      :data:`SCATTER_LIMIT_PERCENT_FS` rms.

    Parameters
    ----------
    scale_factor : float
        S (output unit per °/s).
    nonlinearity_percent_fs : float
        NL (%FS).
    rates_deg_s, residuals : ndarray
        The set rates (°/s) and the point means' residuals about the line (output unit).
    point_u : ndarray or None
        Standard uncertainty of each point mean (output unit), Type A; None when unknown.
    full_scale_deg_s : float
        FS (°/s).
    output_unit : str
        For the message.
    quantum : float or None
        Output step (output unit): its rounding q²/12 adds to each point mean's variance.
    """
    out = []
    unit = f" {output_unit}" if output_unit else ""
    if scale_factor < 0:
        out.append(
            f"the scale factor {scale_factor:.6g}{unit}/(°/s) is negative: the output falls as the "
            "set rate rises — the gyro is mounted upside down, the table's sense of rotation is "
            "reversed, or rate_deg_s has the wrong sign; check the mounting and the sign of the "
            "set rates"
        )
    if nonlinearity_percent_fs > NONLINEARITY_LIMIT_PERCENT_FS:
        out.append(
            f"the nonlinearity {nonlinearity_percent_fs:.4g} %FS is beyond "
            f"{NONLINEARITY_LIMIT_PERCENT_FS:g} %FS, more than a working gyro shows: points at "
            "the gyro's rails, a --full-scale-deg-s beyond the gyro's range, or an output column "
            "that is not the gyro's; check the rate points and the columns"
        )
    rates = np.asarray(rates_deg_s, dtype=float)
    rounding = 0.0 if quantum is None else quantum**2 / 12.0
    u = None if point_u is None else np.sqrt(np.asarray(point_u, dtype=float) ** 2 + rounding)
    if (
        u is not None
        and rates.size > _SMOOTH_DEGREE + 1
        and full_scale_deg_s > 0
        and np.all(np.isfinite(u) & (u > 0))
    ):
        x = rates / full_scale_deg_s
        coef = np.polyfit(x, residuals, _SMOOTH_DEGREE, w=1.0 / u)
        smooth = residuals - np.polyval(coef, x)
        scatter = 100.0 * float(np.sqrt(np.mean(smooth**2))) / abs(scale_factor * full_scale_deg_s)
        test = chi_square_test(smooth, u, rates.size - _SMOOTH_DEGREE - 1)
        if not scatter > SCATTER_LIMIT_PERCENT_FS:
            test = None
        line = lack_of_fit_warning(
            "a smooth cubic through the residuals of the rate points",
            test,
            f"the points scatter {scatter:.3g} %FS rms about it (limit "
            f"{SCATTER_LIMIT_PERCENT_FS:g} %FS) — a set rate the table did not reach, "
            f"drift between the points, or a disturbed point (largest: "
            f"{_worst_point(rates, smooth, u)}); repeat that point",
        )
        if line is not None:
            out.append(line)
    return out


def _worst_point(rates: np.ndarray, resid: np.ndarray, u: np.ndarray) -> str:
    z = np.abs(resid) / u
    i = int(np.argmax(z))
    return f"{rates[i]:g} °/s at {z[i]:.3g} u" if math.isfinite(z[i]) else f"{rates[i]:g} °/s"


def rotation_warnings(
    rate: np.ndarray,
    offset: np.ndarray,
    sections: Sequence[tuple[str, int, int]],
    angle_residual_deg: np.ndarray,
    angle_u_deg: np.ndarray,
) -> list[str]:
    """Warnings of a calibration from rotations through known angles (Ferraris).

    * a rotation section that does not start or end at rest: |u − b| at its first or last sample
      above :data:`REST_LIMIT` of the section's peak — the integral then misses part of the turn
      (Ferraris et al. 1995 integrate from rest to rest);
    * lack of fit with more than three rotations: the χ² test of the angle residuals
      (K⁻¹·Θ − φ, 3 per rotation, ν = 3m − 9) against their white-noise uncertainty.

    Parameters
    ----------
    rate, offset : ndarray (n, 3)
        Raw outputs and the offset removed (output unit).
    sections : sequence of (label, start, stop)
        The rotation sections (half-open sample ranges).
    angle_residual_deg, angle_u_deg : ndarray (m, 3)
        Angle residual of each rotation (deg) and its standard uncertainty (deg).

    References
    ----------
    Ferraris F., Grimaldi U., Parvis M. (1995), Sensors and Materials 7(5):311–330, eqs.
    (12)–(15); Cox M. G. (2002), Metrologia 39:589–595, §5.1 (the χ² test).
    """
    out = []
    for label, s, e in sections:
        mag = np.linalg.norm(rate[s:e] - offset[s:e], axis=1)
        peak = float(mag.max())
        ends = {"starts": float(mag[0]), "ends": float(mag[-1])}
        for where, value in ends.items():
            if peak > 0 and value > REST_LIMIT * peak:
                out.append(
                    f"the rotation section about {label} [{s}, {e}) {where} while turning (rate "
                    f"{100 * value / peak:.3g} % of its peak, limit {100 * REST_LIMIT:g} %): the "
                    "integral misses part of the turn — widen the section to rest on both sides"
                )
    m = len(sections)
    if m > 3:
        test = chi_square_test(angle_residual_deg, angle_u_deg, 3 * m - 9)
        line = lack_of_fit_warning(
            "K·φ through the rotations",
            test,
            "the rotations disagree beyond their noise — an angle other than the one set, a "
            "rotation labelled with the wrong axis, or the offset changing during a turn; check "
            "the section list and the angles",
        )
        if line is not None:
            out.append(line)
    return out


def allan_warnings(
    *, bias_instability: float | None, local_slope: np.ndarray, tau_s: np.ndarray
) -> list[str]:
    """Warning of a rate record too short to show the bias instability.

    IEEE Std 952 Annex C reads B on the flat part of σ(τ); when no flat part was found and the
    curve still falls at the longest τ (log-log slope below :data:`FALLING_SLOPE`), the record
    ends before the floor and B is not reported.

    Parameters
    ----------
    bias_instability : float or None
        B as found (°/h), None when not seen.
    local_slope, tau_s : ndarray
        Log-log slope of σ(τ) and the τ it was taken at (s).

    References
    ----------
    IEEE Std 952-1997, Annex C, Table C.1 and Fig. C.2 (the slopes of σ(τ)).
    """
    slopes = np.asarray(local_slope, dtype=float)
    taus = np.asarray(tau_s, dtype=float)
    if bias_instability is not None or slopes.size == 0 or not slopes[-1] < FALLING_SLOPE:
        return []
    return [
        f"no bias instability: the Allan deviation still falls at the longest τ, {taus[-1]:.4g} s "
        f"(slope {slopes[-1]:+.2f}, limit {FALLING_SLOPE:+.2f}) — the record is too short to "
        "reach the flat floor; record several times longer (τ up to a tenth of the record)"
    ]


def multiposition_warnings(residuals: np.ndarray, position: np.ndarray, n_params: int) -> list[str]:
    """Lack of fit of the multiposition drift model, where positions hold repeated readings.

    The lack-of-fit F test (:func:`rotacal.signal.plausibility.replicate_lack_of_fit`) of the
    position means about the 7-coefficient model against the repeats' pure error.

    Parameters
    ----------
    residuals : ndarray (N,)
        Output minus model, one per reading (deg/h).
    position : ndarray (N,) of int
        The position of each reading.
    n_params : int
        Coefficients fitted.

    References
    ----------
    Seed 001 eqs. (1)–(6) (the model); NIST/SEMATECH e-Handbook (2012) §4.4.4.3.
    """
    line = lack_of_fit_warning(
        "the drift model through the positions",
        replicate_lack_of_fit(residuals, position, n_params),
        "the position means scatter about the model more than their repeats do — a term the "
        "model lacks (a g-sensitivity of another axis, temperature), a wrong --latitude-deg or "
        "--axis, or positions other than the angles recorded; check the position list",
    )
    return [] if line is None else [line]
