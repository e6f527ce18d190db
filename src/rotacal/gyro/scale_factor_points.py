"""Rate points of a gyro's scale-factor test: grouping by set rate, the output quantum, saturation.

Rows whose set rates lie within a tolerance of their sorted neighbour are one rate point (single
linkage, ``_group``); :func:`output_quantum` finds the grid the recorded values lie on;
``_check_saturation`` refuses outer points where the output stops following the rate
(Kokuyama et al. 2015, §4: the points of the least-squares line).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rotacal.errors import CaptureError

__all__ = ["DEFAULT_RATE_TOLERANCE_DEG_S", "PointData", "output_quantum"]

#: Set rates closer than this (°/s) to their sorted neighbour are one rate point.
DEFAULT_RATE_TOLERANCE_DEG_S = 1e-3
_SHOW_ROWS = 8
#: Samples per rate point examined for an output quantum (see :func:`output_quantum`).
_QUANTUM_SAMPLES = 50_000
# Saturation: a segment between neighbouring outer points whose slope is below this fraction of
# the median slope, by more than _SAT_SIGMAS standard errors, is a saturated output.
_SAT_SLOPE_FRACTION = 0.5
_SAT_SIGMAS = 5.0


def _rows(idx: np.ndarray, count: int | None = None) -> str:
    """The first rows of ``idx`` and how many more (``count``: all of them, default idx.size)."""
    n = idx.size if count is None else count
    shown = ", ".join(str(int(i)) for i in idx[:_SHOW_ROWS])
    more = f" and {n - _SHOW_ROWS} more" if n > _SHOW_ROWS else ""
    return f"{shown}{more}"


@dataclasses.dataclass(frozen=True)
class PointData:
    """What the line, NL, the budgets and the resolution need of the samples, per rate point.

    ``rates`` mean set rate (°/s), ``spread`` max − min set rate (°/s), ``counts`` finite outputs,
    ``means`` and ``std`` (ddof 1, NaN for one sample) of the output (output units), ``quantum``
    q (output units, None: no grid; :func:`output_quantum`), ``noise`` σ_B of each point's block
    means (output units, NaN below two blocks; :mod:`rotacal.gyro.resolution`),
    ``output_abs_max`` the largest finite |output|, ``clipped`` the clipping warnings (analysed
    with ``allow_clipped``), ``notes`` what the reading left out. The same from the whole arrays
    and from a capture streamed in chunks.
    """

    rates: np.ndarray
    spread: np.ndarray
    counts: np.ndarray
    means: np.ndarray
    std: np.ndarray
    quantum: float | None
    noise: np.ndarray
    output_abs_max: float
    clipped: tuple[str, ...]
    notes: tuple[str, ...]


def _fmt_rate(r: float) -> str:
    return f"{r:+.6g} °/s"


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
    return _grid_step(y, g, max_median_steps)


def _grid_step(y: np.ndarray, g: np.ndarray, max_median_steps: float = 4.0) -> float | None:
    """The quantum test of :func:`output_quantum` on finite samples ``y`` with their groups ``g``
    (already thinned to at most ``_QUANTUM_SAMPLES`` per group)."""
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
    low = rs[starts]
    # the mean as the lowest rate plus the mean excess: exact for a rate written identically on
    # every row, and the same sum a streamed capture accumulates
    excess = rs - np.repeat(low, counts)
    rate_mean = low + np.add.reduceat(excess, starts) / counts
    spread = np.maximum.reduceat(rs, starts) - low
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
