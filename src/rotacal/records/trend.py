"""The drift of a quantity over an item's calibrations, and the date its prediction reaches a limit.

Pure functions on arrays (no database): :func:`fit_drift` fits a straight line ``value = a + b·t``
to the values of one quantity against the calibration date by weighted least squares;
:func:`limit_crossing` finds when the predicted value plus (or minus) its expanded uncertainty
reaches an acceptance limit; :func:`add_months` and :func:`years_since` are the calendar helpers
the calibration interval needs.

Time is measured in years of 365.25 days (the Julian year), so a slope is in the quantity's unit
per year.

References
----------
JCGM 100:2008 (GUM), H.3 (a straight line fitted by least squares; its parameters' variances and
covariance; the prediction's variance). ISO/TS 28037:2010, §6 (straight-line calibration functions
with uncertainties associated with the y values only: weights 1/u², the parameters' covariance,
the χ² check of the model). Birge R. T. (1932), The calculation of errors by the method of least
squares, Phys. Rev. 40, 207–227 (the Birge ratio). ILAC-G24:2022 / OIML D 10:2022 §6.3 (method 2,
control chart: the drift between calibrations sets the interval); NCSLI RP-1 (2010), variables
data methods (the predicted value and its uncertainty reach a tolerance limit).
"""

from __future__ import annotations

import calendar
import dataclasses
import datetime as dt
import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "DAYS_PER_YEAR",
    "SIGNIFICANCE_K",
    "DriftLine",
    "add_months",
    "date_after",
    "fit_drift",
    "limit_crossing",
    "years_since",
]

#: Days of the year the slope is expressed in (the Julian year).
DAYS_PER_YEAR = 365.25
#: Coverage factor of a drift's significance test (|b| > 2 u(b)) and of the predicted value's
#: expanded uncertainty at the limit (k = 2, about 95 % for a normal distribution).
SIGNIFICANCE_K = 2.0


