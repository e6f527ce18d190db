"""Plausibility checks of a constant-rate calibration from pulse timing (Kokuyama et al. 2015).

* the mean rate against the set rate: off by a factor near a power of ten or two, or by more than
  20 % (:func:`rotacal.signal.plausibility.set_value_warning`) — ``--pulses-per-rev`` or the set
  rate given wrong;
* a trend: the rate changes steadily over the record (the table still spinning up or down), so
  the "constant rate" the stability figures assume is not there.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rotacal.signal.plausibility import set_value_warning

__all__ = ["TREND_LIMIT", "TrendSums", "rate_warnings"]

#: Change of the rate over the record, over the rms scatter about its straight line, beyond which
#: the rate is not constant.
TREND_LIMIT = 3.0
_MIN_POINTS = 10


@dataclasses.dataclass
class TrendSums:
    """Count, means and centred co-moments of (t, d) over a stream of rate points, merged chunk
    by chunk (Chan, Golub & LeVeque 1983: no cancellation of large raw sums)."""

    n: int = 0
    mean_t: float = 0.0
    mean_d: float = 0.0
    ctt: float = 0.0
    ctd: float = 0.0
    cdd: float = 0.0
    first_t: float = math.nan
    last_t: float = math.nan

    def update(self, t: np.ndarray, d: np.ndarray) -> None:
        """Add rate points: times (s), deviations (%)."""
        ok = np.isfinite(t) & np.isfinite(d)
        t, d = t[ok], d[ok]
        if t.size == 0:
            return
        mt, md = float(np.mean(t)), float(np.mean(d))
        tc, dc = t - mt, d - md
        part = TrendSums(
            t.size,
            mt,
            md,
            float(np.dot(tc, tc)),
            float(np.dot(tc, dc)),
            float(np.dot(dc, dc)),
            float(t[0]),
            float(t[-1]),
        )
        self.merge(part)

    def merge(self, other: TrendSums) -> None:
        """Add the sums of the rate points that follow these (Chan et al.'s pairwise update)."""
        k = other.n
        if k == 0:
            return
        if self.n == 0:
            self.first_t = other.first_t
        self.last_t = other.last_t
        n = self.n + k
        dt, dd = other.mean_t - self.mean_t, other.mean_d - self.mean_d
        w = self.n * k / n
        self.ctt += other.ctt + w * dt * dt
        self.ctd += other.ctd + w * dt * dd
        self.cdd += other.cdd + w * dd * dd
        self.mean_t += dt * k / n
        self.mean_d += dd * k / n
        self.n = n

    def line(self, scale: float = 1.0) -> tuple[float, float, float]:
        """(slope, rms scatter about the line, change over the record) of scale·d."""
        slope = self.ctd / self.ctt if self.ctt > 0 else 0.0
        resid = max(self.cdd - slope * self.ctd, 0.0) / max(self.n, 1)
        return (
            scale * slope,
            abs(scale) * math.sqrt(resid),
            scale * slope * (self.last_t - self.first_t),
        )


def rate_warnings(
    *,
    mean_rate_deg_s: float,
    set_rate_deg_s: float | None,
    time_s: np.ndarray | None = None,
    deviation_percent: np.ndarray | None = None,
    trend: TrendSums | None = None,
    trend_scale: float = 1.0,
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
    trend, trend_scale : TrendSums, float
        Or their sums over a stream, of a deviation that ``trend_scale`` times gives this one
        (its offset does not change the line's slope or scatter).

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
    if trend is None:
        trend = TrendSums()
        trend.update(np.asarray(time_s, dtype=float), np.asarray(deviation_percent, dtype=float))
    if trend.n < _MIN_POINTS or not trend.last_t > trend.first_t:
        return out
    _slope, scatter, change = trend.line(trend_scale)
    span = trend.last_t - trend.first_t
    if scatter > 0 and math.isfinite(change) and abs(change) > TREND_LIMIT * scatter:
        out.append(
            f"the rate is not constant: it changes by {change:+.3g} % of the mean over the "
            f"{span:.4g} s recorded, {abs(change) / scatter:.3g} times its scatter about "
            f"that trend (limit {TREND_LIMIT:g}) — the table was still spinning up or down; start "
            "recording once the rate has settled"
        )
    return out
