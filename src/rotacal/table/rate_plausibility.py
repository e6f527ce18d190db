"""Plausibility checks of a constant-rate calibration from pulse timing (Kokuyama et al. 2015).

* the mean rate against the set rate: off by a factor near a power of ten or two, or by more than
  20 % (:func:`rotacal.signal.plausibility.set_value_warning`) — ``--pulses-per-rev`` or the set
  rate given wrong;
* a trend: the rate changes steadily over the record (the table still spinning up or down), so
  the "constant rate" the stability figures assume is not there.
"""

from __future__ import annotations

import math

import numpy as np

from rotacal.signal.plausibility import set_value_warning

__all__ = ["TREND_LIMIT", "rate_warnings"]

#: Change of the rate over the record, over the rms scatter about its straight line, beyond which
#: the rate is not constant.
TREND_LIMIT = 3.0
_MIN_POINTS = 10


def rate_warnings(
    *,
    mean_rate_deg_s: float,
    set_rate_deg_s: float | None,
    time_s: np.ndarray,
    deviation_percent: np.ndarray,
) -> list[str]:
    """The plausibility warnings of a rate calibration (empty when all is plausible).

    The trend is the least-squares line through the rate deviation over time: its change across
    the record (slope × duration) against the rms scatter of the deviation about that line. A
    fluctuation (periodic, random) leaves the line nearly flat; a spin-up or spin-down does not.

    Parameters
    ----------
    mean_rate_deg_s : float
        Mean rate (°/s), a magnitude.
    set_rate_deg_s : float or None
        |Set rate| (°/s), when given.
    time_s, deviation_percent : ndarray
        Times (s) and the rate's deviation from the mean (% of the mean rate), per rate point.

    References
    ----------
    NIST/SEMATECH e-Handbook of Statistical Methods (2012), §4.4.4 (straight-line fit, residual
    scatter); Kokuyama et al. (2015), §3 (rate stability assumes a constant set rate).
    """
    out: list[str] = []
    if set_rate_deg_s is not None:
        line = set_value_warning(
            "the mean rate",
            mean_rate_deg_s,
            set_rate_deg_s,
            "°/s",
            "--pulses-per-rev (lines of the scale) and the set rate",
        )
        if line is not None:
            out.append(line)
    t = np.asarray(time_s, dtype=float)
    d = np.asarray(deviation_percent, dtype=float)
    ok = np.isfinite(t) & np.isfinite(d)
    t, d = t[ok], d[ok]
    if t.size < _MIN_POINTS or not t[-1] > t[0]:
        return out
    slope, intercept = np.polyfit(t - t[0], d, 1)
    scatter = float(np.sqrt(np.mean((d - intercept - slope * (t - t[0])) ** 2)))
    change = float(slope * (t[-1] - t[0]))
    if scatter > 0 and math.isfinite(change) and abs(change) > TREND_LIMIT * scatter:
        out.append(
            f"the rate is not constant: it changes by {change:+.3g} % of the mean over the "
            f"{t[-1] - t[0]:.4g} s recorded, {abs(change) / scatter:.3g} times its scatter about "
            f"that trend (limit {TREND_LIMIT:g}) — the table was still spinning up or down; start "
            "recording once the rate has settled"
        )
    return out
