"""Uncertainty budgets of the gyro calibrations on the table: the helpers they share.

The scale-factor (Kokuyama et al. 2015), 3-axis (robot-manipulator study 2023) and rotation (Ferraris) calibrations build one
:class:`~rotacal.uncertainty.UncertaintyBudget` per reported quantity from two kinds of input:

- **Type A**, from the capture: the spread of the samples at each rate point, the least-squares
  covariance of a fit, the noise of static sections (JCGM 100:2008 §4.2);
- **Type B**, from the lab's instrument specifications (:class:`~rotacal.uncertainty.InstrumentSpecs`,
  JCGM 100:2008 §4.3): ``table.set_rate_relative``, ``table.set_angle_arcsec``,
  ``timebase.relative_error``, ``table.orientation_error_arcsec``, ``site.latitude_deg``, read
  through :func:`rotacal.uncertainty.specs.spec_input` (its notes: ``type_a_note``,
  ``corrected_note``); a stated non-zero mean is corrected for (GUM §3.2.4).

Models that are linear in their inputs use the GUM law of propagation (:func:`linear_gum`); the
nonlinearity, a maximum of absolute residuals, uses Monte Carlo (:func:`monte_carlo_budget`). Array
quantities (K, b) get one budget per element; :func:`uncertainty_json` turns the budgets into the
JSON keys ``<name>_u``/``<name>_U`` (arrays for array quantities), ``k``, ``coverage_probability``
and ``uncertainty_budgets``.

References
----------
JCGM 100:2008 (GUM) §4.2, §4.3, §5.1.2, §6, G.4; JCGM 101:2008 §7.7.1 (probabilistically symmetric
coverage interval), §8 (validation of the GUM framework by Monte Carlo).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from rotacal.errors import ConfigError
from rotacal.uncertainty.budget import BudgetRow, UncertaintyBudget, uncertainty_keys
from rotacal.uncertainty.distributions import Distribution
from rotacal.uncertainty.gum import GUMResult, Input, coverage_factor, propagate
from rotacal.uncertainty.montecarlo import MonteCarloResult, validate_gum
from rotacal.uncertainty.quantiles import norm_isf, norm_pdf
from rotacal.uncertainty.specs import InstrumentSpecs, load_specs

__all__ = [
    "COVERAGE_PROBABILITY",
    "TScale",
    "as_specs",
    "axis_budgets",
    "element_key",
    "linear_gum",
    "monte_carlo_budget",
    "uncertainty_json",
    "validated",
]

#: Coverage probability of every expanded uncertainty of the gyro calibrations.
COVERAGE_PROBABILITY = 0.95


def as_specs(specs: Any) -> InstrumentSpecs | None:
    """``specs`` as :class:`InstrumentSpecs`: None, an InstrumentSpecs, or what
    :func:`~rotacal.uncertainty.load_specs` reads (a TOML path or text, a parsed mapping).

    Raises
    ------
    ConfigError
        Anything else, or a specification the engine refuses (unknown name or distribution,
        negative u, …), in one line.
    """
    if specs is None or isinstance(specs, InstrumentSpecs):
        return specs
    if isinstance(specs, (str, Path)) and "\n" not in str(specs) and not Path(specs).is_file():
        raise ConfigError(f"the specifications file {str(specs)!r} does not exist; give its path.")
    if isinstance(specs, (Mapping, str, Path)):
        return load_specs(specs)
    raise ConfigError(
        "specs must be rotacal.uncertainty.InstrumentSpecs (from load_specs('lab.toml')), a TOML "
        f"path or a mapping of specifications; got {type(specs).__name__}."
    )


def linear_gum(
    quantity: str,
    unit: str,
    value: float,
    inputs: Sequence[Input],
    sensitivities: Sequence[float],
) -> GUMResult:
    """The GUM result of ``y = value + Σ c_i·(x_i − x̂_i)`` for independent inputs.

    The model is the first-order (here exact) expansion of a calibration's measurement model
    about the input estimates; the sensitivities c_i are derived analytically by the caller.

    Parameters
    ----------
    quantity, unit : str
        Name and unit of the measurand.
    value : float
        Its estimate (unit ``unit``).
    inputs : sequence of Input
        Independent input quantities.
    sensitivities : sequence of float
        c_i = ∂y/∂x_i (``unit`` per unit of x_i).

    Returns
    -------
    GUMResult
        u_c, ν_eff by Welch–Satterthwaite, k = t_95(ν_eff), U.

    References
    ----------
    JCGM 100:2008 (GUM) §5.1.2 eq. (10), G.4.1 eq. (G.2b), §6.
    """
    c = np.asarray(sensitivities, dtype=float)
    x0 = np.array([i.value for i in inputs], dtype=float)

    def model(*x: float) -> float:
        return float(value + c @ (np.asarray(x, dtype=float) - x0))

    return propagate(
        model,
        list(inputs),
        jacobian=lambda *x: c,
        p=COVERAGE_PROBABILITY,
        names_out=[quantity],
        units_out=[unit],
    )


def validated(gum: GUMResult, mc: MonteCarloResult, notes: Sequence[str] = ()) -> UncertaintyBudget:
    """The budget of a one-output GUM result, checked against a Monte Carlo run (JCGM 101 §8).

    The ends of the GUM interval y ± U are compared with the Monte Carlo probabilistically
    symmetric interval. They agree when both differences are within max(δ, 3·s_q): δ the numerical
    tolerance of u at two significant digits (JCGM 101 §8.1), s_q the sampling standard deviation
    of a 2.5 % quantile of M trials, u·√(0.025·0.975/M)/φ(1.96) (a normal density assumed), so that
    the Monte Carlo's own noise does not decide when M is below the δ/5 run of JCGM 101 §8.2.
    When they agree, ``method`` is ``"GUM, validated by Monte Carlo"``. Otherwise (JCGM 101 §8.3:
    use the Monte Carlo result) U becomes the half-width of the Monte Carlo interval and k = U/u,
    u staying the GUM one (the rows add up to it), ``method`` is ``"Monte Carlo"``, the GUM's
    truncation note (its k = t_p(ν)) is dropped and a note states both intervals and the k used —
    typical when one rectangular input dominates (JCGM 101 §9.2.4).

    References
    ----------
    JCGM 101:2008, §8.1–8.3 (validation of the GUM framework), §7.7.1 (probabilistically
    symmetric interval), §9.2.4 (a dominant rectangular input).
    """
    b = gum.budget(0)
    out = list(b.notes) + list(notes)
    check = validate_gum(gum, mc, shortest=False)
    lo, hi = check["mc_interval"]
    unit = f" {b.unit}" if b.unit else ""
    tail = 0.5 * (1.0 - float(mc.p))
    z = norm_isf(tail)
    s_q = float(mc.u) * math.sqrt(tail * (1.0 - tail) / mc.trials) / norm_pdf(z)
    tol = max(float(check["delta"]), 3.0 * s_q)
    if check["d_low"] <= tol and check["d_high"] <= tol:
        out.append(
            f"validated by Monte Carlo (JCGM 101 §8; {mc.trials} trials): the symmetric 95 % "
            f"interval [{lo:.6g}, {hi:.6g}]{unit} matches y ± U within {tol:.2g}."
        )
        return dataclasses.replace(b, method="GUM, validated by Monte Carlo", notes=tuple(out))
    big_u = 0.5 * (hi - lo)
    k = big_u / b.u if b.u > 0 else b.k
    # the GUM's k (and its truncated ν_eff) is not the one stated: say what was done instead
    out = [n for n in out if "for k = t_p(ν)" not in n]
    out.append(
        f"the GUM interval y ± {b.U:.3g}{unit} (k = t_p(ν_eff) = {b.k:.3g}) is not validated by "
        f"Monte Carlo (JCGM 101 §8; {mc.trials} trials: its ends differ from the symmetric 95 % "
        f"interval [{lo:.6g}, {hi:.6g}]{unit} by {check['d_low']:.2g} and "
        f"{check['d_high']:.2g} > {tol:.2g}). Stated instead (JCGM 101 §8.3): U = "
        f"{big_u:.3g}{unit}, the half-width of the Monte Carlo interval, and k = U/u = {k:.3g}; "
        "u is the GUM combined standard uncertainty, which the rows add up to."
    )
    return dataclasses.replace(
        b, U=float(big_u), k=float(k), method="Monte Carlo", notes=tuple(out)
    )


def monte_carlo_budget(
    quantity: str,
    unit: str,
    value: float,
    mc: MonteCarloResult,
    rows: Sequence[BudgetRow],
    notes: Sequence[str] = (),
) -> UncertaintyBudget:
    """The budget of a quantity whose uncertainty comes from Monte Carlo (method "Monte Carlo").

    u is the standard deviation of the Monte Carlo values; U is the half-width of their
    probabilistically symmetric 95 % interval [y_low, y_high] (stated in the notes, as the interval
    need not be centred on the value) and k = U/u; ν_eff is not defined (∞).

    References
    ----------
    JCGM 101:2008, §7.6 (standard uncertainty), §7.7.1 (probabilistically symmetric interval).
    """
    lo, hi = mc.interval_symmetric
    u = float(mc.u)
    big_u = 0.5 * (hi - lo)
    k = big_u / u if u > 0 else coverage_factor(math.inf, COVERAGE_PROBABILITY)
    return UncertaintyBudget(
        quantity=quantity,
        unit=unit,
        value=float(value),
        u=u,
        dof_eff=math.inf,
        k=float(k),
        p=float(mc.p),
        U=float(big_u),
        rows=tuple(rows),
        method="Monte Carlo",
        notes=tuple(notes),
    )


@dataclasses.dataclass(frozen=True)
class TScale(Distribution):
    """The common scale w = √(ν/χ²_ν) of a multivariate t-distribution (dimensionless).

    Deviations z_i ~ N(0, s²) that share one standard deviation s estimated with ν degrees of
    freedom, multiplied by one draw of w per trial, follow the multivariate t-distribution that
    JCGM 102 assigns to the mean of repeated observations whose covariance is estimated from
    them (the points of a straight line that share the residual s of GUM H.3).

    Parameters
    ----------
    dof : float
        Degrees of freedom ν > 0.

    References
    ----------
    JCGM 102:2011, §5.3.2 (multivariate t-distribution); JCGM 101:2008, §6.4.9 (its univariate
    form).
    """

    dof: float
    kind: ClassVar[str] = "t scale"

    def __post_init__(self) -> None:
        nu = float(self.dof)
        if not nu > 0:
            raise ConfigError(f"TScale: dof must be > 0, got {self.dof!r}.")
        object.__setattr__(self, "dof", nu)

    @property
    def mean(self) -> float:
        nu = self.dof
        if math.isinf(nu):
            return 1.0
        if nu <= 1.0:
            return math.inf
        return math.sqrt(nu / 2.0) * math.exp(math.lgamma((nu - 1) / 2) - math.lgamma(nu / 2))

    @property
    def std(self) -> float:
        nu = self.dof
        if math.isinf(nu):
            return 0.0
        if nu <= 2.0:
            return math.inf
        return math.sqrt(max(nu / (nu - 2.0) - self.mean**2, 0.0))

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        if math.isinf(self.dof):
            return np.ones(size)
        return np.sqrt(self.dof / rng.chisquare(self.dof, size))

    def describe(self) -> str:
        return f"√(ν/χ²_ν), ν = {self.dof:g}"


def _axis_gradients(row: np.ndarray, i: int) -> tuple[float, np.ndarray, float, np.ndarray]:
    """|k| and the misalignment θ (rad) of the sensitivity row ``row`` of gyro ``i``, with their
    gradients with respect to the row's elements.

    θ = atan2(r, |k_i|) with r = √(Σ_{j≠i} k_j²): the same angle as arccos(|k_i|/|k|), written so
    that its derivative stays finite at small angles.
    """
    norm = float(np.linalg.norm(row))
    a = abs(float(row[i]))
    off = row.copy()
    off[i] = 0.0
    r = float(np.linalg.norm(off))
    grad_norm = row / norm
    grad_theta = np.zeros(3)
    if r > 0.0:
        grad_theta = a * off / (r * norm**2)
    grad_theta[i] = -r * math.copysign(1.0, float(row[i])) / norm**2
    return norm, grad_norm, math.atan2(r, a), grad_theta


def axis_budgets(
    k_fit: np.ndarray,
    row_covariances: Sequence[np.ndarray],
    dofs: Sequence[float],
    eps_in: Input | None,
    unit_k: str,
    out_names: Sequence[str],
) -> dict[str, UncertaintyBudget]:
    """GUM budgets of each gyro's scale factor |K_i| and misalignment angle from a fitted K.

    Row i of K is gyro i's sensitivity vector; its length is the scale factor and its angle to
    the nominal axis i the misalignment (Ferraris et al. 1995, eq. 12;
    :func:`rotacal.gyro.triad.decompose_scale_misalignment`). With K = K₀/(1 + ε):
    |K_i| = |K₀_i|/(1 + ε) and the angle does not depend on ε.

    Parameters
    ----------
    k_fit : ndarray (3, 3)
        K₀ fitted against the set rates (``unit_k``).
    row_covariances : sequence of ndarray (3, 3)
        Covariance of row i of K₀ from the least squares (``unit_k``²).
    dofs : sequence of float
        Degrees of freedom of each row's covariance (rows kept − 4).
    eps_in : Input or None
        The table's relative set-rate error ε (Type B), when stated.
    unit_k : str
        Unit of K (output unit per °/s).
    out_names : sequence of str
        The output columns, for the budgets' wording.

    Returns
    -------
    dict
        ``scale_factors[i]`` (``unit_k``) and ``misalignment_deg[i]`` (°) by
        :func:`element_key`. The row's correlated elements enter as one Type A input each:
        u² = gᵀ·C·g, g the gradient of |k| or θ with respect to the row (GUM §5.2.2 eq. (13)).
        Near θ = 0 the angle is bounded at zero and its first-order u does not describe the
        bias; the budget's notes say so when θ < 2u.

    References
    ----------
    JCGM 100:2008 (GUM) §5.1.2 eq. (10), §5.2.2 eq. (13) (correlated inputs), G.4.1 (ν_eff);
    Ferraris F., Grimaldi U., Parvis M. (1995), Sensors and Materials 7(5):311–330, eq. (12).
    """
    eps = 0.0 if eps_in is None else eps_in.value
    budgets: dict[str, UncertaintyBudget] = {}
    for i in range(3):
        norm0, g_norm, theta, g_theta = _axis_gradients(np.asarray(k_fit[i], dtype=float), i)
        cov = np.asarray(row_covariances[i], dtype=float)
        origin = f"Type A: least squares of column {out_names[i]} (covariance of the row)"
        u_norm = math.sqrt(max(float(g_norm @ cov @ g_norm), 0.0))
        u_theta = math.degrees(math.sqrt(max(float(g_theta @ cov @ g_theta), 0.0)))
        n_in = Input(
            f"|K₀_{i}| of row {out_names[i]}", norm0, u_norm, dofs[i], "normal", unit_k, origin
        )
        inputs, sens = [n_in], [1.0 / (1.0 + eps)]
        if eps_in is not None:
            inputs.append(eps_in)
            sens.append(-norm0 / (1.0 + eps) ** 2)
        name = f"scale factor |K| of {out_names[i]}"
        budgets[element_key("scale_factors", (i,))] = linear_gum(
            name, unit_k, norm0 / (1.0 + eps), inputs, sens
        ).budget(0)
        angle = math.degrees(theta)
        t_in = Input(f"θ of row {out_names[i]}", angle, u_theta, dofs[i], "normal", "°", origin)
        b = linear_gum(f"misalignment of {out_names[i]}", "°", angle, [t_in], [1.0]).budget(0)
        notes = ["A relative set-rate error scales the whole row and leaves the angle unchanged."]
        if angle < 2.0 * u_theta:
            notes.append(
                "The angle is within 2u of zero: an angle cannot be negative, so the value is "
                "biased upward and ± U is only a first-order statement."
            )
        budgets[element_key("misalignment_deg", (i,))] = dataclasses.replace(
            b, notes=b.notes + tuple(notes)
        )
    return budgets


def element_key(name: str, index: tuple[int, ...]) -> str:
    """The budget key of one element of an array quantity: ``"bias[1]"``, ``"K[0][2]"``."""
    return name + "".join(f"[{i}]" for i in index)


def uncertainty_json(
    budgets: Mapping[str, UncertaintyBudget], arrays: Mapping[str, tuple[int, ...]] | None = None
) -> dict[str, Any]:
    """The JSON uncertainty keys of a result, with arrays for array quantities.

    Scalar quantities get ``<name>_u`` and ``<name>_U`` as
    :func:`~rotacal.uncertainty.uncertainty_keys` gives them. An array quantity ``name`` of shape
    ``arrays[name]`` has one budget per element under :func:`element_key` and gets ``<name>_u``,
    ``<name>_U`` arrays of that shape and ``k[name]`` the array of its coverage factors.
    ``coverage_probability`` and ``uncertainty_budgets`` (every budget, by key) follow.

    References
    ----------
    JCGM 100:2008 (GUM), §7.2.2 (u_c), §7.2.4 (U, k and p).
    """
    out = uncertainty_keys(budgets)
    for name, shape in (arrays or {}).items():
        idx = list(np.ndindex(*shape))
        keys = [element_key(name, i) for i in idx]
        for key in keys:
            out.pop(f"{key}_u", None)
            out.pop(f"{key}_U", None)
            out["k"].pop(key, None)
        out[f"{name}_u"] = np.reshape([budgets[key].u for key in keys], shape).tolist()
        out[f"{name}_U"] = np.reshape([budgets[key].U for key in keys], shape).tolist()
        out["k"][name] = np.reshape([budgets[key].k for key in keys], shape).tolist()
    return out
