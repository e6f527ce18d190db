"""The LTS and FOG schemes' signal steps (Feng et al. 2023, §4–§5): angle, reversals, integration.

Shared by the in-memory calibrations (:mod:`rotacal.table.motion`) and the chunked ones
(:mod:`rotacal.table.streaming`), so both take the same steps on the same samples:

- LTS: θ = arctan(D/R) (eq. (15)) and the reversing moments by extreme values
  (:func:`extreme_reversals`: a Schmitt trigger, then a parabola at each extreme);
- FOG: the zero crossings of the fitted rate (the reversing moments) and the angle integrated
  from the rate less D0 by the trapezoid rule (eqs. (11)–(12)).

References
----------
Feng R., Yan J., Wu Y., Yu N., Yin X. (2023). Sensors 23, 4876, §4, §5, eqs. (11), (12), (15).
"""

from __future__ import annotations

import numpy as np

from rotacal.errors import CaptureError
from rotacal.signal import SineFit

__all__ = [
    "TRIGGER_PERCENTILES",
    "check_reach",
    "extreme_reversals",
    "fog_angle",
    "fog_angle_steps",
    "fog_bias_note",
    "lts_angle",
    "model_zero_crossings",
    "refine_extreme",
    "reversal_half_window",
    "trigger_levels",
]


def extreme_reversals(
    t: np.ndarray, x: np.ndarray, *, hysteresis: float | None = None, drift: float = 0.0
) -> np.ndarray:
    """Reversing moments of a displacement signal by its extreme values.

    The LTS signal is proportional to the displacement, so its reversing moments are its extremes
    (Feng et al. 2023, §5). Each swing of the signal above or below its mid level is found with a
    Schmitt trigger (hysteresis ``hysteresis``, default 10 % of the 2–98 % range, so noise cannot
    start a swing); the extreme of each complete swing is then refined by a least-squares parabola
    through the samples within ±1/20 of a period, which averages the noise down. With ``drift``
    the trigger (its mid level, range and hysteresis) works on ``x − drift·(t − t₀)``, so that a
    drifting signal still crosses its mid level every swing; the extremes are those of x itself
    (a drifting table reverses where its rate, drift included, is zero).

    Parameters
    ----------
    t : array, s
    x : array — displacement in any unit.
    hysteresis : float, optional — in the unit of x.
    drift : float — the signal's drift (unit of x per s), e.g. from a fit with a linear term.

    Returns
    -------
    array of float, s — the reversing moments, in time order, alternately maxima and minima.

    References
    ----------
    Feng et al. (2023), Sensors 23:4876, §5 (reversals of the LTS signal by extreme values).
    """
    xt = x if drift == 0.0 else x - drift * (t - t[0])  # what the trigger sees
    lo, hi = np.percentile(xt, TRIGGER_PERCENTILES)
    mid, h = trigger_levels(float(lo), float(hi), hysteresis)
    state = np.where(xt > mid + h, 1, np.where(xt < mid - h, -1, 0)).astype(np.int8)
    set_at = np.flatnonzero(state)
    if set_at.size == 0:
        return np.empty(0)
    # Forward-fill the Schmitt trigger's state; samples before the first decision take that one.
    filled = state[
        set_at[np.maximum(np.searchsorted(set_at, np.arange(x.size), side="right") - 1, 0)]
    ]
    edges = np.flatnonzero(np.diff(filled)) + 1
    # Swings lie between state changes. The first and last ones are cut by the record's ends: their
    # extreme counts only if the signal is at least `h` away from it at that end (zigzag rule).
    starts = np.concatenate(([0], edges))
    stops = np.concatenate((edges, [x.size]))
    signs = filled[starts]
    signed = x * filled  # maxima of a "+" swing and minima of a "−" swing both become maxima
    seg_max = np.maximum.reduceat(signed, starts)
    seg_id = np.repeat(np.arange(starts.size), stops - starts)
    hit = np.flatnonzero(signed == seg_max[seg_id])
    extreme = hit[np.unique(seg_id[hit], return_index=True)[1]]
    keep = np.ones(starts.size, dtype=bool)
    keep[0] = signed[0] < seg_max[0] - h and extreme[0] > 0
    keep[-1] = signed[-1] < seg_max[-1] - h and extreme[-1] < x.size - 1
    extreme, signs = extreme[keep], signs[keep]
    if extreme.size == 0:
        return np.empty(0)
    half_window = reversal_half_window(t[extreme], float(t[-1] - t[0]))
    times = t[extreme].astype(float)
    for j, s in enumerate(signs):
        times[j] = refine_extreme(t, x, float(times[j]), int(s), half_window)
    return times


#: The percentiles of the displacement whose mean is the trigger's mid level (extreme_reversals).
TRIGGER_PERCENTILES = (2.0, 98.0)


