"""Probability distributions of input quantities for uncertainty evaluation (JCGM 101 §6.4).

Each distribution is a frozen dataclass that knows its expectation (``mean``), its standard
deviation (``std`` — the standard uncertainty u that the GUM law of propagation uses), its degrees
of freedom ``dof`` (``math.inf`` for an exactly known distribution, n − 1 for a Type A mean), and
how to draw whole arrays of samples for the Monte Carlo method of
:mod:`rotacal.uncertainty.montecarlo`. All quantities are in the unit of the input quantity; the
library never converts units.

The sampling formulas are those of JCGM 101:2008 §6.4 (rectangular §6.4.2, curvilinear trapezoid
§6.4.3, trapezoidal §6.4.4, triangular §6.4.5, arc sine §6.4.6, Gaussian §6.4.7, multivariate
Gaussian §6.4.8, scaled-and-shifted t §6.4.9), driven by a :class:`numpy.random.Generator`.

:func:`distribution_from_spec` builds one from the TOML/dict form of a configuration file.

References
----------
JCGM 100:2008 (GUM), §4.3 (Type B evaluation: rectangular, triangular, trapezoidal).
JCGM 101:2008 (GUM Supplement 1), §6.4 (probability density functions and their sampling).
"""

from __future__ import annotations

import abc
import dataclasses
import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from rotacal.errors import ConfigError

__all__ = [
    "Arcsine",
    "Constant",
    "CurvilinearTrapezoid",
    "Distribution",
    "MultivariateNormal",
    "Normal",
    "Rectangular",
    "StudentT",
    "Trapezoidal",
    "Triangular",
    "distribution_from_spec",
]


