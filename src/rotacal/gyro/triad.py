"""3-axis gyro calibration from rotations at several rates (robot-manipulator study 2023, modified six-position method).

Model of the gyro triad (output ``u`` in its own unit, reference rate ``ω`` in °/s in the DUT's
nominal axes)::

    u = K·ω + b                                   (K: 3×3 scale/misalignment, b: bias)

The test rotates the DUT at rates such as 6, 18, 30, 60, 90 °/s about each of its three axes, in
both directions (robot-manipulator study 2023, Table 2 and Fig. 5). The outputs fill U (3×N), the reference rates
augmented by a row of ones fill A (4×N, eq. (5)); the coefficient matrix C = [K | b] solves
U = C·A by least squares (eq. (4)); the calibrated output is ω̂ = K⁻¹(u − b) (eq. (7)). The
plan of reference rates and its identifiability check are in :mod:`rotacal.gyro.triad_plan`.

Anomalous measurements (robot-manipulator study 2023, processing step 2) are rejected by a robust, documented rule
(:func:`calibrate_triad`): a Huber M-estimate of each output's row of C gives residuals whose
scale σ = 1.4826·MAD is insensitive to the outliers; measurements with |r| > k·σ are rejected
and C is refitted by ordinary least squares on the rest, until the rejected set no longer
changes. By default k is the Bonferroni bound that a good Gaussian measurement of the channel is
rejected with a total probability of 5 %: k = Φ⁻¹(1 − 0.025/n), at least 3 (k ≈ 4.65 for
n = 15 000 rows, 3.9 for 600).

References
----------
Calibration Method of MEMS Gyroscopes Using a Robot Manipulator. IEEE Aerospace and Electronic
Systems Magazine, March 2023: eqs. (4), (5), (7), Table 2.
Huber P. J. (1981), Robust Statistics, Wiley, §7 (M-estimates of regression).
Rousseeuw P. J., Croux C. (1993), Alternatives to the median absolute deviation, JASA 88:1273
(MAD consistency factor 1.4826).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.columns import RATE_COLUMNS, TRIAD_OUTPUT_COLUMNS
from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.plausibility import negative_diagonal_warnings, triad_fit_warnings
from rotacal.gyro.triad_plan import (
    _AXES,
    SEED_RATES_DEG_S,
    TriadPlanCheck,
    _as_triplet,
    _check_plan,
    _design,
    triad_plan,
    triad_plan_check,
)
from rotacal.gyro.uncertainty import (
    as_specs,
    axis_budgets,
    element_key,
    linear_gum,
    uncertainty_json,
)
from rotacal.results import Result, to_jsonable
from rotacal.signal._values import check_magnitudes, check_not_constant, check_not_copies
from rotacal.signal.clipping import check_clipping
from rotacal.uncertainty.budget import UncertaintyBudget
from rotacal.uncertainty.gum import Input
from rotacal.uncertainty.quantiles import norm_isf
from rotacal.uncertainty.specs import InstrumentSpecs, spec_input, type_a_note

__all__ = [
    "RATE_COLUMNS",
    "SEED_RATES_DEG_S",
    "TRIAD_OUTPUT_COLUMNS",
    "TriadPlanCheck",
    "TriadResult",
    "apply_triad_calibration",
    "calibrate_triad",
    "calibrate_triad_columns",
    "decompose_scale_misalignment",
    "triad_plan",
    "triad_plan_check",
]

_MAD_TO_SIGMA = 1.4826
_HUBER_C = 1.345  # 95 % efficiency at the normal distribution (Huber 1981)
_EPS = float(np.finfo(np.float64).eps)
#: A plan whose equilibrated condition number exceeds this is reported as poorly conditioned.
_COND_WARN = 1e3
_MIN_ROWS = 8


# ------------------------------------------------------------------------------------ helpers
def _check_magnitudes(
    omega: np.ndarray, u: np.ndarray, rate_cols: Sequence[str], out_cols: Sequence[str]
) -> None:
    """Refuse values beyond float64's working range (before any arithmetic on them)."""
    for j, name in enumerate(rate_cols):
        check_magnitudes(name, omega[:, j], what="a reference rate")
    for j, name in enumerate(out_cols):
        check_magnitudes(name, u[:, j], what="a gyro output")


