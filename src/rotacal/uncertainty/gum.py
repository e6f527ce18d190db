"""The GUM law of propagation of uncertainty: sensitivities, combined and expanded uncertainty.

A measurement model ``y = f(x_1, …, x_n)`` (one or several outputs) and its input quantities
(:class:`Input`: estimate x_i, standard uncertainty u(x_i), degrees of freedom ν_i) give

* the sensitivity coefficients c_i = ∂f/∂x_i (central differences, or a Jacobian you supply);
* the covariance matrix of the outputs ``U_y = J·U_x·Jᵀ`` with ``U_x = D·R·D``, D = diag(u(x_i)),
  R the correlation matrix of the inputs — GUM eq. (10) for uncorrelated, eq. (13)/(16) for
  correlated inputs, and the output covariances of GUM H.2 for several outputs;
* optionally the second-order terms of GUM §5.1.2 note (uncorrelated inputs), which matter when the
  model is strongly nonlinear where the sensitivities vanish (GUM H.1: 32 nm → 34 nm);
* the effective degrees of freedom by Welch–Satterthwaite (GUM eq. (G.2b)), the coverage factor
  k = t_p(ν_eff) (GUM G.3–G.4, ν_eff truncated to an integer as G.4.1 note 1 allows) and the
  expanded uncertainty U = k·u_c (GUM §6).

:func:`linear_fit_uncertainty` is the straight-line calibration of GUM H.3 (intercept, slope,
their uncertainties and correlation), the same shape as a gyro scale-factor fit.

References
----------
JCGM 100:2008 (GUM): §5.1.2 eq. (10) and its note (second-order terms); §5.2.2 eq. (13), (16); §6; Annex G (G.3, G.4, eq. (G.2b),
Table G.2); Annex H.1–H.3. JCGM 101:2008 §5 (the GUM uncertainty framework).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result
from rotacal.uncertainty.budget import BudgetRow, UncertaintyBudget

if TYPE_CHECKING:
    from rotacal.uncertainty.distributions import Distribution

__all__ = [
    "GUMResult",
    "Input",
    "LinearFit",
    "correlation_matrix",
    "coverage_factor",
    "linear_fit_uncertainty",
    "propagate",
    "welch_satterthwaite",
]

#: Smallest eigenvalue a correlation matrix may have (round-off of a valid PSD matrix).
PSD_TOLERANCE = 1e-12
#: Tolerance of the checks for symmetry, unit diagonal and |r| ≤ 1.
_R_TOLERANCE = 1e-12
#: Relative and absolute-by-u steps of the central differences for the Jacobian.
_STEP_U = 1e-3
_STEP_X = 1e-9
#: ν_eff from which the truncation note is left out (the t-factor equals the normal one there).
_NU_NOTE_MAX = 1e6
#: Steps of the second- and third-order differences for GUM §5.1.2 note, as fractions of u(x_i).
_STEP_SECOND = 0.02
_STEP_THIRD = 0.5


def _number(value: Any, what: str) -> float:
    if isinstance(value, bool):
        raise ConfigError(f"{what} = {value!r} is not a number; give a float.")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{what} = {value!r} is not a number; give a float.") from None


# ---------------------------------------------------------------------------------------- input
@dataclasses.dataclass(frozen=True)
class Input:
    """One input quantity X_i of a measurement model.

    Attributes
    ----------
    name : name of the quantity (unique within a model, e.g. ``"l_s"``).
    value : its estimate x_i (unit ``unit``).
    u : its standard uncertainty u(x_i) ≥ 0 (unit ``unit``).
    dof : degrees of freedom ν_i (> 0; ``math.inf`` when the distribution is taken as exactly
        known — GUM G.4.2; n − 1 for the mean of n observations, GUM G.3.3).
    distribution : name of the assigned distribution (``"normal"``, ``"rectangular"``, …).
    unit : unit of ``value`` and ``u`` (text, for budgets).
    source : where the knowledge comes from (``"certificate"``, ``"Type A, 5 readings"``, …).
    description : one short phrase for a budget row (``"rectangular ±2e-06"``); optional.

    Raises
    ------
    ConfigError
        On a non-finite value, a negative or non-finite u, or ν ≤ 0 — naming the input.

    References
    ----------
    JCGM 100:2008 (GUM), §4.2 (Type A), §4.3 (Type B), G.3–G.4 (degrees of freedom).
    """

    name: str
    value: float
    u: float
    dof: float = math.inf
    distribution: str = "normal"
    unit: str = ""
    source: str = ""
    description: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ConfigError(f"every input needs a non-empty name; got {self.name!r}.")
        where = f"input '{self.name}'"
        value = _number(self.value, f"{where}: value")
        u = _number(self.u, f"{where}: u")
        dof = _number(self.dof, f"{where}: dof")
        if not math.isfinite(value):
            raise ConfigError(f"{where}: value = {value!r} is not finite; give its estimate.")
        if math.isnan(u) or math.isinf(u):
            raise ConfigError(
                f"{where}: u = {u!r} is not finite; give the standard uncertainty as a number."
            )
        if u < 0.0:
            raise ConfigError(
                f"{where}: u = {u!r} is negative; a standard uncertainty is ≥ 0 (same unit as "
                "the value)."
            )
        if math.isnan(dof) or dof <= 0.0:
            raise ConfigError(
                f"{where}: dof = {dof!r} must be > 0 (n − 1 for a mean of n readings, math.inf "
                "for an exactly known distribution)."
            )
        for field in ("distribution", "unit", "source", "description"):
            if not isinstance(getattr(self, field), str):
                raise ConfigError(f"{where}: {field} must be text; got {getattr(self, field)!r}.")
        if not self.distribution:
            raise ConfigError(f"{where}: distribution must name the distribution, e.g. 'normal'.")
        object.__setattr__(self, "value", value)
        object.__setattr__(self, "u", u)
        object.__setattr__(self, "dof", dof)

    @classmethod
    def from_distribution(
        cls, name: str, dist: Distribution, unit: str = "", source: str = ""
    ) -> Input:
        """The input whose estimate, u and ν are the mean, standard deviation and ν of ``dist``.

        Parameters
        ----------
        name : str
            Name of the quantity.
        dist : rotacal.uncertainty.distributions.Distribution
            A univariate distribution (JCGM 101 §6.4); multivariate ones need one Input per
            component and a correlation matrix.
        unit, source : str
            As in :class:`Input`.

        Returns
        -------
        Input
            ``value = dist.mean``, ``u = dist.std``, ``dof = dist.dof``,
            ``distribution = dist.name``, ``description = dist.describe()``.

        References
        ----------
        JCGM 101:2008 §6.4 (expectation and standard deviation of the assigned distributions);
        JCGM 100:2008 §4.3.7–4.3.9 (rectangular, trapezoidal, triangular Type B evaluations).
        """
        mean = dist.mean
        if np.ndim(mean) != 0:
            raise ConfigError(
                f"input '{name}': a multivariate distribution cannot be one Input; give one Input "
                "per component and their correlation matrix."
            )
        return cls(
            name=name,
            value=float(mean),
            u=float(dist.std),
            dof=float(getattr(dist, "dof", math.inf)),
            distribution=str(dist.name),
            unit=unit,
            source=source,
            description=str(dist.describe()),
        )


# ------------------------------------------------------------------------- correlation matrix
def correlation_matrix(r: Any, n: int, *, names: Sequence[str] | None = None) -> np.ndarray:
    """A validated n×n correlation matrix of the inputs.

    Parameters
    ----------
    r : None, array_like (n, n) or mapping
        ``None`` → uncorrelated (identity). An n×n matrix of correlation coefficients r(x_i, x_k)
        (dimensionless). Or a mapping ``{(a, b): r_ab}`` whose keys are pairs of input names (with
        ``names``) or of indices; unnamed pairs are uncorrelated.
    n : int
        Number of inputs.
    names : sequence of str, optional
        Names of the inputs, for the keys of a mapping and for the error messages.

    Returns
    -------
    numpy.ndarray
        (n, n) float64, symmetric, unit diagonal, |r| ≤ 1, positive semi-definite (smallest
        eigenvalue ≥ −1e-12). A new array.

    Raises
    ------
    ConfigError
        One line naming the offending entry: wrong shape, non-finite, not symmetric, diagonal ≠ 1,
        |r| > 1, or not positive semi-definite.

    References
    ----------
    JCGM 100:2008 (GUM), §5.2.2 (r(x_i, x_j) = u(x_i, x_j)/(u(x_i)·u(x_j)), |r| ≤ 1),
    C.3.6 (correlation coefficient); JCGM 101:2008 §6.4.8 (the covariance matrix is positive
    semi-definite).
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ConfigError(f"the number of inputs must be an integer ≥ 1; got {n!r}.")
    n = int(n)
    labels = [str(s) for s in names] if names is not None else [str(i) for i in range(n)]
    if len(labels) != n:
        raise ConfigError(f"{len(labels)} names were given for {n} inputs; give one per input.")
    if r is None:
        return np.eye(n)
    if isinstance(r, Mapping):
        mat = _from_pairs(r, n, labels)
    else:
        try:
            mat = np.array(r, dtype=np.float64)
        except (TypeError, ValueError):
            raise ConfigError(
                "the correlation matrix is not numeric; give an n×n array of numbers."
            ) from None
        if mat.shape != (n, n):
            raise ConfigError(
                f"the correlation matrix has shape {mat.shape}; give an {n}×{n} matrix "
                f"(one row and column per input: {', '.join(labels)})."
            )
    if not np.all(np.isfinite(mat)):
        i, j = np.argwhere(~np.isfinite(mat))[0]
        raise ConfigError(
            f"correlation r[{labels[i]}, {labels[j]}] = {mat[i, j]!r} is not finite; give a number "
            "in [−1, 1]."
        )
    diag_err = np.abs(np.diag(mat) - 1.0)
    if np.any(diag_err > _R_TOLERANCE):
        i = int(np.argmax(diag_err))
        raise ConfigError(
            f"correlation r[{labels[i]}, {labels[i]}] = {mat[i, i]:g}; the diagonal of a "
            "correlation matrix must be 1."
        )
    asym = np.abs(mat - mat.T)
    if np.any(asym > _R_TOLERANCE):
        i, j = np.unravel_index(int(np.argmax(asym)), asym.shape)
        raise ConfigError(
            f"the correlation matrix is not symmetric: r[{labels[i]}, {labels[j]}] = "
            f"{mat[i, j]:g} but r[{labels[j]}, {labels[i]}] = {mat[j, i]:g}; give the same value."
        )
    excess = np.abs(mat) - 1.0
    if np.any(excess > _R_TOLERANCE):
        i, j = np.unravel_index(int(np.argmax(excess)), excess.shape)
        raise ConfigError(
            f"correlation r[{labels[i]}, {labels[j]}] = {mat[i, j]:g} is outside [−1, 1]."
        )
    mat = 0.5 * (mat + mat.T)
    np.fill_diagonal(mat, 1.0)
    lam_min = float(np.linalg.eigvalsh(mat)[0]) if n > 1 else 1.0
    if lam_min < -PSD_TOLERANCE:
        raise ConfigError(
            f"the correlation matrix of {', '.join(labels)} is not positive semi-definite "
            f"(smallest eigenvalue {lam_min:.3g}); the correlations contradict each other — "
            "derive them from one covariance estimate."
        )
    return mat


