"""Plateaus of a continuous rate-table log: where the table holds a rate, and how long the DUT settles.

A real rate-table test is one long log: the table steps through set rates, the DUT's output lags
and rings after each step. :func:`find_plateaus` finds the spans where the table's rate
(``rate_deg_s``, commanded or measured) is steady, drops the first ``settle_s`` seconds of each
(the DUT's transient), rejects spans that are too short (``min_plateau_s`` after settling), whose
table rate is too noisy (σ above 4× the median over the plateaus) or drifts (its last third's mean
differs from its first's by more than 6 standard errors), and
returns the spans used. :func:`plateau_rows` turns them into the rows the rate-table
scale-factor fit takes (each plateau one rate point: its mean table rate on every row).

Method (change detection with a filtered derivative, Basseville & Nikiforov 1993, §2.1): at each
sample boundary k the mean of the h samples after it is compared with the mean of the h samples
before it, D[k] = mean(r[k:k+h]) − mean(r[k−h:k]), both from one cumulative sum (whole-array,
O(n)). A boundary is a change when |D[k]| > z·σ·√(2/h) + r_tol, σ being the table rate's white
noise estimated robustly from its first differences (σ = 1.4826·MAD(Δr)/√2, a few large steps do
not move the median) and r_tol the rate tolerance of a rate point (0.001 °/s, as in
:mod:`rotacal.gyro.scale_factor_points`: a commanded rate is exactly constant, σ = 0). Runs of
samples between changes are the steady spans. A step at sample s makes |D| large for
|k − s| < h, so a run starts ~h samples late; each edge is then moved to the sample where the
rate itself enters its plateau's band, |r − r̄| ≤ z·σ + r_tol, which puts the edge at the step
(commanded rate) or where the ramp reaches the plateau within the noise (measured rate).
Neighbouring runs whose means, and the mean of the rows between them, agree within z standard
errors (of the larger of σ and the runs' own standard deviations) are one plateau (an
outlier sample cannot split a plateau, nor can a plateau noisier than the rest, which is then
judged whole). A run shorter than the window is no plateau (the crest of a ramp or a sine).

The DUT's settling (the default ``settle_s``) is read from the output: within each plateau the
output is averaged in blocks of h/10 samples (short enough to follow a ringing DUT); the band is 5
robust standard deviations (1.4826·MAD) of the block means of the plateau's second half about
their median; the output enters the band after the last pair of consecutive first-half blocks
outside it (a transient lasts, an outlier sample does not). Inside the band the transient still
biases the plateau's mean, so its envelope, taken as exponential from the largest deviation d₀ to
the band, is extended down to a tenth of the plateau mean's standard error (at most half the
plateau). The default ``settle_s`` is the largest settling time over the plateaus, and at least
one window (the DUT lags the table). Rate-table scale-factor procedures (IEEE Std 952, IEEE Std
1431) take the readings at each rate after the output has stabilised; this states how long that
took in the log itself.

References
----------
Basseville M., Nikiforov I. V., *Detection of Abrupt Changes: Theory and Application*, Prentice
Hall (1993), §2.1 (elementary algorithms: the filtered-derivative detector). Kokuyama et al.
(2015), §4 (the rate points of the scale-factor fit).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro.scale_factor_points import DEFAULT_RATE_TOLERANCE_DEG_S
from rotacal.results import Result

__all__ = [
    "DEFAULT_PLATEAU_WINDOW_S",
    "Plateau",
    "PlateauSearch",
    "find_plateaus",
    "plateau_rates",
    "plateau_rows",
]

#: Window of the filtered derivative (s): one second averages the table's noise down and is short
#: against the plateaus of a rate-table test (tens of seconds to minutes).
DEFAULT_PLATEAU_WINDOW_S = 1.0
#: Change threshold in standard errors of D: for Gaussian noise a false change per boundary has a
#: probability ~2·10⁻⁹, and a false change splits a plateau that the merge joins again.
_Z = 6.0
#: Settling band: block means of the plateau's first half farther than this many robust standard
#: deviations of the second half's block means from their median are still settling.
_SETTLE_SIGMAS = 5.0
#: A plateau whose table-rate standard deviation exceeds this many times the median over the
#: plateaus (and the rate tolerance) is too noisy.
_NOISY_FACTOR = 4.0
#: Differences examined for the robust noise estimate (evenly strided): plenty for a MAD.
_NOISE_SAMPLES = 2_000_000


@dataclasses.dataclass(frozen=True)
class Plateau(Result):
    """One span of steady table rate, as used (after settling) or as rejected.

    ``start_s``/``end_s`` the times (s) of the first and last sample used (for a rejected span:
    of the span after settling, or the whole span when nothing is left); ``rate_deg_s`` the mean
    table rate over it (°/s); ``samples`` its rows; ``rate_std_deg_s`` the table rate's standard
    deviation over it (°/s); ``reason`` why it was rejected (empty when used).
    """

    start_s: float
    end_s: float
    rate_deg_s: float
    samples: int
    rate_std_deg_s: float
    reason: str = ""


@dataclasses.dataclass(frozen=True)
class PlateauSearch(Result):
    """The plateaus of a log (:func:`find_plateaus`).

    ``plateaus`` the used ones (time order), ``rejected`` the others with their reason;
    ``settle_s`` the settling time dropped from each plateau's start (s) and ``settle_source``
    where it came from (``"given"`` or ``"output"``); ``window_s`` the filtered derivative's
    window (s); ``rate_noise_deg_s`` σ of the table rate (°/s); ``threshold_deg_s`` the change
    threshold on D (°/s). ``_rows`` holds the [start, stop) row range of each used plateau.
    """

    plateaus: tuple[Plateau, ...]
    rejected: tuple[Plateau, ...]
    settle_s: float
    settle_source: str
    window_s: float
    rate_noise_deg_s: float
    threshold_deg_s: float
    _rows: np.ndarray = dataclasses.field(
        repr=False, compare=False, default_factory=lambda: np.zeros((0, 2), dtype=np.int64)
    )


def _check_log(t: np.ndarray, r: np.ndarray, y: np.ndarray | None) -> None:
    """Refuse a log the detection cannot read: lengths, non-finite values, time not increasing."""
    if t.size != r.size or (y is not None and y.size != t.size):
        raise CaptureError(
            f"columns time_s ({t.size} rows), rate_deg_s ({r.size})"
            + ("" if y is None else f" and output ({y.size})")
            + " must have one row per sample"
        )
    if t.size < 4:
        raise CaptureError(f"the log has {t.size} rows: too few to find plateaus in")
    for name, x in (("time_s", t), ("rate_deg_s", r)):
        bad = np.flatnonzero(~np.isfinite(x))
        if bad.size:
            raise CaptureError(
                f"column {name} holds {x[bad[0]]} at row {bad[0]} (0-based, {bad.size} such): "
                "every row of a continuous log needs a finite time and table rate"
            )
    dt = np.diff(t)
    back = np.flatnonzero(dt <= 0)
    if back.size:
        k = int(back[0])
        raise CaptureError(
            f"column time_s does not increase at row {k + 1} (0-based): {t[k + 1]!r} s after "
            f"{t[k]!r} s ({back.size} such rows); a continuous log needs strictly increasing time"
        )


def _positive(name: str, value: float | None, default: float) -> float:
    v = default if value is None else value
    bad = isinstance(v, bool) or not isinstance(v, (int, float, np.floating))
    if bad or not math.isfinite(v) or v < 0:
        raise ConfigError(f"{name} must be a number ≥ 0 s, got {value!r}")
    return float(v)


def _rate_noise(r: np.ndarray) -> float:
    """σ of the table rate's white noise (°/s): 1.4826·MAD of its first differences over √2."""
    stride = max(1, (r.size - 1) // _NOISE_SAMPLES)
    d = np.diff(r)[::stride]
    med = np.median(d)
    return float(1.4826 * np.median(np.abs(d - med)) / math.sqrt(2.0))


def _steady_runs(r: np.ndarray, h: int, thr: float) -> np.ndarray:
    """[start, stop) rows of the runs between changes (filtered derivative, module docstring)."""
    n = r.size
    c = np.empty(n + 1)
    c[0] = 0.0
    np.cumsum(r - r[0], out=c[1:])  # less the first value: the sums keep their digits
    # D at boundaries k = h … n − h from shifted views (no index arrays): h·D = c[k+h] − 2c[k] + c[k−h]
    d = c[2 * h :] - c[h : n + 1 - h]
    d -= c[h : n + 1 - h]
    d += c[: n + 1 - 2 * h]
    change = np.zeros(n + 1, dtype=bool)  # boundary k: between rows k − 1 and k
    change[h : n - h + 1] = np.abs(d) > thr * h
    # a row is unsteady when the boundary before it is a change (the first h rows follow the
    # first computed boundary, the last h rows the last one)
    unsteady = change[:n].copy()
    unsteady[:h] = change[h]
    unsteady[n - h + 1 :] = change[n - h]
    edges = np.flatnonzero(np.diff(np.r_[1, unsteady.view(np.int8), 1]))
    return edges.reshape(-1, 2).astype(np.int64)


def _refine(r: np.ndarray, runs: np.ndarray, band: float, reach: int) -> np.ndarray:
    """Move each run's edges out to where the rate enters its band (at most ``reach`` rows,
    never into the neighbouring run)."""
    out = runs.copy()
    n = r.size
    for i, (a, b) in enumerate(runs):
        mean = float(np.mean(r[a:b]))
        lo = max(int(out[i - 1, 1]) if i else 0, int(a) - reach)
        far = np.flatnonzero(np.abs(r[lo:a] - mean) > band)
        out[i, 0] = lo + (int(far[-1]) + 1 if far.size else 0)
        hi = min(int(runs[i + 1, 0]) if i + 1 < len(runs) else n, int(b) + reach)
        far = np.flatnonzero(np.abs(r[b:hi] - mean) > band)
        out[i, 1] = b + (int(far[0]) if far.size else hi - b)
    return out


def _merge(r: np.ndarray, runs: np.ndarray, sigma: float, tol: float) -> np.ndarray:
    """Join neighbouring runs whose means, and the mean of the rows between them, agree within
    the change threshold taken with the noisier of σ and the runs' own standard deviations (an
    outlier cannot split a plateau; a plateau noisier than the log is not cut in pieces but
    stays one, to be judged whole)."""
    merged: list[list[int]] = []
    last_mean = last_sd = math.nan
    for a, b in runs:
        mean, sd = float(np.mean(r[a:b])), float(np.std(r[a:b]))
        if merged:
            spread = _Z * max(sigma, sd, last_sd)
            n_last = merged[-1][1] - merged[-1][0]
            same = abs(mean - last_mean) <= spread * math.sqrt(1.0 / (b - a) + 1.0 / n_last) + tol
            gap = r[merged[-1][1] : a]
            if same and gap.size:
                limit = spread * math.sqrt(1.0 / gap.size + 1.0 / n_last) + tol
                same = abs(float(gap.mean()) - last_mean) <= limit
            if same:
                merged[-1][1] = int(b)
                seg = r[merged[-1][0] : b]
                last_mean, last_sd = float(np.mean(seg)), float(np.std(seg))
                continue
        merged.append([int(a), int(b)])
        last_mean, last_sd = mean, sd
    return np.asarray(merged, dtype=np.int64).reshape(-1, 2)


def _drift(seg: np.ndarray) -> float:
    """|mean of the last third − mean of the first third| of a span's table rate (°/s)."""
    k = seg.size // 3
    return abs(float(seg[-k:].mean() - seg[:k].mean())) if k else 0.0


def _drift_limit(n: int, sigma: float, sd: float, tol: float) -> float:
    """z standard errors of the difference of two thirds' means of ``n`` rows (°/s), plus tol."""
    return _Z * max(sigma, sd) * math.sqrt(2.0 / max(n // 3, 1)) + tol


def _settling_rows(y: np.ndarray, runs: np.ndarray, h: int) -> int:
    """The largest settling (rows) of the output over the plateaus (module docstring)."""
    m = max(1, h // 10)  # blocks of a tenth of the window: they follow a ringing DUT
    most = 0
    for a, b in runs:
        nb = (int(b) - int(a)) // m
        if nb < 8:
            continue
        block = y[a : a + nb * m].reshape(nb, m).mean(axis=1)
        tail = block[nb // 2 :]
        ref = float(np.median(tail))
        sd = 1.4826 * float(np.median(np.abs(tail - ref)))
        band = _SETTLE_SIGMAS * sd + 64 * np.finfo(float).eps * abs(ref)
        far = np.abs(block[: nb // 2 + 1] - ref) > band
        # two blocks in a row outside: a transient lasts, an outlier sample does not
        out = np.flatnonzero(far[:-1] & far[1:])
        if not out.size:
            continue
        enter = int(out[-1]) + 2  # blocks until the band
        # the transient still biases the plateau mean inside the band: extend its exponential
        # envelope (from the largest deviation to the band) down to a tenth of the mean's SE
        d0 = float(np.max(np.abs(block[:enter] - ref)))
        target = 0.1 * sd / math.sqrt(nb) + 64 * np.finfo(float).eps * abs(ref)
        if d0 > band > 0 and target < band:
            enter = math.ceil(enter * math.log(d0 / target) / math.log(d0 / band))
        most = max(most, min(enter, nb // 2) * m)
    return most


def find_plateaus(
    time_s: np.ndarray,
    rate_deg_s: np.ndarray,
    output: np.ndarray | None = None,
    *,
    settle_s: float | None = None,
    window_s: float | None = None,
    min_plateau_s: float | None = None,
    rate_tolerance_deg_s: float = DEFAULT_RATE_TOLERANCE_DEG_S,
) -> PlateauSearch:
    """The plateaus of a continuous rate-table log (filtered-derivative change detection).

    Parameters
    ----------
    time_s : array
        Time of each row (s), finite and strictly increasing.
    rate_deg_s : array
        The table's rate on each row (°/s), commanded or measured (noisy).
    output : array or None
        The DUT's output (output units), for the default settling time; None: ``settle_s``
        defaults to one window.
    settle_s : float or None
        Seconds dropped from each plateau's start (s, ≥ 0); None: from the output (module
        docstring), at least one window.
    window_s : float or None
        Window of the filtered derivative (s; default 1 s), at least 3 rows.
    min_plateau_s : float or None
        Shortest plateau used, after settling (s; default 5 windows, at least 10 rows).
    rate_tolerance_deg_s : float
        Rate tolerance r_tol (°/s) added to the thresholds (a commanded rate has no noise).

    Returns
    -------
    PlateauSearch
        The used and rejected plateaus, the settling time and the detection's settings;
        ``warnings`` names each rejected plateau and why.

    Raises
    ------
    CaptureError
        Time not finite or not increasing, a non-finite table rate, no steady span at all (the
        rate never settles), or fewer than two used plateaus at different rates.
    """
    t = np.asarray(time_s, dtype=float).reshape(-1)
    r = np.asarray(rate_deg_s, dtype=float).reshape(-1)
    y = None if output is None else np.asarray(output, dtype=float).reshape(-1)
    _check_log(t, r, y)
    window = _positive("window_s", window_s, DEFAULT_PLATEAU_WINDOW_S)
    dt = float(np.median(np.diff(t[: min(t.size, _NOISE_SAMPLES)])))
    h = max(3, round(window / dt))
    if 2 * h >= r.size:
        raise CaptureError(
            f"the log spans {r.size} rows ({t[-1] - t[0]:.6g} s): too short to find plateaus in "
            f"with a window of {h} rows ({h * dt:.3g} s)"
        )
    min_s = _positive("min_plateau_s", min_plateau_s, 5.0 * h * dt)
    tol = _positive("rate_tolerance_deg_s", rate_tolerance_deg_s, DEFAULT_RATE_TOLERANCE_DEG_S)
    sigma = _rate_noise(r)
    thr = _Z * sigma * math.sqrt(2.0 / h) + tol
    runs = _steady_runs(r, h, thr)
    if runs.size:
        runs = _merge(r, _refine(r, runs, _Z * sigma + tol, 2 * h), sigma, tol)
    # a steady run shorter than the window is no plateau (a ramp's turning point, a sine's crest)
    runs = runs[runs[:, 1] - runs[:, 0] >= h] if runs.size else runs
    min_rows = max(10, math.ceil(min_s / dt - 1e-9))
    if not np.any(runs[:, 1] - runs[:, 0] >= min_rows):
        raise CaptureError(
            f"the table rate never settles: no span of {min_rows} rows ({min_rows * dt:.3g} s, "
            f"min_plateau_s) holds a steady rate (noise σ = {sigma:.3g} °/s); a continuous log "
            "must hold each rate for a while"
        )
    if settle_s is not None:
        settle, source = _positive("settle_s", settle_s, 0.0), "given"
        settle_rows = math.ceil(settle / dt - 1e-9)
    else:
        settle_rows = max(h, 0 if y is None else _settling_rows(y, runs, h))
        settle, source = round(settle_rows * dt, 9), ("output" if y is not None else "window")

    used: list[Plateau] = []
    rejected: list[Plateau] = []
    rows: list[tuple[int, int]] = []
    stds = []
    for a, b in runs:
        a2 = min(int(a) + settle_rows, int(b))
        seg = r[a2:b]
        stds.append(float(seg.std()) if seg.size > 1 else math.nan)
    typical = float(np.nanmedian(stds)) if np.isfinite(stds).any() else 0.0
    for (a, b), sd in zip(runs, stds, strict=True):
        a, b = int(a), int(b)
        a2 = min(a + settle_rows, b)
        span = (a2, b) if b - a2 >= 1 else (a, b)
        seg = r[span[0] : span[1]]
        values = (
            float(t[span[0]]),
            float(t[span[1] - 1]),
            float(seg.mean()),
            span[1] - span[0],
            float(seg.std()) if seg.size > 1 else 0.0,
        )
        if b - a2 < min_rows:
            why = (
                f"too short: {b - a2} rows ({(b - a2) * dt:.3g} s) after settling "
                f"{settle:.3g} s, fewer than {min_rows} ({min_rows * dt:.3g} s)"
            )
        elif sd > _NOISY_FACTOR * typical + tol:
            why = (
                f"too noisy: table rate σ = {sd:.3g} °/s, above {_NOISY_FACTOR:g}× the plateaus' "
                f"median {typical:.3g} °/s (+ {tol:g} °/s)"
            )
        elif (drift := _drift(r[a2:b])) > (limit := _drift_limit(b - a2, sigma, sd, tol)):
            why = (
                f"not steady: the table rate drifts by {drift:.3g} °/s from its first to its "
                f"last third, more than {limit:.3g} °/s ({_Z:g} standard errors)"
            )
        else:
            used.append(Plateau(*values))
            rows.append((a2, b))
            continue
        rejected.append(Plateau(*values, reason=why))
    warnings = tuple(
        f"plateau {p.start_s:.6g}–{p.end_s:.6g} s at {p.rate_deg_s:+.6g} °/s rejected, {p.reason}"
        for p in rejected
    )
    distinct = np.unique(np.round(np.array([p.rate_deg_s for p in used]) / max(tol, 1e-12)))
    if distinct.size < 2:
        found = "no plateau" if not used else f"one plateau rate ({used[0].rate_deg_s:+.6g} °/s)"
        extra = f" ({len(rejected)} rejected: {rejected[0].reason})" if rejected else ""
        raise CaptureError(
            f"the log holds {found} usable for a scale factor{extra}: it needs plateaus at two "
            "rates at least; check the rate_deg_s column, --settle-s and the log's length"
        )
    return PlateauSearch(
        plateaus=tuple(used),
        rejected=tuple(rejected),
        settle_s=settle,
        settle_source=source,
        window_s=h * dt,
        rate_noise_deg_s=sigma,
        threshold_deg_s=thr,
        _rows=np.asarray(rows, dtype=np.int64).reshape(-1, 2),
        warnings=warnings,
    )


def plateau_rows(search: PlateauSearch, column: np.ndarray) -> np.ndarray:
    """The rows of ``column`` on the used plateaus, in time order (one copy)."""
    x = np.asarray(column)
    return np.concatenate([x[a:b] for a, b in search._rows])


def plateau_rates(search: PlateauSearch) -> np.ndarray:
    """Each used row's rate point: its plateau's mean table rate (°/s), as :func:`plateau_rows`."""
    counts = search._rows[:, 1] - search._rows[:, 0]
    return np.repeat([p.rate_deg_s for p in search.plateaus], counts)
