"""A self-calibrated encoder as the reference of a position test (Kokuyama et al. 2015, seed 004).

``rotacal selfcal`` gives the graduation deviation of a multi-head encoder by the equal-division
averaged method: ``deviation_arcsec`` holds m values, one per line, such that the true rotation
from line 0 to line j is j·360°/m + (deviation[j] − deviation[0])/3600 (INTERFACE.md, key
``selfcal``). An encoder so calibrated — the table's own, or a reference encoder on its axis —
reads a true angle of

    θ_true = θ + (D(θ − θ₀) − D(0))/3600,

θ its reading (deg), θ₀ its reading at line 0 of the self-calibration (``zero_deg``) and D the
deviation interpolated linearly between lines, periodic over 360°. The self-calibration's
standard uncertainty per line (``deviation_u_arcsec``) is the reference's Type B uncertainty at
every position; orders that are multiples of the number of heads are undetectable by the method
(seed 004) and are not in the correction.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rotacal.errors import ConfigError

__all__ = ["SelfcalCorrection", "selfcal_correction"]


@dataclasses.dataclass(frozen=True)
class SelfcalCorrection:
    """The correction (arcsec) at each reading, the curve's u (arcsec, None when the JSON has
    none), its lines m, heads n and the undetectable orders' note."""

    correction_arcsec: NDArray[np.float64]
    u_arcsec: float | None
    lines: int
    heads: int | None
    note: str


def selfcal_correction(
    reading_deg: ArrayLike, selfcal: Mapping[str, Any], *, zero_deg: float = 0.0
) -> SelfcalCorrection:
    """The correction (arcsec) to add to a self-calibrated encoder's readings (deg).

    Parameters
    ----------
    reading_deg : array_like, deg
        The encoder's readings.
    selfcal : mapping
        A ``rotacal selfcal --json`` result (``deviation_arcsec``; optional
        ``pulses_per_rev``, ``heads``, ``deviation_u_arcsec``).
    zero_deg : float, deg
        The encoder's reading at line 0 of the self-calibration.

    Raises
    ------
    ConfigError
        The mapping has no usable ``deviation_arcsec`` (fewer than 2 finite values) or its length
        differs from ``pulses_per_rev``.
    """
    dev = selfcal.get("deviation_arcsec")
    try:
        curve = np.asarray(dev, dtype=np.float64)
    except (TypeError, ValueError):
        curve = np.empty(0)
    if curve.ndim != 1 or curve.size < 2 or not np.all(np.abs(curve) < 1_296_000.0):
        raise ConfigError(
            "--selfcal: deviation_arcsec must be a list of at least 2 finite numbers below one "
            "turn (the `rotacal selfcal --json` result)"
        )
    if not abs(zero_deg) <= 1e6:
        raise ConfigError(f"--selfcal-zero-deg {zero_deg}: give an angle in degrees")
    m = curve.size
    declared = selfcal.get("pulses_per_rev")
    if declared is not None and int(declared) != m:
        raise ConfigError(
            f"--selfcal: deviation_arcsec has {m} values but pulses_per_rev is {declared}"
        )
    where = np.mod(np.asarray(reading_deg, dtype=np.float64) - zero_deg, 360.0) * (m / 360.0)
    line = np.floor(where).astype(np.int64) % m
    frac = where - np.floor(where)
    corr = curve[line] + frac * (curve[(line + 1) % m] - curve[line]) - curve[0]
    u = selfcal.get("deviation_u_arcsec")
    heads = selfcal.get("heads")
    return SelfcalCorrection(
        correction_arcsec=corr,
        u_arcsec=None if u is None else float(u),
        lines=m,
        heads=None if heads is None else int(heads),
        note=str(selfcal.get("undetectable_harmonics_note", "")),
    )