def _from_pairs(r: Mapping[Any, Any], n: int, labels: list[str]) -> np.ndarray:
    index = {name: i for i, name in enumerate(labels)}
    mat = np.eye(n)
    given = np.eye(n, dtype=bool)

    def position(key: Any) -> int:
        if isinstance(key, str):
            if key not in index:
                raise ConfigError(
                    f"correlation names unknown input '{key}'; the inputs are {', '.join(labels)}."
                )
            return index[key]
        if isinstance(key, (int, np.integer)) and not isinstance(key, bool) and 0 <= key < n:
            return int(key)
        raise ConfigError(
            f"correlation key {key!r} is neither an input name nor an index 0…{n - 1}."
        )

    for key, val in r.items():
        if not (isinstance(key, tuple) and len(key) == 2):
            raise ConfigError(
                f"correlation key {key!r} must be a pair (a, b) of input names; e.g. "
                "{('V', 'I'): -0.36}."
            )
        a, b = position(key[0]), position(key[1])
        v = _number(val, f"correlation r[{labels[a]}, {labels[b]}]")
        if a == b:
            if v != 1.0:
                raise ConfigError(
                    f"correlation r[{labels[a]}, {labels[a]}] = {v:g}; the correlation of an "
                    "input with itself is 1."
                )
            continue
        if given[a, b] and mat[a, b] != v:
            raise ConfigError(
                f"correlation r[{labels[a]}, {labels[b]}] is given twice ({mat[a, b]:g} and {v:g}); "
                "give it once."
            )
        mat[a, b] = mat[b, a] = v
        given[a, b] = given[b, a] = True
    return mat