def _finite(cls: str, field: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ConfigError(f"{cls}: {field} must be a finite number, got {value!r}.")
    return v


def _nonneg(cls: str, field: str, value: float) -> float:
    v = _finite(cls, field, value)
    if v < 0.0:
        raise ConfigError(f"{cls}: {field} must be ≥ 0, got {value!r}; give its magnitude.")
    return v


def _check_dof(cls: str, dof: float) -> float:
    v = float(dof)
    if math.isnan(v) or v <= 0.0:
        raise ConfigError(
            f"{cls}: dof (degrees of freedom) must be > 0 or inf, got {dof!r}; "
            "use n − 1 for the mean of n readings and inf for an exactly known distribution."
        )
    return v


def _fmt(x: float) -> str:
    return f"{x:.3g}"


@dataclasses.dataclass(frozen=True)
class Distribution(abc.ABC):
    """Base of the input-quantity distributions (frozen dataclass).

    Subclasses provide ``mean`` (expectation), ``std`` (standard deviation, the standard
    uncertainty u), ``dof`` (degrees of freedom ν), ``name`` and ``sample``; all in the unit of
    the quantity.
    """

    #: Short name for budget tables ("normal", "rectangular", …).
    kind: ClassVar[str] = "distribution"

    if TYPE_CHECKING:  # fields in some subclasses, properties in others

        @property
        def mean(self) -> float:
            """Expectation of the quantity (its unit)."""

        @property
        def std(self) -> float:
            """Standard deviation = standard uncertainty u (unit of the quantity)."""

        @property
        def dof(self) -> float:
            """Degrees of freedom ν (``math.inf`` for an exactly known distribution)."""

    @property
    def name(self) -> str:
        """Short distribution name for budget tables."""
        return self.kind

    @abc.abstractmethod
    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        """Draw ``size`` independent samples (float64, unit of the quantity) in one array."""

    @abc.abstractmethod
    def describe(self) -> str:
        """One short phrase for a budget row, e.g. ``"rectangular ±2e-06"``."""


# ------------------------------------------------------------------------------------ Gaussian
@dataclasses.dataclass(frozen=True)
class Normal(Distribution):
    """Gaussian N(mean, std²) — JCGM 101 §6.4.7.

    Parameters
    ----------
    mean : float
        Expectation (unit of the quantity).
    std : float
        Standard deviation = standard uncertainty u (same unit), ≥ 0.
    dof : float
        Degrees of freedom of u (``inf`` when u is known exactly; n − 1 for a Type A mean).

    References
    ----------
    JCGM 101:2008, §6.4.7 (Gaussian distribution); JCGM 100:2008, §4.2 (Type A evaluation).
    """

    mean: float
    std: float
    dof: float = math.inf
    kind: ClassVar[str] = "normal"

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean", _finite("Normal", "mean", self.mean))
        object.__setattr__(self, "std", _nonneg("Normal", "std", self.std))
        object.__setattr__(self, "dof", _check_dof("Normal", self.dof))

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        if self.std == 0.0:
            return np.full(size, self.mean)
        return self.mean + self.std * rng.standard_normal(size)

    def describe(self) -> str:
        return f"normal u={_fmt(self.std)}"


# ---------------------------------------------------------------------------------- rectangular
@dataclasses.dataclass(frozen=True)
class Rectangular(Distribution):
    """Rectangular (uniform) R(lower, upper) — JCGM 101 §6.4.2; u = (upper − lower)/√12.

    Parameters
    ----------
    lower, upper : float
        Limits (unit of the quantity), lower ≤ upper.
    dof : float
        Degrees of freedom of u (``inf``: the limits are known exactly).

    References
    ----------
    JCGM 101:2008, §6.4.2 (rectangular distribution); JCGM 100:2008, §4.3.7, eq. (7).
    """

    lower: float
    upper: float
    dof: float = math.inf
    kind: ClassVar[str] = "rectangular"

    def __post_init__(self) -> None:
        lo = _finite("Rectangular", "lower", self.lower)
        hi = _finite("Rectangular", "upper", self.upper)
        if lo > hi:
            raise ConfigError(
                f"Rectangular: lower ({lo:g}) is above upper ({hi:g}); swap the limits."
            )
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        object.__setattr__(self, "dof", _check_dof("Rectangular", self.dof))

    @classmethod
    def centered(cls, mean: float, half_width: float, dof: float = math.inf) -> Rectangular:
        """R(mean − half_width, mean + half_width); half_width ≥ 0 in the unit of the quantity."""
        a = _nonneg("Rectangular", "half_width", half_width)
        m = _finite("Rectangular", "mean", mean)
        return cls(m - a, m + a, dof)

    @property
    def mean(self) -> float:
        return 0.5 * (self.lower + self.upper)

    @property
    def half_width(self) -> float:
        """Half-width a = (upper − lower)/2 (unit of the quantity)."""
        return 0.5 * (self.upper - self.lower)

    @property
    def std(self) -> float:
        return self.half_width / math.sqrt(3.0)

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        return self.lower + (self.upper - self.lower) * rng.random(size)

    def describe(self) -> str:
        return f"rectangular ±{_fmt(self.half_width)}"


# ----------------------------------------------------------------------------------- triangular
@dataclasses.dataclass(frozen=True)
class Triangular(Distribution):
    """Triangular on [lower, upper] with peak at ``mode`` (the midpoint when None) — JCGM 101 §6.4.5.

    Symmetric: u = (upper − lower)/√24. General: u² = (a² + b² + c² − ab − ac − bc)/18.

    Parameters
    ----------
    lower, upper : float
        Limits (unit of the quantity), lower ≤ upper.
    mode : float or None
        Position of the peak (same unit), lower ≤ mode ≤ upper; None for symmetric.
    dof : float
        Degrees of freedom of u.

    References
    ----------
    JCGM 101:2008, §6.4.5 (triangular distribution); JCGM 100:2008, §4.3.9.
    """

    lower: float
    upper: float
    mode: float | None = None
    dof: float = math.inf
    kind: ClassVar[str] = "triangular"

    def __post_init__(self) -> None:
        lo = _finite("Triangular", "lower", self.lower)
        hi = _finite("Triangular", "upper", self.upper)
        if lo > hi:
            raise ConfigError(f"Triangular: lower ({lo:g}) is above upper ({hi:g}); swap them.")
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        if self.mode is not None:
            c = _finite("Triangular", "mode", self.mode)
            if not lo <= c <= hi:
                raise ConfigError(
                    f"Triangular: mode ({c:g}) must lie within [{lo:g}, {hi:g}]; move it inside."
                )
            object.__setattr__(self, "mode", c)
        object.__setattr__(self, "dof", _check_dof("Triangular", self.dof))

    @property
    def _c(self) -> float:
        return 0.5 * (self.lower + self.upper) if self.mode is None else float(self.mode)

    @property
    def mean(self) -> float:
        return (self.lower + self.upper + self._c) / 3.0

    @property
    def std(self) -> float:
        a, b, c = self.lower, self.upper, self._c
        return math.sqrt(max((a * a + b * b + c * c - a * b - a * c - b * c) / 18.0, 0.0))

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        a, b, c = self.lower, self.upper, self._c
        if b == a:
            return np.full(size, a)
        if self.mode is None:
            # JCGM 101 §6.4.5.4: ξ = a + (b − a)(r₁ + r₂)/2
            r = rng.random((2, size))
            return a + 0.5 * (b - a) * (r[0] + r[1])
        return rng.triangular(a, c, b, size)

    def describe(self) -> str:
        if self.mode is None:
            return f"triangular ±{_fmt(0.5 * (self.upper - self.lower))}"
        return f"triangular [{_fmt(self.lower)}, {_fmt(self.upper)}] mode {_fmt(self._c)}"


# ---------------------------------------------------------------------------------- trapezoidal
@dataclasses.dataclass(frozen=True)
class Trapezoidal(Distribution):
    """Symmetric trapezoid on [lower, upper], top width β·(upper − lower) — JCGM 101 §6.4.4.

    u² = (upper − lower)²·(1 + β²)/24 (β = 0: triangular, β = 1: rectangular).

    Parameters
    ----------
    lower, upper : float
        Limits of the base (unit of the quantity), lower ≤ upper.
    beta : float
        Ratio of the top width to the base width, 0 ≤ β ≤ 1 (dimensionless).
    dof : float
        Degrees of freedom of u.

    References
    ----------
    JCGM 101:2008, §6.4.4 (trapezoidal distribution, sampling §6.4.4.4);
    JCGM 100:2008, §4.3.9 (eq. of the note).
    """

    lower: float
    upper: float
    beta: float
    dof: float = math.inf
    kind: ClassVar[str] = "trapezoidal"

    def __post_init__(self) -> None:
        lo = _finite("Trapezoidal", "lower", self.lower)
        hi = _finite("Trapezoidal", "upper", self.upper)
        if lo > hi:
            raise ConfigError(f"Trapezoidal: lower ({lo:g}) is above upper ({hi:g}); swap them.")
        beta = _finite("Trapezoidal", "beta", self.beta)
        if not 0.0 <= beta <= 1.0:
            raise ConfigError(
                f"Trapezoidal: beta (top width / base width) must be within [0, 1], got {beta:g}."
            )
        object.__setattr__(self, "lower", lo)
        object.__setattr__(self, "upper", hi)
        object.__setattr__(self, "beta", beta)
        object.__setattr__(self, "dof", _check_dof("Trapezoidal", self.dof))

    @property
    def mean(self) -> float:
        return 0.5 * (self.lower + self.upper)

    @property
    def std(self) -> float:
        return (self.upper - self.lower) * math.sqrt((1.0 + self.beta**2) / 24.0)

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        # JCGM 101 §6.4.4.4: ξ = a + (b − a)[(1 + β)r₁ + (1 − β)r₂]/2
        r = rng.random((2, size))
        w = self.upper - self.lower
        return self.lower + 0.5 * w * ((1.0 + self.beta) * r[0] + (1.0 - self.beta) * r[1])

    def describe(self) -> str:
        return f"trapezoidal ±{_fmt(0.5 * (self.upper - self.lower))}, β={self.beta:g}"


# ------------------------------------------------------------------------ curvilinear trapezoid
@dataclasses.dataclass(frozen=True)
class CurvilinearTrapezoid(Distribution):
    """Rectangular with inexactly known limits mean ± (a ± d) — JCGM 101 §6.4.3.

    The half-width is itself uniform on [a − d, a + d]; u² = a²/3 + d²/9.

    Parameters
    ----------
    mean : float
        Centre of the interval (unit of the quantity).
    half_width : float
        Nominal half-width a (same unit), ≥ 0.
    half_width_uncertainty : float
        d: the half-width is known only to lie in a ± d (same unit), 0 ≤ d ≤ a.
    dof : float
        Degrees of freedom of u.

    References
    ----------
    JCGM 101:2008, §6.4.3 (rectangular distribution with inexactly prescribed limits; expectation
    and variance §6.4.3.3, sampling §6.4.3.4).
    """

    mean: float
    half_width: float
    half_width_uncertainty: float
    dof: float = math.inf
    kind: ClassVar[str] = "curvilinear trapezoid"

    def __post_init__(self) -> None:
        cls = "CurvilinearTrapezoid"
        m = _finite(cls, "mean", self.mean)
        a = _nonneg(cls, "half_width", self.half_width)
        d = _nonneg(cls, "half_width_uncertainty", self.half_width_uncertainty)
        if d > a:
            raise ConfigError(
                f"{cls}: half_width_uncertainty ({d:g}) exceeds half_width ({a:g}); "
                "the limits a ± d must not cross the centre."
            )
        object.__setattr__(self, "mean", m)
        object.__setattr__(self, "half_width", a)
        object.__setattr__(self, "half_width_uncertainty", d)
        object.__setattr__(self, "dof", _check_dof(cls, self.dof))

    @property
    def std(self) -> float:
        a, d = self.half_width, self.half_width_uncertainty
        return math.sqrt(a * a / 3.0 + d * d / 9.0)

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        # JCGM 101 §6.4.3.4: lower limit a_s = (x − a − d) + 2d·r₁, upper b_s = 2x − a_s,
        # ξ = a_s + (b_s − a_s)·r₂
        r = rng.random((2, size))
        a, d = self.half_width, self.half_width_uncertainty
        a_s = (self.mean - a - d) + 2.0 * d * r[0]
        return a_s + 2.0 * (self.mean - a_s) * r[1]

    def describe(self) -> str:
        return (
            f"curvilinear trapezoid ±{_fmt(self.half_width)} "
            f"(limits ±{_fmt(self.half_width_uncertainty)})"
        )


# -------------------------------------------------------------------------------------- arcsine
@dataclasses.dataclass(frozen=True)
class Arcsine(Distribution):
    """Arc sine (U-shaped) on mean ± half_width — JCGM 101 §6.4.6; u = half_width/√2.

    The distribution of a sinusoidally varying quantity (e.g. a cycling temperature).

    Parameters
    ----------
    mean : float
        Centre (unit of the quantity).
    half_width : float
        Amplitude a (same unit), ≥ 0.
    dof : float
        Degrees of freedom of u.

    References
    ----------
    JCGM 101:2008, §6.4.6 (arc sine distribution, sampling §6.4.6.4).
    """

    mean: float
    half_width: float
    dof: float = math.inf
    kind: ClassVar[str] = "arcsine"

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean", _finite("Arcsine", "mean", self.mean))
        object.__setattr__(self, "half_width", _nonneg("Arcsine", "half_width", self.half_width))
        object.__setattr__(self, "dof", _check_dof("Arcsine", self.dof))

    @property
    def std(self) -> float:
        return self.half_width / math.sqrt(2.0)

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        # JCGM 101 §6.4.6.4: ξ = (a + b)/2 + (b − a)/2 · sin(2πr)
        return self.mean + self.half_width * np.sin(2.0 * math.pi * rng.random(size))

    def describe(self) -> str:
        return f"arcsine ±{_fmt(self.half_width)}"


# ------------------------------------------------------------------------------------- t (Type A)
@dataclasses.dataclass(frozen=True)
class StudentT(Distribution):
    """Scaled-and-shifted t: mean + scale·t_ν — JCGM 101 §6.4.9; u = scale·√(ν/(ν − 2)).

    For the mean x̄ of n readings with standard deviation s: mean = x̄, scale = s/√n, ν = n − 1.

    Parameters
    ----------
    mean : float
        Location (unit of the quantity).
    scale : float
        Scale parameter (same unit), ≥ 0 — the GUM Type A standard uncertainty s/√n.
    dof : float
        Degrees of freedom ν > 0. The standard deviation is infinite for ν ≤ 2 (the Monte Carlo
        method still works; the GUM law of propagation does not).

    References
    ----------
    JCGM 101:2008, §6.4.9 (scaled and shifted t-distribution; variance §6.4.9.3, sampling
    §6.4.9.5).
    """

    mean: float
    scale: float
    dof: float
    kind: ClassVar[str] = "t"

    def __post_init__(self) -> None:
        object.__setattr__(self, "mean", _finite("StudentT", "mean", self.mean))
        object.__setattr__(self, "scale", _nonneg("StudentT", "scale", self.scale))
        object.__setattr__(self, "dof", _check_dof("StudentT", self.dof))

    @property
    def std(self) -> float:
        nu = self.dof
        if math.isinf(nu):
            return self.scale
        if nu <= 2.0:
            return math.inf
        return self.scale * math.sqrt(nu / (nu - 2.0))

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        if math.isinf(self.dof):
            return self.mean + self.scale * rng.standard_normal(size)
        return self.mean + self.scale * rng.standard_t(self.dof, size)

    def describe(self) -> str:
        nu = "∞" if math.isinf(self.dof) else f"{self.dof:g}"
        return f"t (ν={nu}) scale {_fmt(self.scale)}"


# ------------------------------------------------------------------------------------- constant
@dataclasses.dataclass(frozen=True)
class Constant(Distribution):
    """An exactly known value (u = 0), in the unit of the quantity."""

    value: float
    kind: ClassVar[str] = "constant"

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", _finite("Constant", "value", self.value))

    @property
    def mean(self) -> float:
        return self.value

    @property
    def std(self) -> float:
        return 0.0

    @property
    def dof(self) -> float:
        return math.inf

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        return np.full(size, self.value)

    def describe(self) -> str:
        return "constant"


# ------------------------------------------------------------------------ multivariate Gaussian
def _psd_factor(cov: np.ndarray) -> np.ndarray:
    """A matrix L with L·Lᵀ = cov (Cholesky; eigen-factor when cov is only semi-definite)."""
    try:
        return np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:
        w, v = np.linalg.eigh(cov)
        return v * np.sqrt(np.clip(w, 0.0, None))


@dataclasses.dataclass(frozen=True, eq=False)
class MultivariateNormal(Distribution):
    """Multivariate Gaussian N(mean, cov) for correlated inputs — JCGM 101 §6.4.8.

    ``sample`` returns an array of shape (size, n). ``std`` is the vector of standard deviations
    (√ of the diagonal of cov) and ``mean`` the vector of expectations.

    Parameters
    ----------
    mean : array_like, shape (n,)
        Expectations (units of the components).
    cov : array_like, shape (n, n)
        Covariance matrix (products of the units), symmetric positive semi-definite.
    dof : float
        Degrees of freedom.

    References
    ----------
    JCGM 101:2008, §6.4.8 (multivariate Gaussian distribution; sampling by the Cholesky factor,
    §6.4.8.4).
    """

    mean: np.ndarray  # type: ignore[assignment]
    cov: np.ndarray
    dof: float = math.inf
    kind: ClassVar[str] = "multivariate normal"

    def __post_init__(self) -> None:
        cls = "MultivariateNormal"
        mean = np.atleast_1d(np.asarray(self.mean, dtype=np.float64))
        cov = np.asarray(self.cov, dtype=np.float64)
        n = mean.size
        if mean.ndim != 1 or cov.shape != (n, n):
            raise ConfigError(
                f"{cls}: cov must be a square ({n}, {n}) matrix matching mean, got shape "
                f"{cov.shape}."
            )
        if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov))):
            raise ConfigError(f"{cls}: mean and cov must be finite numbers.")
        scale = max(float(np.max(np.abs(cov))), np.finfo(np.float64).tiny)
        if not np.allclose(cov, cov.T, rtol=0.0, atol=1e-12 * scale):
            raise ConfigError(f"{cls}: cov must be symmetric; make cov[i, j] equal cov[j, i].")
        w = np.linalg.eigvalsh(cov)
        if w.size and w.min() < -1e-12 * scale:
            raise ConfigError(
                f"{cls}: cov is not positive semi-definite (smallest eigenvalue {w.min():.3g}); "
                "check the correlations."
            )
        mean.flags.writeable = False
        cov = cov.copy()
        cov.flags.writeable = False
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "cov", cov)
        object.__setattr__(self, "dof", _check_dof(cls, self.dof))

    @property
    def std(self) -> np.ndarray:  # type: ignore[override]
        return np.sqrt(np.diag(self.cov))

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        factor = _psd_factor(self.cov)
        z = rng.standard_normal((size, self.mean.size))
        return self.mean + z @ factor.T

    def describe(self) -> str:
        return f"multivariate normal ({self.mean.size})"


