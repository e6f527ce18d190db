"""Single-axis gyro scale factor and nonlinearity from a rate-table test (Kokuyama et al. 2015, §4).

The table holds a set rate Ω while the DUT's output is recorded, for several rates. Rows with the
same set rate form one *rate point*; its samples are averaged (keeping n, standard deviation and
standard error). A straight line is fitted to the point means by least squares,

    V(Ω) = S·Ω + V0 + δ(Ω),

S is the scale factor (output unit per °/s), V0 the bias (output unit), δ the residuals, and the
nonlinearity is ``NL = 100·max|δ| / (|S|·FS)`` in %FS (Kokuyama et al. 2015: NL = max|δ|/FS with δ and FS in
the same unit; rotacal converts δ to °/s by S). Seed 004 recommends at least 11 points.

Choices (documented in :func:`calibrate_scale_factor`):

- **Same set rate.** Rates within ``rate_tolerance_deg_s`` (default 0.001 °/s) of their sorted
  neighbour are one point (single linkage): a commanded rate is written identically on every row,
  and no test resolves points closer than a millidegree per second.
- **Unweighted fit.** Every point has equal weight, as in Kokuyama et al. (2015) and IEEE Std 952-1997 /
  IEEE Std 1431-2004 (least-squares straight line through the averaged points). The residuals of a
  real gyro are dominated by its systematic nonlinearity, not by noise: weighting by the points'
  standard errors would let the quietest points define the line and make NL depend on how long
  each point was recorded. On the xinli_turntable recording the unweighted fit reproduces the
  published S = 1.000199, NL = 0.082 %FS; a 1/SE² fit gives 1.000489 and 0.122 %FS.
- **Uncertainties** (one budget per quantity, :mod:`rotacal.gyro.uncertainty`). The measurand S
  is the slope of the least-squares line through the DUT's mean output at the set rates (Kokuyama et al. 2015:
  δ(Ω) is part of the model, reported as NL, not an error of S). Type A: the standard error of
  each point mean (the spread of its samples) propagated through the line, u²(S₀) = Σ c_i²·u_i²
  with c_i = (Ω_i − Ω̄)/Σ(Ω_k − Ω̄)², ν by Welch–Satterthwaite; points of one sample take the
  pooled standard deviation of the others, and when no point has two samples the scatter of the
  points about the line stands for the noise, s²·(AᵀA)⁻¹ with s² = Σδ²/(N − 2), ν = N − 2
  (GUM, JCGM 100:2008, H.3). Type B: ``table.set_rate_relative`` ε, the table's realised rate
  being Ω·(1 + ε), so S = S₀/(1 + ε) (V0 does not depend on ε). S and V0 are validated by Monte
  Carlo. NL, a maximum of |δ|, is biased upward by noise and bounded below by 0: its JSON value
  and budget value are the plain NL, u the standard deviation of NL re-measured (Monte Carlo,
  JCGM 101), the bias from the point means' noise and the bias-corrected NL stand beside
  it, and the budget states a 95 % interval for the TRUE NL (it reaches 0 when the residuals are
  consistent with noise), U being half its width. A lack-of-fit test tells when the points
  scatter about the line more than their noise explains (nonlinearity, or drift between the
  points).

References
----------
Kokuyama W., Watanabe T., Nozato H., Ota A., "Development of angular velocity calibration facility
using self-calibratable rotary encoder", §4 and Table 1.
IEEE Std 952-1997, Annex C (scale factor and nonlinearity from a least-squares line).
NHTSA, FMVSS 126 Laboratory Test Procedure for Electronic Stability Control Systems (2008).
JCGM 100:2008 (GUM) §4.2, §5.1.2, G.4, H.3; JCGM 101:2008 §7, §8; JCGM 102:2011 §9; Efron &
Tibshirani, An Introduction to the Bootstrap (1993) §6, §10; ILAC-G8:09/2019 §4.2 (decision rules
with a guard band).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np
from scipy import stats

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.plausibility import scale_factor_warnings
from rotacal.gyro.resolution import OutputResolution, output_resolution
from rotacal.gyro.uncertainty import (
    TScale,
    as_specs,
    linear_gum,
    monte_carlo_budget,
    uncertainty_json,
    validated,
)
from rotacal.results import Result, to_jsonable
from rotacal.signal._values import check_magnitudes, check_not_copies, check_setting
from rotacal.signal.clipping import check_clipping
from rotacal.uncertainty.budget import BudgetRow, UncertaintyBudget
from rotacal.uncertainty.distributions import Distribution, Normal
from rotacal.uncertainty.gum import Input, linear_fit_uncertainty, welch_satterthwaite
from rotacal.uncertainty.montecarlo import MonteCarloResult, monte_carlo
from rotacal.uncertainty.specs import (
    InstrumentSpecs,
    spec_distribution,
    spec_input,
    type_a_note,
)

__all__ = [
    "DEFAULT_MC_TRIALS",
    "DEFAULT_RATE_TOLERANCE_DEG_S",
    "MIN_POINTS_RECOMMENDED",
    "REQUIREMENTS",
    "DecisionWithU",
    "RatePoint",
    "RequirementCheck",
    "RequirementVerdict",
    "ScaleFactorResult",
    "calibrate_scale_factor",
    "evaluate_requirement",
    "output_quantum",
    "resolve_requirement",
]

#: Set rates closer than this (°/s) to their sorted neighbour are one rate point.
DEFAULT_RATE_TOLERANCE_DEG_S = 1e-3
#: Seed 004, §4: "the number of measurement points should be greater than or equal 11".
MIN_POINTS_RECOMMENDED = 11
#: Monte Carlo trials for NL and for validating u(S), u(V0) (JCGM 101 §7.2 asks for ~10⁶ when the
#: interval's ends must hold two digits; 2·10⁵ keeps one calibration well under a second).
DEFAULT_MC_TRIALS = 200_000
#: Seed of the Monte Carlo streams: the same capture gives the same budget.
_MC_SEED = 2026
#: Random numbers held at once by the interval's Monte Carlo (memory).
_CHUNK_ELEMENTS = 4_000_000
#: Point means with ν at or below this are drawn normal in the Monte Carlo (see the note there).
_MC_MIN_DOF = 4.0
#: Lack of fit is reported when Σδ²/(ν·ū²) exceeds the χ²(ν)/ν quantile at this probability.
_LACK_OF_FIT_P = 0.999

#: Named requirements, FMVSS 126 first. Limits: ``range_deg_s`` (the tested rates must reach ±it),
#: ``resolution_deg_s`` (must be below), ``accuracy_percent_fs`` (the nonlinearity must be below).
REQUIREMENTS: dict[str, dict[str, Any]] = {
    "fmvss126": {
        "title": "FMVSS 126",
        "source": "Kokuyama et al. (2015), Table 1 (NHTSA FMVSS 126 laboratory test procedure, 2008)",
        "range_deg_s": 100.0,
        "resolution_deg_s": 0.004,
        "accuracy_percent_fs": 0.05,
    },
}
_LIMIT_KEYS = ("range_deg_s", "resolution_deg_s", "accuracy_percent_fs")
_TEXT_KEYS = ("name", "title", "source")
_SHOW_ROWS = 8
#: Samples per rate point examined for an output quantum (see :func:`output_quantum`).
_QUANTUM_SAMPLES = 50_000
# Saturation: a segment between neighbouring outer points whose slope is below this fraction of
# the median slope, by more than _SAT_SIGMAS standard errors, is a saturated output.
_SAT_SLOPE_FRACTION = 0.5
_SAT_SIGMAS = 5.0


@dataclasses.dataclass(frozen=True)
class RatePoint(Result):
    """One set rate: the statistics of its samples and its residual from the fitted line.

    ``mean``, ``std`` (ddof = 1), ``standard_error`` (std/√n) and ``residual`` (mean − S·Ω − V0) are
    in output units; ``residual_percent_fs`` = 100·residual/(|S|·FS).
    """

    rate_deg_s: float
    n: int
    mean: float
    std: float
    standard_error: float
    residual: float
    residual_percent_fs: float


@dataclasses.dataclass(frozen=True)
class RequirementCheck(Result):
    """One line of a requirement: the limit, the measured value, pass/fail and the margin.

    ``margin`` is in ``unit`` and positive when the requirement is met (limit − value for an upper
    limit; tested reach − range for the range). ``passed`` is None when the value could not be
    assessed from the capture.
    """

    quantity: str
    limit: float
    value: float | None
    unit: str
    passed: bool | None
    margin: float | None
    basis: str
    line: str


@dataclasses.dataclass(frozen=True)
class RequirementVerdict(Result):
    """A named requirement applied to a scale-factor result (``passed``: every check passed)."""

    name: str
    title: str
    source: str
    passed: bool | None
    checks: tuple[RequirementCheck, ...]
    note: str

    def lines(self) -> list[str]:
        """One pass/fail line per check, headed by the requirement's title."""
        head = {True: "PASS", False: "FAIL", None: "NOT ASSESSED"}[self.passed]
        return [f"{self.title}: {head}"] + [f"  {c.line}" for c in self.checks]


