"""Noise terms of a gyro from a static or constant-rate record (IEEE Std 952-1997, Annex C).

A thin calibration layer over :mod:`rotacal.signal.allan`: it takes a rate column (and its time
column, or a sampling rate), checks the sampling, computes the overlapping Allan deviation on a
dense log-spaced τ grid and reads the noise terms off it, giving the JSON of INTERFACE.md's
``allan`` command.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result
from rotacal.signal import check_sampling
from rotacal.signal.allan import AllanDeviation, NoiseTerms, noise_terms, overlapping_adev

__all__ = ["GyroNoise", "gyro_noise"]

#: Relative spread of the sampling steps above which a time column is not a constant rate.
_MAX_STEP_SPREAD = 1e-3


@dataclasses.dataclass(frozen=True)
class GyroNoise(Result):
    """Allan deviation and IEEE 952 noise terms of one gyro channel (INTERFACE.md ``allan``).

    Attributes
    ----------
    tau_s : list of float, s
    adev_deg_s : list of float, deg/s
        Overlapping Allan deviation at ``tau_s`` (in the record's unit when it is not °/s).
    adev_low_deg_s, adev_high_deg_s : list of float
        Its 68.3 % chi-squared interval (equivalent degrees of freedom for white rate noise).
    arw_deg_rt_h, bias_instability_deg_h, rrw_deg_h_rt_h : float or None
        Angle random walk (°/√h), bias instability (°/h, with the 0.664 factor), rate random
        walk (°/h/√h); None where the curve shows no such slope.
    quantization_deg, rate_ramp_deg_h2 : float or None
    intervals : dict
        ``{name: [low, high]}`` of every term found, in the units above (cluster-count rule of
        IEEE 952 C.4).
    fs_hz : float, Hz
    samples : int
    duration_s : float, s
    column : str
    notes : list of str
    """

    tau_s: list[float]
    adev_deg_s: list[float]
    adev_low_deg_s: list[float]
    adev_high_deg_s: list[float]
    arw_deg_rt_h: float | None
    bias_instability_deg_h: float | None
    rrw_deg_h_rt_h: float | None
    quantization_deg: float | None
    rate_ramp_deg_h2: float | None
    intervals: dict[str, list[float]]
    fs_hz: float
    samples: int
    duration_s: float
    column: str
    notes: list[str]
    _adev: AllanDeviation = dataclasses.field(repr=False)
    _terms: NoiseTerms = dataclasses.field(repr=False)

    @property
    def allan(self) -> AllanDeviation:
        return self._adev

    @property
    def terms(self) -> NoiseTerms:
        return self._terms


def _sampling_rate(time_s: ArrayLike | None, fs_hz: float | None, n: int) -> float:
    if time_s is None:
        if fs_hz is None:
            raise ConfigError("give the sampling rate (fs_hz, --fs-hz) or a time_s column.")
        fs = float(fs_hz)
        if not math.isfinite(fs) or fs <= 0:
            raise ConfigError(f"fs_hz must be > 0, got {fs_hz!r}.")
        return fs
    t = np.asarray(time_s, dtype=np.float64)
    if t.shape != (n,):
        raise CaptureError(f"time_s has {t.size} values, the rate column {n}; they must match.")
    check_sampling(t, "time_s")
    steps = np.diff(t)
    step = float(np.median(steps))
    spread = float(np.max(np.abs(steps - step))) / step
    if spread > _MAX_STEP_SPREAD * 100:
        raise CaptureError(
            f"time_s is not sampled at a constant rate (steps vary by {100 * spread:.3g} %): the "
            "Allan deviation needs equally spaced samples; resample the record first."
        )
    fs = 1.0 / step
    if fs_hz is not None and not math.isclose(fs, float(fs_hz), rel_tol=1e-3):
        raise ConfigError(
            f"--fs-hz {fs_hz:g} contradicts the time column ({fs:.6g} Hz); give one of them."
        )
    return fs


def gyro_noise(
    rate: ArrayLike,
    *,
    fs_hz: float | None = None,
    time_s: ArrayLike | None = None,
    unit: str = "deg/s",
    taus: Any = "log",
    column: str = "rate_deg_s",
) -> GyroNoise:
    """Overlapping Allan deviation and IEEE 952 noise terms of a gyro's rate record.

    Parameters
    ----------
    rate : array_like
        Rate samples, in ``unit`` (°/s by default; "rad/s", "deg/h" are converted for the named
        terms).
    fs_hz : float, Hz, optional
        Sampling rate; or give ``time_s``.
    time_s : array_like, s, optional
        Sample times (equally spaced; gaps are refused).
    unit : str
        Unit of ``rate``.
    taus : None, str or array_like
        τ grid (see :func:`rotacal.signal.allan.overlapping_adev`); default ``"log"``.
    column : str
        The column's name, for messages and the report.

    Returns
    -------
    GyroNoise

    References
    ----------
    IEEE Std 952-1997, Annex C (Allan variance, Table C.1 slopes, §C.4 confidence);
    IEEE Std 1139 / NIST SP 1065 (overlapping ADEV).
    """
    y = np.asarray(rate, dtype=np.float64)
    if y.ndim != 1:
        raise CaptureError(f"column '{column}' must be 1-D, got shape {y.shape}.")
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise CaptureError(
            f"column '{column}' has {bad.size} NaN/inf value(s), the first at sample {bad[0]}; "
            "the Allan deviation needs a gap-free record."
        )
    fs = _sampling_rate(time_s, fs_hz, y.size)
    adev = overlapping_adev(y, fs=fs, taus=taus, data_type="rate")
    terms = noise_terms(adev, unit=unit)
    named = {
        "angle_random_walk": "arw_deg_rt_h",
        "bias_instability": "bias_instability_deg_h",
        "rate_random_walk": "rrw_deg_h_rt_h",
        "quantization": "quantization_deg",
        "rate_ramp": "rate_ramp_deg_h2",
    }
    intervals = {}
    for name, key in named.items():
        low, high = getattr(terms, key + "_low"), getattr(terms, key + "_high")
        if low is not None and high is not None:
            intervals[name] = [float(low), float(high)]
    return GyroNoise(
        tau_s=[float(x) for x in adev.tau_s],
        adev_deg_s=[float(x) for x in adev.adev],
        adev_low_deg_s=[float(x) for x in adev.adev_low],
        adev_high_deg_s=[float(x) for x in adev.adev_high],
        arw_deg_rt_h=terms.arw_deg_rt_h,
        bias_instability_deg_h=terms.bias_instability_deg_h,
        rrw_deg_h_rt_h=terms.rrw_deg_h_rt_h,
        quantization_deg=terms.quantization_deg,
        rate_ramp_deg_h2=terms.rate_ramp_deg_h2,
        intervals=intervals,
        fs_hz=fs,
        samples=int(y.size),
        duration_s=float(y.size / fs),
        column=column,
        notes=[*adev.notes, *terms.notes],
        _adev=adev,
        _terms=terms,
    )
