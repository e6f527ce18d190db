"""Positioning accuracy and repeatability of an axis by ISO 230-2, applied to a rotary axis.

ISO 230-2:2014 ("Test code for machine tools — Part 2: Determination of accuracy and repeatability
of positioning of numerically controlled axes", clause 3, terms and definitions; it applies to
rotary axes with angles in place of lengths) defines, from the positional deviations
x_ij = P_ij − P_i (actual minus target position) of approach j = 1 … n to target position i,
for each direction of approach (↑ positive, ↓ negative):

* mean unidirectional positional deviation  x̄_i↑ = (1/n) Σ_j x_ij↑;
* mean bidirectional positional deviation   x̄_i = (x̄_i↑ + x̄_i↓)/2;
* reversal value at a position              B_i = x̄_i↑ − x̄_i↓;  of the axis B = max |B_i|,
  mean reversal value B̄ = (1/m) Σ_i B_i;
* estimator of unidirectional repeatability s_i↑ = √(Σ_j (x_ij↑ − x̄_i↑)²/(n − 1));
* unidirectional repeatability              R_i↑ = 4 s_i↑ (the width of ±2s), R↑ = max R_i↑;
* bidirectional repeatability               R_i = max(2s_i↑ + 2s_i↓ + |B_i|, R_i↑, R_i↓),
  R = max R_i;
* unidirectional systematic positional deviation of the axis E↑ = max x̄_i↑ − min x̄_i↑;
* bidirectional systematic positional deviation E = max(x̄_i↑, x̄_i↓) − min(x̄_i↑, x̄_i↓);
* range of the mean bidirectional positional deviation M = max x̄_i − min x̄_i;
* unidirectional accuracy A↑ = max(x̄_i↑ + 2s_i↑) − min(x̄_i↑ − 2s_i↑);
* bidirectional accuracy A = max(x̄_i↑ + 2s_i↑, x̄_i↓ + 2s_i↓) − min(x̄_i↑ − 2s_i↑, x̄_i↓ − 2s_i↓).

The standard's test cycle approaches every target position five times in each direction; fewer
runs are evaluated with a warning. Uncertainties (not part of ISO 230-2; GUM, JCGM 100:2008 §5.1.2,
first order): u²(x̄_i↑) = s_i↑²/n + u_ref,i² with u_ref,i the reference's standard uncertainty at
the position (the same for both directions, so it cancels in B_i); u(s) = s/√(2(n − 1)) (normal
readings); a maximum or a range takes the u of the positions that decide it. With one run (or no
residual left) the scatter is unknown and the u are NaN (``null`` in the JSON).

Each value's effective degrees of freedom (GUM G.4.1, Welch–Satterthwaite) count the readings'
scatter at each deciding position as a component with ν_s = n − 1 (fewer when a polygon's face
errors were estimated from the same readings) and the reference's u as exactly known: with the
standard's five runs ν_s = 4 and, where the scatter dominates, k = t₉₅(4) = 2.78, not 2.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["AXIS_VALUES", "ISO_RUNS", "AxisStatistics", "axis_statistics", "scatter_dof"]

#: Approaches per position and direction in ISO 230-2's standard test cycle.
ISO_RUNS = 5

FloatArray = NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class AxisStatistics:
    """ISO 230-2 values (arcsec) and their standard uncertainties (``…_u``, arcsec).

    ``mean[d]``/``std[d]`` are x̄_i and s_i per direction d (``std`` None with one run); the
    axis values are None where their inputs are missing (one direction: no B, R, E, M, A of the
    bidirectional kind; one run: no repeatability or accuracy).
    """

    mean: FloatArray  # (D, P)
    mean_u: FloatArray  # (D, P)
    std: FloatArray | None  # (D, P)
    std_u: FloatArray | None
    curve: FloatArray  # x̄_i (bidirectional) or x̄_i of the one direction, (P,)
    curve_u: FloatArray
    values: dict[str, float | None]
    values_u: dict[str, float | None]
    values_dof: dict[str, float | None]  # effective ν of each u (inf: no scatter in it)
    curve_scatter: FloatArray  # the readings' scatter's share of curve_u², (D, P): by direction
    dof_scatter: float  # ν of that scatter at one position


def scatter_dof(u: float, scatter: list[float], nu: float) -> float | None:
    """Effective degrees of freedom of a standard uncertainty ``u`` (arcsec) whose variance
    holds the readings' scatter ``scatter`` (variances in arcsec², one per deciding position,
    each with ``nu`` degrees of freedom) and otherwise exactly known Type B parts (ν = ∞);
    None for an undefined u.

    References
    ----------
    JCGM 100:2008 (GUM), G.4.1, eq. (G.2b) (Welch–Satterthwaite).
    """
    if not math.isfinite(u):
        return None
    denominator = sum(v * v for v in scatter) / nu
    return math.inf if not denominator > 0 else u**4 / denominator


def _range(
    hi: FloatArray,
    hi_u: FloatArray,
    lo: FloatArray,
    lo_u: FloatArray,
    hi_scatter: FloatArray,
    lo_scatter: FloatArray,
) -> tuple[float, float, list[float]]:
    """max(hi) − min(lo), its u and the independent scatter variances in it (``*_scatter``:
    components × elements), from the two elements that decide it."""
    a, b = int(np.argmax(hi)), int(np.argmin(lo))
    scatter = [*hi_scatter[:, a].tolist(), *lo_scatter[:, b].tolist()]
    return float(hi[a] - lo[b]), float(math.hypot(hi_u[a], lo_u[b])), scatter


#: The axis values :func:`axis_statistics` gives (names of the JSON keys, less ``_arcsec``).
AXIS_VALUES = (
    "systematic_deviation_forward",
    "systematic_deviation_reverse",
    "systematic_deviation_bidirectional",
    "mean_deviation_range",
    "reversal_value",
    "reversal_value_mean",
    "repeatability_forward",
    "repeatability_reverse",
    "repeatability_bidirectional",
    "positioning_accuracy_forward",
    "positioning_accuracy_reverse",
    "positioning_accuracy_bidirectional",
)


def axis_statistics(
    x: FloatArray,
    u_ref: FloatArray,
    *,
    directions: tuple[int, ...] = (1, -1),
    std_scale: float | None = 1.0,
) -> AxisStatistics:
    """ISO 230-2 statistics of positional deviations ``x[d, r, p]`` (arcsec).

    Parameters
    ----------
    x : ndarray (D, R, P), arcsec
        Positional deviation of run r at target position p, direction d (d = 0: ↑, 1: ↓).
    u_ref : ndarray (P,), arcsec
        Standard uncertainty of the reference at each position (Type B), 0 when none stated.
    directions : tuple of int
        The sign of approach of each row of ``x`` (+1 ↑, −1 ↓).
    std_scale : float
        Factor on every s_i: √(ν_ISO/ν_model) when parameters (a polygon's face errors, run
        offsets) were estimated from the same readings, so that s_i² stays unbiased; None when
        those estimates leave no residual (no s_i then, as with one run).
    """
    n_dir, n_runs, _ = x.shape
    mean = x.mean(axis=1)
    std = std_u = None
    # without repeated approaches the readings' scatter is unknown, and so is every u below
    var_of_mean = np.full_like(mean, np.nan)
    nu = math.nan
    if n_runs > 1 and std_scale is not None:
        std = x.std(axis=1, ddof=1) * std_scale
        std_u = std / math.sqrt(2.0 * (n_runs - 1))
        var_of_mean = std**2 / n_runs
        nu = (n_runs - 1) / std_scale**2  # a model fitted to the same readings took some
    mean_u = np.sqrt(var_of_mean + u_ref[None, :] ** 2)
    values: dict[str, float | None] = dict.fromkeys(AXIS_VALUES)
    values_u: dict[str, float | None] = dict.fromkeys(AXIS_VALUES)
    values_dof: dict[str, float | None] = dict.fromkeys(AXIS_VALUES)

    def put(name: str, value: float, u: float, scatter: list[float]) -> None:
        values[name], values_u[name] = value, u
        values_dof[name] = scatter_dof(u, scatter, nu)

    for d, sign in enumerate(directions):
        word = "forward" if sign > 0 else "reverse"
        put(
            f"systematic_deviation_{word}",
            *_range(
                mean[d],
                mean_u[d],
                mean[d],
                mean_u[d],
                var_of_mean[d : d + 1],
                var_of_mean[d : d + 1],
            ),
        )
        if std is not None and std_u is not None:
            k = int(np.argmax(std[d]))
            u = 4.0 * float(std_u[d, k])
            put(f"repeatability_{word}", 4.0 * float(std[d, k]), u, [u * u])
            hi_u = np.hypot(mean_u[d], 2.0 * std_u[d])
            # x̄ and s of one position and direction: one estimate of σ², one component
            hi_scatter = (var_of_mean[d] + 4.0 * std_u[d] ** 2)[None, :]
            put(
                f"positioning_accuracy_{word}",
                *_range(
                    mean[d] + 2 * std[d], hi_u, mean[d] - 2 * std[d], hi_u, hi_scatter, hi_scatter
                ),
            )

    def finish(curve: FloatArray, curve_u: FloatArray, curve_scatter: FloatArray) -> AxisStatistics:
        return AxisStatistics(
            mean, mean_u, std, std_u, curve, curve_u, values, values_u, values_dof,
            curve_scatter, nu,
        )  # fmt: skip

    if n_dir == 1:
        return finish(mean[0], mean_u[0], var_of_mean)
    # bidirectional: the reference's own error is common to ↑ and ↓ and cancels in B_i
    b_i = mean[0] - mean[1]
    b_u = np.sqrt(var_of_mean[0] + var_of_mean[1])
    k = int(np.argmax(np.abs(b_i)))
    put("reversal_value", float(abs(b_i[k])), float(b_u[k]), var_of_mean[:, k].tolist())
    b_mean_scatter = (var_of_mean / b_i.size**2).ravel().tolist()
    put("reversal_value_mean", float(b_i.mean()), math.sqrt(sum(b_mean_scatter)), b_mean_scatter)
    curve = 0.5 * (mean[0] + mean[1])
    curve_scatter = 0.25 * var_of_mean
    curve_u = np.sqrt(curve_scatter.sum(axis=0) + u_ref**2)
    put(
        "mean_deviation_range",
        *_range(curve, curve_u, curve, curve_u, curve_scatter, curve_scatter),
    )
    flat_mean, flat_u, flat_scatter = mean.ravel(), mean_u.ravel(), var_of_mean.reshape(1, -1)
    put(
        "systematic_deviation_bidirectional",
        *_range(flat_mean, flat_u, flat_mean, flat_u, flat_scatter, flat_scatter),
    )
    if std is not None and std_u is not None:
        both = 2 * std[0] + 2 * std[1] + np.abs(b_i)
        both_u = np.sqrt(4 * std_u[0] ** 2 + 4 * std_u[1] ** 2 + b_u**2)
        cands = np.stack([both, 4 * std[0], 4 * std[1]])
        cands_u = np.stack([both_u, 4 * std_u[0], 4 * std_u[1]])
        # each direction's x̄ and s at a position are one estimate of σ²: one component each
        by_direction = var_of_mean + 4.0 * std_u**2
        which, at = divmod(int(np.argmax(cands)), cands.shape[1])
        if which == 0:
            scatter = by_direction[:, at].tolist()
        else:
            scatter = [float(cands_u[which, at]) ** 2]
        value, u = float(cands[which, at]), float(cands_u[which, at])
        put("repeatability_bidirectional", value, u, scatter)
        hi_u = np.hypot(mean_u, 2.0 * std_u).ravel()
        hi_scatter = by_direction.reshape(1, -1)
        put(
            "positioning_accuracy_bidirectional",
            *_range(
                (mean + 2 * std).ravel(),
                hi_u,
                (mean - 2 * std).ravel(),
                hi_u,
                hi_scatter,
                hi_scatter,
            ),
        )
    return finish(curve, curve_u, curve_scatter)
