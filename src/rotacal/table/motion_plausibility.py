"""Plausibility checks of a sinusoidal-motion calibration (encoder, LTS, FOG schemes).

Two findings turn into ``warnings`` of :class:`~rotacal.table.MotionResult`:

* set values the measurement contradicts — an amplitude or frequency off by a factor near a power
  of ten, of two or of 180/π, or by more than 20 % (:func:`rotacal.signal.plausibility.
  set_value_warning`): a line count, a radius, a gyro unit or a time unit given wrong;
* lack of fit — the fit's residual far above the sample-to-sample noise (more than
  :data:`RESIDUAL_NOISE_LIMIT` times) and large enough to matter (more than
  :data:`RESIDUAL_AMPLITUDE_LIMIT` of the fitted fundamental, five times the 0.02 pp THD accuracy
  bar): motion the harmonics do not explain (a vibration, stick-slip, a changing frequency,
  harmonics beyond ``--harmonics``). A table's small stagnation and creep at the reversals (seed
  000 Table 1) stay below it.

Both run on what every path of the analysis has (the fit, the decimated residual kept for the
figures), so the chunked encoder path (:mod:`rotacal.table.streaming`) gets them too.
"""

from __future__ import annotations

import math

import numpy as np

from rotacal.signal.plausibility import set_value_warning

__all__ = [
    "RESIDUAL_AMPLITUDE_LIMIT",
    "RESIDUAL_NOISE_LIMIT",
    "motion_warnings",
    "residual_to_noise_ratio",
]

#: Residual rms over the white noise beyond which the harmonics do not explain the data.
RESIDUAL_NOISE_LIMIT = 3.0
#: Residual rms over the fitted fundamental's amplitude below which a lack of fit is too small to
#: matter (0.1 %).
RESIDUAL_AMPLITUDE_LIMIT = 1e-3
#: Fewest residual samples the ratio is judged on.
_MIN_RESIDUALS = 50

#: What a wrong amplitude points at, per scheme.
_AMPLITUDE_CHECK = {
    "encoder": "--lines (the encoder's lines per revolution) and --set-amplitude-deg",
    "lts": "--radius-mm (laser spot to table axis, in mm) and --set-amplitude-deg",
    "fog": "the gyro's unit (rate_deg_s must be in °/s, not rad/s or raw counts), its scale "
    "factor, and --set-amplitude-deg",
}


def residual_to_noise_ratio(residual: np.ndarray) -> float:
    """rms of ``residual`` over its white-noise level from successive differences.

    For white noise the mean square successive difference is twice the variance (von Neumann
    1941), so σ_white = √(mean(Δr²)/2) and the ratio is ≈ 1; motion the model misses varies
    slowly from sample to sample and raises the rms, not σ_white.

    Parameters
    ----------
    residual : ndarray
        Data minus fit, evenly strided samples (any unit).

    Returns
    -------
    float
        The ratio (dimensionless); NaN with fewer than 50 samples or no sample-to-sample change.

    References
    ----------
    von Neumann J. (1941), Distribution of the ratio of the mean square successive difference to
    the variance, Ann. Math. Statist. 12(4):367–395.
    """
    r = np.asarray(residual, dtype=float)
    r = r[np.isfinite(r)]
    if r.size < _MIN_RESIDUALS:
        return math.nan
    r = r - r.mean()
    white = float(np.mean(np.diff(r) ** 2)) / 2.0
    if not white > 0:
        return math.nan
    return math.sqrt(float(np.mean(r**2)) / white)


def motion_warnings(
    scheme: str,
    *,
    amplitude_deg: float,
    frequency_hz: float,
    harmonics: int,
    fundamental: float,
    residual: np.ndarray | None,
    residual_unit: str,
    set_amplitude_deg: float | None,
    set_frequency_hz: float | None,
) -> list[str]:
    """The plausibility warnings of a motion calibration (empty when all is plausible).

    Parameters
    ----------
    scheme : ``"encoder"``, ``"lts"`` or ``"fog"``.
    amplitude_deg, frequency_hz : float
        Measured displacement amplitude (deg) and frequency (Hz).
    harmonics : int
        Harmonics fitted.
    fundamental : float
        Amplitude of the fitted fundamental (unit of ``residual``).
    residual : ndarray or None
        The fit's residual, decimated evenly (deg, or deg/s for the FOG).
    residual_unit : str
        Its unit, for the message.
    set_amplitude_deg, set_frequency_hz : float or None
        The set values (deg, Hz), when given.
    """
    out: list[str] = []
    if set_amplitude_deg is not None:
        line = set_value_warning(
            "the measured amplitude",
            amplitude_deg,
            set_amplitude_deg,
            "deg",
            _AMPLITUDE_CHECK.get(scheme, "--set-amplitude-deg"),
        )
        if line is not None:
            out.append(line)
    if set_frequency_hz is not None:
        line = set_value_warning(
            "the measured frequency",
            frequency_hz,
            set_frequency_hz,
            "Hz",
            "--set-frequency-hz and the unit of time_s (seconds)",
        )
        if line is not None:
            out.append(line)
    if residual is not None:
        ratio = residual_to_noise_ratio(residual)
        rms = float(np.sqrt(np.mean(np.square(residual - np.mean(residual)))))
        share = rms / abs(fundamental) if fundamental else math.inf
        if ratio > RESIDUAL_NOISE_LIMIT and share > RESIDUAL_AMPLITUDE_LIMIT:
            out.append(
                f"lack of fit: the residual of the {harmonics}-harmonic fit ({rms:.3g} "
                f"{residual_unit} rms, {100 * share:.3g} % of the fundamental) is {ratio:.3g} "
                f"times the sample-to-sample noise (limits {RESIDUAL_NOISE_LIMIT:g} and "
                f"{100 * RESIDUAL_AMPLITUDE_LIMIT:g} %): motion the harmonics do not explain — a vibration, "
                "stick-slip, a frequency that changes, or harmonics above --harmonics; look at "
                "the residual in the report"
            )
    return out
