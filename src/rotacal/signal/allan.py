"""Overlapping Allan deviation and the IEEE Std 952 noise terms of a gyro (or any oscillator).

:func:`overlapping_adev` computes the overlapping Allan deviation of rate samples (°/s, fractional
frequency, any unit: the result is in that unit) or of phase/angle samples (their integral: °, or
time error in s), at octave, decade, log-spaced, explicit or *all* averaging times, with the
equivalent degrees of freedom and a chi-squared confidence interval for each τ.

* A few τ (octave, decade, explicit): each τ by the definition, one whole-array O(N) pass.
* Every τ (``taus="all"``, cluster sizes m = 1 … ⌊(N−1)/2⌋): an exact O(N log² N) method — the
  sum of squared second differences expanded into prefix sums and lagged products from FFT
  correlations, with local piecewise-linear detrending so that it keeps ≤ 1e-9 relative precision
  for any noise colour (derivation: :mod:`rotacal.signal._allan_fast`). 10⁷ samples (5·10⁶ τ)
  take seconds on one core (``benchmarks/bench_allan.py``), where the O(N²) definition would
  take hours. A record read in chunks: :mod:`rotacal.signal.allan_stream` (octave or decade τ).

:func:`noise_terms` reads the IEEE Std 952-1997 Annex C terms off a curve: quantization Q (slope
−1), angle random walk N (−½), bias instability B (0), rate random walk K (+½) and rate ramp R (+1),
each where the local log-log slope shows that it dominates, with a confidence interval from the
number of independent clusters. It is the quick reading by eye that IEEE Std 952 Annex C
describes; ``rotacal allan`` and :func:`rotacal.gyro.gyro_noise` give the terms of one weighted
least-squares fit of all five on the whole curve instead (:mod:`rotacal.gyro.noise_fit`), which
separates terms that overlap (the slope reading takes B where N still adds, e.g.).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result
from rotacal.signal._allan_edf import edf_oadev
from rotacal.signal._allan_fast import direct_sums, second_difference_sums
from rotacal.signal._checks import as_samples, check_finite
from rotacal.signal._phase import phase_record
from rotacal.signal._values import check_magnitudes
from rotacal.signal.clipping import check_clipping

__all__ = [
    "ONE_SIGMA",
    "AllanDeviation",
    "NoiseTerm",
    "NoiseTerms",
    "adev_confidence_interval",
    "edf_overlapping_adev",
    "noise_terms",
    "overlapping_adev",
]

DataType = Literal["rate", "phase"]
#: Confidence level of a ±1σ interval, erf(1/√2) ≈ 68.3 %.
ONE_SIGMA = math.erf(1.0 / math.sqrt(2.0))
#: Fewest phase points accepted (a rate record of n samples gives n + 1).
MIN_SAMPLES = 10
#: The noise exponents α (S_y(f) ∝ f^α) for which the edf is known.
NOISE_ALPHAS = (2, 1, 0, -1, -2)
_LOG_PER_DECADE = 20


# ====================================================================================== results
@dataclasses.dataclass(frozen=True, eq=False)
class AllanDeviation(Result):
    """Overlapping Allan deviation of one record.

    Attributes
    ----------
    tau_s : averaging times τ = m/fs (s), increasing.
    adev : overlapping Allan deviation σ(τ), in the unit of the rate (for ``data_type="rate"``)
        or of the phase per second (for ``"phase"``): °/s for °/s or ° input, dimensionless for
        fractional frequency or time error in s.
    adev_low, adev_high : chi-squared confidence interval of σ(τ) at ``confidence`` (same unit).
    edf : equivalent degrees of freedom of σ²(τ) for the noise type ``noise_alpha``.
    n_terms : number of overlapping second differences used at each τ (N − 2m).
    cluster_sizes : m, samples per cluster.
    fs_hz : sampling rate (Hz).
    n_samples : samples in the record as given.
    n_phase : phase points used (n_samples + 1 for rate data, whose integral starts at 0).
    data_type : "rate" or "phase".
    confidence : confidence level of the interval (0–1).
    noise_alpha : power-law exponent(s) α assumed for the edf (0 = white rate / white FM).
    method : "direct" (each τ by the definition) or "fast" (the all-τ expansion; τ where its
        rounding estimate is too large are still computed directly).
    notes : remarks on the τ list (rounded or dropped values).
    """

    tau_s: np.ndarray
    adev: np.ndarray
    adev_low: np.ndarray
    adev_high: np.ndarray
    edf: np.ndarray
    n_terms: np.ndarray
    cluster_sizes: np.ndarray
    fs_hz: float
    n_samples: int
    n_phase: int
    data_type: str
    confidence: float
    noise_alpha: Any
    method: str
    notes: tuple[str, ...] = ()
    _n_direct: int = 0


@dataclasses.dataclass(frozen=True, eq=False)
class NoiseTerm(Result):
    """One IEEE Std 952 noise term read off an Allan deviation curve.

    Attributes
    ----------
    name : "quantization", "angle_random_walk", "bias_instability", "rate_random_walk",
        "rate_ramp".
    slope : its log-log slope of σ(τ): −1, −½, 0, +½, +1.
    coefficient : Q, N, B, K or R in the input's units (``unit``): with the rate unit u,
        Q in u·s, N in u·√s, B in u, K in u/√s, R in u/s.
    low, high : its confidence interval (same unit), ±δ with δ = 1/√(2(N/m − 1)) at ``tau_used_s``.
    unit : the unit of ``coefficient``.
    tau_ref_s : where the fitted line is read (√3, 1, 3, √2 s; B: the τ of the flat minimum).
    tau_used_s : the fitted τ nearest to ``tau_ref_s``, whose cluster count gives δ.
    relative_error : δ.
    fit_tau_s : (first, last) τ of the points the line was fitted through (s).
    n_points : number of those points.
    line_tau_s, line_adev : two points of the fitted line (B: the plateau 0.664·B) for plotting.
    """

    name: str
    slope: float
    coefficient: float
    low: float
    high: float
    unit: str
    tau_ref_s: float
    tau_used_s: float
    relative_error: float
    fit_tau_s: tuple[float, float]
    n_points: int
    line_tau_s: np.ndarray
    line_adev: np.ndarray


@dataclasses.dataclass(frozen=True, eq=False)
class NoiseTerms(Result):
    """The IEEE Std 952-1997 Annex C noise terms of a gyro; ``None`` where a term is not seen.

    The named values assume a rate record in ``unit`` (°/s by default; rad/s and °/h are
    converted): ``arw_deg_rt_h`` (angle random walk, °/√h), ``bias_instability_deg_h`` (°/h),
    ``rrw_deg_h_rt_h`` (rate random walk, °/h/√h), ``quantization_deg`` (angle quantization, °),
    ``rate_ramp_deg_h2`` (°/h²), each with its interval ``*_low``/``*_high``. For other units
    (``unit="other"``) they are ``None`` and ``terms`` holds the values in the input's units.

    ``terms`` maps each term found to its :class:`NoiseTerm` (line segments for the figure);
    ``local_slope`` is the log-log slope of the curve at each τ of ``slope_tau_s`` that decided
    which terms are present (see :func:`noise_terms`).
    """

    arw_deg_rt_h: float | None
    arw_deg_rt_h_low: float | None
    arw_deg_rt_h_high: float | None
    bias_instability_deg_h: float | None
    bias_instability_deg_h_low: float | None
    bias_instability_deg_h_high: float | None
    rrw_deg_h_rt_h: float | None
    rrw_deg_h_rt_h_low: float | None
    rrw_deg_h_rt_h_high: float | None
    quantization_deg: float | None
    quantization_deg_low: float | None
    quantization_deg_high: float | None
    rate_ramp_deg_h2: float | None
    rate_ramp_deg_h2_low: float | None
    rate_ramp_deg_h2_high: float | None
    unit: str
    terms: dict[str, NoiseTerm]
    slope_tau_s: np.ndarray
    local_slope: np.ndarray
    notes: tuple[str, ...] = ()


# ====================================================================================== checks
def _check_fs(fs: Any) -> float:
    try:
        f = float(fs)
    except (TypeError, ValueError):
        raise ConfigError(
            f"fs must be the sampling rate in Hz (a positive number); got {fs!r}."
        ) from None
    if not (math.isfinite(f) and f > 0):
        raise ConfigError(f"fs must be a finite positive sampling rate in Hz; got {f!r}.")
    return f


def _check_confidence(confidence: Any) -> float:
    try:
        c = float(confidence)
    except (TypeError, ValueError):
        raise ConfigError(
            f"confidence must be a number between 0 and 1; got {confidence!r}."
        ) from None
    if not 0.0 < c < 1.0:
        raise ConfigError(
            f"confidence must lie strictly between 0 and 1 (0.683 for ±1σ); got {c!r}."
        )
    return c


def _check_alpha(noise_alpha: Any, size: int) -> np.ndarray:
    arr = np.asarray(noise_alpha)
    if arr.ndim == 0:
        arr = np.full(size, arr)
    if arr.shape != (size,):
        raise ConfigError(
            f"noise_alpha must be one integer or one per τ ({size} values); got shape {arr.shape}."
        )
    bad = np.flatnonzero(~np.isin(arr, NOISE_ALPHAS))
    if bad.size:
        raise ConfigError(
            f"noise_alpha must be one of {NOISE_ALPHAS} (2 white PM … −2 random-walk FM; 0 is "
            f"white rate noise); got {arr[bad[0]]!r}."
        )
    return arr.astype(np.int64)


def _check_variation(y: np.ndarray, data_type: str, allow_clipped: bool) -> tuple[str, ...]:
    """A constant or clipped rate record would give a silently meaningless deviation: refuse a
    constant one, and one at the rails (:mod:`rotacal.signal.clipping`; the warnings when
    ``allow_clipped``)."""
    if data_type != "rate":
        return ()
    lo, hi = float(y.min()), float(y.max())
    if lo == hi:
        raise CaptureError(
            f"the rate record is constant ({hi!r} in all {y.size} samples): the sensor is stuck "
            "or saturated, or the column is a set value; supply the sensor output."
        )
    return check_clipping({"data": y}, allow_clipped=allow_clipped)


# ====================================================================================== τ lists
def _cluster_sizes(
    taus: Any, n_phase: int, fs: float, m_max: int | None = None, m_list: int | None = None
) -> tuple[np.ndarray, list[str]]:
    """Cluster sizes m for the τ specification, and notes about rounding or dropping.

    ``m_max`` is the longest cluster the deviation can use (default the Allan deviation's
    ⌊(N − 1)/2⌋, which leaves one second difference); ``m_list`` the longest that the octave
    and decade lists keep (default ⌊(N − 2)/2⌋: at least two terms, as allantools).
    """
    if m_max is None:
        m_max = (n_phase - 1) // 2
    if m_list is None:
        m_list = (n_phase - 2) // 2
    notes: list[str] = []
    if taus is None:
        taus = "octave"
    if isinstance(taus, str):
        kind = taus.lower()
        if kind == "all":
            return np.arange(1, m_max + 1, dtype=np.int64), notes
        if kind == "octave":  # allantools' "octave": 2^k, keeping at least 2 second differences
            ms = 2 ** np.arange(int(math.log2(n_phase)) + 1, dtype=np.int64)
        elif kind == "decade":  # 1, 2, 4, 10, 20, 40, … (Stable32's decade spacing)
            dec = 10 ** np.arange(int(math.log10(n_phase)) + 1, dtype=np.int64)
            ms = (dec[:, None] * np.array([1, 2, 4])).ravel()
        elif kind == "log":
            count = max(2, math.ceil(_LOG_PER_DECADE * math.log10(max(m_max, 2))) + 1)
            ms = np.unique(np.rint(np.geomspace(1, max(m_max, 1), count)).astype(np.int64))
            return ms, notes
        else:
            raise ConfigError(
                f"taus must be 'octave', 'decade', 'log', 'all' or an array of τ in s; got {taus!r}."
            )
        # allantools' octave/decade lists keep at least two terms (for the ADEV: N − 2m ≥ 2)
        ms = ms[ms <= min(m_max, m_list)]
        return np.unique(ms), notes
    try:
        t = np.asarray(taus, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise ConfigError(f"taus must be a keyword or an array of τ in s; got {taus!r}.") from None
    if t.size == 0:
        raise ConfigError("taus is empty; give τ values in s, or 'octave'/'decade'/'log'/'all'.")
    bad = np.flatnonzero(~(np.isfinite(t) & (t > 0)))
    if bad.size:
        raise ConfigError(
            f"τ must be finite and positive (s); got taus[{int(bad[0])}] = {t[bad[0]]!r}."
        )
    m = np.rint(t * fs).astype(np.int64)
    if (m < 1).any():
        i = int(np.flatnonzero(m < 1)[0])
        raise ConfigError(
            f"τ = {t[i]:.6g} s is shorter than one sample interval (1/fs = {1.0 / fs:.6g} s); "
            "drop it or sample faster."
        )
    if (m > m_max).any():
        i = int(np.flatnonzero(m > m_max)[0])
        raise ConfigError(
            f"τ = {t[i]:.6g} s needs at least {2 * int(m[i]) + 1} phase points, but the record "
            f"gives {n_phase}; the longest τ for this record is {m_max / fs:.6g} s."
        )
    off = np.abs(m / fs - t) > 1e-9 * t
    if off.any():
        notes.append(
            f"{int(off.sum())} τ value(s) rounded to whole cluster sizes m = round(τ·fs), "
            f"e.g. {t[off][0]:.6g} s → {m[off][0] / fs:.6g} s."
        )
    ms = np.unique(m)
    if ms.size < m.size:
        notes.append(
            f"{m.size - ms.size} duplicate τ value(s) (after rounding to samples) dropped."
        )
    return ms, notes


# ====================================================================================== ADEV
def edf_overlapping_adev(n_phase: int, cluster_sizes: Any, noise_alpha: int = 0) -> np.ndarray:
    """Equivalent degrees of freedom of the overlapping Allan variance.

    Parameters
    ----------
    n_phase : int
        Number of phase points N (rate samples + 1).
    cluster_sizes : array_like of int
        Cluster sizes m (τ = m/fs), each with N − 2m ≥ 1.
    noise_alpha : int
        Power-law exponent α of the rate (fractional-frequency) noise, S_y(f) ∝ f^α: 2 white PM
        (white angle noise, quantization), 1 flicker PM, 0 white FM (angle random walk),
        −1 flicker FM (bias instability), −2 random-walk FM (rate random walk).

    Returns
    -------
    ndarray
        edf for each m (dimensionless).

    References
    ----------
    C. A. Greenhall and W. J. Riley, "Uncertainty of stability variances based on finite
    differences", Proc. 35th PTTI Meeting (2003), eqs. (7)–(10) and Tables 2–3; NIST SP 1065
    (Riley 2008), §5.3. For α = 2 the basic sum (eq. 10) is evaluated exactly in closed form.
    """
    m = np.asarray(cluster_sizes, dtype=np.int64).ravel()
    alpha = int(_check_alpha(noise_alpha, 1)[0])
    if (m < 1).any() or (n_phase - 2 * m < 1).any():
        raise ConfigError(f"cluster sizes must satisfy 1 ≤ m ≤ (N − 1)/2 = {(n_phase - 1) // 2}.")
    return edf_oadev(int(n_phase), m, alpha)


def adev_confidence_interval(
    adev: Any, edf: Any, confidence: float = ONE_SIGMA
) -> tuple[np.ndarray, np.ndarray]:
    """Chi-squared confidence interval of a deviation with ``edf`` degrees of freedom.

    Parameters
    ----------
    adev : array_like — the deviation(s), any unit.
    edf : array_like — equivalent degrees of freedom.
    confidence : float — two-sided confidence level (0–1); default ±1σ (68.3 %).

    Returns
    -------
    (low, high) : arrays in the unit of ``adev``:
        σ·√(edf/χ²(1 − (1 − c)/2)) and σ·√(edf/χ²((1 − c)/2)).

    References
    ----------
    NIST SP 1065 (Riley 2008), §5.3.1, eq. (45); IEEE Std 1139-2008, Annex C.
    """
    c = _check_confidence(confidence)
    dev = np.asarray(adev, dtype=np.float64)
    nu = np.asarray(edf, dtype=np.float64)
    tail = 0.5 * (1.0 - c)
    lo = dev * np.sqrt(nu / _chi2_ppf(1.0 - tail, nu))
    hi = dev * np.sqrt(nu / _chi2_ppf(tail, nu))
    return lo, hi


#: Above this many degrees-of-freedom values, χ²-quantiles are spline-interpolated.
_CHI2_GRID_ABOVE = 2048


def _chi2_ppf(q: float, nu: np.ndarray) -> np.ndarray:
    """χ²_q(ν); for many ν, ``log(χ²_q(ν)/ν)`` (smooth in log ν) is spline-interpolated.

    The interpolation error is below 1e-8 relative for ν ≥ 0.9 (checked in the tests), far under
    the meaning of a confidence limit; it turns 5·10⁶ exact quantiles (≈ 7 s) into 0.3 s.
    """
    # imported here: a process that only sums (a Dask worker's block) skips SciPy's 0.5 s
    from scipy import special

    def exact(nu: np.ndarray) -> np.ndarray:
        # χ²_q(ν) = 2·P⁻¹(ν/2, q), P the regularised lower incomplete gamma function: what
        # scipy.stats.chi2.ppf computes, to the bit (tested), without importing scipy.stats
        # (0.4 s of a streamed rate command's 1 s)
        return np.asarray(2.0 * special.gammaincinv(nu / 2.0, q))

    if nu.size <= _CHI2_GRID_ABOVE:
        return exact(nu)
    from scipy import interpolate

    lo, hi = float(nu.min()), float(nu.max())
    grid = np.geomspace(lo, max(hi, lo * 1.001), 2048)
    spline = interpolate.CubicSpline(np.log(grid), np.log(exact(grid) / grid))
    return np.asarray(np.exp(spline(np.log(nu))) * nu)


def prepared_phase(
    data: Any,
    fs: Any,
    data_type: str,
    confidence: Any,
    allow_clipped: bool,
    what: str,
    *,
    ramp_blind: bool = False,
) -> tuple[float, float, np.ndarray, int, tuple[str, ...]]:
    """The checks every deviation makes of its input, and the phase it is computed from.

    Returns (fs in Hz, confidence, phase with its best line removed — and a rate's best line,
    a phase's best parabola, if ``ramp_blind``: :func:`~rotacal.signal._phase.phase_record` —,
    samples given, clipping warnings); raises what :func:`overlapping_adev` documents (``what``
    names the deviation).
    """
    fs_hz = _check_fs(fs)
    if data_type not in ("rate", "phase"):
        raise ConfigError(f"data_type must be 'rate' or 'phase'; got {data_type!r}.")
    conf = _check_confidence(confidence)
    y = as_samples("data", data)
    if y.size + (data_type == "rate") < MIN_SAMPLES:
        raise CaptureError(
            f"the record holds {y.size} {data_type} samples; {what} needs at least "
            f"{MIN_SAMPLES} phase points ({MIN_SAMPLES} phase or {MIN_SAMPLES - 1} rate samples): "
            "supply a longer record."
        )
    check_finite("data", y)
    check_magnitudes("data", y, what=f"{data_type} data")
    clipped = _check_variation(y, data_type, allow_clipped)
    x = phase_record(y, fs_hz, data_type, ramp_blind=ramp_blind)
    if not float(np.max(np.abs(x))) > 1e-12 * float(np.max(np.abs(y))):
        shape = "a parabola (a rate ramp)" if ramp_blind else "a straight line (constant rate)"
        raise CaptureError(
            f"the phase record is {shape} to the last bit: {what} is zero at every τ; check "
            "that the column holds the sensor output."
        )
    return fs_hz, conf, x, int(y.size), clipped


def overlapping_adev(
    data: Any,
    *,
    fs: float,
    taus: Any = None,
    data_type: DataType = "rate",
    confidence: float = ONE_SIGMA,
    noise_alpha: Any = 0,
    method: Literal["auto", "direct"] = "auto",
    allow_clipped: bool = False,
) -> AllanDeviation:
    """Overlapping Allan deviation with equivalent degrees of freedom and confidence intervals.

    σ²(τ) = Σ_{i=0}^{N−2m−1} (x_{i+2m} − 2x_{i+m} + x_i)² / (2·τ²·(N − 2m)),  τ = m/fs,
    for N phase points x (the rate's running integral, x_0 = 0, or the phase as given).

    Parameters
    ----------
    data : array_like
        One-dimensional record: rate samples (°/s, rad/s, fractional frequency, …) when
        ``data_type="rate"``, phase/angle samples (°, or time error in s) when ``"phase"``.
    fs : float
        Sampling rate (Hz).
    taus : None, str or array_like
        ``None``/``"octave"``: m = 1, 2, 4, … (allantools' octave list, at least two second
        differences each); ``"decade"``: m = 1, 2, 4, 10, 20, 40, …; ``"log"``: about 20
        log-spaced m per decade up to ⌊(N−1)/2⌋; ``"all"``: every m = 1 … ⌊(N−1)/2⌋ (the
        O(N log² N) method); or τ values in s, rounded to whole cluster sizes m = round(τ·fs)
        (rounding and dropped duplicates are reported in ``notes``).
    data_type : "rate" or "phase"
        What ``data`` holds.
    confidence : float
        Confidence level of ``adev_low``/``adev_high`` (default ±1σ, 68.3 %).
    noise_alpha : int or array_like of int
        Noise type for the edf (one value, or one per resulting τ): 2 white PM, 1 flicker PM,
        0 white FM (the default: white rate noise, angle random walk), −1 flicker FM, −2 RW FM.
    method : "auto" or "direct"
        ``"auto"`` uses the fast all-τ expansion where it is cheaper than the definition;
        ``"direct"`` evaluates every τ by the definition (O(N) per τ).
    allow_clipped : bool
        Compute the deviation of a rate record with samples at the rails anyway (``warnings``
        name the clipping); refused by default.

    Returns
    -------
    AllanDeviation
        τ (s), σ(τ) in the rate unit (the phase unit per second for phase data), its confidence
        interval, edf and the number of terms per τ.

    Raises
    ------
    CaptureError
        NaN/inf samples, values beyond float64's working range (one sample of 1e300 would turn
        every deviation into inf/NaN), fewer than 10 samples, a constant rate record, one at the
        rails (:mod:`rotacal.signal.clipping`).
    ConfigError
        fs ≤ 0, an unknown ``taus``/``data_type``/``method``, a τ that the record cannot
        represent (shorter than 1/fs or longer than (N−1)/(2·fs)), a bad confidence or α.

    References
    ----------
    IEEE Std 1139-2008, §5.2 and Annex C (overlapping Allan variance); IEEE Std 952-1997, Annex C,
    eq. (C.4) ff.; NIST SP 1065 (Riley 2008), eq. (11) (overlapping ADEV from phase data) and
    §5.3 (edf, Greenhall & Riley 2003).
    """
    if method not in ("auto", "direct"):
        raise ConfigError(f"method must be 'auto' or 'direct'; got {method!r}.")
    fs_hz, conf, x, n_samples, clipped = prepared_phase(
        data, fs, data_type, confidence, allow_clipped, "the Allan deviation"
    )
    n_phase = x.size
    ms, notes = _cluster_sizes(taus, n_phase, fs_hz)
    if ms.size == 0:
        raise ConfigError(
            f"no τ is representable with {n_phase} phase points; supply a longer record."
        )
    alphas = _check_alpha(noise_alpha, ms.size)
    if method == "direct":
        sums = direct_sums(x, ms)
        n_direct = int(ms.size)
    else:
        sums, n_direct = second_difference_sums(x, ms)
    return deviation_from_sums(
        sums,
        ms,
        n_phase=int(n_phase),
        n_samples=n_samples,
        fs_hz=fs_hz,
        data_type=data_type,
        confidence=conf,
        alphas=alphas,
        notes=tuple(notes),
        warnings=clipped,
        n_direct=n_direct,
    )


def deviation_from_sums(
    sums: np.ndarray,
    ms: np.ndarray,
    *,
    n_phase: int,
    n_samples: int,
    fs_hz: float,
    data_type: str,
    confidence: float,
    alphas: np.ndarray,
    notes: tuple[str, ...],
    warnings: tuple[str, ...],
    n_direct: int,
) -> AllanDeviation:
    """The :class:`AllanDeviation` of the sums of squared second differences ``S(m)`` (phase
    unit²) at cluster sizes ``ms``: σ(τ) = √(S/(2(N − 2m)))/τ, its edf and χ² interval."""
    n_terms = n_phase - 2 * ms
    tau = ms / fs_hz
    adev = np.sqrt(np.maximum(sums, 0.0) / (2.0 * n_terms)) / tau
    if alphas.min() == alphas.max():  # one noise type (the usual case): no masks over every τ
        edf = edf_oadev(n_phase, ms, int(alphas[0]))
    else:
        edf = np.empty(ms.size)
        for a in np.unique(alphas).tolist():
            sel = alphas == a
            edf[sel] = edf_oadev(n_phase, ms[sel], int(a))
    lo, hi = adev_confidence_interval(adev, edf, confidence)
    alpha_out: Any = int(alphas[0]) if np.all(alphas == alphas[0]) else alphas
    return AllanDeviation(
        tau_s=tau,
        adev=adev,
        adev_low=lo,
        adev_high=hi,
        edf=edf,
        n_terms=n_terms,
        cluster_sizes=ms,
        fs_hz=fs_hz,
        n_samples=n_samples,
        n_phase=n_phase,
        data_type=data_type,
        confidence=confidence,
        noise_alpha=alpha_out,
        method="direct" if n_direct == ms.size else "fast",
        notes=notes,
        warnings=warnings,
        _n_direct=n_direct,
    )


# ====================================================================================== terms
#: (name, slope of σ(τ), τ where the line is read (s), unit suffix relative to the rate unit u).
_TERMS = (
    ("quantization", -1.0, math.sqrt(3.0), "·s"),
    ("angle_random_walk", -0.5, 1.0, "·√s"),
    ("bias_instability", 0.0, math.nan, ""),
    ("rate_random_walk", 0.5, 3.0, "/√s"),
    ("rate_ramp", 1.0, math.sqrt(2.0), "/s"),
)
#: σ/B on the flicker plateau, √(2·ln 2/π) ≈ 0.664 (IEEE Std 952-1997, Table C.1).
BIAS_INSTABILITY_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)
#: Rate units with a known factor to °/s.
_UNIT_TO_DEG_S = {"deg/s": 1.0, "rad/s": 180.0 / math.pi, "deg/h": 1.0 / 3600.0}
#: Factor from (°/s-based native coefficient) to the named unit of INTERFACE.md.
_NAMED = {
    "quantization": ("quantization_deg", 1.0),
    "angle_random_walk": ("arw_deg_rt_h", 60.0),
    "bias_instability": ("bias_instability_deg_h", 3600.0),
    "rate_random_walk": ("rrw_deg_h_rt_h", 3600.0 * 60.0),
    "rate_ramp": ("rate_ramp_deg_h2", 3600.0**2),
}
#: Half-width of a slope class: a point belongs to the nearest of −1, −½, 0, ½, 1 within this.
SLOPE_CLASS_HALF_WIDTH = 0.25
#: Points whose local slope is this close to a term's slope are its core (used for the fit).
SLOPE_CORE = 0.1
#: A line is fitted through its points within this many decades of where it is read, if ≥ 2.
FIT_HALF_DECADES = 0.5
#: Half-width (decades) of the window over which the local slope is fitted.
SLOPE_WINDOW_DECADES = 0.2
#: Fewest independent clusters N/m for a point to be used (δ ≤ 1/√(2·(9 − 1)) = 25 %).
MIN_CLUSTERS = 9.0
#: Points per decade kept when a dense curve (e.g. every τ) is thinned before the slope analysis.
_THIN_PER_DECADE = 16


def _thin(tau: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """Indices of ``keep`` thinned to at most ``_THIN_PER_DECADE`` per decade (log-uniform)."""
    idx = np.flatnonzero(keep)
    bins = np.floor(np.log10(tau[idx]) * _THIN_PER_DECADE).astype(np.int64)
    first = np.ones(idx.size, dtype=bool)
    first[1:] = bins[1:] != bins[:-1]
    return idx[first]


def _local_slopes(lt: np.ndarray, ls: np.ndarray) -> np.ndarray:
    """Least-squares slope of log σ against log τ in a window around each point (decades)."""
    gaps = np.diff(lt)
    left = np.concatenate(([0.0], gaps))
    right = np.concatenate((gaps, [0.0]))
    half = np.maximum(SLOPE_WINDOW_DECADES, 1.0001 * np.maximum(left, right))
    inside = np.abs(lt[None, :] - lt[:, None]) <= half[:, None]
    w = inside.astype(np.float64)
    cnt = w.sum(axis=1)
    mt = (w * lt).sum(axis=1) / cnt
    ms = (w * ls).sum(axis=1) / cnt
    dt = lt[None, :] - mt[:, None]
    num = (w * dt * (ls[None, :] - ms[:, None])).sum(axis=1)
    den = (w * dt * dt).sum(axis=1)
    return np.asarray(num / den)


def _runs(mask: np.ndarray) -> list[np.ndarray]:
    """Index arrays of the runs of consecutive True in ``mask``."""
    idx = np.flatnonzero(mask)
    if not idx.size:
        return []
    cuts = np.flatnonzero(np.diff(idx) > 1) + 1
    return list(np.split(idx, cuts))


def noise_terms(
    adev: AllanDeviation, *, unit: str = "deg/s", min_clusters: float = MIN_CLUSTERS
) -> NoiseTerms:
    """IEEE Std 952 noise terms from an overlapping Allan deviation curve (slope method; the
    commands use the five-term fit of :func:`rotacal.gyro.noise_fit.fit_noise_terms`).

    Rule. Points with at least ``min_clusters`` independent clusters N/m are kept (a dense curve
    is thinned to 16 points per decade). The local log-log slope at each point is the
    least-squares slope over ±0.2 decade (at least its neighbours). A point belongs to the term
    whose slope (−1 Q, −½ N, 0 B, +½ K, +1 R) is nearest, within ±0.25; a term is *present* when
    at least two consecutive points belong to it. Its line, of the term's fixed slope, is fitted
    (least squares in log–log) through the longest such run, narrowed to the points within ±0.1
    of the slope and then to those within ±0.5 decade of where the line is read, each when at
    least two remain. The coefficient is the line read at √3 s (Q = σ(√3)), 1 s (N = σ(1)),
    3 s (K = σ(3)), √2 s (R = σ(√2)). Bias instability B = σ_min / √(2 ln 2/π) (σ_min/0.664),
    with σ_min the smallest deviation among the points of the flat class (slope 0). Each term gets ±δ with
    δ = 1/√(2(N/m − 1)) at the fitted τ nearest to where it is read (B: at the minimum).

    Parameters
    ----------
    adev : AllanDeviation
        From :func:`overlapping_adev` of a *rate* record; a dense τ list (``"log"`` or ``"all"``)
        resolves the slopes best, ``"octave"`` works.
    unit : str
        The rate unit of the record: ``"deg/s"`` (default), ``"rad/s"`` or ``"deg/h"`` fill the
        named fields (°/√h, °/h, °/h/√h, °, °/h²); ``"other"`` leaves them None and reports
        the coefficients in the record's own unit (``terms``).
    min_clusters : float
        Fewest independent clusters N/m for a point to be used.

    Returns
    -------
    NoiseTerms

    Raises
    ------
    ConfigError
        An unknown unit, or a phase-type curve with a named unit.
    CaptureError
        Fewer than three usable points (the record is too short for a slope analysis).

    References
    ----------
    IEEE Std 952-1997, Annex C: §C.1 (Allan variance), Table C.1 and §C.2–C.4 (the slope method:
    N at τ = 1, K at τ = 3, Q at τ = √3, R at τ = √2, B from the flat part / 0.664) and eq. (C.4)
    (percentage error 1/√(2(N/n − 1)) of σ with n samples per cluster); NIST SP 1065 (Riley
    2008), §5.2.
    """
    if unit not in _UNIT_TO_DEG_S and unit != "other":
        raise ConfigError(
            f"unit must be 'deg/s', 'rad/s', 'deg/h' or 'other' (the record's rate unit); got {unit!r}."
        )
    if unit != "other" and adev.data_type != "rate":
        raise ConfigError(
            "the named noise terms need a rate record in °/s, rad/s or °/h; this curve is from "
            "phase data: pass unit='other' or compute the deviation from the rate."
        )
    total = adev.n_phase - 1  # samples (rate-equivalent) in the record
    tau = np.asarray(adev.tau_s, dtype=np.float64)
    sig = np.asarray(adev.adev, dtype=np.float64)
    clusters = total / np.asarray(adev.cluster_sizes, dtype=np.float64)
    keep = (clusters >= min_clusters) & (sig > 0)
    idx = _thin(tau, keep)
    if idx.size < 3:
        raise CaptureError(
            f"only {idx.size} τ values have at least {min_clusters:g} independent clusters; the "
            "record is too short for the slope analysis: supply a longer record or more τ."
        )
    t, s, k = tau[idx], sig[idx], clusters[idx]
    lt, ls = np.log10(t), np.log10(s)
    slope = _local_slopes(lt, ls)
    centres = np.array([p for _, p, _, _ in _TERMS])
    dist = np.abs(slope[:, None] - centres[None, :])
    cls = np.where(dist.min(axis=1) <= SLOPE_CLASS_HALF_WIDTH, dist.argmin(axis=1), -1)
    to_deg = _UNIT_TO_DEG_S.get(unit)
    base_unit = unit if unit != "other" else "u"
    found: dict[str, NoiseTerm] = {}
    named: dict[str, float | None] = {}
    notes: list[str] = []
    for c, (name, p, tau_ref, suffix) in enumerate(_TERMS):
        if name == "bias_instability":
            flat = [r for r in _runs(cls == c) if r.size >= 2]
            if not flat:
                continue
            members = np.concatenate(flat)
            j = int(members[np.argmin(s[members])])
            run = next(r for r in flat if j in r)
            plateau = float(s[j])
            coef = plateau / BIAS_INSTABILITY_FACTOR
            ref, used, pts = float(t[j]), j, run
            line_t = np.array([t[run[0]], t[run[-1]]]) if run.size > 1 else t[[j, j]]
            line_s = np.full(2, plateau)
        else:
            runs = [r for r in _runs(cls == c) if r.size >= 2]
            if not runs:
                continue
            run = max(runs, key=lambda r: (r.size, -np.min(np.abs(slope[r] - p))))
            core = run[np.abs(slope[run] - p) <= SLOPE_CORE]
            pts = core if core.size >= 2 else run
            near = pts[np.abs(lt[pts] - math.log10(tau_ref)) <= FIT_HALF_DECADES]
            if near.size >= 2:
                pts = near
            logc = float(np.mean(ls[pts] - p * lt[pts]))
            coef = 10.0 ** (logc + p * math.log10(tau_ref))
            ref = tau_ref
            used = int(pts[np.argmin(np.abs(lt[pts] - math.log10(tau_ref)))])
            lo_t = min(float(t[pts[0]]), tau_ref)
            hi_t = max(float(t[pts[-1]]), tau_ref)
            line_t = np.array([lo_t, hi_t])
            line_s = 10.0 ** (logc + p * np.log10(line_t))
            if not t[pts[0]] <= tau_ref <= t[pts[-1]]:
                notes.append(
                    f"{name}: read at τ = {tau_ref:.4g} s on the line extrapolated from "
                    f"{t[pts[0]]:.4g}–{t[pts[-1]]:.4g} s."
                )
        delta = 1.0 / math.sqrt(2.0 * (float(k[used]) - 1.0))
        term = NoiseTerm(
            name=name,
            slope=p,
            coefficient=coef,
            low=coef * (1.0 - delta),
            high=coef * (1.0 + delta),
            unit=base_unit + suffix,
            tau_ref_s=ref,
            tau_used_s=float(t[used]),
            relative_error=delta,
            fit_tau_s=(float(t[pts[0]]), float(t[pts[-1]])),
            n_points=int(pts.size),
            line_tau_s=line_t,
            line_adev=line_s,
        )
        found[name] = term
        if to_deg is not None:
            key, factor = _NAMED[name]
            f = to_deg * factor
            named[key] = coef * f
            named[key + "_low"] = term.low * f
            named[key + "_high"] = term.high * f
    if "bias_instability" not in found:
        notes.append("no flat part (slope 0) in the curve: bias instability not observed.")
    fields: dict[str, Any] = {}
    for key, _ in _NAMED.values():
        for suffix in ("", "_low", "_high"):
            fields[key + suffix] = named.get(key + suffix)
    return NoiseTerms(
        **fields,
        unit=unit,
        terms=found,
        slope_tau_s=t,
        local_slope=slope,
        notes=tuple(notes),
    )