# ----------------------------------------------------------------- coverage factor and ν_eff
def coverage_factor(dof: float, p: float = 0.95, *, truncate: bool = True) -> float:
    """The coverage factor k_p = t_p(ν) of a two-sided interval with coverage probability p.

    Parameters
    ----------
    dof : float
        Degrees of freedom ν (> 0; ``math.inf`` gives the normal quantile, 1.959964 for p = 0.95).
    p : float, optional
        Coverage probability, 0 < p < 1 (e.g. 0.95, 0.99). Default 0.95.
    truncate : bool, optional
        Truncate a non-integer ν to the next lower integer before taking the t quantile, as GUM
        G.4.1 note 1 allows (the other option it names is interpolating Table G.2); the
        conservative choice, and the one the GUM's own examples use (H.1: ν_eff = 16.75 →
        t_99(16) = 2.92). A ν within 1e-9 (relative) below an integer counts as that integer.
        Default True; False uses the t distribution at the fractional ν.

    Returns
    -------
    float
        k_p (dimensionless), so that U_p = k_p·u_c.

    Raises
    ------
    ConfigError
        When p is not in (0, 1), ν is NaN or ≤ 0, or ν < 1 with ``truncate``.

    References
    ----------
    JCGM 100:2008 (GUM), G.3.2–G.3.4, G.4.1 (step 3 and note 1), Table G.2; §6.3.
    """
    pf = _number(p, "coverage probability p")
    if not 0.0 < pf < 1.0:
        raise ConfigError(f"coverage probability p = {pf!r} must be in (0, 1), e.g. 0.95.")
    nu = _number(dof, "degrees of freedom ν")
    if math.isnan(nu) or nu <= 0.0:
        raise ConfigError(f"degrees of freedom ν = {nu!r} must be > 0 (math.inf for none).")
    tail = 0.5 * (1.0 - pf)
    if math.isinf(nu):
        return _upper_quantile(tail, math.inf)
    if truncate:
        nu_t = math.floor(nu + 1e-9 * max(1.0, nu))
        if nu_t < 1:
            raise ConfigError(
                f"ν = {nu:g} truncates to 0 (GUM G.4.1 note 1); an uncertainty with fewer than one "
                "degree of freedom has no t-based coverage factor — give k or more readings."
            )
        nu = float(nu_t)
    return _upper_quantile(tail, nu)


@functools.lru_cache(maxsize=4096)
def _upper_quantile(tail: float, nu: float) -> float:
    """The upper ``tail`` quantile of Student's t with ν degrees of freedom (the normal's for
    ν = inf), kept by its arguments: scipy takes ~0.3 ms a call, and the budgets of every
    calibration ask for the same few (p = 0.95, integer ν) again and again."""
    # scipy.special, not scipy.stats: the same functions (stats.norm.isf(q) is -ndtri(q),
    # stats.t.isf(q, ν) is -stdtrit(ν, q), bit for bit; a test checks it) at ~0.2 s of import
    # instead of ~0.6 s, paid only when a quantile is computed
    from scipy import special

    if math.isinf(nu):
        return float(-special.ndtri(tail))
    return float(-special.stdtrit(nu, tail))