@dataclasses.dataclass(frozen=True)
class DecisionWithU(Result):
    """A requirement's accuracy check judged with the uncertainty of NL (ILAC-G8).

    With the 95 % interval [low, high] for the true NL (``interval``): ``verdict`` is
    ``"pass with U"`` when high < limit, ``"fail with U"`` when low > limit and ``"inconclusive"``
    when the limit lies within it. Without one, the interval is NL ± U (guard band w = U,
    ILAC-G8:09/2019 §4.2). ``value`` is the plain NL (the value the verdict without U uses), ``U``
    its expanded uncertainty (half the interval's width), all in ``unit``.
    """

    quantity: str
    limit: float
    value: float
    U: float
    unit: str
    verdict: str
    agrees: bool
    rule: str
    line: str
    interval: tuple[float, float] | None = None


@dataclasses.dataclass(frozen=True)
class ScaleFactorResult(Result):
    """Scale factor, bias and nonlinearity (JSON keys of INTERFACE.md, ``gyro scale-factor``).

    Units: ``scale_factor`` output unit per °/s; ``bias``, ``residuals`` output unit;
    ``full_scale_deg_s``, ``rates_deg_s``, ``resolution_deg_s`` °/s; ``nonlinearity_percent_fs``,
    ``residuals_percent_fs`` % of full scale.

    Uncertainties: ``scale_factor_u`` and ``bias_u`` are the standard uncertainties of the budgets
    in ``_budgets`` (keys ``scale_factor``, ``bias``, ``nonlinearity_percent_fs``); the JSON adds
    ``<name>_u``, ``<name>_U``, ``k``, ``coverage_probability``, ``uncertainty_budgets`` and
    ``nonlinearity_percent_fs_interval`` — the 95 % interval for the TRUE NL (%FS), which the
    budget of NL states instead of ± U (U is half its width; it reaches 0 when the residuals are
    consistent with noise). ``nonlinearity_percent_fs`` stays the plain NL (the budget's value).
    ``nonlinearity_percent_fs_bias`` is how much the noise of the point means raises NL (SIMEX,
    %FS; NaN when the noise level is not known apart from the nonlinearity — one sample per
    point) and ``nonlinearity_percent_fs_bias_corrected`` = max(NL − bias, 0). ``decision_with_uncertainty``
    is the accuracy check judged with the interval (ILAC-G8). ``resolution`` says what set
    ``resolution_deg_s`` (the output quantum or the noise of one reading), both numbers and the
    bandwidth with its source (:class:`~rotacal.gyro.resolution.OutputResolution`).
    """

    scale_factor: float
    bias: float
    full_scale_deg_s: float
    nonlinearity_percent_fs: float
    residuals: np.ndarray
    scale_factor_u: float
    bias_u: float
    residuals_percent_fs: np.ndarray
    rates_deg_s: np.ndarray
    points: tuple[RatePoint, ...]
    n_points: int
    samples_used: int
    residual_std: float
    dof: int
    output_unit: str
    rate_tolerance_deg_s: float
    resolution_deg_s: float | None
    resolution_basis: str
    output_quantum: float | None
    requirement: RequirementVerdict | None = None
    notes: tuple[str, ...] = ()
    nonlinearity_percent_fs_bias: float = math.nan
    nonlinearity_percent_fs_bias_corrected: float = math.nan
    decision_with_uncertainty: DecisionWithU | None = None
    resolution: OutputResolution | None = None
    _budgets: dict[str, UncertaintyBudget] = dataclasses.field(
        default_factory=dict, repr=False, compare=False
    )

    @property
    def nonlinearity_percent_fs_interval(self) -> tuple[float, float] | None:
        """The 95 % interval for the true NL (%FS), from its budget (None without a budget)."""
        b = self._budgets.get("nonlinearity_percent_fs")
        return None if b is None else b.interval

    def to_dict(self) -> dict[str, Any]:
        """The JSON of INTERFACE.md plus the uncertainty keys of every budget."""
        out = super().to_dict()
        if self._budgets:
            out.update(to_jsonable(uncertainty_json(self._budgets)))
        return out

    def summary_lines(self) -> list[str]:
        """Human-readable result lines (for the CLI and logs): value ± U (k, p ≈ 95 %)."""
        unit = f" {self.output_unit}" if self.output_unit else ""
        b = self._budgets
        if b:
            out = [f"{b[name].statement()}" for name in b]
            corr = self.nonlinearity_percent_fs_bias_corrected
            if math.isfinite(corr):
                head = f"bias-corrected NL {corr:.4g} %FS"
            elif "nonlinearity_percent_fs" in b:
                head = "NL not bias-corrected (noise level not known apart from the NL)"
            else:
                head = f"nonlinearity  {self.nonlinearity_percent_fs:.4g} %FS (no uncertainty)"
            out.append(f"{head} (FS {self.full_scale_deg_s:g} °/s, {self.n_points} rate points)")
        else:
            out = [
                f"scale factor  {self.scale_factor:.8g} ± {self.scale_factor_u:.2g}{unit}/(°/s)",
                f"bias          {self.bias:.6g} ± {self.bias_u:.2g}{unit}",
                f"nonlinearity  {self.nonlinearity_percent_fs:.4g} %FS "
                f"(FS {self.full_scale_deg_s:g} °/s, {self.n_points} rate points)",
            ]
        if self.requirement is not None:
            out += self.requirement.lines()
        elif self.resolution is not None:
            value = self.resolution.resolution_deg_s
            out.append(
                f"resolution    {'—' if value is None else f'{value:.3g} °/s'} "
                f"({self.resolution.basis})"
            )
        if self.decision_with_uncertainty is not None:
            out.append(f"  {self.decision_with_uncertainty.line}")
        return out


# ------------------------------------------------------------------------------- helpers
def _rows(idx: np.ndarray) -> str:
    shown = ", ".join(str(int(i)) for i in idx[:_SHOW_ROWS])
    more = f" and {idx.size - _SHOW_ROWS} more" if idx.size > _SHOW_ROWS else ""
    return f"{shown}{more}"


def _fmt_rate(r: float) -> str:
    return f"{r:+.6g} °/s"


