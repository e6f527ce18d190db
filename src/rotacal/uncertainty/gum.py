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

The correlation matrix of the inputs is checked in :mod:`rotacal.uncertainty.correlation`, k and
ν_eff come from :mod:`rotacal.uncertainty.coverage`; the straight-line calibration of GUM H.3
(:func:`~rotacal.uncertainty.linear_fit.linear_fit_uncertainty`, the shape of a gyro
scale-factor fit) is :mod:`rotacal.uncertainty.linear_fit`. Their names stay importable from here.

References
----------
JCGM 100:2008 (GUM): §5.1.2 eq. (10) and its note (second-order terms); §5.2.2 eq. (13), (16); §6; Annex G (G.3, G.4, eq. (G.2b),
Table G.2); Annex H.1–H.3. JCGM 101:2008 §5 (the GUM uncertainty framework).
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.results import Result
from rotacal.uncertainty._checked import _frozen, _number
from rotacal.uncertainty.budget import BudgetRow, UncertaintyBudget
from rotacal.uncertainty.correlation import correlation_matrix
from rotacal.uncertainty.coverage import coverage_factor, welch_satterthwaite

if TYPE_CHECKING:
    from rotacal.uncertainty.distributions import Distribution
    from rotacal.uncertainty.linear_fit import LinearFit, linear_fit_uncertainty

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

#: Relative and absolute-by-u steps of the central differences for the Jacobian.
_STEP_U = 1e-3
_STEP_X = 1e-9
#: ν_eff from which the truncation note is left out (the t-factor equals the normal one there).
_NU_NOTE_MAX = 1e6
#: Steps of the second- and third-order differences for GUM §5.1.2 note, as fractions of u(x_i).
_STEP_SECOND = 0.02
_STEP_THIRD = 0.5


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


def __getattr__(name: str) -> Any:
    # the straight-line fit of GUM H.3 lives in rotacal.uncertainty.linear_fit, which builds on
    # Input; its names stay importable from here, loaded on first use (no import cycle)
    if name in ("LinearFit", "linear_fit_uncertainty"):
        from rotacal.uncertainty import linear_fit

        return getattr(linear_fit, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
