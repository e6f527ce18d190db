"""Straight-line calibration with uncertainty (GUM H.3): intercept, slope, their u and correlation.

The shape of a gyro scale-factor fit; see :func:`linear_fit_uncertainty`.

References
----------
JCGM 100:2008 (GUM) Annex H.3 (calibration of a thermometer: least-squares straight line).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result

if TYPE_CHECKING:
    pass

from rotacal.uncertainty._checked import _frozen, _number
from rotacal.uncertainty.gum import Input

__all__ = ["LinearFit", "linear_fit_uncertainty"]


@dataclasses.dataclass(frozen=True, eq=False)
class LinearFit(Result):
    """A least-squares straight line ``y = intercept + slope·(x − x0)`` with Type A uncertainties.

    Attributes
    ----------
    intercept : y_1, the value at x = x0 (unit of y).
    slope : y_2 (unit of y per unit of x).
    u_intercept, u_slope : their standard uncertainties (same units).
    correlation : r(y_1, y_2) (dimensionless).
    covariance : (2, 2) covariance matrix of (y_1, y_2).
    residual_std : s, the standard deviation of the residuals, √(Σr²/(n − 2)) (unit of y).
    dof : n − 2.
    n : number of points.
    x0 : the reference abscissa (unit of x).

    References
    ----------
    JCGM 100:2008 (GUM), Annex H.3 (calibration of a thermometer by a straight line).
    """

    intercept: float
    slope: float
    u_intercept: float
    u_slope: float
    correlation: float
    covariance: np.ndarray
    residual_std: float
    dof: int
    n: int
    x0: float

    def inputs(
        self,
        names: tuple[str, str] = ("y1", "y2"),
        *,
        unit_y: str = "",
        unit_x: str = "",
    ) -> tuple[tuple[Input, Input], np.ndarray]:
        """The two fitted parameters as :class:`Input` objects and their 2×2 correlation matrix.

        Ready for :func:`propagate` (``propagate(f, ins, correlation=r)``); both carry ν = n − 2,
        so ν_eff of a prediction is n − 2 as in GUM H.3.
        """
        slope_unit = f"{unit_y or '1'}/{unit_x}" if unit_x else unit_y
        origin = f"least-squares line, {self.n} points"
        ins = (
            Input(names[0], self.intercept, self.u_intercept, self.dof, "normal", unit_y, origin),
            Input(names[1], self.slope, self.u_slope, self.dof, "normal", slope_unit, origin),
        )
        r = np.array([[1.0, self.correlation], [self.correlation, 1.0]])
        return ins, r


def linear_fit_uncertainty(x: Any, y: Any, *, x0: float = 0.0) -> LinearFit:
    """Fit ``y = y_1 + y_2·(x − x0)`` by least squares, with the uncertainties of GUM H.3.

    The variances and covariance of (y_1, y_2) are s²·(AᵀA)⁻¹ with s² = Σ r_k²/(n − 2), computed
    from the centred abscissae; their degrees of freedom are n − 2.

    Parameters
    ----------
    x : array_like (n,)
        Abscissae (e.g. temperature in °C, or reference rate in °/s for a gyro scale factor).
    y : array_like (n,)
        Ordinates (any unit).
    x0 : float, optional
        Reference abscissa (unit of x); the intercept is the line's value there. Default 0.

    Returns
    -------
    LinearFit

    Raises
    ------
    CaptureError
        Different lengths, fewer than 3 points, NaN/inf, or all x equal.

    References
    ----------
    JCGM 100:2008 (GUM), Annex H.3: least-squares estimates of y_1 and y_2, s², their variances
    and correlation coefficient, and a predicted correction with ν = n − 2.
    """
    xa = np.asarray(x, dtype=np.float64).ravel()
    ya = np.asarray(y, dtype=np.float64).ravel()
    if xa.size != ya.size:
        raise CaptureError(f"x has {xa.size} points but y has {ya.size}; give one y per x.")
    if xa.size < 3:
        raise CaptureError(
            f"a straight line with an uncertainty needs at least 3 points; got {xa.size}."
        )
    for name, arr in (("x", xa), ("y", ya)):
        if not np.all(np.isfinite(arr)):
            i = int(np.flatnonzero(~np.isfinite(arr))[0])
            raise CaptureError(f"{name}[{i}] = {arr[i]!r} is not finite; remove or fix that point.")
    x0f = _number(x0, "x0")
    if not math.isfinite(x0f):
        raise ConfigError(f"x0 = {x0f!r} is not finite.")
    n = xa.size
    t = xa - x0f
    t_mean = float(np.mean(t))
    dt = t - t_mean
    sxx = float(dt @ dt)
    if not sxx > 0.0 or sxx <= (1e-13 * max(1.0, float(np.max(np.abs(t))))) ** 2 * n:
        raise CaptureError("all x values are equal; a slope needs at least two different x.")
    y_mean = float(np.mean(ya))
    slope = float(dt @ (ya - y_mean)) / sxx
    intercept = y_mean - slope * t_mean
    resid = ya - (intercept + slope * t)
    dof = n - 2
    s2 = float(resid @ resid) / dof
    var_slope = s2 / sxx
    var_int = s2 * (1.0 / n + t_mean * t_mean / sxx)
    cov = -t_mean * s2 / sxx
    denom = math.sqrt(var_int * var_slope)
    r = cov / denom if denom > 0.0 else 0.0
    return LinearFit(
        intercept=intercept,
        slope=slope,
        u_intercept=math.sqrt(var_int),
        u_slope=math.sqrt(var_slope),
        correlation=float(np.clip(r, -1.0, 1.0)),
        covariance=_frozen(np.array([[var_int, cov], [cov, var_slope]])),
        residual_std=math.sqrt(s2),
        dof=dof,
        n=n,
        x0=x0f,
    )