@dataclasses.dataclass(frozen=True)
class DriftLine:
    """A straight line ``value(t) = at_centre + slope·(t − t_centre)`` fitted by weighted least
    squares, with the standard uncertainties of its two parameters (uncorrelated at the weighted
    mean time ``t_centre``).

    Attributes
    ----------
    t_centre : float
        The weighted mean time of the points [years, on the caller's time axis].
    at_centre : float
        The fitted value at ``t_centre`` [unit of the quantity].
    slope : float
        The drift [unit per year].
    u_at_centre, u_slope : float
        Standard uncertainties of ``at_centre`` [unit] and ``slope`` [unit per year], scaled by
        the Birge ratio where it exceeds 1 (``scaled``).
    n : int
        Number of points fitted.
    chi2 : float
        Σ wᵢ rᵢ² of the residuals with the weights 1/uᵢ² (dimensionless).
    birge_ratio : float or None
        R = √(χ²/(n − 2)); None for two points (a line through two points leaves no residual).
    scaled : bool
        True when the uncertainties were multiplied by R because R > 1.
    """

    t_centre: float
    at_centre: float
    slope: float
    u_at_centre: float
    u_slope: float
    n: int
    chi2: float
    birge_ratio: float | None
    scaled: bool

    @property
    def significant(self) -> bool:
        """|b| > 2 u(b): the drift is distinguishable from none at about 95 %."""
        return abs(self.slope) > SIGNIFICANCE_K * self.u_slope

    def predict(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """The predicted value and its standard uncertainty at times ``t`` [years].

        u²(ŷ(t)) = u²(â) + (t − t̄)² u²(b̂), since â (the value at the weighted mean time t̄) and
        b̂ are uncorrelated (GUM H.3.4 with t₀ = t̄). Returns ``(value [unit], u [unit])``.
        """
        s = np.asarray(t, dtype=float) - self.t_centre
        value = self.at_centre + self.slope * s
        u = np.sqrt(self.u_at_centre**2 + (s * self.u_slope) ** 2)
        return value, u


def fit_drift(t: ArrayLike, values: ArrayLike, u: ArrayLike) -> DriftLine:
    """Fit ``value = a + b·t`` by weighted least squares with weights 1/u².

    With wᵢ = 1/uᵢ², W = Σwᵢ, t̄ = Σwᵢtᵢ/W, ȳ = Σwᵢyᵢ/W and S = Σwᵢ(tᵢ − t̄)²:
    b = Σwᵢ(tᵢ − t̄)(yᵢ − ȳ)/S, the value at t̄ is ȳ, u²(b) = 1/S, u²(ȳ) = 1/W and their covariance
    is zero (ISO/TS 28037:2010 §6; GUM H.3 with the origin of time at t̄). χ² = Σwᵢ(yᵢ − ȳ −
    b(tᵢ − t̄))². With more than two points the Birge ratio R = √(χ²/(n − 2)) compares the scatter
    with the stated uncertainties; when R > 1 (the values scatter more than their u allow) both
    u(b) and u(ȳ) are multiplied by R, so that the drift's uncertainty reflects the scatter seen
    (Birge 1932). With R ≤ 1 the stated uncertainties are kept (never made smaller).

    Parameters
    ----------
    t : array_like
        Calibration times [years], at least two distinct ones.
    values : array_like
        The quantity's values [its unit].
    u : array_like
        Their standard uncertainties [same unit], all > 0.

    Returns
    -------
    DriftLine
        Slope in unit per year.

    Raises
    ------
    ValueError
        Fewer than two points, times all equal, or a u that is not positive and finite (the
        caller checks these; it is not a user's mistake here).
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(values, dtype=float)
    u = np.asarray(u, dtype=float)
    if t.size < 2 or not (t.shape == y.shape == u.shape):
        raise ValueError("fit_drift: needs at least two points with t, values and u alike")
    if not (np.all(np.isfinite(u)) and np.all(u > 0)):
        raise ValueError("fit_drift: every u must be finite and > 0")
    w = 1.0 / u**2
    total = w.sum()
    t_centre = float(np.dot(w, t) / total)
    y_centre = float(np.dot(w, y) / total)
    s = t - t_centre
    spread = float(np.dot(w, s * s))
    if not spread > 0:
        raise ValueError("fit_drift: the times are all equal")
    slope = float(np.dot(w * s, y - y_centre) / spread)
    residual = y - y_centre - slope * s
    chi2 = float(np.dot(w, residual * residual))
    n = int(t.size)
    birge = math.sqrt(chi2 / (n - 2)) if n > 2 else None
    scale = birge if birge is not None and birge > 1.0 else 1.0
    return DriftLine(
        t_centre=t_centre,
        at_centre=y_centre,
        slope=slope,
        u_at_centre=scale / math.sqrt(total),
        u_slope=scale / math.sqrt(spread),
        n=n,
        chi2=chi2,
        birge_ratio=birge,
        scaled=scale > 1.0,
    )


def limit_crossing(line: DriftLine, limit: float, upper: bool) -> float | None:
    """The time at which the predicted value plus its expanded uncertainty (``upper``; minus it
    for a lower limit) reaches ``limit``, k = 2.

    Solves ŷ(t) ± k·u(ŷ(t)) = L with ŷ and u(ŷ) of :meth:`DriftLine.predict`. With σ = +1 for an
    upper limit and −1 for a lower one, D = σ(L − â), β = σb and s = t − t̄, squaring
    k²(u²(â) + s²u²(b)) = (D − βs)² gives (β² − k²u²(b))s² − 2βDs + D² − k²u²(â) = 0. When the
    drift is significant (|b| > k u(b)) and towards the limit (β > 0), the band's edge moves
    monotonically towards the limit and the smaller root is the only one with D − βs ≥ 0:
    s = (βD − k√(u²(b)D² + (β² − k²u²(b))u²(â))) / (β² − k²u²(b)).

    This is the variables-data approach of NCSLI RP-1 (2010) and method 2 of ILAC-G24:2022 /
    OIML D 10:2022 §6.3 (the drift seen in the calibrations predicts when the item leaves its
    tolerance).

    Parameters
    ----------
    line : DriftLine
        The fitted drift [unit, unit per year].
    limit : float
        The acceptance limit [unit].
    upper : bool
        True for an upper limit (limit_max), False for a lower one (limit_min).

    Returns
    -------
    float or None
        The time [years, on the line's time axis]; None when the drift is not significant or
        runs away from this limit (the band's edge never reaches it going forward). The time may
        lie in the past: the prediction is out of tolerance already.
    """
    k = SIGNIFICANCE_K
    sign = 1.0 if upper else -1.0
    beta = sign * line.slope
    if not line.significant or beta <= 0:
        return None
    distance = sign * (limit - line.at_centre)
    ua, ub = line.u_at_centre, line.u_slope
    lead = beta * beta - (k * ub) ** 2
    root = math.sqrt((ub * distance) ** 2 + lead * ua * ua)
    return line.t_centre + (beta * distance - k * root) / lead


def years_since(dates: Sequence[dt.date] | np.ndarray, origin: dt.date) -> np.ndarray:
    """The times of ``dates`` (an array of ``datetime64``, or dates) after ``origin`` [years of
    365.25 days]."""
    if isinstance(dates, np.ndarray):
        days = (dates.astype("datetime64[D]") - np.datetime64(origin, "D")).astype(np.float64)
    else:  # whole days from the dates themselves (NumPy's conversion of date objects is slow)
        days = np.fromiter(((d - origin).days for d in dates), np.float64, count=len(dates))
    return days / DAYS_PER_YEAR


def date_after(origin: dt.date, years: float) -> dt.date | None:
    """The day on which ``years`` after ``origin`` falls (rounded down to the whole day, so a
    limit is never reported as reached later than it is); None beyond the calendar (year 9999)."""
    try:
        return origin + dt.timedelta(days=math.floor(years * DAYS_PER_YEAR))
    except (OverflowError, ValueError):  # beyond the calendar, or not a number
        return None


def add_months(day: dt.date, months: int) -> dt.date:
    """``day`` plus a whole number of calendar months, the day of the month kept where the month
    has it and the month's last day otherwise (31 January + 1 month = 28 or 29 February)."""
    index = day.year * 12 + day.month - 1 + months
    year, month = divmod(index, 12)
    month += 1
    return dt.date(year, month, min(day.day, calendar.monthrange(year, month)[1]))