def welch_satterthwaite(contributions: Any, dofs: Any) -> float:
    """The effective degrees of freedom of a sum of independent uncertainty components.

    ``ν_eff = u_c⁴ / Σ_i (u_i⁴/ν_i)`` with ``u_c² = Σ_i u_i²``, where u_i = c_i·u(x_i).

    Parameters
    ----------
    contributions : array_like (n,)
        The components u_i(y) = c_i·u(x_i) (same unit as y; signs are ignored).
    dofs : array_like (n,)
        Their degrees of freedom ν_i (> 0; ``math.inf`` for exactly known ones).

    Returns
    -------
    float
        ν_eff ≥ min ν_i; ``math.inf`` when every ν_i with a non-zero component is infinite (or
        every component is 0).

    Raises
    ------
    ConfigError
        Different lengths, no components, a non-finite component, or ν ≤ 0 / NaN.

    References
    ----------
    JCGM 100:2008 (GUM), G.4.1, eq. (G.2b); Welch (1947), Satterthwaite (1946).
    """
    c = np.asarray(contributions, dtype=np.float64).ravel()
    nu = np.asarray(dofs, dtype=np.float64).ravel()
    if c.size != nu.size:
        raise ConfigError(
            f"welch_satterthwaite got {c.size} contributions and {nu.size} degrees of freedom; "
            "give one ν per contribution."
        )
    if c.size == 0:
        raise ConfigError("welch_satterthwaite needs at least one contribution.")
    if not np.all(np.isfinite(c)):
        i = int(np.flatnonzero(~np.isfinite(c))[0])
        raise ConfigError(f"contribution {i} = {float(c[i])!r} is not finite; give c_i·u(x_i).")
    if np.any(np.isnan(nu)) or np.any(nu <= 0.0):
        i = int(np.flatnonzero(np.isnan(nu) | (nu <= 0.0))[0])
        raise ConfigError(f"degrees of freedom ν_{i} = {nu[i]!r} must be > 0 (math.inf for none).")
    scale = float(np.max(np.abs(c)))
    if scale == 0.0:
        return math.inf
    w = (c / scale) ** 2
    finite = np.isfinite(nu)
    den = float(np.sum(w[finite] ** 2 / nu[finite]))
    if den == 0.0:
        return math.inf
    return float(np.sum(w) ** 2 / den)


# -------------------------------------------------------------------------------- the result
@dataclasses.dataclass(frozen=True, eq=False)
class GUMResult(Result):
    """The result of the law of propagation of uncertainty for m outputs and n inputs.

    Attributes
    ----------
    names_out : names of the outputs y_j.
    value : (m,) estimates y_j = f_j(x) (unit of each output).
    u : (m,) combined standard uncertainties u_c(y_j) (with the second-order terms when asked).
    covariance : (m, m) covariance matrix of the outputs (first order; second-order terms only
        on the diagonal).
    correlation : (m, m) correlation matrix of the outputs (dimensionless).
    sensitivities : (m, n) c_ji = ∂f_j/∂x_i (unit of y_j per unit of x_i).
    contributions : (m, n) c_ji·u(x_i) (unit of y_j; signed).
    dof_eff : (m,) effective degrees of freedom ν_eff (Welch–Satterthwaite; ``inf`` → JSON null).
    k : (m,) coverage factors.
    p : coverage probability (fraction).
    U : (m,) expanded uncertainties k·u (unit of y_j).
    names_in : names of the inputs.
    units_out : units of the outputs (text).
    inputs : the :class:`Input` objects, in model order.
    input_correlation : (n, n) correlation matrix of the inputs used.
    variance_second_order : (m,) the GUM §5.1.2 note second-order variance added to u² (0 when not
        asked).
    notes : sentences a reader needs (truncation of ν_eff, correlated inputs, user k, …).

    References
    ----------
    JCGM 100:2008 (GUM), §5.1–5.2, §6, Annex G, H.2 (several outputs and their correlation).
    """

    names_out: tuple[str, ...]
    value: np.ndarray
    u: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    sensitivities: np.ndarray
    contributions: np.ndarray
    dof_eff: np.ndarray
    k: np.ndarray
    p: float
    U: np.ndarray
    names_in: tuple[str, ...] = ()
    units_out: tuple[str, ...] = ()
    inputs: tuple[Input, ...] = ()
    input_correlation: np.ndarray | None = None
    variance_second_order: np.ndarray | None = None
    notes: tuple[str, ...] = ()
    _notes_by_output: tuple[tuple[str, ...], ...] = dataclasses.field(default=(), repr=False)

    def budget(self, j: int = 0) -> UncertaintyBudget:
        """The uncertainty budget of output ``j`` (one row per input; GUM §7.2, Table H.1 style).

        Shares are c_i²u_i²/u_c² — they sum to 1 for uncorrelated inputs. With correlated inputs
        they do not (the rest is the correlation terms of GUM eq. (16)), and a note says so. When
        second-order terms were added they get their own row, so the shares still sum to 1.

        Parameters
        ----------
        j : int, optional
            Index of the output (0 … m − 1). Default 0.

        Returns
        -------
        UncertaintyBudget
            With ``method = "GUM"``.

        References
        ----------
        JCGM 100:2008 (GUM), §7.2.2–7.2.7, Table H.1; eq. (10), (16) and the note to §5.1.2.
        """
        m = len(self.names_out)
        if isinstance(j, bool) or not isinstance(j, (int, np.integer)) or not 0 <= j < m:
            raise ConfigError(
                f"output index j = {j!r} is out of range; this result has {m} output(s): "
                f"{', '.join(self.names_out)}."
            )
        j = int(j)
        uc = float(self.u[j])
        uc2 = uc * uc
        rows: list[BudgetRow] = []
        for i, inp in enumerate(self.inputs):
            ci = float(self.contributions[j, i])
            rows.append(
                BudgetRow(
                    source=inp.name,
                    value=inp.value,
                    unit=inp.unit,
                    distribution=inp.description or inp.distribution,
                    u=inp.u,
                    sensitivity=float(self.sensitivities[j, i]),
                    contribution=ci,
                    share=(ci * ci / uc2) if uc2 > 0.0 else 0.0,
                    dof=inp.dof,
                    origin=inp.source,
                )
            )
        notes = list(self._notes_by_output[j]) if self._notes_by_output else list(self.notes)
        v2 = 0.0 if self.variance_second_order is None else float(self.variance_second_order[j])
        if v2 != 0.0:
            rows.append(
                BudgetRow(
                    source="second-order terms (GUM §5.1.2 note)",
                    value=math.nan,
                    unit="",
                    distribution="",
                    u=math.nan,
                    sensitivity=math.nan,
                    contribution=math.copysign(math.sqrt(abs(v2)), v2),
                    share=(v2 / uc2) if uc2 > 0.0 else 0.0,
                    dof=math.inf,
                )
            )
        corr = self.input_correlation
        if corr is not None and uc2 > 0.0:
            c = self.contributions[j]
            off = np.outer(c, c) * corr
            np.fill_diagonal(off, 0.0)
            if np.any(off != 0.0):
                total = sum(row.share for row in rows)
                notes.append(
                    f"inputs are correlated: the shares c_i²u_i²/u_c² sum to {total:.3f}, not 1; "
                    "the rest is the correlation terms 2·c_i·c_k·u_i·u_k·r_ik (GUM eq. (16))."
                )
        return UncertaintyBudget(
            quantity=self.names_out[j],
            unit=self.units_out[j] if self.units_out else "",
            value=float(self.value[j]),
            u=uc,
            dof_eff=float(self.dof_eff[j]),
            k=float(self.k[j]),
            p=float(self.p),
            U=float(self.U[j]),
            rows=tuple(rows),
            method="GUM",
            notes=tuple(notes),
        )