def trigger_levels(lo: float, hi: float, hysteresis: float | None) -> tuple[float, float]:
    """Mid level and hysteresis of :func:`extreme_reversals`'s Schmitt trigger from the 2 % and
    98 % percentiles ``lo``, ``hi`` of what it sees (default hysteresis: 10 % of hi − lo)."""
    mid = 0.5 * (lo + hi)
    h = 0.1 * (hi - lo) if hysteresis is None else float(hysteresis)
    if not hi - lo > 0:
        raise CaptureError("the signal does not move: no reversing moments can be found")
    return mid, h


def reversal_half_window(extreme_times: np.ndarray, span_s: float) -> float:
    """Half width (s) of the parabola's window: 1/20 of the period, twice the median time between
    successive extremes (the record's span when there is only one)."""
    period = 2 * float(np.median(np.diff(extreme_times))) if extreme_times.size > 1 else span_s
    return period / 20


def refine_extreme(
    t: np.ndarray, x: np.ndarray, centre: float, sign: int, half_window: float
) -> float:
    """The reversing moment (s) near the extreme sample at ``centre``: the vertex of a
    least-squares parabola through the samples within ±``half_window``, re-centred once on the
    vertex; ``sign`` +1 for a maximum, −1 for a minimum (Feng et al. 2023, §5). ``t`` and ``x``
    need to hold only the samples within ±2·``half_window`` of ``centre``."""
    for _ in range(2):  # fit, then re-centre the window on the vertex and fit again
        lo_i = np.searchsorted(t, centre - half_window)
        hi_i = np.searchsorted(t, centre + half_window, side="right")
        if hi_i - lo_i < 5:
            break
        tt = t[lo_i:hi_i] - centre
        c2, c1, _ = np.polyfit(tt, x[lo_i:hi_i], 2)
        if c2 * sign >= 0:  # not a maximum (or minimum) of the expected kind: keep the sample
            break
        vertex = -c1 / (2 * c2)
        if abs(vertex) > half_window:
            break
        centre += vertex
    return centre


def lts_angle(displacement_mm: np.ndarray, radius_mm: float) -> np.ndarray:
    """θ = arctan(D/R) in degrees (Feng et al. 2023, eq. (15)); D and R in mm."""
    return np.asarray(np.degrees(np.arctan(displacement_mm / radius_mm)))


def check_reach(reach_mm: float, radius_mm: float) -> None:
    """Refuse a displacement whose largest |D| (mm) exceeds R: beyond 45° eq. (15) is no longer
    a small-angle sensor reading, so R or the unit is wrong."""
    if reach_mm > radius_mm:
        raise CaptureError(
            f"displacement_mm reaches {reach_mm:.6g} mm, more than R = {radius_mm:g} mm: check "
            "--radius-mm and that D is in mm, measured from the table's zero position"
        )


def model_zero_crossings(fit: SineFit, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) where the fitted rate model less its offset (and drift) changes sign between
    two samples, linearly interpolated, and the index of the sample before each."""
    # D0 is the gyro's bias (eq. 9), not motion; so is a fitted drift D0 + D1·τ
    rate = fit.evaluate(t) - (fit.offset if fit.drift is None else fit.trend(t))
    i = np.flatnonzero(np.signbit(rate[:-1]) != np.signbit(rate[1:]))
    r0, r1 = rate[i], rate[i + 1]
    return np.asarray(t[i] + (t[i + 1] - t[i]) * r0 / (r0 - r1)), i


def fog_angle_steps(tt: np.ndarray, ww: np.ndarray, fit: SineFit) -> np.ndarray:
    """The trapezoid steps of the angle (deg) integrated from the rate ``ww`` (deg/s) less the
    fitted D0 (or D0 + D1·τ): ``angle[i+1] − angle[i]`` for each pair of samples."""
    if fit.drift is None:
        rate_sum = ww[1:] + ww[:-1] - 2 * fit.offset
    else:
        motion_rate = ww - fit.trend(tt)
        rate_sum = motion_rate[1:] + motion_rate[:-1]
    return np.asarray(0.5 * rate_sum * np.diff(tt))


def fog_angle(tt: np.ndarray, ww: np.ndarray, fit: SineFit) -> np.ndarray:
    """The angle (deg) integrated from the rate ``ww`` (deg/s) less the fitted D0 (or D0 + D1·τ)
    by the trapezoid rule, less its mean (Feng et al. 2023, eq. (12) without D0·t)."""
    angle = np.concatenate(([0.0], np.cumsum(fog_angle_steps(tt, ww, fit))))
    angle -= angle.mean()
    return angle


def fog_bias_note(fit: SineFit) -> str:
    """The FOG result's note on the fitted rate bias D0."""
    return f"rate bias D0 = {fit.offset:.6g} deg/s (fitted, removed by the analytic integration)"
