"""Sinusoidal-motion calibration from angle or counter readings (Feng et al. 2023 on the angle itself).

Most labs read a table's encoder through a counter card or the table's controller and log the
angle (``angle_deg``) or the up/down count (``count``), not the analogue sine/cosine. The angle
is then the measurand of Feng et al. (2023) directly: as in their LTS scheme (§5), the reversing
moments are its extremes (:func:`~rotacal.table.extreme_reversals`), n whole periods are cut
between 2n + 1 of them (§3.3), and the IEEE 1057 multi-harmonic fit of the angle gives the
amplitude, frequency, angular acceleration, THD (eq. (1)) and, with set values, their errors and
the angular position error (eq. (2)). The budgets are those of
:func:`~rotacal.table.motion_uncertainty.motion_budgets` (Type A from the fit, timebase), with the
readout's resolution added as a Type B input (:func:`with_resolution`).

Before that, the DAQ's lost and doubled samples are found from ``time_s``
(:mod:`rotacal.signal.daq_faults`) and a counter's register wrap is unwrapped
(:mod:`rotacal.signal.counter`).

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Sensors 23, 4876, eqs. (1), (2), §3.3, §5.
IEEE Std 1057-2017 §4.1.3 (sine fit); JCGM 100:2008 §4.3.7 (Type B); R. M. Gray (1990),
Quantization noise spectra, IEEE Trans. Inf. Theory 36(6):1220 (the quantisation error of a sine).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rotacal._threads import one_blas_thread
from rotacal.errors import CaptureError, ConfigError
from rotacal.results import with_warnings
from rotacal.signal import check_sampling
from rotacal.signal._values import check_magnitudes
from rotacal.signal.counter import counts_to_angle_deg, unwrap_counts
from rotacal.signal.daq_faults import find_daq_faults
from rotacal.table.motion import (
    MotionResult,
    _check_settings,
    check_pair_shapes,
    displacement_motion,
)
from rotacal.uncertainty import Input, InstrumentSpecs, UncertaintyBudget, propagate
from rotacal.uncertainty.notes import tidy

__all__ = [
    "angle_quantum",
    "calibrate_angle_motion",
    "calibrate_count_motion",
    "quantisation_u",
    "with_resolution",
]

#: Samples looked at to tell a quantised readout (its values on a grid).
_QUANTUM_SAMPLES = 200_000
#: The budgets the readout's quantisation of A₁ enters.
_RESOLUTION_KEYS = (
    "amplitude_deg",
    "angular_acceleration_amplitude_deg_s2",
    "amplitude_error_percent",
    "angular_acceleration_error_percent",
)
#: The amplitude-check hint of the LTS scheme's plausibility lines, and the angle's own.
_LTS_HINT = "--radius-mm (laser spot to table axis, in mm) and --set-amplitude-deg"
_ANGLE_HINT = "--counts-per-rev (or the readout's unit: degrees) and --set-amplitude-deg"
#: The result's note on where θ comes from.
READ_DIRECTLY = "θ read directly (angle readout or counter)"


def angle_quantum(angle_deg: np.ndarray) -> float | None:
    """The quantum q (deg) of a quantised angle readout, or None for a continuous one.

    Rule: the smallest positive difference q between distinct readings among the first
    :data:`_QUANTUM_SAMPLES`; the readout is quantised when every one of those readings is a
    whole multiple of q (to 10⁻⁶·q, the decimal rounding of a logged value) and at most 10⁴
    quanta span them (a finer grid is noise, not a readout's step).
    """
    a = np.unique(np.asarray(angle_deg[:_QUANTUM_SAMPLES], dtype=np.float64))
    if a.size < 3:
        return None
    d = np.diff(a)
    q = float(np.min(d))
    if not q > 0:
        return None
    span = (a[-1] - a[0]) / q
    if span > 1e4 * a.size:  # more grid steps than readings by far: a continuous signal
        return None
    k = (a - a[0]) / q
    if np.max(np.abs(k - np.rint(k))) > 1e-6 * max(1.0, float(np.max(np.abs(k)))) + 1e-6:
        return None
    return q


def quantisation_u(
    quantum_deg: float,
    amplitude_deg: float,
    harmonics: int,
    samples_per_period: float,
    noise_deg: float = 0.0,
) -> np.ndarray:
    """Standard uncertainty (deg) of each harmonic amplitude A_h, h = 1…N, from a readout's
    quantisation of a sinusoidal angle (Type B).

    The quantisation error of θ = A·sin φ + c is periodic in θ,
    ``e = (q/π)·Σ_k ((−1)^k/k)·sin(2πkθ/q)``, so it repeats with the motion and is not averaged
    by a fit over many periods. Two evaluations, the larger taken:

    * continuous time (Gray 1990, eq. (21)): by the Jacobi–Anger expansion harmonic h of e has,
      over an unknown offset c uniform within a quantum, the rms
      ``(q/π)·√(2·Σ_k J_h(2πkA/q)²·g_k²/k²)``;
    * sampled: with P samples per period (commensurate sampling repeats the same phases) the
      error's repeating power ``(q²/2π²)·Σ_k g_k²/k²`` (= q²/12 without noise) is averaged over
      one period's samples only, and the motion's symmetry θ(φ) = θ(π − φ) puts it all in one
      quadrature of each harmonic: ``u = √(power·4/P)``.

    Both are the rms of the error's magnitude at harmonic h (checked against a Monte Carlo over
    the offset, commensurate and not: the larger of the two holds it, at most twice over).

    ``g_k = exp(−2π²k²σ²/q²)`` is the attenuation by white noise σ on θ before the readout (a
    dithered quantiser's error no longer repeats; the noise itself is in the fit's Type A).

    Parameters
    ----------
    quantum_deg : q (deg); amplitude_deg : A (deg), the fundamental; harmonics : N;
    samples_per_period : P; noise_deg : σ (deg).

    References
    ----------
    R. M. Gray (1990), Quantization noise spectra, IEEE Trans. Inf. Theory 36(6):1220–1244, §IV
    (sinusoidal input); JCGM 100:2008 §4.3.7.
    """
    from scipy.special import jv

    q = float(quantum_deg)
    k = np.arange(1, 4001, dtype=np.float64)  # terms fall as k^-3: 4000 leave < 10⁻⁷ of the sum
    g = np.exp(-2.0 * (math.pi * k * float(noise_deg) / q) ** 2)
    beta = 2.0 * math.pi * k * abs(float(amplitude_deg)) / q
    h = np.arange(1, int(harmonics) + 1, dtype=np.float64)[:, None]
    gray = (q / math.pi) * np.sqrt(2.0 * np.sum((jv(h, beta) * g) ** 2 / k**2, axis=1))
    power = q * q / (2.0 * math.pi**2) * float(np.sum(g**2 / k**2))
    sampled = math.sqrt(power * 4.0 / max(float(samples_per_period), 1.0))
    return np.asarray(np.maximum(gray, sampled))


def with_resolution(result: MotionResult, quantum_deg: float, what: str) -> MotionResult:
    """``result`` with the readout's quantisation in the budgets of A, α, their errors and THD.

    Each harmonic amplitude A_h gets the Type B u of :func:`quantisation_u` (q = the quantum;
    P = samples per motion period; σ² = the fit's residual variance less q²/12, the noise that
    dithers the readout). A_1's enters the amplitude budget (sensitivity 1; α: ω²; the errors
    against set values: 100/A_set and 100·ω²/α_set); all enter the THD's evaluation
    (:func:`~rotacal.table.motion_uncertainty.thd_uncertainty` with u_h² + u_q,h²).

    Parameters
    ----------
    result : MotionResult — a calibration of the angle.
    quantum_deg : float, deg — the readout's resolution q (one count: 360/N).
    what : str — the resolution's name in the budget (e.g. ``"1 count of 36000/rev"``).
    """
    from rotacal.table.motion_uncertainty import fit_dof, thd_uncertainty

    if not (math.isfinite(quantum_deg) and quantum_deg > 0):
        raise ConfigError(f"the readout's resolution must be positive, got {quantum_deg}")
    q = float(quantum_deg)
    sigma = math.sqrt(max(result.residual_rms_deg**2 - q * q / 12.0, 0.0))
    per_period = result.samples_used / max(result.periods_used, 1)
    amps = np.asarray(result.harmonic_amplitudes_deg, dtype=float)
    u_q = quantisation_u(q, float(amps[0]), amps.size, per_period, sigma)
    budgets = dict(result._budgets)
    w = 2.0 * math.pi * result.frequency_hz
    per_a = {"amplitude_deg": 1.0, "angular_acceleration_amplitude_deg_s2": w * w}
    if result.set_amplitude_deg is not None and result.set_frequency_hz is not None:
        set_acc = result.set_amplitude_deg * (2 * math.pi * result.set_frequency_hz) ** 2
        per_a["amplitude_error_percent"] = 100.0 / result.set_amplitude_deg
        per_a["angular_acceleration_error_percent"] = 100.0 * w * w / set_acc
    for key in _RESOLUTION_KEYS:
        if key in budgets and key in per_a:
            budgets[key] = _add_resolution(budgets[key], per_a[key], float(u_q[0]), what)
    plot = dict(result._plot)
    amps_u = np.hypot(np.asarray(plot["harmonic_amplitudes_u_deg"], dtype=float), u_q)
    plot["harmonic_amplitudes_u_deg"] = amps_u
    thd = thd_uncertainty(amps, amps_u, dof=fit_dof(result._fit)) if result._fit else None
    extra: dict[str, Any] = {}
    if thd is not None:
        budgets["thd_percent"] = tidy(thd.budget, f"with the readout's quantisation ({what})")
        extra = {
            "thd_percent_u": thd.budget.u,
            "thd_percent_bias": thd.bias,
            "thd_percent_bias_corrected": thd.bias_corrected,
        }
    return dataclasses.replace(
        result,
        amplitude_deg_u=budgets["amplitude_deg"].u,
        _budgets=budgets,
        _plot=plot,
        notes=(*result.notes, f"readout resolution {q:.6g}° ({what}) in the budgets"),
        **extra,
    )


def _add_resolution(
    b: UncertaintyBudget, per_a: float, u_a1: float, what: str
) -> UncertaintyBudget:
    """Budget ``b`` (a linear model, its rows independent) with the quantisation of A_1 added."""
    inputs = [
        Input(
            r.source,
            r.value,
            r.u,
            dof=r.dof,
            unit=r.unit,
            source=r.origin,
            description=r.distribution,
        )
        for r in b.rows
    ]
    sens = [r.sensitivity for r in b.rows]
    inputs.append(
        Input(
            f"readout quantisation of A₁ ({what})",
            0.0,
            u_a1,
            unit="°",
            source="Type B: quantisation of a sine (Gray 1990)",
            description="rms over the readout's unknown offset",
        )
    )
    sens.append(per_a)
    jac = np.array([sens])
    x0 = np.array([i.value for i in inputs])

    def model(*x: float) -> np.ndarray:
        return np.asarray(b.value + jac @ (np.asarray(x) - x0))

    gum = propagate(
        model, inputs, jacobian=lambda *x: jac, p=b.p, names_out=[b.quantity], units_out=[b.unit]
    )
    note = (
        "the readout's quantisation error repeats with the motion, so the fit does not average "
        "it: its share of A₁ is a Type B input (rotacal.table.motion_angle.quantisation_u)."
    )
    return tidy(gum.budget(0), *b.notes, note)


def _check_arrays(t: Any, y: Any, name: str) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=np.float64)
    y = np.asarray(y)
    check_pair_shapes(t, name, y)
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise CaptureError(f"column 'time_s' has a NaN or inf at sample {int(bad[0])}")
    return t, y


@one_blas_thread
def calibrate_angle_motion(
    t: np.ndarray,
    angle_deg: np.ndarray,
    *,
    resolution_deg: float | None = None,
    harmonics: int = 10,
    periods: int | None = None,
    set_amplitude_deg: float | None = None,
    set_frequency_hz: float | None = None,
    specs: InstrumentSpecs | None = None,
    allow_clipped: bool = False,
    drift: bool = False,
    allow_gaps: bool = False,
    resolution_name: str | None = None,
) -> MotionResult:
    """Sinusoidal-motion calibration from an angle readout (scheme ``"angle"``).

    The DAQ's faults (gaps, duplicated times, repeated rows) are found and named; reversing
    moments by extreme values; n whole periods between 2n + 1 reversals; IEEE 1057
    multi-harmonic fit of θ and THD (eq. (1)); the resolution as a Type B input.

    Parameters
    ----------
    t : array, s — time stamps.
    angle_deg : array, deg — the angle readout θ.
    resolution_deg : float, optional, deg — the readout's quantum; None: inferred when the
        readings lie on a grid (:func:`angle_quantum`), else left out (a continuous readout).
    harmonics, periods, set_amplitude_deg, set_frequency_hz : as
        :func:`~rotacal.table.calibrate_encoder_motion` (N_H; whole periods; deg; Hz).
    specs : InstrumentSpecs, optional — Type B inputs (``timebase.relative_error``).
    allow_clipped : bool — accepted for the CLI's common options; an angle readout has no rails
        (a counter wraps, it does not clip), so it changes nothing.
    drift : bool — fit a linear drift term beside the harmonics (``drift_deg_s``).
    allow_gaps : bool — analyse a record with more than 1 % faulty samples anyway.
    resolution_name : str, optional — the resolution's name in the budget.

    Returns
    -------
    MotionResult — ``scheme = "angle"``; the keys of INTERFACE.md's ``motion``.

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, eqs. (1), (2), §3.3, §5; IEEE Std 1057-2017 §4.1.3;
    Gray (1990), IEEE Trans. Inf. Theory 36(6):1220 (quantisation).
    """
    del allow_clipped  # an angle readout has no rails
    _check_settings(harmonics, periods)
    t, angle = _check_arrays(t, angle_deg, "angle_deg")
    angle = angle.astype(np.float64, copy=False)
    bad = np.flatnonzero(~np.isfinite(angle))
    if bad.size:
        raise CaptureError(f"column angle_deg has a NaN or inf at sample {int(bad[0])}")
    faults, keep = find_daq_faults(t, angle)
    faults.check(allow_gaps)
    if not keep.all():
        t, angle = t[keep], angle[keep]
    check_magnitudes("angle_deg", angle)
    check_sampling(t, "time_s", max_gap=math.inf)  # gaps are named above, not refused
    if np.ptp(angle) == 0:
        raise CaptureError("column angle_deg is constant: the table does not move in this capture")
    if resolution_deg is None:
        resolution_deg = angle_quantum(angle)
        if resolution_deg is not None and resolution_name is None:
            resolution_name = "quantum of the readings"
    elif not (math.isfinite(resolution_deg) and resolution_deg > 0):
        raise ConfigError(f"--resolution-deg must be positive, got {resolution_deg}")
    result = displacement_motion(
        t, angle, harmonics=harmonics, periods=periods, drift=drift, what="angle capture",
        notes=[READ_DIRECTLY], set_values=(set_amplitude_deg, set_frequency_hz), specs=specs,
    )  # fmt: skip
    result = dataclasses.replace(
        result,
        scheme="angle",
        warnings=tuple(w.replace(_LTS_HINT, _ANGLE_HINT) for w in result.warnings),
    )
    if resolution_deg is not None:
        result = with_resolution(result, float(resolution_deg), resolution_name or "stated")
    return with_warnings(result, faults.warnings())


def calibrate_count_motion(
    t: np.ndarray,
    count: np.ndarray,
    *,
    counts_per_rev: float,
    counter_bits: int | None = None,
    signed: bool | None = None,
    **kw: Any,
) -> MotionResult:
    """:func:`calibrate_angle_motion` of an up/down counter's readings.

    The register's wrap-around is unwrapped (:func:`~rotacal.signal.counter.unwrap_counts`,
    width ``counter_bits`` or inferred), θ = 360·count/N, and the resolution is one count,
    360/N degrees; the angle is counted from the first reading. Repeated rows are dropped before unwrapping (they are zero steps anyway).

    Parameters
    ----------
    t : array, s.
    count : array of int — the register's readings.
    counts_per_rev : float — N, counts per revolution of the table (after the card's
        quadrature multiplication, e.g. 4 × lines).
    counter_bits : int, optional — register width (8, 16, 24, 32 or 64); None: inferred.
    signed : bool, optional — a signed (two's complement) register; None: inferred.
    **kw : as :func:`calibrate_angle_motion`.
    """
    if not (math.isfinite(counts_per_rev) and counts_per_rev > 0):
        raise ConfigError(f"--counts-per-rev must be positive, got {counts_per_rev}")
    t, c = _check_arrays(t, count, "count")
    true, bits, is_signed = unwrap_counts(c, counter_bits, signed)
    # from the first reading: a 64-bit count near 2^63 would lose its last bits in float64
    angle = counts_to_angle_deg(true - true[0], counts_per_rev)
    kind = "signed" if is_signed else "unsigned"
    inferred = "given" if counter_bits is not None else "inferred from the readings"
    note = f"count unwrapped in a {bits}-bit {kind} register ({inferred})"
    result = calibrate_angle_motion(
        t,
        angle,
        resolution_deg=360.0 / float(counts_per_rev),
        resolution_name=f"1 count of {counts_per_rev:g}/rev",
        **kw,
    )
    return dataclasses.replace(result, notes=(*result.notes, note))
