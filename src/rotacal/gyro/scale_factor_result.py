"""The result of a gyro's scale-factor test: the rate points and :class:`ScaleFactorResult`."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from rotacal.gyro.resolution import OutputResolution
from rotacal.gyro.scale_factor_requirement import DecisionWithU, RequirementVerdict
from rotacal.gyro.sf_items import ScaleFactorRepeatability, SignedScaleFactors
from rotacal.gyro.sf_temperature import TemperatureCoefficients
from rotacal.gyro.uncertainty import uncertainty_json
from rotacal.results import Result, to_jsonable
from rotacal.uncertainty.budget import UncertaintyBudget

__all__ = ["RatePoint", "ScaleFactorResult"]

_SIGNED_KEYS = [f.name for f in dataclasses.fields(SignedScaleFactors)]


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
    #: the IEEE Std 952/1431 items (rotacal.gyro.sf_items, rotacal.gyro.sf_temperature), their
    #: keys at the top level of the JSON (those of ``signed`` always, null when not found)
    signed: SignedScaleFactors | None = None
    repeatability: ScaleFactorRepeatability | None = None
    temperature: TemperatureCoefficients | None = None

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
        for name in ("signed", "repeatability", "temperature"):
            item = out.pop(name) or {}
            item.pop("warnings", None)  # the result's own warnings hold theirs
            out.update(item)
        if self.signed is None:
            out.update(dict.fromkeys(_SIGNED_KEYS))
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