# ------------------------------------------------------------------------------ from a TOML spec
_KEYS = (
    "distribution",
    "value",
    "u",
    "half_width",
    "lower",
    "upper",
    "dof",
    "beta",
    "half_width_uncertainty",
    "k",
    "U",
    "mode",
)
_ALIASES = {
    "normal": "normal",
    "gaussian": "normal",
    "rectangular": "rectangular",
    "uniform": "rectangular",
    "triangular": "triangular",
    "trapezoidal": "trapezoidal",
    "trapezoid": "trapezoidal",
    "curvilinear_trapezoid": "curvilinear_trapezoid",
    "curvilinear trapezoid": "curvilinear_trapezoid",
    "curvilinear-trapezoid": "curvilinear_trapezoid",
    "arcsine": "arcsine",
    "u-shaped": "arcsine",
    "t": "t",
    "student_t": "t",
    "student-t": "t",
    "constant": "constant",
    "exact": "constant",
}
#: Keys allowed for each distribution (beside "distribution").
_ALLOWED = {
    "normal": {"value", "u", "U", "k", "dof"},
    "rectangular": {"value", "half_width", "u", "lower", "upper", "dof"},
    "triangular": {"value", "half_width", "lower", "upper", "mode", "dof"},
    "trapezoidal": {"value", "half_width", "lower", "upper", "beta", "dof"},
    "curvilinear_trapezoid": {"value", "half_width", "half_width_uncertainty", "dof"},
    "arcsine": {"value", "half_width", "u", "dof"},
    "t": {"value", "u", "U", "k", "dof"},
    "constant": {"value"},
}
_NAMES = "normal, rectangular, triangular, trapezoidal, curvilinear_trapezoid, arcsine, t, constant"


