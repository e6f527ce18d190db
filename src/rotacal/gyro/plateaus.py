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
before it, D[k] = mean(r[k:k+h]) − mean(r[k−h:k]), both from one cumulative sum (O(n); the
whole method runs as passes over chunks with carried state, :mod:`rotacal.gyro.plateaus_stream`,
and :func:`find_plateaus` is those passes over one chunk). A boundary is a change when |D[k]| > z·σ·√(2/h) + r_tol, σ being the table rate's white
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

The DUT's settling (the default ``settle_s``) is read from the output: within each plateau (its
first 2·10⁶ blocks at most) the output is averaged in blocks of h/10 samples (short enough to
follow a ringing DUT); the band is 5
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
    threshold on D (°/s). ``_rows`` holds the [start, stop) row range of each used plateau,
    ``_log`` a strided copy of the log (time, rate, output) for its figure, ``_temperature_c``
    each used plateau's mean temperature (°C) when the log has one.
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
    _log: tuple[np.ndarray, np.ndarray, np.ndarray] | None = dataclasses.field(
        default=None, repr=False, compare=False
    )
    _temperature_c: tuple[float, ...] | None = dataclasses.field(
        default=None, repr=False, compare=False
    )


def _positive(name: str, value: float | None, default: float) -> float:
    v = default if value is None else value
    bad = isinstance(v, bool) or not isinstance(v, (int, float, np.floating))
    if bad or not math.isfinite(v) or v < 0:
        raise ConfigError(f"{name} must be a number ≥ 0 s, got {value!r}")
    return float(v)


def _drift_limit(n: int, sigma: float, sd: float, tol: float) -> float:
    """z standard errors of the difference of two thirds' means of ``n`` rows (°/s), plus tol."""
    return _Z * max(sigma, sd) * math.sqrt(2.0 / max(n // 3, 1)) + tol


def _settling_of(block: np.ndarray, m: int) -> int:
    """The output's settling (rows) in one plateau from the means of its blocks of ``m`` rows
    (module docstring); 0 when it holds fewer than 8 blocks or never leaves the band."""
    nb = block.size
    if nb < 8:
        return 0
    tail = block[nb // 2 :]
    ref = float(np.median(tail))
    sd = 1.4826 * float(np.median(np.abs(tail - ref)))
    band = _SETTLE_SIGMAS * sd + 64 * np.finfo(float).eps * abs(ref)
    far = np.abs(block[: nb // 2 + 1] - ref) > band
    # two blocks in a row outside: a transient lasts, an outlier sample does not
    out = np.flatnonzero(far[:-1] & far[1:])
    if not out.size:
        return 0
    enter = int(out[-1]) + 2  # blocks until the band
    # the transient still biases the plateau mean inside the band: extend its exponential
    # envelope (from the largest deviation to the band) down to a tenth of the mean's SE
    d0 = float(np.max(np.abs(block[:enter] - ref)))
    target = 0.1 * sd / math.sqrt(nb) + 64 * np.finfo(float).eps * abs(ref)
    if d0 > band > 0 and target < band:
        enter = math.ceil(enter * math.log(d0 / target) / math.log(d0 / band))
    return min(enter, nb // 2) * m


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
    from rotacal.gyro.plateaus_stream import find_plateaus_chunked, log_chunks

    t = np.asarray(time_s, dtype=float).reshape(-1)
    r = np.asarray(rate_deg_s, dtype=float).reshape(-1)
    y = None if output is None else np.asarray(output, dtype=float).reshape(-1)
    if t.size != r.size or (y is not None and y.size != t.size):
        raise CaptureError(
            f"columns time_s ({t.size} rows), rate_deg_s ({r.size})"
            + ("" if y is None else f" and output ({y.size})")
            + " must have one row per sample"
        )
    return find_plateaus_chunked(
        log_chunks(t, r, y),
        rows=t.size,
        output=y is not None,
        settle_s=settle_s,
        window_s=window_s,
        min_plateau_s=min_plateau_s,
        rate_tolerance_deg_s=rate_tolerance_deg_s,
    )


def plateau_rows(search: PlateauSearch, column: np.ndarray) -> np.ndarray:
    """The rows of ``column`` on the used plateaus, in time order (one copy)."""
    x = np.asarray(column)
    return np.concatenate([x[a:b] for a, b in search._rows])


def plateau_rates(search: PlateauSearch) -> np.ndarray:
    """Each used row's rate point: its plateau's mean table rate (°/s), as :func:`plateau_rows`."""
    counts = search._rows[:, 1] - search._rows[:, 0]
    return np.repeat([p.rate_deg_s for p in search.plateaus], counts)
