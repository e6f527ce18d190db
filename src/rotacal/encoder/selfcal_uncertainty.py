"""Uncertainty of a self-calibrated deviation curve (GUM, JCGM 100; Monte Carlo, JCGM 101): the
noise model order by order, the budget of every point, the budgets of the peak-to-peak and rms,
and the head placements' Type A uncertainty (Kokuyama et al. 2015, §3, Figure 5)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rotacal.uncertainty import Input, InstrumentSpecs, UncertaintyBudget, propagate
from rotacal.uncertainty.specs import TYPE_A_ONLY_NOTE, spec_input
from rotacal.uncertainty.summaries import (
    COVERAGE,
    CirculantError,
    ErrorProcess,
    drop_large_dof_notes,
    mc_budget,
    rms_budget,
)

FloatArray = NDArray[np.float64]

__all__ = ["UNDETECTABLE_SPEC", "DeviationNoise", "undetectable_input"]

#: Specification of the deviation at the orders the heads cannot see.
UNDETECTABLE_SPEC = "encoder.undetectable_harmonics_arcsec"
#: Half-width (orders) of the moving average that smooths the noise spectrum of the curve.
_SPECTRUM_SMOOTH = 8


def undetectable_input(specs: InstrumentSpecs | None) -> tuple[Input | None, str | None]:
    """The budget row of ``encoder.undetectable_harmonics_arcsec`` and, when its stated mean is
    not 0, the note on how it is used; (None, None) when it is not stated.

    The specification is the rms of the scale's deviation at the orders no head arrangement sees.
    Their phases are unknown, so a stated mean cannot be a correction of the curve: the rms used
    is √(mean² + u²), the root mean square of the stated distribution (GUM §3.2.4 asks to correct
    for a known systematic effect; here the known part raises the rms the truth holds).
    """
    inp = spec_input(
        specs,
        UNDETECTABLE_SPEC,
        name="orders no head arrangement sees (multiples of n)",
        unit="arcsec",
    )
    if inp is None or inp.value == 0.0:
        return inp, None
    rms = math.hypot(inp.value, inp.u)
    note = (
        f"{UNDETECTABLE_SPEC} is stated with mean {inp.value:g} arcsec: the orders' phases are "
        f"unknown, so it is not a correction of the curve; their rms is taken as "
        f"√(mean² + u²) = {rms:.3g} arcsec (the row shows the stated mean and u)."
    )
    return dataclasses.replace(inp, u=rms, description=f"{inp.description}; rms {rms:.3g}"), note


def _order_weights(m: int) -> FloatArray:
    """Weight of each rfft order in a sum of squares over the lines (Parseval): 2, 1 at 0, m/2."""
    w = np.full(m // 2 + 1, 2.0)
    w[0] = 1.0
    if m % 2 == 0:
        w[-1] = 1.0
    return w


@dataclasses.dataclass(frozen=True)
class DeviationNoise:
    """What the error of a self-calibrated deviation curve may be, order by order.

    The curve's estimator is the same linear fit at every Fourier order, so its error is a
    stationary random curve: Gaussian rfft coefficients, independent between orders, whose
    variances say everything. The error at the orders no head arrangement can see is a second,
    independent curve with a stated rms (Type B).

    Attributes
    ----------
    pulses_per_rev : int
        m.
    variance : ndarray, shape (m//2 + 1,), arcsec²
        E|ε_q|² of the rfft coefficient (numpy's unnormalised rfft) of the measured curve's error
        at order q; 0 at the undetectable orders and at order 0 (the curve has zero mean).
    undetectable : ndarray of bool, shape (m//2 + 1,)
        Orders the heads cannot see (their part of the true deviation is not in the curve).
    undetectable_u : float, arcsec
        Standard deviation, at any line, of the true deviation's part at those orders (0: not
        stated).
    """

    pulses_per_rev: int
    variance: FloatArray
    undetectable: NDArray[np.bool_]
    undetectable_u: float = 0.0

    @property
    def point_u(self) -> float:
        """Standard deviation (arcsec) of the detectable error at any line: √(Σ w_q v_q)/m."""
        m = self.pulses_per_rev
        return math.sqrt(float(np.sum(_order_weights(m) * self.variance))) / m

    @classmethod
    def white(
        cls, pulses_per_rev: int, point_u: float, undetectable_u: float = 0.0
    ) -> DeviationNoise:
        """A white error curve of standard deviation ``point_u`` (arcsec) at every line (all
        orders but 0), when only the per-point uncertainty is known (a selfcal JSON)."""
        m = pulses_per_rev
        w = _order_weights(m)
        var = np.full(m // 2 + 1, 1.0)
        var[0] = 0.0
        var *= (point_u * m) ** 2 / float(np.sum(w * var))
        return cls(m, var, np.zeros(m // 2 + 1, dtype=bool), float(undetectable_u))

    def undetectable_variance(self) -> FloatArray:
        """E|c_q|² of a curve at the undetectable orders with rms ``undetectable_u`` (white
        across them; every order but 0 when none is marked)."""
        m = self.pulses_per_rev
        mask = self.undetectable.copy()
        mask[0] = False
        if not mask.any():
            mask = np.ones_like(mask)
            mask[0] = False
        w = _order_weights(m)
        return np.where(mask, (self.undetectable_u * m) ** 2 / float(np.sum(w[mask])), 0.0)

    def autocov(self, *, undetectable: bool = False) -> FloatArray:
        """Autocovariance c(k), k = 0 … m − 1 (arcsec²), of the curve's error along the lines
        (``undetectable``: of the true deviation's part at the undetectable orders)."""
        var = self.undetectable_variance() if undetectable else self.variance
        return np.fft.irfft(var, self.pulses_per_rev) / self.pulses_per_rev


def _smooth_spectrum(var: FloatArray, keep: NDArray[np.bool_]) -> FloatArray:
    """Moving average of ``var`` over ±_SPECTRUM_SMOOTH neighbouring kept orders (others 0)."""
    out = np.zeros_like(var)
    idx = np.flatnonzero(keep)
    if idx.size == 0:
        return out
    vals = var[idx]
    c = np.concatenate(([0.0], np.cumsum(vals)))
    pos = np.arange(idx.size)
    lo = np.maximum(pos - _SPECTRUM_SMOOTH, 0)
    hi = np.minimum(pos + _SPECTRUM_SMOOTH + 1, idx.size)
    out[idx] = (c[hi] - c[lo]) / (hi - lo)
    return out


def _order_spread(per_rev: FloatArray, deviation: FloatArray) -> FloatArray:
    """Σ_r |rfft(per_rev[r] − deviation)|² per order (arcsec²): the revolutions' spread about
    their mean, order by order — all the budget needs of the single-revolution curves."""
    resid = np.fft.rfft(per_rev - deviation, axis=-1)
    return np.asarray(np.sum(np.abs(resid) ** 2, axis=0), dtype=np.float64)


def _repeatability_rms(spread: FloatArray, revs: int, m: int) -> float:
    """rms over revolutions and lines of each revolution's curve minus the mean (arcsec), from
    :func:`_order_spread` by Parseval: Σ_j x_j² = Σ_q w_q |X_q|²/m."""
    return math.sqrt(float(np.sum(_order_weights(m) * spread)) / (m * m * revs))


def _deviation_uncertainty(
    spread: FloatArray,
    revs: int,
    deviation: FloatArray,
    undetect: list[int],
    specs: InstrumentSpecs | None,
) -> tuple[DeviationNoise | None, UncertaintyBudget | None, dict[str, Any]]:
    """Noise model, per-point budget and the budgets of the peak-to-peak and rms.

    With two or more revolutions the curve's noise comes from their spread (Type A; ``spread``
    is :func:`_order_spread` of the R single-revolution curves); with one, only a stated
    ``encoder.undetectable_harmonics_arcsec`` can be budgeted (no budget without).

    Returns
    -------
    noise : DeviationNoise or None
    point : UncertaintyBudget or None
    summaries : dict
        ``{"deviation_pp_arcsec": Summary, "deviation_rms_arcsec": Summary}`` (empty without any
        input).

    References
    ----------
    JCGM 100:2008 (GUM) §4.2 (Type A: the mean of R revolutions, s²/R), §4.3 (Type B), G.4
    (Welch–Satterthwaite over the orders); JCGM 101:2008 §7 (Monte Carlo of the peak-to-peak).
    """
    m = deviation.size
    w = _order_weights(m)
    und = np.zeros(m // 2 + 1, dtype=bool)
    und[np.asarray(undetect, dtype=np.int64)] = True
    und_input, und_note = undetectable_input(specs)
    u_und = und_input.u if und_input is not None else 0.0
    inputs: list[Input] = []
    notes: list[str] = []
    noise: DeviationNoise | None = None
    nu_a = math.inf
    if revs >= 2:
        var = spread / ((revs - 1) * revs)  # of the mean's orders
        keep = ~und
        keep[0] = False
        var = np.where(keep, var, 0.0)
        total = float(np.sum(w * var))
        smooth = _smooth_spectrum(var, keep)
        s_total = float(np.sum(w * smooth))
        if s_total > 0:
            smooth *= total / s_total
        # Welch–Satterthwaite over the orders: each order's variance has 2(R − 1) degrees of
        # freedom (R − 1 for the real Nyquist order), the pooled one their effective number
        nu_q = np.where(w == 2.0, 2.0 * (revs - 1), float(revs - 1))
        den = float(np.sum((w * smooth) ** 2 / nu_q))
        nu_a = (float(np.sum(w * smooth)) ** 2 / den) if den > 0 else math.inf
        noise = DeviationNoise(m, smooth if s_total > 0 else var, und, u_und)
        inputs.append(
            Input(
                name=f"repeatability over {revs} revolutions",
                value=0.0,
                u=math.sqrt(total) / m,
                dof=nu_a,
                distribution="normal",
                unit="arcsec",
                source=f"Type A, the spread of {revs} single-revolution curves pooled over the lines",
                description="normal (per order, from the revolutions' spread)",
            )
        )
    elif und_input is None:
        return None, None, {}
    else:
        notes.append(
            "one whole revolution: the curve's own noise cannot be estimated from the data and is "
            "not in this budget (record several revolutions); only the stated specification is."
        )
    if und_input is not None:
        inputs.append(und_input)
        if und_note:
            notes.append(und_note)
    else:
        notes.append(
            "the orders that are multiples of the number of heads are neither in the curve nor in "
            f"its uncertainty; state {UNDETECTABLE_SPEC} to include them."
        )
    if specs is None:
        notes.append(TYPE_A_ONLY_NOTE)
    gum = propagate(
        lambda *x: float(sum(x)),
        [dataclasses.replace(inp, value=0.0) for inp in inputs],  # errors about their estimates
        p=COVERAGE,
        names_out=["deviation_arcsec (every line)"],
        units_out=["arcsec"],
    )
    point = drop_large_dof_notes(gum.budget(0))
    point = dataclasses.replace(
        point,
        rows=tuple(
            dataclasses.replace(row, value=inp.value)
            for row, inp in zip(point.rows, inputs, strict=True)
        ),
        notes=(
            *point.notes,
            "the fit is the same at every Fourier order, so every line has this uncertainty"
            + (
                f" (ν = {nu_a:.4g} from the spread of every detectable order, Welch–Satterthwaite)."
                if revs >= 2
                else "."
            ),
            *notes,
        ),
    )

    # the curve holds its noise (it biases pp and rms) but lacks the undetectable orders
    sources: list[ErrorProcess] = []
    if noise is not None:
        sources.append(CirculantError(inputs[0], "noise", autocov=noise.autocov()))
    if und_input is not None:
        model = noise or DeviationNoise(m, np.zeros(m // 2 + 1), und, u_und)
        sources.append(
            CirculantError(und_input, "absent", autocov=model.autocov(undetectable=True))
        )
        notes.append(
            f"{UNDETECTABLE_SPEC} is taken as a random curve over the undetectable orders with "
            "the stated rms (white across them)."
        )
    summaries = {
        "deviation_pp_arcsec": mc_budget(
            "deviation_pp_arcsec", "arcsec", deviation, sources, statistic="pp", notes=notes
        ),
        "deviation_rms_arcsec": rms_budget(
            "deviation_rms_arcsec", "arcsec", deviation, sources, notes=notes
        ),
    }
    return noise, point, summaries


def _head_offsets_u(per_rev: FloatArray) -> tuple[list[float] | None, float | None]:
    """Type A standard uncertainty (arcsec) of each head's placement and its degrees of freedom.

    ``per_rev`` holds each whole revolution's mean head difference (arcsec) of heads 1 … n−1
    against head 0, shape (R, n−1). Over a whole revolution the scale deviation averages out, so
    each revolution's mean difference is one reading of the placement; u = s/√R with s their
    standard deviation, ν = R − 1 (GUM §4.2.2–4.2.3). Head 0 is the reference: u = 0.
    """
    revs = per_rev.shape[0]
    if revs < 2:
        return None, None
    u = per_rev.std(axis=0, ddof=1) / math.sqrt(revs)
    return [0.0, *(float(x) for x in u)], float(revs - 1)


def _bias(summaries: Mapping[str, Any], key: str, corrected: bool = False) -> float | None:
    if key not in summaries:
        return None
    sm = summaries[key]
    return sm.bias_corrected if corrected else sm.bias