# ----------------------------------------------------------------------------- propagation
def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a, dtype=np.float64)
    a.setflags(write=False)
    return a


class _Model:
    """Calls the user's model at a point, checks the shape and that the outputs are finite."""

    def __init__(self, model: Callable[..., Any], names_in: tuple[str, ...]) -> None:
        self.model = model
        self.names_in = names_in
        self.m: int | None = None
        self.names_out: tuple[str, ...] | None = None

    def __call__(self, x: np.ndarray, where: str) -> np.ndarray:
        with np.errstate(all="ignore"):
            out = self.model(*(float(v) for v in x))
        try:
            arr = np.asarray(out, dtype=np.float64)
        except (TypeError, ValueError):
            raise ConfigError(
                f"the model returned {type(out).__name__} {where}; it must return a float or a "
                "1-D array of floats."
            ) from None
        if arr.ndim > 1 or arr.size == 0:
            raise ConfigError(
                f"the model returned an array of shape {arr.shape} {where}; it must return a float "
                "or a 1-D array (one value per output)."
            )
        arr = arr.reshape(-1)
        if self.m is not None and arr.size != self.m:
            raise ConfigError(
                f"the model returned {arr.size} values {where} but {self.m} at the input "
                "estimates; it must always return the same number of outputs."
            )
        bad = ~np.isfinite(arr)
        if np.any(bad):
            j = int(np.flatnonzero(bad)[0])
            label = self.names_out[j] if self.names_out and j < len(self.names_out) else f"{j}"
            raise ConfigError(
                f"the model returned {float(arr[j])!r} for output '{label}' {where}; check the model and "
                "the values of the inputs."
            )
        return arr


def _moved(names_in: tuple[str, ...], x: np.ndarray, *idx: int) -> str:
    moved = ", ".join(f"'{names_in[i]}' to {x[i]:.10g}" for i in idx)
    return f"with input {moved} (finite-difference step)"


def _check_inputs(inputs: Any) -> tuple[Input, ...]:
    if isinstance(inputs, Input):
        inputs = (inputs,)
    try:
        items = tuple(inputs)
    except TypeError:
        raise ConfigError("inputs must be a sequence of Input objects.") from None
    if not items:
        raise ConfigError("the model has no inputs; give at least one Input.")
    for i, item in enumerate(items):
        if not isinstance(item, Input):
            raise ConfigError(
                f"input {i} is a {type(item).__name__}, not an Input; build it with Input(name, "
                "value, u) or Input.from_distribution(name, dist)."
            )
    names = [item.name for item in items]
    dupes = sorted({name for name in names if names.count(name) > 1})
    if dupes:
        raise ConfigError(f"input name(s) {', '.join(dupes)} appear more than once; rename them.")
    return items


def _labels(
    given: Sequence[str] | None, m: int, what: str, default: Sequence[str]
) -> tuple[str, ...]:
    if given is None:
        return tuple(default)
    labels = (given,) if isinstance(given, str) else tuple(str(s) for s in given)
    if len(labels) != m:
        raise ConfigError(
            f"{len(labels)} {what} were given but the model has {m} output(s); give one per output."
        )
    return labels