def distribution_from_spec(spec: Mapping[str, Any], *, where: str) -> Distribution:
    """Build a :class:`Distribution` from its TOML/dict form.

    Forms (all values in the unit of the quantity):

    - ``{distribution="normal", value=…, u=…}`` or ``U=…, k=…`` (u = U/k); optional ``dof``;
    - ``{distribution="rectangular", value=…, half_width=…}``, or ``lower=…, upper=…``, or
      ``value=…, u=…`` (half_width = √3·u);
    - ``{distribution="triangular", value=…, half_width=…}`` or ``lower, upper[, mode]``;
    - ``{distribution="trapezoidal", value=…, half_width=… | lower, upper, beta=…}``;
    - ``{distribution="curvilinear_trapezoid", value=…, half_width=a, half_width_uncertainty=d}``;
    - ``{distribution="arcsine", value=…, half_width=…}`` or ``u=…`` (half_width = √2·u);
    - ``{distribution="t", value=…, u=s/√n, dof=ν}`` (u is the scale; or ``U, k``: scale = U/k);
    - ``{distribution="constant", value=…}``.

    Parameters
    ----------
    spec : mapping
        The keys above (``distribution`` is case-insensitive; aliases ``gaussian``, ``uniform``,
        ``u-shaped``, ``student_t``, ``exact`` are accepted).
    where : str
        What the spec is, for error messages (e.g. ``"[inputs.l_s] in budget.toml"``).

    Returns
    -------
    Distribution

    Raises
    ------
    ConfigError
        One line naming ``where``: unknown distribution, unknown or missing key, a key that does
        not apply, a non-number, a negative u or half-width, lower > upper, a t distribution
        with dof ≤ 2, a u that is not finite (or whose square overflows).

    References
    ----------
    JCGM 101:2008, §6.4 and Table 1 (assignment of distributions); JCGM 100:2008, §4.3
    (Type B: U/k, limits).
    """
    if not isinstance(spec, Mapping):
        raise ConfigError(f"{where}: expected a table of keys (distribution, value, …).")
    unknown = [k for k in spec if k not in _KEYS]
    if unknown:
        raise ConfigError(
            f"{where}: unknown key {unknown[0]!r}; allowed keys are {', '.join(_KEYS)}."
        )
    if "distribution" not in spec:
        raise ConfigError(f"{where}: missing key 'distribution' (one of {_NAMES}).")
    raw = spec["distribution"]
    kind = _ALIASES.get(str(raw).strip().lower()) if isinstance(raw, str) else None
    if kind is None:
        raise ConfigError(f"{where}: unknown distribution {raw!r}; use one of {_NAMES}.")
    for key in spec:
        if key != "distribution" and key not in _ALLOWED[kind]:
            raise ConfigError(
                f"{where}: key {key!r} does not apply to a {kind} distribution; "
                f"it takes {', '.join(sorted(_ALLOWED[kind]))}."
            )

    def num(key: str, *, nonneg: bool = False, allow_inf: bool = False) -> float:
        v = spec[key]
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise ConfigError(f"{where}: {key!r} must be a number, got {v!r}.")
        f = float(v)
        if math.isnan(f) or (math.isinf(f) and not allow_inf):
            raise ConfigError(f"{where}: {key!r} must be a finite number, got {v!r}.")
        if nonneg and f < 0.0:
            raise ConfigError(f"{where}: {key!r} must be ≥ 0, got {v!r}; give its magnitude.")
        return f

    def need(*keys: str) -> None:
        for key in keys:
            if key not in spec:
                raise ConfigError(f"{where}: missing key {key!r} for a {kind} distribution.")

    def std_u() -> float:
        if "u" in spec and ("U" in spec or "k" in spec):
            raise ConfigError(f"{where}: give either 'u' or 'U' with 'k', not both.")
        if "u" in spec:
            return num("u", nonneg=True)
        if "U" in spec or "k" in spec:
            need("U", "k")
            k = num("k")
            if k <= 0.0:
                raise ConfigError(f"{where}: 'k' (coverage factor) must be > 0, got {k:g}.")
            return num("U", nonneg=True) / k
        raise ConfigError(f"{where}: missing key 'u' (or 'U' with 'k') for a {kind} distribution.")

    def limits(half_keys: tuple[str, ...] = ("half_width",)) -> tuple[float, float]:
        has_lim = "lower" in spec or "upper" in spec
        has_half = any(k in spec for k in half_keys) or "value" in spec
        if has_lim and has_half:
            raise ConfigError(f"{where}: give either 'lower' and 'upper', or 'value' and a width.")
        if has_lim:
            need("lower", "upper")
            lo, hi = num("lower"), num("upper")
            if lo > hi:
                raise ConfigError(
                    f"{where}: 'lower' ({lo:g}) is above 'upper' ({hi:g}); swap the limits."
                )
            return lo, hi
        need("value")
        x = num("value")
        if "half_width" in spec:
            a = num("half_width", nonneg=True)
        elif "u" in spec and "u" in half_keys:
            a = num("u", nonneg=True) * (
                math.sqrt(3.0) if kind == "rectangular" else math.sqrt(2.0)
            )
        else:
            raise ConfigError(f"{where}: missing key 'half_width' for a {kind} distribution.")
        if "half_width" in spec and "u" in spec:
            raise ConfigError(f"{where}: give either 'half_width' or 'u', not both.")
        return x - a, x + a

    dof = num("dof", allow_inf=True) if "dof" in spec else math.inf
    if "dof" in spec and dof <= 0.0:
        raise ConfigError(f"{where}: 'dof' must be > 0 (or inf), got {spec['dof']!r}.")

    def build() -> Distribution:
        if kind == "normal":
            need("value")
            return Normal(num("value"), std_u(), dof)
        if kind == "rectangular":
            lo, hi = limits(("half_width", "u"))
            return Rectangular(lo, hi, dof)
        if kind == "triangular":
            lo, hi = limits()
            mode = num("mode") if "mode" in spec else None
            return Triangular(lo, hi, mode, dof)
        if kind == "trapezoidal":
            lo, hi = limits()
            need("beta")
            return Trapezoidal(lo, hi, num("beta"), dof)
        if kind == "curvilinear_trapezoid":
            need("value", "half_width", "half_width_uncertainty")
            return CurvilinearTrapezoid(
                num("value"),
                num("half_width", nonneg=True),
                num("half_width_uncertainty", nonneg=True),
                dof,
            )
        if kind == "arcsine":
            lo, hi = limits(("half_width", "u"))
            return Arcsine(0.5 * (lo + hi), 0.5 * (hi - lo), dof)
        if kind == "t":
            need("value", "dof")
            if dof <= 2.0:
                raise ConfigError(
                    f"{where}: a t distribution needs dof > 2 (for ν ≤ 2 its standard "
                    f"uncertainty is infinite), got {spec['dof']!r}; give ν = n − 1 ≥ 3."
                )
            return StudentT(num("value"), std_u(), dof)
        need("value")
        return Constant(num("value"))

    try:
        dist = build()
    except ConfigError as exc:
        if str(exc).startswith(where):
            raise
        raise ConfigError(f"{where}: {exc}") from None
    u = float(dist.std)
    if not (math.isfinite(u) and math.isfinite(u * u)):
        why = "too large (u² overflows)" if math.isfinite(u) else "not finite"
        raise ConfigError(
            f"{where}: the standard uncertainty u = {u:.3g} is {why}; "
            "state a finite width in the unit of the quantity."
        )
    return dist