def _check_degenerate(
    omega: np.ndarray, u: np.ndarray, rate_cols: Sequence[str], out_cols: Sequence[str]
) -> None:
    """Refuse a constant output and copied columns (after the plan: its message comes first)."""
    for j, name in enumerate(out_cols):
        check_not_constant(name, u[:, j], "the output does not respond to the rotations")
    columns = {name: omega[:, j] for j, name in enumerate(rate_cols)}
    columns.update({name: u[:, j] for j, name in enumerate(out_cols)})
    check_not_copies(columns, "each column must hold its own axis's reference rate or output")


def _mad_sigma(r: np.ndarray) -> float:
    return _MAD_TO_SIGMA * float(np.median(np.abs(r - np.median(r))))


def decompose_scale_misalignment(k: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split K into scale factors and unit sensitive axes: K = diag(s)·R.

    Row i of K is the sensitivity vector of gyro i (output unit per °/s, in the reference axes);
    its length is that gyro's scale factor and its direction the gyro's sensitive axis. This is
    the K_g·R_g split of imucal (Ferraris et al. 1995).

    Parameters
    ----------
    k : array_like, (3, 3)
        Scale/misalignment matrix (output unit per °/s).

    Returns
    -------
    scale_factors : ndarray, (3,)
        Row norms of K (output unit per °/s).
    sensitive_axes : ndarray, (3, 3)
        Unit rows R (dimensionless).
    misalignment_deg : ndarray, (3,)
        Angle between each sensitive axis and the line of its nominal axis (deg), from
        arccos(|R_ii|) (so an inverted axis counts as aligned).

    References
    ----------
    Ferraris F., Grimaldi U., Parvis M. (1995), Procedure for effortless in-field calibration of
    three-axial rate gyro and accelerometers, Sensors and Materials 7(5):311–330, eq. (12).
    """
    k = np.asarray(k, dtype=float)
    s = np.linalg.norm(k, axis=1)
    r = k / s[:, None]
    mis = np.degrees(np.arccos(np.clip(np.abs(np.diag(r)), 0.0, 1.0)))
    return s, r, mis


def apply_triad_calibration(u: Any, scale_misalignment: Any, bias: Any) -> np.ndarray:
    """Calibrated rate ω̂ = K⁻¹(u − b) (robot-manipulator study 2023, eq. (7)).

    Parameters
    ----------
    u : array_like, (n, 3) or (3,)
        Raw outputs (output unit).
    scale_misalignment : array_like, (3, 3)
        K (output unit per °/s).
    bias : array_like, (3,)
        b (output unit).

    Returns
    -------
    ndarray, same shape as ``u``
        Angular rate in the DUT's nominal axes (°/s).

    References
    ----------
    Calibration Method of MEMS Gyroscopes Using a Robot Manipulator, IEEE A&E Systems Magazine,
    March 2023, eq. (7).
    """
    k = np.asarray(scale_misalignment, dtype=float)
    b = np.asarray(bias, dtype=float)
    if k.shape != (3, 3) or b.shape != (3,):
        raise ConfigError(
            f"scale_misalignment must be 3×3 and bias of length 3; got {k.shape} and {b.shape}."
        )
    if not np.isfinite(k).all() or abs(np.linalg.det(k)) < _EPS * np.abs(k).max() ** 3:
        raise ConfigError("scale_misalignment must be finite and invertible.")
    uu = np.asarray(u, dtype=float)
    flat = np.atleast_2d(uu)
    if flat.shape[-1] != 3:
        raise CaptureError(f"u must have 3 columns (ux, uy, uz); got shape {uu.shape}.")
    out = np.linalg.solve(k, (flat - b).T).T
    return out.reshape(uu.shape)


# ------------------------------------------------------------------------------------ result
@dataclasses.dataclass(frozen=True)
class TriadResult(Result):
    """3-axis gyro calibration (JSON keys of INTERFACE.md, ``gyro triad``).

    Output quantities are in the output unit of ``u`` ("u"); rates in °/s.

    Attributes
    ----------
    scale_misalignment : ndarray (3, 3)
        K in u = K·ω + b (u per °/s); row i: output i, column j: rate about axis j.
    bias : ndarray (3,)
        b (u).
    outliers_rejected : int
        Rows with at least one output rejected as anomalous (details in ``rejected``).
    residual_rms : ndarray (3,)
        rms of ω̂ − ω per axis after calibration (°/s), over the rows kept in all outputs.
    residual_rms_before : ndarray (3,)
        rms of u/nominal_scale − ω per axis (°/s): the raw outputs taken at face value.
    fit_residual_rms : ndarray (3,)
        rms of u − (K·ω + b) per output over its kept rows (u).
    scale_misalignment_u, bias_u : ndarray
        Combined standard uncertainties of K (u per °/s) and b (u): those of the budgets in
        ``_budgets`` (one per element, keys ``scale_misalignment[i][j]`` and ``bias[i]``). Type A
        from the least squares (white, uncorrelated noise per row, the linear model: correlated
        noise such as MEMS flicker or drift during the test makes it optimistic); Type B from
        ``table.set_rate_relative`` (K only). The JSON adds ``scale_misalignment_U``, ``bias_U``
        (same shapes), ``k``, ``coverage_probability`` and ``uncertainty_budgets``.
    scale_factors, sensitive_axes, misalignment_deg
        :func:`decompose_scale_misalignment` of K (u per °/s; unit rows; deg).
    robust_sigma : ndarray (3,)
        1.4826·MAD of the residuals per output at the final fit (u).
    reject_k : float
        Rejection threshold in units of ``robust_sigma`` (inf: rejection off).
    rejected : tuple of dict
        One entry per rejected measurement: ``row``, ``column``, ``residual`` (u),
        ``threshold`` (u), ``reason``.
    rows, rows_used, points : int
        Rows given; rows kept in all three outputs; distinct reference-rate vectors.
    plan : TriadPlanCheck
        Rank and conditioning of the plan in the capture.
    output_unit : str
        Name of the output unit (for budgets and reports; "" when not given).
    """

    scale_misalignment: np.ndarray
    bias: np.ndarray
    outliers_rejected: int
    residual_rms: np.ndarray
    residual_rms_before: np.ndarray
    fit_residual_rms: np.ndarray
    scale_misalignment_u: np.ndarray
    bias_u: np.ndarray
    scale_factors: np.ndarray
    sensitive_axes: np.ndarray
    misalignment_deg: np.ndarray
    robust_sigma: np.ndarray
    reject_k: float
    rejected: tuple[dict[str, Any], ...]
    rows: int
    rows_used: int
    points: int
    nominal_scale: float
    plan: TriadPlanCheck
    notes: tuple[str, ...] = ()
    output_unit: str = ""
    _plot: dict[str, Any] = dataclasses.field(default_factory=dict, repr=False, compare=False)
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(
        default_factory=dict, repr=False, compare=False
    )
    _axis_budgets: dict[str, UncertaintyBudget] = dataclasses.field(
        default_factory=dict, repr=False, compare=False
    )

    @property
    def axis_budgets(self) -> dict[str, UncertaintyBudget]:
        """Budgets of ``scale_factors[i]`` and ``misalignment_deg[i]`` (:func:`axis_budgets`)."""
        return dict(self._axis_budgets)

    def calibrate(self, u: Any) -> np.ndarray:
        """ω̂ = K⁻¹(u − b) (°/s) for raw outputs ``u`` (n, 3) — the robot-manipulator study (2023), eq. (7)."""
        return apply_triad_calibration(u, self.scale_misalignment, self.bias)

    def to_dict(self) -> dict[str, Any]:
        """The JSON of INTERFACE.md plus the uncertainty keys (arrays shaped like K and b)."""
        out = super().to_dict()
        if self._budgets:
            keys = uncertainty_json(self._budgets, {"scale_misalignment": (3, 3), "bias": (3,)})
            out.update(to_jsonable(keys))
        if self._axis_budgets:  # new keys only: the budgets of K and b above stay as they were
            axes = uncertainty_json(
                self._axis_budgets, {"scale_factors": (3,), "misalignment_deg": (3,)}
            )
            for name in ("scale_factors", "misalignment_deg"):
                out[f"{name}_u"] = axes[f"{name}_u"]
                out[f"{name}_U"] = axes[f"{name}_U"]
                out["k"][name] = axes["k"][name]
        return out


# ------------------------------------------------------------------------------------ fitting
def _huber_fit(x: np.ndarray, y: np.ndarray, floor: float) -> np.ndarray:
    """Huber M-estimate of y ≈ x·β by IRLS, scale re-estimated by the MAD at each step."""
    beta = np.linalg.lstsq(x, y, rcond=None)[0]
    for _ in range(100):
        r = y - x @ beta
        s = max(_mad_sigma(r), floor)
        w = np.minimum(1.0, _HUBER_C * s / np.maximum(np.abs(r), _HUBER_C * s * 1e-12))
        sw = np.sqrt(w)
        new = np.linalg.lstsq(x * sw[:, None], y * sw, rcond=None)[0]
        step = np.abs(new - beta)
        beta = new
        if np.all(step <= 1e-12 * (np.abs(beta) + s)):
            break
    return np.asarray(beta)


def _robust_channel(
    x: np.ndarray, y: np.ndarray, k: float, floor: float
) -> tuple[np.ndarray, np.ndarray, float]:
    """(β, keep mask, σ) of one output: Huber start, then reject |r| > k·σ and refit, to a fixed point."""
    if not math.isfinite(k):
        beta = np.linalg.lstsq(x, y, rcond=None)[0]
        return beta, np.ones(y.size, bool), max(_mad_sigma(y - x @ beta), floor)
    beta = _huber_fit(x, y, floor)
    r = y - x @ beta
    s = max(_mad_sigma(r), floor)
    keep = np.abs(r) <= k * s
    for _ in range(30):
        if np.count_nonzero(keep) < x.shape[1]:
            break
        beta = np.linalg.lstsq(x[keep], y[keep], rcond=None)[0]
        r = y - x @ beta
        s = max(_mad_sigma(r), floor)
        new = np.abs(r) <= k * s
        if np.array_equal(new, keep):
            break
        keep = new
    return np.asarray(beta), keep, s


def _quantum(y: np.ndarray) -> float:
    """The output's step when its values lie on a grid (an ADC or digital output), else 0."""
    vals = np.unique(y)
    if vals.size < 3 or vals.size > y.size // 2:
        return 0.0
    d = np.diff(vals)
    q = float(d.min())
    if q <= 0:
        return 0.0
    ratio = d / q
    return q if float(np.max(np.abs(ratio - np.round(ratio)))) < 1e-6 else 0.0


def _default_k(n: int) -> float:
    """Bonferroni threshold: P(any of n good Gaussian measurements rejected) = 5 %; at least 3."""
    return max(3.0, norm_isf(0.025 / max(n, 1)))


def _groups(omega: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distinct reference vectors and each row's group index."""
    pts, inv = np.unique(omega, axis=0, return_inverse=True)
    return pts, inv.ravel()


def calibrate_triad(
    omega_deg_s: Any,
    u: Any,
    *,
    reject_k: float | None = None,
    nominal_scale: float = 1.0,
    output_limits: tuple[float, float] | None = None,
    max_reject_fraction: float = 0.2,
    columns: Sequence[str] = RATE_COLUMNS + TRIAD_OUTPUT_COLUMNS,
    specs: InstrumentSpecs | None = None,
    output_unit: str = "",
    allow_clipped: bool = False,
) -> TriadResult:
    """Scale/misalignment matrix K and bias b of a gyro triad by least squares (robot-manipulator study 2023).

    Builds U (outputs) and A (reference rates with a row of ones, eq. (5)), rejects anomalous
    measurements by the robust rule of this module's docstring (per output: Huber M-estimate,
    σ = 1.4826·MAD of its residuals, reject |r| > k·σ, refit by least squares until the rejected
    set is stable), solves U = [K | b]·A by least squares (eq. (4)) and applies ω̂ = K⁻¹(u − b)
    (eq. (7)) to give the residuals after calibration.

    Parameters
    ----------
    omega_deg_s : array_like, (n, 3)
        Reference rate of each row in the DUT's nominal axes (°/s): columns ``wx_deg_s``,
        ``wy_deg_s``, ``wz_deg_s``. Rows may be single samples or per-point means.
    u : array_like, (n, 3)
        Raw outputs ``ux``, ``uy``, ``uz`` (output unit, e.g. °/s, V or counts).
    reject_k : float or None
        Rejection threshold in robust standard deviations; None: Φ⁻¹(1 − 0.025/n), at least 3
        (5 % family-wise chance of rejecting a good Gaussian measurement); ``math.inf``: no
        rejection (plain least squares).
    nominal_scale : float
        Nominal output per °/s (output unit per °/s), only to state the residuals before
        calibration, u/nominal_scale − ω (°/s).
    output_limits : (float, float) or None
        The output's range (output unit); a row at or beyond either limit is a saturated output
        and an error. Besides, an output at its rails is detected from the data
        (:mod:`rotacal.signal.clipping`: the rate points as groups, the rows at rest as rest).
    max_reject_fraction : float
        Largest fraction of an output's rows the rule may reject before the capture is refused
        as not following u = K·ω + b (default 0.2).
    columns : sequence of 6 str
        Names used in messages for the rate and output columns.
    specs : InstrumentSpecs or None
        The lab's instrument specifications (Type B; a TOML path or a mapping also work). Used:
        ``table.set_rate_relative`` (relative error ε of the table's rates, realised ω·(1 + ε), so
        K = K₀/(1 + ε) with K₀ fitted against the set rates; b does not depend on ε). None: Type A
        only.
    output_unit : str
        Name of the output unit, for the budgets and reports.
    allow_clipped : bool
        Fit outputs with samples at the rails anyway (``--allow-clipped``); ``warnings`` name the
        clipping. Refused by default.

    Returns
    -------
    TriadResult
        K (output unit per °/s), b (output unit), their standard uncertainties and budgets
        (``_budgets``), rejected rows, residual rms before and after (°/s).

    Raises
    ------
    CaptureError
        NaN/inf, values beyond float64's working range (|x| > 1e100, or a column all below
        1e-100), fewer than 8 rows, a plan in the capture that leaves coefficients unidentifiable,
        a constant output, a column that copies another (or its negative), a saturated output, or
        more rejected rows than ``max_reject_fraction``.
    ConfigError
        An invalid setting.

    References
    ----------
    Calibration Method of MEMS Gyroscopes Using a Robot Manipulator, IEEE A&E Systems Magazine,
    March 2023: U and A, eq. (5); least squares, eq. (4); calibrated output, eq. (7);
    rejection of anomalous measurements (processing step 2).
    Huber P. J. (1981), Robust Statistics, Wiley, §7; Rousseeuw P. J., Croux C. (1993), JASA
    88:1273 (1.4826·MAD). JCGM 100:2008 (GUM) §4.2, §4.3, §5.1.2, G.4.1 (the budgets).
    """
    spec = as_specs(specs)
    cols = tuple(columns)
    if len(cols) != 6:
        raise ConfigError(f"columns must name 3 rate and 3 output columns, got {columns!r}.")
    rate_cols, out_cols = cols[:3], cols[3:]
    omega = _as_triplet("omega_deg_s", rate_cols, omega_deg_s)
    uu = _as_triplet("u", out_cols, u)
    if omega.shape[0] != uu.shape[0]:
        raise CaptureError(
            f"the reference rates have {omega.shape[0]} rows but the outputs {uu.shape[0]}; "
            "give one reference rate per output row."
        )
    n = omega.shape[0]
    if n < _MIN_ROWS:
        raise CaptureError(
            f"the capture has only {n} rows; the 4 coefficients per output need at least "
            f"{_MIN_ROWS} rows (rotations about x, y and z at two or more rates)."
        )
    _check_magnitudes(omega, uu, rate_cols, out_cols)
    try:
        ns = float(nominal_scale)
    except (TypeError, ValueError):
        ns = math.nan
    if not math.isfinite(ns) or ns == 0:
        raise ConfigError(
            f"nominal_scale must be a finite, non-zero number, got {nominal_scale!r}."
        )
    if reject_k is None:
        k = _default_k(n)
    else:
        try:
            k = float(reject_k)
        except (TypeError, ValueError):
            k = math.nan
        if math.isnan(k) or k < 2.0:
            raise ConfigError(
                f"reject_k must be at least 2 (or inf for no rejection), got {reject_k!r}."
            )
    if not 0.0 < float(max_reject_fraction) < 1.0:
        raise ConfigError(
            f"max_reject_fraction must lie between 0 and 1, got {max_reject_fraction!r}."
        )
    if output_limits is not None:
        lo, hi = (float(v) for v in output_limits)
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ConfigError(
                f"output_limits must be (low, high) with low < high, got {output_limits!r}."
            )
        hit = (uu <= lo) | (uu >= hi)
        if hit.any():
            row, c = (int(i) for i in np.argwhere(hit)[0])
            raise CaptureError(
                f"column {out_cols[c]} reaches its limit ({uu[row, c]:.6g}, range {lo:g}…{hi:g}) "
                f"in {int(hit[:, c].sum())} rows, first at row {row}: the output is saturated; "
                "lower the test rates or drop those rows."
            )

    plan = _check_plan(omega)
    if not plan.identifiable:
        raise CaptureError(
            f"the reference rates in {', '.join(rate_cols)} leave {', '.join(plan.unidentifiable)} "
            f"unidentifiable (rank {plan.rank} of 4): {plan.advice}."
        )
    _check_degenerate(omega, uu, rate_cols, out_cols)
    pts, inv = _groups(omega)
    clipped = check_clipping(
        {name: uu[:, c] for c, name in enumerate(out_cols)},
        allow_clipped=allow_clipped,
        groups=inv,
        rest=~np.any(omega != 0, axis=1),
    )

    x = _design(omega)
    coef = np.zeros((4, 3))
    keep = np.zeros((n, 3), bool)
    sigma = np.zeros(3)
    cov = np.zeros((3, 4, 4))
    for c in range(3):
        y = uu[:, c]
        # σ is at least the rounding noise of a quantised output (q/√12): residuals of a few
        # codes are not outliers, even when the analog noise is much smaller than a code.
        floor = max(
            64.0 * _EPS * max(float(np.max(np.abs(y))), 1e-300), _quantum(y) / math.sqrt(12)
        )
        beta, kc, s = _robust_channel(x, y, k, floor)
        frac = 1.0 - np.count_nonzero(kc) / n
        if frac > max_reject_fraction:
            raise CaptureError(
                f"the robust rule rejects {100 * frac:.0f} % of the rows of column {out_cols[c]}: "
                "that output does not follow u = K·ω + b (wrong or swapped columns, a saturated "
                "or nonlinear gyro?); check the capture."
            )
        xk = x[kc]
        sub = _check_plan(omega[kc])
        if not sub.identifiable:
            raise CaptureError(
                f"after rejecting anomalous rows of column {out_cols[c]}, "
                f"{', '.join(sub.unidentifiable)} are no longer identifiable; check the rows "
                "of that rate point."
            )
        beta = np.linalg.lstsq(xk, y[kc], rcond=None)[0]
        rk = y[kc] - xk @ beta
        dof = xk.shape[0] - 4
        s2 = float(rk @ rk) / dof if dof > 0 else math.nan
        cov[c] = s2 * np.linalg.inv(xk.T @ xk)
        coef[:, c] = beta
        keep[:, c] = kc
        sigma[c] = s
    k_fit = coef[:3].T.copy()
    bias = coef[3].copy()
    eps_in = spec_input(spec, "table.set_rate_relative", name="table set-rate error ε")
    eps = 0.0 if eps_in is None else eps_in.value
    kmat = k_fit / (1.0 + eps)
    budgets = _triad_budgets(
        k_fit, bias, cov, np.count_nonzero(keep, axis=0), eps_in, spec, out_cols, output_unit
    )
    u_k = np.array(
        [[budgets[element_key("scale_misalignment", (i, j))].u for j in range(3)] for i in range(3)]
    )
    u_b = np.array([budgets[element_key("bias", (i,))].u for i in range(3)])
    unit_k = f"{output_unit or 'output units'}/(°/s)"
    rows_kept = np.count_nonzero(keep, axis=0)
    axis_u = axis_budgets(
        k_fit, [c[:3, :3] for c in cov], [float(n - 4) for n in rows_kept], eps_in, unit_k, out_cols
    )

    fitted = x @ coef
    fit_res = uu - fitted
    all_kept = keep.all(axis=1)
    fit_rms = np.array([math.sqrt(float(np.mean(fit_res[keep[:, c], c] ** 2))) for c in range(3)])
    omega_hat = apply_triad_calibration(uu, kmat, bias)
    omega_true = omega * (1.0 + eps)  # the rates the table realised (ε̄ stated, else 0)
    after = omega_hat - omega_true
    before = uu / ns - omega_true
    rms_after = np.sqrt(np.mean(after[all_kept] ** 2, axis=0))
    rms_before = np.sqrt(np.mean(before[all_kept] ** 2, axis=0))

    rej_r, rej_c = np.nonzero(~keep)
    order = np.lexsort((rej_c, rej_r))
    rejected = tuple(
        {
            "row": int(rej_r[i]),
            "column": out_cols[int(rej_c[i])],
            "residual": float(fit_res[rej_r[i], rej_c[i]]),
            "threshold": float(k * sigma[rej_c[i]]),
            "reason": f"|residual| > {k:.3g}·σ_robust",
        }
        for i in order
    )
    scale, axes_r, mis = decompose_scale_misalignment(kmat)
    notes = []
    if plan.condition_number_scaled > _COND_WARN:
        notes.append(
            f"the plan is poorly conditioned (scaled condition number "
            f"{plan.condition_number_scaled:.3g}): the coefficients are imprecise"
        )
    if eps != 0.0:
        notes.append(
            f"the stated mean set-rate error ε̄ = {eps:.3g} (table.set_rate_relative) corrects K: "
            "K = K₀/(1 + ε̄), K₀ fitted against the set rates"
        )
    if math.isfinite(k) and (~keep).any():
        notes.append(
            f"{int((~keep).sum())} measurements in {int((~all_kept).sum())} rows rejected "
            f"(|r| > {k:.3g}·1.4826·MAD)"
        )

    # per-point means for the figures
    counts = np.bincount(inv[all_kept], minlength=pts.shape[0]).astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        pm_before = (
            np.stack(
                [np.bincount(inv[all_kept], before[all_kept, j], pts.shape[0]) for j in range(3)], 1
            )
            / counts[:, None]
        )
        pm_after = (
            np.stack(
                [np.bincount(inv[all_kept], after[all_kept, j], pts.shape[0]) for j in range(3)], 1
            )
            / counts[:, None]
        )
        sq = (
            np.stack(
                [
                    np.bincount(inv[all_kept], after[all_kept, j] ** 2, pts.shape[0])
                    for j in range(3)
                ],
                1,
            )
            / counts[:, None]
        )
    ps_after = np.sqrt(np.maximum(sq - pm_after**2, 0.0))
    plot = {
        "points_deg_s": pts,
        "point_rows": counts,
        "point_before_deg_s": pm_before,
        "point_after_deg_s": pm_after,
        "point_after_std_deg_s": ps_after,
        "fit_residual": fit_res,
        "keep": keep,
        "columns": cols,
    }
    return TriadResult(
        scale_misalignment=kmat,
        bias=bias,
        outliers_rejected=int((~all_kept).sum()),
        residual_rms=rms_after,
        residual_rms_before=rms_before,
        fit_residual_rms=fit_rms,
        scale_misalignment_u=u_k,
        bias_u=u_b,
        scale_factors=scale,
        sensitive_axes=axes_r,
        misalignment_deg=mis,
        robust_sigma=sigma,
        reject_k=k,
        rejected=rejected,
        rows=n,
        rows_used=int(all_kept.sum()),
        points=int(pts.shape[0]),
        nominal_scale=ns,
        plan=plan,
        notes=tuple(notes),
        output_unit=output_unit,
        _plot=plot,
        _budgets=budgets,
        _axis_budgets=axis_u,
        warnings=(
            *clipped,
            *negative_diagonal_warnings(
                kmat, out_cols, "the reference rates wx/wy/wz_deg_s have the other sign"
            ),
            *triad_fit_warnings(
                fit_res, inv, keep, out_cols, [_quantum(uu[:, c]) for c in range(3)]
            ),
        ),
    )


def _triad_budgets(
    k_fit: np.ndarray,
    bias: np.ndarray,
    cov: np.ndarray,
    rows_kept: np.ndarray,
    eps_in: Input | None,
    spec: InstrumentSpecs | None,
    out_cols: Sequence[str],
    output_unit: str,
) -> dict[str, UncertaintyBudget]:
    """One GUM budget per element of K (9) and b (3).

    K_ij = K₀_ij/(1 + ε): inputs K₀_ij (Type A, the least-squares covariance s²(XᵀX)⁻¹ of output
    i, ν = rows kept − 4) with c = 1/(1 + ε), and ε (Type B, ``table.set_rate_relative``) with
    c = −K₀_ij/(1 + ε)². b_i: the fitted b_i alone (a relative rate error does not move it).

    References
    ----------
    Seed 003, eqs. (4)–(5); JCGM 100:2008 (GUM) §4.2 (Type A), §4.3 (Type B), §5.1.2 eq. (10),
    G.4.1 (ν_eff), H.3 (least-squares parameters).
    """
    ou = output_unit or "output unit"
    unit_k = f"{ou}/(°/s)"
    eps = 0.0 if eps_in is None else eps_in.value
    general = (
        "Type A assumes white, uncorrelated noise per row and the linear model u = K·ω + b; "
        "correlated noise (MEMS flicker, drift during the test) makes it optimistic."
    )
    extra = [general]
    if (note := type_a_note(spec, ("table.set_rate_relative",))) is not None:
        extra.append(note)
    # a stated mean ε̄ corrects K = K₀/(1 + ε̄) (GUM §3.2.4); the constant term b does not change
    fixed = [] if spec is None else [spec.correction_note("table.set_rate_relative")]
    k_extra = extra + [n for n in fixed if n is not None]
    budgets: dict[str, UncertaintyBudget] = {}
    for i in range(3):
        dof = float(rows_kept[i] - 4)
        origin = f"Type A: least squares of column {out_cols[i]}, {int(rows_kept[i])} rows"
        for j in range(3):
            name = f"K_{_AXES[i]}{_AXES[j]}"
            k0 = Input(
                f"{name},0: fitted against the set rates",
                float(k_fit[i, j]),
                math.sqrt(max(float(cov[i][j, j]), 0.0)),
                dof,
                "normal",
                unit_k,
                origin,
            )
            inputs, sens = [k0], [1.0 / (1.0 + eps)]
            if eps_in is not None:
                inputs.append(eps_in)
                sens.append(-float(k_fit[i, j]) / (1.0 + eps) ** 2)
            b = linear_gum(name, unit_k, float(k_fit[i, j]) / (1.0 + eps), inputs, sens).budget(0)
            budgets[element_key("scale_misalignment", (i, j))] = dataclasses.replace(
                b, notes=b.notes + tuple(k_extra)
            )
    for i in range(3):
        name = f"b_{_AXES[i]}"
        b0 = Input(
            f"{name}: fitted",
            float(bias[i]),
            math.sqrt(max(float(cov[i][3, 3]), 0.0)),
            float(rows_kept[i] - 4),
            "normal",
            ou,
            f"Type A: least squares of column {out_cols[i]}, {int(rows_kept[i])} rows",
        )
        b = linear_gum(name, ou, float(bias[i]), [b0], [1.0]).budget(0)
        notes = list(b.notes) + extra
        if eps_in is not None:
            notes.append(
                "table.set_rate_relative does not enter: a relative rate error leaves the "
                "constant term of the fit unchanged."
            )
        budgets[element_key("bias", (i,))] = dataclasses.replace(b, notes=tuple(notes))
    return budgets


def calibrate_triad_columns(columns: Mapping[str, Any] | Any, **options: Any) -> TriadResult:
    """:func:`calibrate_triad` on a capture's canonical columns.

    Parameters
    ----------
    columns : mapping or rotacal.io.Capture
        Holds ``wx_deg_s``, ``wy_deg_s``, ``wz_deg_s`` (°/s) and ``ux``, ``uy``, ``uz`` (output
        unit), equal lengths.
    **options
        Passed to :func:`calibrate_triad`.

    Returns
    -------
    TriadResult

    References
    ----------
    As :func:`calibrate_triad` (robot-manipulator study 2023, eqs. (4), (5), (7)).
    """
    names = RATE_COLUMNS + TRIAD_OUTPUT_COLUMNS
    arrays = []
    for name in names:
        try:
            col = columns[name]
        except (KeyError, IndexError):
            raise CaptureError(
                f"the capture has no column {name!r}; a 3-axis gyro test needs "
                f"{', '.join(names)} (map your own names with --column OLD=NEW)."
            ) from None
        arrays.append(np.asarray(col, dtype=float).ravel())
    lengths = {a.size for a in arrays}
    if len(lengths) != 1:
        raise CaptureError(
            "the columns "
            + ", ".join(f"{n} ({a.size})" for n, a in zip(names, arrays, strict=True))
            + " differ in length; give one value per row in each."
        )
    return calibrate_triad(np.column_stack(arrays[:3]), np.column_stack(arrays[3:]), **options)