def _numeric_jacobian(
    call: _Model, x: np.ndarray, u: np.ndarray, y0: np.ndarray, names_in: tuple[str, ...]
) -> np.ndarray:
    n, m = x.size, y0.size
    h = np.maximum(u * _STEP_U, np.abs(x) * _STEP_X)
    h[h == 0.0] = _STEP_X
    jac = np.empty((m, n))
    for i in range(n):  # one pair of model calls per input (not per sample)
        xp = x.copy()
        xm = x.copy()
        xp[i] += h[i]
        xm[i] -= h[i]
        fp = call(xp, _moved(names_in, xp, i))
        fm = call(xm, _moved(names_in, xm, i))
        jac[:, i] = (fp - fm) / (xp[i] - xm[i])
    return jac


def _user_jacobian(jacobian: Callable[..., Any], x: np.ndarray, m: int, n: int) -> np.ndarray:
    with np.errstate(all="ignore"):
        out = jacobian(*(float(v) for v in x))
    try:
        jac = np.array(out, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(
            f"the jacobian returned {type(out).__name__}; it must return an ({m}, {n}) array of "
            "∂y_j/∂x_i."
        ) from None
    if m == 1 and jac.shape == (n,):
        jac = jac.reshape(1, n)
    if jac.shape != (m, n):
        raise ConfigError(
            f"the jacobian returned shape {jac.shape}; it must be ({m}, {n}) — one row per output, "
            "one column per input."
        )
    if not np.all(np.isfinite(jac)):
        j, i = np.argwhere(~np.isfinite(jac))[0]
        raise ConfigError(
            f"the jacobian entry [{j}, {i}] is {jac[j, i]!r}; check the derivative formulas."
        )
    return jac


def _second_order_variance(
    call: _Model,
    x: np.ndarray,
    u: np.ndarray,
    y0: np.ndarray,
    jac: np.ndarray,
    names_in: tuple[str, ...],
) -> np.ndarray:
    """Σ_i Σ_k [½(∂²f/∂x_i∂x_k)² + ∂f/∂x_i·∂³f/∂x_i∂x_k²]·u_i²·u_k² — GUM §5.1.2 note.

    Central differences: second derivatives with step 0.02·u(x_i) (truncation ~(0.02·u/scale)²),
    third derivatives with step 0.5·u(x_i) (their round-off grows as 1/h³; the terms they enter
    are themselves small). Both are exact for models that are polynomials of degree ≤ 3 in each
    input. Inputs with u = 0 contribute nothing and are skipped.
    """
    act = [int(i) for i in np.flatnonzero(u > 0.0)]

    def point(steps: dict[int, float]) -> np.ndarray:
        xs = x.copy()
        for i, h in steps.items():
            xs[i] = x[i] + h
        return call(xs, _moved(names_in, xs, *steps))

    h2 = {i: _STEP_SECOND * float(u[i]) for i in act}
    h3 = {i: _STEP_THIRD * float(u[i]) for i in act}
    # (i, s): f(x + s·h3_i·e_i), s ∈ {±1, ±2}
    f3 = {(i, s): point({i: s * h3[i]}) for i in act for s in (-2, -1, 1, 2)}
    var = np.zeros(y0.size)
    for i in act:
        h, g = h2[i], h3[i]
        d2 = (point({i: h}) - 2.0 * y0 + point({i: -h})) / (h * h)
        d3 = (f3[(i, 2)] - 2.0 * f3[(i, 1)] + 2.0 * f3[(i, -1)] - f3[(i, -2)]) / (2.0 * g**3)
        var += (0.5 * d2 * d2 + jac[:, i] * d3) * u[i] ** 4
    signs = ((1, 1), (1, -1), (-1, 1), (-1, -1))
    for a, b in itertools.combinations(act, 2):  # n(n−1)/2 pairs of inputs, 8 calls each
        ha, hb = h2[a], h2[b]
        pp, pm, mp, mm = (point({a: sa * ha, b: sb * hb}) for sa, sb in signs)
        d_ab = (pp - pm - mp + mm) / (4.0 * ha * hb)
        ga, gb = h3[a], h3[b]
        pp, pm, mp, mm = (point({a: sa * ga, b: sb * gb}) for sa, sb in signs)
        # ∂/∂x_a of ∂²f/∂x_b², and ∂/∂x_b of ∂²f/∂x_a²
        d_abb = ((pp - 2.0 * f3[(a, 1)] + pm) - (mp - 2.0 * f3[(a, -1)] + mm)) / (2.0 * ga * gb**2)
        d_baa = ((pp - 2.0 * f3[(b, 1)] + mp) - (pm - 2.0 * f3[(b, -1)] + mm)) / (2.0 * gb * ga**2)
        w = u[a] ** 2 * u[b] ** 2
        var += (d_ab * d_ab + jac[:, a] * d_abb + jac[:, b] * d_baa) * w
    return var


def _dof_eff(
    jac_row: np.ndarray,
    cov_x: np.ndarray,
    nu: np.ndarray,
    blocks: np.ndarray,
    n_blocks: int,
    names_in: tuple[str, ...],
) -> tuple[float, list[str]]:
    """ν_eff by W–S over blocks of mutually correlated inputs (one component per block)."""
    notes: list[str] = []
    comps: list[float] = []
    dofs: list[float] = []
    contrib = np.abs(jac_row) * np.sqrt(np.diag(cov_x))
    if n_blocks == jac_row.size:  # uncorrelated: each input one component, c_i·u_i·c_i as below
        active = contrib > 0.0
        if not np.any(active):
            return math.inf, notes
        c = jac_row[active]
        var = np.maximum(c * np.diag(cov_x)[active] * c, 0.0)
        return welch_satterthwaite(np.sqrt(var), nu[active]), notes
    for b in range(n_blocks):
        members = np.flatnonzero(blocks == b)
        active = members[contrib[members] > 0.0]
        if active.size == 0:
            continue
        c = jac_row[members]
        var_b = max(float(c @ cov_x[np.ix_(members, members)] @ c), 0.0)
        nus = nu[active]
        nu_b = float(np.min(nus))
        if members.size > 1:
            who = ", ".join(names_in[i] for i in active)
            if np.all(nus == nu_b):
                notes.append(
                    f"correlated inputs {who} enter Welch–Satterthwaite as one component with "
                    f"their common ν = {nu_b:g} (GUM H.2, H.3)."
                )
            else:
                nu_list = ", ".join(f"{v:g}" for v in nus)
                notes.append(
                    f"correlated inputs {who} have different ν ({nu_list}); GUM eq. (G.2b) does not "
                    f"cover correlated inputs, so they enter as one component with the smallest, "
                    f"ν = {nu_b:g} (conservative)."
                )
        comps.append(math.sqrt(var_b))
        dofs.append(nu_b)
    if not comps:
        return math.inf, notes
    return welch_satterthwaite(comps, dofs), notes


def propagate(
    model: Callable[..., Any],
    inputs: Sequence[Input],
    *,
    correlation: Any = None,
    jacobian: Callable[..., Any] | None = None,
    p: float = 0.95,
    k: float | None = None,
    names_out: Sequence[str] | None = None,
    second_order: bool = False,
    units_out: Sequence[str] | None = None,
) -> GUMResult:
    """Propagate the uncertainties of the inputs through a measurement model (GUM §5).

    Parameters
    ----------
    model : callable
        ``model(x_1, …, x_n)`` (floats, in the order of ``inputs``) → a float, or a 1-D array of m
        outputs (each in its own unit).
    inputs : sequence of Input
        The input quantities (estimates, standard uncertainties, ν).
    correlation : None, array_like (n, n) or mapping, optional
        Correlation matrix of the inputs (see :func:`correlation_matrix`; ``{("V", "I"): -0.36}``
        works too). None: uncorrelated.
    jacobian : callable, optional
        ``jacobian(x_1, …, x_n)`` → (m, n) array ∂y_j/∂x_i (or (n,) for one output). None: central
        differences with step h_i = max(u(x_i)·1e-3, |x_i|·1e-9) (1e-9 when both are 0) — exact
        for linear models, two model calls per input.
    p : float, optional
        Coverage probability (0 < p < 1). Default 0.95.
    k : float, optional
        A coverage factor to use instead of t_p(ν_eff) (e.g. 2); ``p`` is then only nominal.
    names_out : sequence of str, optional
        Names of the outputs (default ``"y"`` or ``"y1"…"ym"``).
    second_order : bool, optional
        Add the second-order terms of GUM §5.1.2 note to u_c² (uncorrelated inputs only; second and
        third derivatives by central differences, ~2n² model calls). ν_eff stays that of the
        first-order terms. Default False.
    units_out : sequence of str, optional
        Units of the outputs (text for budgets).

    Returns
    -------
    GUMResult
        Values, u_c, covariance and correlation of the outputs, sensitivities, contributions,
        ν_eff, k, U.

    Notes
    -----
    ν_eff is Welch–Satterthwaite (GUM eq. (G.2b)) over independent components. GUM defines it for
    uncorrelated inputs only; here a group of mutually correlated inputs enters as one component
    c_Bᵀ·U_B·c_B. When the group shares one ν (the parameters of one fit, simultaneous readings
    of one series — GUM H.2, H.3) that ν is used, which reproduces GUM H.3 (ν = 9); when their ν
    differ the smallest is used (conservative) and a note says so. k = t_p(ν_eff) with ν_eff
    truncated to the next lower integer (GUM G.4.1 note 1; :func:`coverage_factor`).

    Raises
    ------
    ConfigError
        Bad inputs or correlation matrix, a model that returns NaN/inf or the wrong shape, a
        Jacobian of the wrong shape, second_order with correlated inputs.

    References
    ----------
    JCGM 100:2008 (GUM): §5.1.2 eq. (10) and its note (second-order terms), §5.2.2 eq. (13), (16); §6.2–6.3;
    G.4.1 eq. (G.2b) and note 1; H.1 (second-order terms), H.2 (several correlated outputs),
    H.3 (correlated fit parameters). JCGM 101:2008 §5 (the GUM uncertainty framework).
    """
    items = _check_inputs(inputs)
    names_in = tuple(item.name for item in items)
    n = len(items)
    x = np.array([item.value for item in items], dtype=np.float64)
    u = np.array([item.u for item in items], dtype=np.float64)
    nu = np.array([item.dof for item in items], dtype=np.float64)
    corr = correlation_matrix(correlation, n, names=names_in)
    pf = _number(p, "coverage probability p")
    if not 0.0 < pf < 1.0:
        raise ConfigError(f"coverage probability p = {pf!r} must be in (0, 1), e.g. 0.95.")
    k_user: float | None = None
    if k is not None:
        k_user = _number(k, "coverage factor k")
        if not (math.isfinite(k_user) and k_user > 0.0):
            raise ConfigError(f"coverage factor k = {k_user!r} must be a finite number > 0.")
    correlated = bool(np.any(corr - np.eye(n) != 0.0))
    if second_order and correlated:
        raise ConfigError(
            "second_order=True needs uncorrelated inputs (GUM §5.1.2 note); drop the correlation or "
            "use monte_carlo for a nonlinear model with correlated inputs."
        )

    call = _Model(model, names_in)
    if names_out is not None:  # for the messages of the first call, before m is known
        call.names_out = (names_out,) if isinstance(names_out, str) else tuple(map(str, names_out))
    y0 = call(x, "at the input estimates")
    m = y0.size
    call.m = m
    out_names = _labels(
        names_out, m, "names_out", ("y",) if m == 1 else tuple(f"y{j + 1}" for j in range(m))
    )
    call.names_out = out_names
    out_units = _labels(units_out, m, "units_out", ("",) * m)

    if jacobian is None:
        jac = _numeric_jacobian(call, x, u, y0, names_in)
    else:
        jac = _user_jacobian(jacobian, x, m, n)

    with np.errstate(over="ignore", invalid="ignore"):
        c_check = jac * u[None, :]
        bad = ~np.isfinite(c_check) | ~np.isfinite(c_check**2)
    if np.any(bad):  # a huge u (a unit slip) must not end in an overflow deep inside
        j_bad, i_bad = (int(v[0]) for v in np.nonzero(bad))
        raise ConfigError(
            f"input '{names_in[i_bad]}': its contribution c·u = {float(jac[j_bad, i_bad]):.3g} × "
            f"{float(u[i_bad]):.3g} to {out_names[j_bad]} is too large to combine; check the "
            "input's u and unit (or the model's sensitivity to it)."
        )
    cov_x = u[:, None] * corr * u[None, :]
    cov_y = jac @ cov_x @ jac.T
    cov_y = 0.5 * (cov_y + cov_y.T)
    var2 = np.zeros(m)
    if second_order:
        var2 = _second_order_variance(call, x, u, y0, jac, names_in)
        cov_y[np.diag_indices(m)] += var2
    variance = np.diag(cov_y).copy()
    if np.any(variance < 0.0):
        j = int(np.argmin(variance))
        if variance[j] < -1e-12 * float(np.max(np.abs(cov_y))):
            raise ConfigError(
                f"the variance of output '{out_names[j]}' came out negative ({variance[j]:.3g}); "
                "the second-order terms dominate — use monte_carlo for this model."
            )
        variance = np.maximum(variance, 0.0)
    uy = np.sqrt(variance)
    denom = np.outer(uy, uy)
    corr_y = np.divide(cov_y, denom, out=np.zeros_like(cov_y), where=denom > 0.0)
    corr_y = np.clip(corr_y, -1.0, 1.0)
    np.fill_diagonal(corr_y, 1.0)
    contributions = jac * u[None, :]

    if correlated:
        from scipy.sparse import csr_matrix
        from scipy.sparse.csgraph import connected_components

        n_blocks, blocks = connected_components(csr_matrix(corr - np.eye(n) != 0.0), directed=False)
    else:  # every input a block of its own, as connected_components labels a graph without edges
        n_blocks, blocks = n, np.arange(n)
    dof_eff = np.empty(m)
    kk = np.empty(m)
    notes_by_output: list[tuple[str, ...]] = []
    for j in range(m):
        nu_j, notes_j = _dof_eff(jac[j], cov_x, nu, blocks, int(n_blocks), names_in)
        dof_eff[j] = nu_j
        if k_user is not None:
            kk[j] = k_user
            notes_j.append(f"k = {k_user:g} was given; p = {pf:g} is nominal.")
        else:
            kk[j] = coverage_factor(nu_j, pf)
            if math.isfinite(nu_j) and nu_j < _NU_NOTE_MAX:  # beyond, t_p(ν) = z_p to 6 digits
                nu_t = math.floor(nu_j + 1e-9 * max(1.0, nu_j))
                if nu_t != nu_j:
                    notes_j.append(
                        f"ν_eff = {nu_j:.{len(str(nu_t)) + 2}g} truncated to {nu_t} for "
                        f"k = t_p(ν) = {kk[j]:.4g} (GUM G.4.1 note 1)."
                    )
        if second_order:
            notes_j.append(
                "u includes the second-order terms of GUM §5.1.2 note "
                f"({math.sqrt(max(var2[j], 0.0)):.3g} {out_units[j]} in quadrature); "
                "ν_eff is from the first-order terms."
            )
        notes_by_output.append(tuple(notes_j))
    if m == 1:
        flat_notes = notes_by_output[0]
    else:
        flat_notes = tuple(
            f"{out_names[j]}: {note}" for j in range(m) for note in notes_by_output[j]
        )

    return GUMResult(
        names_out=out_names,
        value=_frozen(y0),
        u=_frozen(uy),
        covariance=_frozen(cov_y),
        correlation=_frozen(corr_y),
        sensitivities=_frozen(jac),
        contributions=_frozen(contributions),
        dof_eff=_frozen(dof_eff),
        k=_frozen(kk),
        p=pf,
        U=_frozen(kk * uy),
        names_in=names_in,
        units_out=out_units,
        inputs=items,
        input_correlation=_frozen(corr),
        variance_second_order=_frozen(var2),
        notes=flat_notes,
        _notes_by_output=tuple(notes_by_output),
    )


# ------------------------------------------------------------------------ straight-line fit
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