def _positive(name: str, value: Any, what: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number ({what}), got {value!r}.") from None
    if not math.isfinite(v) or v <= 0:
        raise ConfigError(f"{name} must be a finite number > 0 ({what}), got {value!r}.")
    return v


def resolve_requirement(requirement: str | Mapping[str, Any]) -> dict[str, Any]:
    """The limits of a named requirement, or a user's own, checked.

    Parameters
    ----------
    requirement : str or mapping
        A name from :data:`REQUIREMENTS` (case, spaces, ``-`` and ``_`` ignored: ``"FMVSS 126"``)
        or a mapping with any of ``range_deg_s`` (°/s), ``resolution_deg_s`` (°/s),
        ``accuracy_percent_fs`` (%FS) and optionally ``name``, ``title``, ``source``.

    Returns
    -------
    dict
        ``name``, ``title``, ``source`` and the limits given.
    """
    if isinstance(requirement, str):
        key = "".join(ch for ch in requirement.lower() if ch not in " -_")
        if key not in REQUIREMENTS:
            raise ConfigError(
                f"unknown requirement {requirement!r}; known: {', '.join(REQUIREMENTS)} (or pass a "
                "dict of range_deg_s, resolution_deg_s, accuracy_percent_fs)."
            )
        return {"name": key, **REQUIREMENTS[key]}
    if not isinstance(requirement, Mapping):
        raise ConfigError(
            f"requirement must be a name ({', '.join(REQUIREMENTS)}) or a dict of limits, got "
            f"{requirement!r}."
        )
    bad = [k for k in requirement if k not in _LIMIT_KEYS + _TEXT_KEYS]
    if bad:
        raise ConfigError(
            f"unknown requirement key {bad[0]!r}; use {', '.join(_LIMIT_KEYS + _TEXT_KEYS)}."
        )
    out: dict[str, Any] = {
        "name": str(requirement.get("name", "custom")),
        "title": str(requirement.get("title", requirement.get("name", "custom requirement"))),
        "source": str(requirement.get("source", "user")),
    }
    for k in _LIMIT_KEYS:
        if k in requirement:
            out[k] = _positive(f"requirement {k}", requirement[k], "a limit")
    if not any(k in out for k in _LIMIT_KEYS):
        raise ConfigError(
            f"the requirement gives no limit: add at least one of {', '.join(_LIMIT_KEYS)}."
        )
    return out


def evaluate_requirement(
    requirement: str | Mapping[str, Any],
    *,
    rate_min_deg_s: float,
    rate_max_deg_s: float,
    nonlinearity_percent_fs: float,
    full_scale_deg_s: float,
    resolution_deg_s: float | None,
    resolution_basis: str = "",
) -> RequirementVerdict:
    """Pass/fail, with margins, of measured gyro figures against a requirement.

    Parameters
    ----------
    requirement : str or mapping
        See :func:`resolve_requirement`.
    rate_min_deg_s, rate_max_deg_s : float
        The lowest and highest set rates tested (°/s); the range passes when they reach −R and +R.
    nonlinearity_percent_fs : float
        NL (%FS) of the fit; the accuracy passes when it is below the limit.
    full_scale_deg_s : float
        FS (°/s) NL refers to (stated on the line).
    resolution_deg_s : float or None
        Estimated resolution (°/s); None leaves the resolution not assessed.
    resolution_basis : str
        How the resolution was estimated (stated on the line).

    Returns
    -------
    RequirementVerdict

    References
    ----------
    Seed 004, Table 1 (FMVSS 126: range ±100 °/s, resolution < 0.004 °/s, accuracy < 0.05 %FS).
    """
    req = resolve_requirement(requirement)
    checks: list[RequirementCheck] = []
    if "range_deg_s" in req:
        lim = req["range_deg_s"]
        reach = min(rate_max_deg_s, -rate_min_deg_s)
        ok = bool(reach >= lim)
        margin = reach - lim
        line = (
            f"{'PASS' if ok else 'FAIL'} range: tested {rate_min_deg_s:+.6g} … "
            f"{rate_max_deg_s:+.6g} °/s {'covers' if ok else 'does not cover'} ±{lim:g} °/s "
            f"(margin {margin:+.4g} °/s)"
        )
        checks.append(
            RequirementCheck(
                "range", lim, reach, "deg/s", ok, margin, "smallest |extreme set rate|", line
            )
        )
    if "resolution_deg_s" in req:
        lim = req["resolution_deg_s"]
        if resolution_deg_s is None or not math.isfinite(resolution_deg_s):
            line = (
                f"NOT ASSESSED resolution: neither an output quantum nor the noise of a point is "
                f"visible in the capture (limit < {lim:g} °/s)"
            )
            checks.append(
                RequirementCheck("resolution", lim, None, "deg/s", None, None, "none", line)
            )
        else:
            ok = bool(resolution_deg_s < lim)
            margin = lim - resolution_deg_s
            line = (
                f"{'PASS' if ok else 'FAIL'} resolution: {resolution_deg_s:.3g} °/s "
                f"{'<' if ok else '≥'} {lim:g} °/s (margin {margin:+.3g} °/s; {resolution_basis})"
            )
            checks.append(
                RequirementCheck(
                    "resolution", lim, resolution_deg_s, "deg/s", ok, margin, resolution_basis, line
                )
            )
    if "accuracy_percent_fs" in req:
        lim = req["accuracy_percent_fs"]
        ok = bool(nonlinearity_percent_fs < lim)
        margin = lim - nonlinearity_percent_fs
        line = (
            f"{'PASS' if ok else 'FAIL'} accuracy: nonlinearity {nonlinearity_percent_fs:.4g} %FS "
            f"{'<' if ok else '≥'} {lim:g} %FS (margin {margin:+.3g} %FS; FS = "
            f"{full_scale_deg_s:g} °/s)"
        )
        checks.append(
            RequirementCheck(
                "accuracy",
                lim,
                nonlinearity_percent_fs,
                "percent_fs",
                ok,
                margin,
                "nonlinearity of the least-squares line",
                line,
            )
        )
    states = [c.passed for c in checks]
    passed: bool | None = (
        False if any(s is False for s in states) else (None if None in states else True)
    )
    note = (
        "Accuracy is judged by the nonlinearity alone. A full accuracy statement would also count "
        "the uncertainty of the scale factor (including the table's rate traceability), the bias "
        "and its repeatability, temperature sensitivity and cross-axis sensitivity."
    )
    return RequirementVerdict(req["name"], req["title"], req["source"], passed, tuple(checks), note)


def output_quantum(
    output: np.ndarray, groups: np.ndarray | None = None, *, max_median_steps: float = 4.0
) -> float | None:
    """The output quantum, when the recorded values visibly lie on a grid; else None.

    Within each group (rate point; at most 50 000 evenly strided samples of it), the gaps between
    consecutive distinct values are taken. The
    smallest gap q is the quantum when every gap is an integer multiple of q (to 10⁻³ of q) and the
    median gap is at most ``max_median_steps``·q (the grid is densely used, so q is not a
    coincidence of sparse printed digits). A quantum below the float resolution of the values is
    not one.

    Parameters
    ----------
    output : array
        Output samples (output units); non-finite values are ignored.
    groups : array of int or None
        Group label of each sample (None: one group).
    max_median_steps : float
        Largest median gap, in quanta, for the grid to count as visible.

    Returns
    -------
    float or None
        q in output units.
    """
    y = np.asarray(output, dtype=float).reshape(-1)
    g = np.zeros(y.size, dtype=np.int64) if groups is None else np.asarray(groups).reshape(-1)
    ok = np.isfinite(y)
    y, g = y[ok], g[ok]
    if y.size < 2:
        return None
    # At most _QUANTUM_SAMPLES evenly strided samples of each group: plenty to see a grid, and
    # the sort stays cheap on long records.
    by_g = np.argsort(g, kind="stable")
    gs0 = g[by_g]
    starts = np.flatnonzero(np.r_[True, gs0[1:] != gs0[:-1]])
    sizes = np.diff(np.r_[starts, gs0.size])
    if sizes.max() > _QUANTUM_SAMPLES:
        within = np.arange(gs0.size) - np.repeat(starts, sizes)
        stride = np.repeat(-(-sizes // _QUANTUM_SAMPLES), sizes)
        keep = by_g[within % stride == 0]
        y, g = y[keep], g[keep]
    order = np.lexsort((y, g))
    ys, gs = y[order], g[order]
    d = np.diff(ys)
    gaps = d[(gs[1:] == gs[:-1]) & (d > 0)]
    if gaps.size == 0:
        return None
    q = float(gaps.min())
    if q <= 64.0 * np.finfo(float).eps * float(np.max(np.abs(ys))):
        return None
    k = gaps / q
    if float(np.max(np.abs(k - np.round(k)))) > 1e-3:
        return None
    if float(np.median(k)) > max_median_steps:
        return None
    return q


def _group(rate: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Group ids (0 = lowest rate), each group's mean set rate and its spread (max − min)."""
    order = np.argsort(rate, kind="stable")
    rs = rate[order]
    new = np.empty(rs.size, dtype=bool)
    new[0] = True
    new[1:] = np.diff(rs) > tol
    gid_sorted = np.cumsum(new) - 1
    gid = np.empty(rs.size, dtype=np.int64)
    gid[order] = gid_sorted
    starts = np.flatnonzero(new)
    ng = starts.size
    counts = np.diff(np.append(starts, rs.size))
    rate_mean = np.add.reduceat(rs, starts) / counts
    spread = np.maximum.reduceat(rs, starts) - np.minimum.reduceat(rs, starts)
    assert rate_mean.size == ng
    return gid, rate_mean, spread


def _check_saturation(
    rates: np.ndarray, means: np.ndarray, std: np.ndarray, counts: np.ndarray, unit: str
) -> None:
    """Refuse outer rate points where the output stops following the rate (saturation)."""
    if rates.size < 3:
        return
    dr = np.diff(rates)
    dm = np.diff(means)
    slopes = dm / dr
    s_ref = float(np.median(slopes))
    if s_ref == 0:
        return
    deficit = np.abs(s_ref * dr - dm)
    # Noise of each segment's change: from the points' standard errors (a pooled standard
    # deviation for single-sample points); when no point has two samples, from the robust scatter
    # (MAD) of the point means about the line of median slope.
    multi = counts > 1
    if multi.any():
        pooled = float(np.sum((counts[multi] - 1) * std[multi] ** 2) / np.sum(counts[multi] - 1))
        sd = np.where(multi, std, math.sqrt(pooled))
        se = sd / np.sqrt(counts)
        noise = np.hypot(se[1:], se[:-1])
    else:
        res = means - s_ref * rates  # about the robust line (median slope, median offset)
        sigma = 1.4826 * float(np.median(np.abs(res - np.median(res))))
        noise = np.full(dr.size, math.sqrt(2.0) * sigma)
    bad = (slopes / s_ref < _SAT_SLOPE_FRACTION) & (deficit > _SAT_SIGMAS * noise)
    # Walk inward from each end: saturation affects the outermost points only. Segment k joins
    # points k and k + 1; a bad outer segment saturates its outer point.
    last = bad.size - 1
    for side in ("high", "low"):
        seg = last if side == "high" else 0
        if not bad[seg]:
            continue
        if side == "high":
            k = seg
            while k - 1 >= 0 and bad[k - 1]:
                k -= 1
            sat = rates[k + 1 :]
            outer, inner = rates.size - 1, rates.size - 2
        else:
            k = seg
            while k + 1 <= last and bad[k + 1]:
                k += 1
            sat = rates[: k + 1][::-1]
            outer, inner = 0, 1
        pts = ", ".join(_fmt_rate(r) for r in sat)
        raise CaptureError(
            f"the output saturates at the rate point {_fmt_rate(rates[outer])}: its mean "
            f"{means[outer]:.6g}{unit} differs by only {dm[seg] * (1 if side == 'high' else -1):+.4g}"
            f"{unit} from that of the {_fmt_rate(rates[inner])} point where the slope of the other "
            f"points predicts {s_ref * dr[seg] * (1 if side == 'high' else -1):+.4g}{unit} "
            f"(saturated points: {pts}); drop them or widen the DUT's output range."
        )


# ------------------------------------------------------------------------------- method
def calibrate_scale_factor(
    rate_deg_s: np.ndarray,
    output: np.ndarray,
    *,
    full_scale_deg_s: float | None = None,
    requirement: str | Mapping[str, Any] | None = None,
    rate_tolerance_deg_s: float = DEFAULT_RATE_TOLERANCE_DEG_S,
    nan_policy: str = "raise",
    output_unit: str = "",
    specs: InstrumentSpecs | None = None,
    mc_trials: int = DEFAULT_MC_TRIALS,
    sample_rate_hz: float | None = None,
    bandwidth_hz: float | None = None,
    allow_clipped: bool = False,
) -> ScaleFactorResult:
    """Scale factor, bias and nonlinearity of a gyro from a rate-table test.

    Rows whose set rates lie within ``rate_tolerance_deg_s`` of each other are one rate point; its
    samples are averaged. An unweighted least-squares line V = S·Ω + V0 through the N point means
    gives S and V0; δ are the point residuals and NL = 100·max|δ|/(|S|·FS) %FS.

    The capture is refused (:class:`~rotacal.errors.CaptureError`) when a set rate is missing, a
    rate point has no finite output, outputs are NaN (unless ``nan_policy="omit"``), a column holds
    values beyond float64's working range (|x| > 1e100, or all below 1e-100), there is only one
    rate, the output copies the set rate (or its negative), the output does not change with the
    rate, the output sits at its rails (:mod:`rotacal.signal.clipping`, with the rate points as
    groups; ``allow_clipped`` analyses it anyway and says so in ``warnings``), or the output
    saturates: at the outer points their mean stops following the rate (local slope below half
    the median slope by more than 5 standard errors).

    The resolution a requirement judges is the smallest rate change the output resolves
    (:func:`rotacal.gyro.resolution.output_resolution`): the larger of the output quantum / |S|
    (when the outputs lie visibly on a grid, :func:`output_quantum`) and the noise of one reading
    at the stated bandwidth / |S| — neither shrinks with the record's length. It does not replace
    the IEEE Std 1431 resolution test with small rate increments.

    Parameters
    ----------
    rate_deg_s : array
        Set rate of the table on each row (°/s).
    output : array
        DUT output on each row (output units: V, LSB, °/s …).
    full_scale_deg_s : float or None
        FS (°/s) for NL; None takes the largest |set rate|.
    requirement : str or mapping or None
        A named requirement (``"fmvss126"``) or a dict of limits (see :func:`resolve_requirement`).
    rate_tolerance_deg_s : float
        Set rates closer than this (°/s, ≥ 0) to their sorted neighbour are one point.
    nan_policy : {"raise", "omit"}
        Non-finite outputs raise, or are left out (with a note).
    output_unit : str
        Name of the output unit, for messages and reports.
    specs : InstrumentSpecs or None
        The lab's instrument specifications (Type B; :func:`rotacal.uncertainty.load_specs`, a
        TOML path or a mapping also work). Used: ``table.set_rate_relative`` (relative error ε of
        the table's set rate, the realised rate being Ω·(1 + ε)); others are ignored. None: the
        budgets hold the capture's Type A part only.
    mc_trials : int
        Monte Carlo trials for NL and for validating u(S) and u(V0) (≥ 2000).
    sample_rate_hz : float or None
        Sample rate of the output (Hz), for the resolution's noise bandwidth (fs/2 by default).
    bandwidth_hz : float or None
        Bandwidth of one reading for the resolution (Hz, ≤ fs/2; needs ``sample_rate_hz``);
        None: the recorded samples' own.
    allow_clipped : bool
        Analyse an output with samples at the rails anyway (``--allow-clipped``); the result's
        ``warnings`` name the clipping. Refused by default.

    Returns
    -------
    ScaleFactorResult
        ``scale_factor`` (output unit per °/s), ``bias`` (output unit), their standard
        uncertainties, ``nonlinearity_percent_fs`` (%FS), ``residuals`` (output unit, one per point),
        the per-point table, the requirement's verdict, the budgets (``_budgets``: GUM for S and V0,
        validated by Monte Carlo; Monte Carlo for NL with its bias and bias-corrected value) and the
        accuracy verdict with U (``decision_with_uncertainty``).

    References
    ----------
    Kokuyama et al. (2015), §4: V(Ω) = S·Ω + V0 + δ(Ω), NL = max|δ|/FS, ≥ 11 points; Table 1
    (FMVSS 126). IEEE Std 952-1997, Annex C. JCGM 100:2008 (GUM), §5.1.2, G.4.1, H.3 (straight-line
    fit and its uncertainties); JCGM 101:2008 §7–8 (Monte Carlo, validation); ILAC-G8:09/2019 §4.2.
    """
    unit = f" {output_unit}" if output_unit else ""
    rate = np.asarray(rate_deg_s, dtype=float).reshape(-1)
    y = np.asarray(output, dtype=float).reshape(-1)
    if rate.size != y.size:
        raise CaptureError(
            f"column rate_deg_s has {rate.size} rows but column output has {y.size}: they must "
            "have one row per sample."
        )
    if rate.size == 0:
        raise CaptureError("the capture has no rows: it needs rate_deg_s and output samples.")
    if nan_policy not in ("raise", "omit"):
        raise ConfigError(f"nan_policy must be 'raise' or 'omit', got {nan_policy!r}.")
    try:
        tol = float(rate_tolerance_deg_s)
    except (TypeError, ValueError):
        raise ConfigError(
            f"rate_tolerance_deg_s must be a number ≥ 0 °/s, got {rate_tolerance_deg_s!r}."
        ) from None
    if not math.isfinite(tol) or tol < 0:
        raise ConfigError(
            f"rate_tolerance_deg_s must be a number ≥ 0 °/s, got {rate_tolerance_deg_s!r}."
        )
    req = None if requirement is None else resolve_requirement(requirement)
    spec = as_specs(specs)
    if isinstance(mc_trials, bool) or not isinstance(mc_trials, (int, np.integer)):
        raise ConfigError(f"mc_trials must be an integer ≥ 2000, got {mc_trials!r}.")
    if mc_trials < 2000:
        raise ConfigError(
            f"mc_trials must be at least 2000 for a 95 % interval (JCGM 101 §7.2), got {mc_trials}."
        )
    trials = int(mc_trials)
    fs_user = (
        None
        if full_scale_deg_s is None
        else _positive("full_scale_deg_s", full_scale_deg_s, "the full scale in °/s")
    )
    if fs_user is not None:
        check_setting("--full-scale-deg-s", fs_user, unit="deg/s")

    bad_rate = np.flatnonzero(~np.isfinite(rate))
    if bad_rate.size:
        raise CaptureError(
            f"column rate_deg_s has {bad_rate.size} non-finite value(s) (NaN or inf) at rows "
            f"{_rows(bad_rate)} (counted from 0): every row needs the table's set rate."
        )
    check_magnitudes("rate_deg_s", rate, what="a set rate")
    gid, rates, spread = _group(rate, tol)
    ng = rates.size
    if ng == 1:
        raise CaptureError(
            f"every row of column rate_deg_s has the same set rate ({_fmt_rate(rates[0])}): a "
            f"scale factor needs at least two rates (Kokuyama et al. 2015 recommend ≥ {MIN_POINTS_RECOMMENDED})."
        )
    ok = np.isfinite(y)
    counts = np.bincount(gid, weights=ok, minlength=ng).astype(np.int64)
    empty = np.flatnonzero(counts == 0)
    if empty.size:
        rows = np.flatnonzero(gid == empty[0])
        raise CaptureError(
            f"the rate point {_fmt_rate(rates[empty[0]])} has no samples: all {rows.size} of its "
            f"outputs are NaN or empty (rows {_rows(rows)}, counted from 0); fix column output or "
            "remove that rate."
        )
    notes: list[str] = []
    bad_out = np.flatnonzero(~ok)
    if bad_out.size:
        if nan_policy == "raise":
            raise CaptureError(
                f"column output has {bad_out.size} non-finite value(s) (NaN or inf) at rows "
                f"{_rows(bad_out)} (counted from 0): remove those rows from the capture."
            )
        notes.append(
            f"{bad_out.size} non-finite output value(s) left out (rows {_rows(bad_out)}, counted "
            "from 0)."
        )
    check_magnitudes("output", y[ok] if bad_out.size else y, what="a gyro output")
    check_not_copies(
        {"rate_deg_s": rate, "output": y},
        "a DUT's output differs from the set rate by its noise at least; map the DUT's output",
    )

    yz = np.where(ok, y, 0.0)
    means = np.bincount(gid, weights=yz, minlength=ng) / counts
    dev = np.where(ok, y - means[gid], 0.0)
    ss = np.bincount(gid, weights=dev * dev, minlength=ng)
    with np.errstate(invalid="ignore", divide="ignore"):
        std = np.where(counts > 1, np.sqrt(ss / np.maximum(counts - 1, 1)), np.nan)
        se = std / np.sqrt(counts)

    if np.ptp(means) == 0:
        raise CaptureError(
            "column output does not change with the set rate (every rate point has the same mean "
            f"{means[0]:.6g}{unit}): check that the right output column is mapped."
        )
    # samples at the rails: the one detector, with the rate points as groups and the rows at
    # zero rate as rest (rotacal.signal.clipping)
    clipped = check_clipping(
        {"output": y}, allow_clipped=allow_clipped, groups=gid, rest=rates[gid] == 0
    )
    _check_saturation(rates, means, std, counts, unit)

    # Unweighted least-squares line through the point means (centred for accuracy), against the
    # set rates; the table's stated mean rate error ε̄ (realised rate Ω·(1 + ε̄)) corrects S.
    eps_dist = spec_distribution(spec, "table.set_rate_relative")
    eps_mean = 0.0 if eps_dist is None else float(eps_dist.mean)
    xbar = float(rates.mean())
    ybar = float(means.mean())
    xc = rates - xbar
    sxx = float(xc @ xc)
    s_fit = float(xc @ (means - ybar)) / sxx
    s = s_fit / (1.0 + eps_mean)
    v0 = ybar - s_fit * xbar
    resid = means - (s_fit * rates + v0)
    dof = ng - 2
    if dof > 0:
        res_std = math.sqrt(float(resid @ resid) / dof)
    else:
        res_std = math.nan
        notes.append(
            "two rate points fit the line exactly: the residuals, the nonlinearity and the "
            "uncertainties mean nothing."
        )
    fs = fs_user if fs_user is not None else float(np.max(np.abs(rates)))
    scale = abs(s) * fs
    res_pct = 100.0 * resid / scale
    nl = float(np.max(np.abs(res_pct)))

    if ng < MIN_POINTS_RECOMMENDED:
        notes.append(
            f"only {ng} rate points: Kokuyama et al. (2015, §4) recommend at least {MIN_POINTS_RECOMMENDED}."
        )
    if fs_user is not None and fs_user < float(np.max(np.abs(rates))):
        notes.append(
            f"the tested rates reach {float(np.max(np.abs(rates))):g} °/s, beyond the full scale "
            f"{fs_user:g} °/s that NL refers to."
        )
    if float(spread.max()) > 0:
        notes.append(
            f"set rates within {tol:g} °/s were merged into one point; the largest spread within "
            f"a point is {float(spread.max()):.3g} °/s."
        )
    if eps_mean != 0.0:
        notes.append(
            f"the stated mean set-rate error ε̄ = {eps_mean:.3g} (table.set_rate_relative) "
            f"corrects S: S = S₀/(1 + ε̄), S₀ = {s_fit:.8g} against the set rates."
        )

    q = output_quantum(y, gid)
    res = output_resolution(
        y,
        gid,
        s,
        quantum=q,
        sample_rate_hz=sample_rate_hz,
        bandwidth_hz=bandwidth_hz,
        output_unit=output_unit,
    )
    resolution, basis = res.resolution_deg_s, res.basis
    notes.append(
        "Unweighted least squares through the point means (Kokuyama et al. 2015, §4, IEEE Std 952 Annex C); "
        "scale_factor_u and bias_u are the combined standard uncertainties of the budgets: the "
        "standard errors of the point means through the line (Type A) and the stated table "
        "set-rate error (Type B); the nonlinearity δ(Ω) is reported as NL, not as an "
        "uncertainty of S."
    )

    budgets: dict[str, UncertaintyBudget] = {}
    nl_bias = nl_corr = math.nan
    u_pt, nu_pt, basis_a = _point_uncertainties(counts, std, q, res_std, dof, unit)
    if u_pt is not None:
        assert nu_pt is not None
        budgets, nl_bias, lof = _scale_factor_budgets(
            rates=rates,
            means=means,
            counts=counts,
            u_pt=u_pt,
            nu_pt=nu_pt,
            basis=basis_a,
            s_fit=s_fit,
            v0=v0,
            nl=nl,
            fs=fs,
            resid=resid,
            spec=spec,
            eps_dist=eps_dist,
            output_unit=output_unit,
            mc_trials=trials,
        )
        nl_corr = max(nl - nl_bias, 0.0) if math.isfinite(nl_bias) else math.nan
        if lof:
            notes.append(lof)
    s_u = budgets["scale_factor"].u if budgets else math.nan
    v0_u = budgets["bias"].u if budgets else math.nan

    decision: DecisionWithU | None = None
    if req is not None:
        verdict: RequirementVerdict | None = evaluate_requirement(
            req,
            rate_min_deg_s=float(rates.min()),
            rate_max_deg_s=float(rates.max()),
            nonlinearity_percent_fs=nl,
            full_scale_deg_s=fs,
            resolution_deg_s=resolution,
            resolution_basis=basis,
        )
        if "accuracy_percent_fs" in req and "nonlinearity_percent_fs" in budgets:
            b_nl = budgets["nonlinearity_percent_fs"]
            decision = decide_with_u(
                nl, b_nl.U, req["accuracy_percent_fs"], title=req["title"], interval=b_nl.interval
            )
    else:
        verdict = None

    points = tuple(
        RatePoint(
            float(rates[i]),
            int(counts[i]),
            float(means[i]),
            float(std[i]),
            float(se[i]),
            float(resid[i]),
            float(res_pct[i]),
        )
        for i in range(ng)
    )
    return ScaleFactorResult(
        scale_factor=s,
        bias=v0,
        full_scale_deg_s=fs,
        nonlinearity_percent_fs=nl,
        residuals=resid,
        scale_factor_u=s_u,
        bias_u=v0_u,
        residuals_percent_fs=res_pct,
        rates_deg_s=rates,
        points=points,
        n_points=ng,
        samples_used=int(counts.sum()),
        residual_std=res_std,
        dof=dof,
        output_unit=output_unit,
        rate_tolerance_deg_s=tol,
        resolution_deg_s=resolution,
        resolution_basis=basis,
        output_quantum=q,
        requirement=verdict,
        notes=tuple(notes),
        nonlinearity_percent_fs_bias=nl_bias,
        nonlinearity_percent_fs_bias_corrected=nl_corr,
        decision_with_uncertainty=decision,
        resolution=res,
        _budgets=budgets,
        warnings=(
            *clipped,
            *scale_factor_warnings(
                scale_factor=s,
                nonlinearity_percent_fs=nl,
                rates_deg_s=rates,
                residuals=resid,
                point_u=u_pt,
                full_scale_deg_s=fs,
                output_unit=output_unit,
                quantum=q,
            ),
        ),
    )


# ------------------------------------------------------------------------------- uncertainty
def decide_with_u(
    value: float,
    big_u: float,
    limit: float,
    *,
    title: str = "",
    interval: tuple[float, float] | None = None,
) -> DecisionWithU:
    """Judge an upper limit on the nonlinearity with its uncertainty (ILAC-G8).

    Parameters
    ----------
    value : float
        The measured (plain) NL (%FS).
    big_u : float
        Its expanded uncertainty U (%FS, p = 95 %).
    limit : float
        The requirement's upper limit (%FS).
    title : str
        Name of the requirement, for the line.
    interval : (float, float) or None
        The 95 % interval [low, high] for the true NL (%FS), when the budget states one (a
        biased, bounded quantity: not centred on the value); None takes value ± U.

    Returns
    -------
    DecisionWithU
        ``"pass with U"`` when high < limit, ``"fail with U"`` when low > limit, otherwise
        ``"inconclusive"``; ``agrees`` tells whether the verdict without U (value < limit) holds
        with U.

    References
    ----------
    ILAC-G8:09/2019, §4.2.2–4.2.3 (guarded acceptance and rejection, guard band w = U);
    JCGM 106:2012, §8 (conformity decisions with a measurement uncertainty: the coverage
    interval for the measurand against the tolerance limit).
    """
    if interval is None:
        low, high = value - big_u, value + big_u
        rule = (
            "guard band w = U (ILAC-G8:09/2019 §4.2): pass when NL + U < limit, fail when NL − U "
            "> limit, inconclusive when the limit lies within NL ± U (p = 95 %)"
        )
        stated = f"NL {value:.4g} ± {big_u:.2g} %FS"
    else:
        low, high = float(interval[0]), float(interval[1])
        rule = (
            "guarded acceptance with the 95 % interval [low, high] for the true NL (ILAC-G8:09/2019 "
            "§4.2, JCGM 106 §8): pass when high < limit, fail when low > limit, inconclusive when "
            "the limit lies within it (the interval is not centred on the plain NL, which noise "
            "biases upward)"
        )
        stated = f"NL {value:.4g} %FS, true NL in [{low:.4g}, {high:.4g}] %FS"
    if high < limit:
        verdict = "pass with U"
    elif low > limit:
        verdict = "fail with U"
    else:
        verdict = "inconclusive"
    plain_pass = value < limit
    agrees = verdict == ("pass with U" if plain_pass else "fail with U")
    head = f"{title} accuracy " if title else "accuracy "
    line = (
        f"{head}with U: {verdict.upper()} — {stated} against < {limit:g} %FS; the verdict "
        f"without U ({'PASS' if plain_pass else 'FAIL'}) "
        f"{'holds' if agrees else 'does not hold'} with U"
    )
    return DecisionWithU(
        "accuracy",
        float(limit),
        float(value),
        float(big_u),
        "percent_fs",
        verdict,
        agrees,
        rule,
        line,
        None if interval is None else (low, high),
    )


def _point_uncertainties(
    counts: np.ndarray,
    std: np.ndarray,
    q: float | None,
    res_std: float,
    dof: int,
    unit: str,
) -> tuple[np.ndarray | None, np.ndarray | None, str]:
    """Standard uncertainty (output unit) and ν of each point mean, and how they were found.

    Points with n ≥ 2 samples: s_i/√n_i, ν = n_i − 1 (a point whose samples are all equal on a
    visible output grid: the rounding, q/√12, ν = ∞). Points of one sample: the pooled standard
    deviation of the others, ν = Σ(n_k − 1). No point with two samples: the residual standard
    deviation of the line (GUM H.3), ν = N − 2; None when N = 2.
    """
    multi = counts > 1
    if multi.any():
        nu_pool = float(np.sum(counts[multi] - 1))
        pooled = math.sqrt(float(np.sum((counts[multi] - 1) * std[multi] ** 2)) / nu_pool)
        sd = np.where(multi, std, pooled)
        u = sd / np.sqrt(counts)
        nu = np.where(multi, counts - 1.0, nu_pool)
        flat = multi & (std == 0)
        if q is not None and flat.any():
            u = np.where(flat, q / math.sqrt(12.0), u)
            nu = np.where(flat, math.inf, nu)
        n_min, n_max = int(counts.min()), int(counts.max())
        n_text = f"{n_min}" if n_min == n_max else f"{n_min}…{n_max}"
        basis = (
            f"Type A: standard errors of the {counts.size} point means ({n_text} samples each) "
            "through the line"
        )
        if not multi.all():
            basis += "; points of one sample take the pooled standard deviation"
        if q is not None and flat.any():
            basis += f"; points without spread take the output rounding q/√12 (q = {q:.3g}{unit})"
        return u, nu, basis
    if dof <= 0:
        return None, None, ""
    u = np.full(counts.size, res_std)
    nu = np.full(counts.size, float(dof))
    basis = (
        f"Type A: one sample per point, so the scatter of the {counts.size} points about the line "
        f"stands for the noise (GUM H.3, ν = {dof})"
    )
    return u, nu, basis


def _quantile_se(x: np.ndarray, q: float) -> float:
    """Monte Carlo standard error of the q-quantile of the values x (their unit): half the
    distance between the order statistics one binomial standard deviation either side of it
    (David & Nagaraja 2003, §7.1)."""
    srt = np.sort(np.asarray(x, dtype=float))
    m = srt.size
    half = math.sqrt(m * q * (1.0 - q))
    i_lo = int(np.clip(math.floor(m * q - half), 0, m - 1))
    i_hi = int(np.clip(math.ceil(m * q + half), 0, m - 1))
    return 0.5 * float(srt[i_hi] - srt[i_lo])


def _nl_interval(
    resid: np.ndarray,
    u_pt: np.ndarray,
    w_dists: list[TScale],
    xc: np.ndarray,
    sxx: float,
    s_fit: float,
    eps_dist: Distribution | None,
    fs: float,
    trials: int,
) -> tuple[float, float, float, float, int]:
    """The 95 % interval for the true NL (%FS), the Monte Carlo standard errors of its ends (%FS)
    and the number of candidate points.

    With e = δ̂ − δ the residual errors (the line's residual projector applied to the errors of
    the point means; independent of the true curve), for any true residuals δ:
    max|δ̂| − max|δ| ≤ |e_k| (k where |δ̂| peaks) and max|δ| ≤ max|δ̂| + |e_j*| (j* where |δ|
    peaks). With τ the 99.9 % quantile of max|e|, both k and j* lie, but for a probability of
    10⁻³, among the points K whose |δ̂| comes within 4τ of max|δ̂| (they have |δ| ≥ max|δ| − 2τ).
    The lower end is max|δ̂| less the 97.5 % quantile of max_K|e_j|, the upper end max|δ̂| plus the
    largest 97.5 % quantile of e_j over K, each divided by |S|·FS/100 drawn with it (S from the
    same errors and the set-rate error ε): each end holds with probability ≥ 97.5 % − 0.1 %.

    Parameters
    ----------
    resid : array
        Residuals δ̂ of the point means from the line (output unit).
    u_pt : array
        Standard uncertainties (t scale) of the point means (output unit).
    w_dists : list of TScale
        One √(ν/χ²_ν) per point, or one shared by all (GUM H.3: a multivariate t).
    xc, sxx : array, float
        Rates less their mean (°/s) and Σxc² ((°/s)²).
    s_fit : float
        Slope of the line against the set rates (output unit per °/s).
    eps_dist : Distribution or None
        Relative set-rate error ε of the table (1).
    fs : float
        Full scale (°/s).
    trials : int
        Monte Carlo trials.

    Returns
    -------
    low, high, se_low, se_high : float
        %FS.
    n_candidates : int

    References
    ----------
    JCGM 101:2008 §6.4.9 (t-distributed means), §7.7 (coverage interval); JCGM 102:2011 §5.3.2
    (multivariate t), §9 (a magnitude near zero); David & Nagaraja, Order Statistics, 3rd ed.
    (2003) §7.1 (Monte Carlo error of a quantile).
    """
    n = resid.size
    a_plain = float(np.max(np.abs(resid)))
    chunk = max(1, min(trials, _CHUNK_ELEMENTS // max(n, 1)))

    def draws() -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """(residual errors (m, N), 100/(|S|·FS) (m,)) in chunks, the same on every call."""
        rng = np.random.default_rng(_MC_SEED + 1)
        done = 0
        while done < trials:
            m = min(chunk, trials - done)
            z = rng.standard_normal((m, n)) * u_pt
            w = np.column_stack([d.sample(rng, m) for d in w_dists])
            e = z * w
            eps = np.zeros(m) if eps_dist is None else eps_dist.sample(rng, m)
            ds = e @ xc / sxx
            pe = e - e.mean(axis=1, keepdims=True) - ds[:, None] * xc
            yield pe, 100.0 * np.abs(1.0 + eps) / (np.abs(s_fit + ds) * fs)
            done += m

    # both passes see the same draws: held in memory when they fit, else drawn again
    held = list(draws()) if trials * n <= 2 * _CHUNK_ELEMENTS else None
    tau = float(
        np.quantile(
            np.concatenate([np.max(np.abs(pe), axis=1) for pe, _ in (held or draws())]), 0.999
        )
    )
    cand = np.flatnonzero(np.abs(resid) >= a_plain - 4.0 * tau)
    lows, highs = [], []
    for pe, g in held or draws():
        pk = pe[:, cand]
        lows.append((a_plain - np.max(np.abs(pk), axis=1)) * g)
        highs.append((a_plain + pk) * g[:, None])
    low_t, high_t = np.concatenate(lows), np.concatenate(highs)
    q_lo, q_hi = 0.025, 0.975
    lo = max(float(np.quantile(low_t, q_lo)), 0.0)
    hi_j = np.quantile(high_t, q_hi, axis=0)
    j = int(np.argmax(hi_j))
    hi = max(float(hi_j[j]), lo)
    return lo, hi, _quantile_se(low_t, q_lo), _quantile_se(high_t[:, j], q_hi), int(cand.size)


def _scale_factor_budgets(
    *,
    rates: np.ndarray,
    means: np.ndarray,
    counts: np.ndarray,
    u_pt: np.ndarray,
    nu_pt: np.ndarray,
    basis: str,
    s_fit: float,
    v0: float,
    nl: float,
    fs: float,
    resid: np.ndarray,
    spec: InstrumentSpecs | None,
    eps_dist: Distribution | None,
    output_unit: str,
    mc_trials: int,
) -> tuple[dict[str, UncertaintyBudget], float, str | None]:
    """Budgets of S, V0 (GUM, validated by Monte Carlo) and NL (Monte Carlo); NL's noise bias
    (%FS; NaN when the noise level is not known apart from the nonlinearity), its 95 % interval
    for the true NL (%FS); a lack-of-fit note (or None).

    The interval for the true NL rests on two inequalities that hold whatever the true residuals
    δ: with e = δ̂ − δ the residual errors (the line's residual projector applied to the errors of
    the point means, independent of the true curve), max|δ̂| − max|e| ≤ max|δ| ≤ max|δ̂| + |e_j*|
    (j* where |δ| peaks). The 97.5 % quantiles of max|e| and of the most widely spread e_j (Monte
    Carlo) then give ends that each hold with probability ≥ 97.5 %, also at NL = 0, where the
    interval becomes [0, high]. u and the noise bias come from re-measuring (parametric
    bootstrap) the residuals shrunk toward the line by √max(0, 1 − tr C/|δ̂|²) (C the covariance
    of e), so that their sum of squares is the unbiased estimate of the true one.

    References
    ----------
    Seed 004 §4; JCGM 100:2008 §5.1.2, G.4.1, H.3; JCGM 101:2008 §6.4.9, §7.6, §7.7, §8;
    JCGM 102:2011 §5.3.2, §9 (a magnitude near zero); Efron B. & Tibshirani R. J., An
    Introduction to the Bootstrap (1993) §6, §10 (parametric bootstrap: standard error, bias);
    Mathai A. M. & Provost S. B., Quadratic Forms in Random Variables (1992) Thm 3.2b.2
    (E|δ̂|² = |δ|² + tr C); David H. A. & Nagaraja H. N., Order Statistics, 3rd ed. (2003) §7.1
    (Monte Carlo error of a quantile).
    """
    ou = output_unit or "output unit"
    unit_s = f"{ou}/(°/s)"
    n = rates.size
    xbar = float(rates.mean())
    xc = rates - xbar
    sxx = float(xc @ xc)
    c_s = xc / sxx  # ∂S₀/∂ȳ_i (1/(°/s))
    c_b = 1.0 / n - xbar * c_s  # ∂V0/∂ȳ_i (1)
    h3 = bool(np.all(counts == 1))
    if h3:
        fit = linear_fit_uncertainty(rates, means)
        u_s0, u_b0 = fit.u_slope, fit.u_intercept
        nu_s = nu_b = float(fit.dof)
    else:
        u_s0 = math.sqrt(float(np.sum((c_s * u_pt) ** 2)))
        u_b0 = math.sqrt(float(np.sum((c_b * u_pt) ** 2)))
        nu_s = welch_satterthwaite(c_s * u_pt, nu_pt)
        nu_b = welch_satterthwaite(c_b * u_pt, nu_pt)
    eps_in = spec_input(spec, "table.set_rate_relative", name="table set-rate error ε")
    eps = 0.0 if eps_in is None else eps_in.value
    type_a = [] if (note := type_a_note(spec, ("table.set_rate_relative",))) is None else [note]
    # a stated mean ε̄ corrects S = S₀/(1 + ε̄) and NL through S (GUM §3.2.4); V0 does not change
    fixed = [] if spec is None else [spec.correction_note("table.set_rate_relative")]
    s_notes = type_a + [n for n in fixed if n is not None]

    s_in = Input("S₀: slope of the line", s_fit, u_s0, nu_s, "normal", unit_s, basis)
    s_inputs, s_sens = [s_in], [1.0 / (1.0 + eps)]
    if eps_in is not None:
        s_inputs.append(eps_in)
        s_sens.append(-s_fit / (1.0 + eps) ** 2)
    gum_s = linear_gum("scale factor S", unit_s, s_fit / (1.0 + eps), s_inputs, s_sens)
    b_in = Input("V0: intercept of the line", v0, u_b0, nu_b, "normal", ou, basis)
    gum_b = linear_gum("bias V0", ou, v0, [b_in], [1.0])
    b_notes = list(type_a)
    if eps_in is not None:
        b_notes.append(
            "table.set_rate_relative does not enter: a relative rate error leaves zero rate at "
            "zero, so the line's intercept does not change."
        )

    # Monte Carlo over the point means and ε (JCGM 101). The error of a point mean is u_i·z_i·w_i
    # with z_i ~ N(0, 1) and w_i = √(ν_i/χ²_ν): a scaled-and-shifted t with ν_i = n_i − 1 (JCGM 101
    # §6.4.9); points that share the residual s of the line (GUM H.3) share one w, a multivariate
    # t (JCGM 102 §5.3.2). A t with ν ≤ 4 has no finite fourth moment, so the standard deviation
    # of the Monte Carlo values would not settle: the re-measurements of S, V0 and NL then use z
    # alone (normal), and S and V0 keep their GUM interval unvalidated. The interval for the true
    # NL (two quantiles) always uses the t.
    heavy = bool(np.any(nu_pt <= _MC_MIN_DOF))
    inputs: dict[str, Distribution] = {f"z{i}": Normal(0.0, float(u_pt[i])) for i in range(n)}
    if h3:
        inputs["w"] = TScale(float(nu_pt[0]))
    else:
        for i in range(n):
            inputs[f"w{i}"] = TScale(float(nu_pt[i]))
    if eps_dist is not None:
        inputs["eps"] = eps_dist
    z_names = [f"z{i}" for i in range(n)]
    w_names = ["w"] if h3 else [f"w{i}" for i in range(n)]
    # The residual errors e = δ̂ − δ = P·(errors of the point means), P = I − H the residual
    # projector of the line (they do not depend on the true curve), C = P·diag(u²)·P.
    proj = np.eye(n) - 1.0 / n - np.outer(xc, xc) / sxx
    var_e = np.einsum("ij,j,ij->i", proj, u_pt**2, proj)  # diagonal of C (output unit²)
    to_nl = 100.0 / fs  # %FS per (output unit / |S|)
    # The base of the re-measurements (parametric bootstrap): the residuals shrunk toward the
    # line so that their sum of squares is the unbiased estimate |δ̂|² − tr C of the true one
    # (E|δ̂|² = |δ|² + tr C, C = P·diag(u²)·P): re-measuring δ̂ itself would count its noise
    # twice. Only when the noise level is known apart from the nonlinearity (n_i ≥ 2); with one
    # sample per point the noise is the scatter about the line itself (then tr C = |δ̂|²), and
    # the data are re-measured as they are, without a bias correction.
    known_noise = not h3
    ss_res = float(resid @ resid)
    shrink = (
        math.sqrt(max(0.0, 1.0 - float(var_e.sum()) / ss_res))
        if known_noise and ss_res > 0
        else 1.0
    )
    base = shrink * resid

    def line_errors(err: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Slope error, intercept error and residual errors P·err of point-mean errors (N, M)."""
        m = err.mean(axis=0)
        ds = c_s @ err
        return ds, m - ds * xbar, err - m - xc[:, None] * ds

    def model(**kw: np.ndarray) -> dict[str, np.ndarray]:
        z = np.stack([kw[k] for k in z_names])  # (N, M): normal part, one row per rate point
        et = z * np.stack([kw[k] for k in w_names])  # the t errors
        e = kw.get("eps", eps)
        ds, db, pe = line_errors(z if heavy else et)
        sf = (s_fit + ds) / (1.0 + e)
        out = {
            "scale factor S": sf,
            "bias V0": v0 + db,
            "nonlinearity NL": to_nl * np.max(np.abs(base[:, None] + pe), axis=0) / np.abs(sf),
        }
        if known_noise:  # the bias: the Type A noise alone at its estimated level, ε at its mean
            _, _, pz = line_errors(z)
            out["max|δ| noise only"] = np.max(np.abs(base[:, None] + pz), axis=0)
        return out

    batch = max(10_000, (4_000_000 // max(n, 1)) // 10_000 * 10_000)
    mc = monte_carlo(model, inputs, trials=mc_trials, seed=_MC_SEED, batch=batch)
    assert isinstance(mc, dict)
    budgets: dict[str, UncertaintyBudget] = {}
    few = (
        f"the point means have ν ≤ {_MC_MIN_DOF:g} (≤ {_MC_MIN_DOF + 1:g} samples, or a line "
        "of few points): the Monte Carlo re-measures them normal (a t with ν ≤ 4 has no settled "
        "standard deviation), so u(NL) leaves out the small-ν widening and S and V0 are not "
        "validated by it; the interval for the true NL keeps the t."
    )
    flat = int(np.count_nonzero(u_pt == 0))
    flat_note = (
        f"{flat} of the {n} points have identical samples and no visible output grid: the "
        "rounding of their means (the output's resolution) is not known here and is not included."
        if flat
        else None
    )
    for key, gum, extra in (("scale_factor", gum_s, s_notes), ("bias", gum_b, b_notes)):
        m = mc[gum.names_out[0]]
        more = list(extra) + ([flat_note] if flat_note else [])
        if float(gum.u[0]) > 0 and m.u > 0 and not heavy:
            budgets[key] = validated(gum, m, more)
        else:
            b = gum.budget(0)
            budgets[key] = dataclasses.replace(
                b, notes=b.notes + tuple(more) + ((few,) if heavy else ())
            )

    m_nl: MonteCarloResult = mc["nonlinearity NL"]
    w_dists = [TScale(float(v)) for v in (nu_pt[:1] if h3 else nu_pt)]
    lo, hi, se_lo, se_hi, n_cand = _nl_interval(
        resid, u_pt, w_dists, xc, sxx, s_fit, eps_dist, fs, mc_trials
    )
    rows = []
    u_eps_part = 0.0
    if eps_in is not None:
        sens = nl / (1.0 + eps)  # NL ∝ (1 + ε): ∂NL/∂ε
        u_eps_part = abs(sens) * eps_in.u
    u_pts_part = math.sqrt(max(m_nl.u**2 - u_eps_part**2, 0.0))
    u2 = m_nl.u**2
    rows.append(
        BudgetRow(
            source=f"point means at the {n} rates",
            value=math.nan,
            unit=ou,
            distribution="multivariate t (GUM H.3)" if h3 else "t, one per point",
            u=math.nan,
            sensitivity=math.nan,
            contribution=u_pts_part,
            share=u_pts_part**2 / u2 if u2 > 0 else 0.0,
            dof=float(np.min(nu_pt)),
            origin=basis.replace(" through the line", ""),
        )
    )
    if eps_in is not None:
        rows.append(
            BudgetRow(
                source=eps_in.name,
                value=eps_in.value,
                unit="",
                distribution=eps_in.description or eps_in.distribution,
                u=eps_in.u,
                sensitivity=nl / (1.0 + eps),
                contribution=u_eps_part,
                share=u_eps_part**2 / u2 if u2 > 0 else 0.0,
                dof=eps_in.dof,
                origin=eps_in.source,
            )
        )
    nl_notes = [
        "NL = 100·max|δ|/(|S|·FS) is a maximum of absolute residuals: noise in the point means "
        "biases it upward (as a magnitude near zero, JCGM 102), and first-order propagation does "
        f"not apply. Monte Carlo (JCGM 101), M = {m_nl.trials} trials (seed {_MC_SEED}) over the "
        "point means and the inputs below; u is the standard deviation of NL re-measured "
        "(parametric bootstrap, JCGM 101 §7.6).",
        f"95 % interval for the TRUE NL: [{lo:.4g}, {hi:.4g}] %FS. The residual errors "
        "e = δ̂ − δ do not depend on the true curve, and max|δ̂| − max_K|e_j| ≤ max|δ| ≤ "
        "max|δ̂| + |e_j*| (j* where the true |δ| peaks; K the points that can hold the peak of "
        f"the true residuals or of the measured ones, here {n_cand} of {n}): the lower end is "
        "max|δ̂| less the 97.5 % quantile of max_K|e_j|, the upper end max|δ̂| plus the largest "
        "97.5 % quantile of e_j in K, both over |S|·FS drawn with S (Monte Carlo, t-distributed "
        "point means) — each end holds with probability ≥ 97.5 % (less 0.1 % for choosing K) "
        "whatever the true NL, also at 0; conservative when the peak is clear. Monte Carlo "
        f"standard errors of the ends ≈ {se_lo:.2g} and {se_hi:.2g} %FS. U is half the "
        "interval's width and k = U/u.",
    ]
    if lo == 0.0:
        nl_notes.append(
            "the residuals are consistent with noise alone (the interval reaches 0): the firm "
            f"statement is the upper end, true NL ≤ {hi:.4g} %FS (p ≥ 97.5 %)."
        )
    bias = math.nan
    if known_noise:
        m_b = mc["max|δ| noise only"]
        a_base = float(np.max(np.abs(base)))
        bias = to_nl * (float(m_b.value) - a_base) / abs(s_fit / (1.0 + eps))
        se_b = to_nl * float(m_b.u) / math.sqrt(m_b.trials) / abs(s_fit / (1.0 + eps))
        nl_notes.append(
            "u and the bias re-measure the residuals shrunk toward the line by the factor "
            f"{shrink:.3g} = √max(0, 1 − tr C/|δ̂|²), which makes their sum of squares the "
            "unbiased estimate |δ̂|² − tr C of the true one (C the covariance of the residual "
            "errors): re-measuring δ̂ itself would count its noise twice. Bias from the noise of "
            "the point means (Type A: its level is the spread of the samples at each rate) "
            f"{bias:+.2g} %FS (Monte Carlo standard error ≈ {se_b:.1g} %FS); bias-corrected NL = "
            f"max(NL − bias, 0) = {max(nl - bias, 0.0):.4g} %FS. A specification (Type B) does "
            "not enter the correction."
        )
        if bias > 0.1 * nl:
            nl_notes.append(
                "the noise makes up much of the plain NL: the bias-corrected value is "
                "approximate; the interval stays valid."
            )
    else:
        nl_notes.append(
            "not bias-corrected: with one sample per point the noise level is the scatter of the "
            "points about the line, which holds the nonlinearity too (an upper bound of the "
            f"noise, not its level); u re-measures the residuals as they are, and the firm "
            f"statement is the upper end, true NL ≤ {hi:.4g} %FS."
        )
    nl_notes.append(
        "contributions: the point means' part is the Monte Carlo u less the set-rate part; the "
        "set-rate part is first order (NL ∝ 1 + ε). A maximum has no sensitivity coefficient "
        "for the point means (—)."
    )
    nl_notes += s_notes
    if heavy:
        nl_notes.append(few)
    if flat_note:
        nl_notes.append(flat_note)
    b_nl = monte_carlo_budget("nonlinearity NL", "%FS", nl, m_nl, rows, nl_notes)
    big_u = 0.5 * (hi - lo)
    if n > 2:  # two points fit the line exactly: NL = 0 says nothing of the truth, no budget
        budgets["nonlinearity_percent_fs"] = dataclasses.replace(
            b_nl,
            U=big_u,
            k=big_u / b_nl.u if b_nl.u > 0 else b_nl.k,
            interval=(lo, hi),
        )
    else:
        bias = math.nan

    # lack of fit: do the points scatter about the line more than their noise explains?
    lof = None
    if not h3 and n > 2:
        var_mean = float(np.mean(u_pt**2))
        if var_mean > 0:
            ratio = float(resid @ resid) / ((n - 2) * var_mean)
            if ratio > float(stats.chi2.ppf(_LACK_OF_FIT_P, n - 2)) / (n - 2):
                s2 = float(resid @ resid) / (n - 2)
                u_h3 = math.sqrt(s2 / sxx) / abs(1.0 + eps)
                lof = (
                    f"lack of fit: the point means scatter about the line {math.sqrt(ratio):.3g} "
                    "times more (rms) than their standard errors explain. That is the "
                    "nonlinearity NL reports (Kokuyama et al. 2015's δ(Ω)) or drift between the points; only "
                    "drift is an uncertainty of S, and u(S) does not hold it — repeat the test to "
                    f"tell. The scatter about the line (GUM H.3) would give u(S) = {u_h3:.2g} "
                    f"{unit_s}."
                )
    return budgets, bias, lof
