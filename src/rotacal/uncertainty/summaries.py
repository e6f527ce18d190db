"""Uncertainty of rms-, peak-to-peak- and peak-type summaries of a measured curve.

A summary of a measured vector d = f + ε (f the truth, ε its errors) — its rms, its
peak-to-peak, its largest magnitude — is biased by ε: noise raises an rms and a peak on average,
and first-order propagation sees none of it (the derivative of a max is one element's error, that
of an rms at zero does not exist; JCGM 102 shows the same for a magnitude near zero). Here every
error source is a stationary Gaussian process along the vector, given by its autocovariance
(:class:`CirculantError`, :class:`FilteredWhite`; a :class:`CovarianceCorrection` adds the
covariance of two that are not independent), in one of three roles:

``"noise"``
    in the data, at a level the capture itself gives (Type A): the summary's bias from it is
    stated and a bias-corrected value given;
``"bound"``
    in the data, at a level that is only bounded or stated (a timing-noise estimate that also
    holds the graduation, a Type B specification): never corrected for — a specification must
    not make a stability look better — but the interval allows for all of it;
``"absent"``
    part of the true curve that the data lack (the scale orders no head arrangement sees): the
    interval for the true value includes it.

What a budget states (the same for every summary): ``value`` is the plain summary of the data
(the JSON value: one truth); u the standard deviation of the summary's error; ``interval`` the
95 % coverage interval for the TRUE value, valid near zero too; U half its width and k = U/u.
:class:`Summary` adds the bias from the known noise and the bias-corrected value.

rms (:func:`rms_budget`, closed form). ms(d) = ms(f) + 2⟨f, ε⟩/N + ms(ε) is a quadratic form in
Gaussian errors with Toeplitz covariance C (autocovariance g): E ms(d) = ms(f) + g(0) and
Var ms(d) = 4 fᵀCf/N² + 2 tr(C²)/N² (fᵀCf estimated without bias by dᵀCd − tr(C²)). The
interval for ms(f) is ms(d) − E(noise) ± z·√Var, its lower end also less the bounded errors'
mean square and both ends plus that of the absent parts; its square root is the interval of the
rms.

Peak-to-peak and peak (:func:`mc_budget`, Monte Carlo). For M(d) = max d: M(d) − M(f) ≥ ε(j*)
(j* where f peaks), and M(d) − M(f) ≤ max ε over the elements where f comes within Δ of its
peak — those are found from d, with Δ large enough that the errors cannot hide one (a union
bound). So the interval for the true value is [plain − q₉₇.₅(largest error the candidate
elements carry), plain + t·σ(error at one extreme)]: each end holds with probability ≥ 97.5 %
whatever the true curve (conservative when the extremes are sharp, tight near zero). Only the
candidate elements are drawn (all of them near zero), each source exactly (circulant draws, or a
Cholesky factor of the covariance among the candidates). The bias is the mean rise of the
statistic when the data's curve with its noise shrunk away (:func:`denoised`, Wiener) is
re-measured with the noise of known level (parametric bootstrap, JCGM 101 §7.6). u is the
geometric mean of the statistic's spread re-measured from the data themselves (their noise then
counts twice: too large where the noise sets the extremes) and from the denoised curve (its
extremes too flat: too small where single elements set them).

References
----------
JCGM 100:2008 (GUM) §4.2, §5.1.2 note; JCGM 101:2008 §7.6, §7.7; JCGM 102:2011 §9 (a magnitude
near zero); J. R. Cook and L. A. Stefanski, "Simulation-extrapolation estimation in parametric
measurement error models", J. Am. Stat. Assoc. 89 (1994) 1314–1328 (why re-measuring noisy
data needs care: the noise enters twice); B. Efron and R. J. Tibshirani, An Introduction to the
Bootstrap (1993) §6, §10 (parametric bootstrap: standard error and bias); A. M. Mathai and
S. B. Provost, Quadratic Forms in Random Variables (1992), Thm 3.2b.2 (mean and variance of a
quadratic form in Gaussian variables); H. A. David and H. N. Nagaraja, Order Statistics, 3rd ed.
(2003) §7.1 (distribution-free confidence intervals for quantiles: the Monte Carlo error of an
interval end).
"""

from __future__ import annotations

import abc
import dataclasses
import math
from collections.abc import Callable, Iterator, Sequence
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from rotacal.errors import ConfigError
from rotacal.uncertainty.budget import BudgetRow, UncertaintyBudget
from rotacal.uncertainty.gum import Input, coverage_factor, welch_satterthwaite
from rotacal.uncertainty.summaries_peak import (
    WINDOW,
    PeakInputs,
    WelchSums,
    denoised_at,
    welch_gain,
    window_length,
)
from rotacal.uncertainty.summaries_rms import SeriesStats, rms_budget

__all__ = [
    "COVERAGE",
    "MC_SEED",
    "MC_TRIALS",
    "CirculantError",
    "CovarianceCorrection",
    "ErrorProcess",
    "FilteredWhite",
    "SeriesStats",
    "Summary",
    "candidate_positions",
    "corrections_drawn",
    "denoise_gain",
    "denoised",
    "drop_large_dof_notes",
    "expected_periodogram",
    "iter_statistic_samples",
    "mc_budget",
    "monte_carlo_statistics",
    "noise_periodogram",
    "rms_budget",
    "statistic_samples",
]

FloatArray = NDArray[np.float64]
Role = Literal["noise", "bound", "absent"]

#: Coverage probability of every interval stated here.
COVERAGE = 0.95
#: Monte Carlo trials and seed of the peak-to-peak/peak budgets (reproducible results). 1000
#: trials put the 97.5 % quantile within about 3 % of the interval's width (stated per budget).
MC_TRIALS = 1000
MC_SEED = 2026
#: Probability that the union bound behind the candidate elements may fail (per summary).
_CANDIDATE_RISK = 1e-3
#: Elements of the random arrays held at once (memory of full-length draws).
_CHUNK_ELEMENTS = 4_000_000
_ROLES = ("noise", "bound", "absent")
#: Largest number of candidate elements whose covariance is factored when a correction needs it.
_JOINT_MAX = 400


def drop_large_dof_notes(b: UncertaintyBudget) -> UncertaintyBudget:
    """Leave out the note on truncating ν_eff when ν_eff ≥ 10⁴ (k is then t_p(∞) to 2·10⁻⁴)."""
    if not (b.dof_eff >= 1e4):
        return b
    return dataclasses.replace(b, notes=tuple(n for n in b.notes if "truncated to" not in n))


# ------------------------------------------------------------------------------ error processes
@dataclasses.dataclass(frozen=True)
class ErrorProcess(abc.ABC):
    """A stationary Gaussian error along a vector of N elements, and its role in a budget.

    Attributes
    ----------
    input : Input
        Its budget row (name, u, ν, distribution, origin); ``input.u`` is in the input's own unit
        (e.g. s for a timing jitter), the process in the unit of the vector.
    role : {"noise", "bound", "absent"}
        See the module docstring.
    """

    input: Input
    role: Role
    #: False for a correction of the covariance that is no process of its own (it may be
    #: negative: a correlation between two sources); see :class:`CovarianceCorrection`.
    drawable: bool = dataclasses.field(default=True, init=False)
    #: Sources with the same non-empty ``level`` scale with one estimated level (e.g. a timing
    #: jitter and a correction proportional to it): its uncertainty counts once, for their sum.
    level: str = ""

    def __post_init__(self) -> None:
        if self.role not in _ROLES:
            raise ConfigError(f"role must be one of {_ROLES}, got {self.role!r}.")

    @abc.abstractmethod
    def lags(self, n: int) -> FloatArray:
        """Autocovariance g(ℓ), ℓ = 0 … n − 1, along the vector (unit of the vector, squared)."""

    @abc.abstractmethod
    def draw_at(
        self, rng: np.random.Generator, size: int, positions: NDArray[np.int64], n: int
    ) -> FloatArray:
        """``size`` draws of the error at the given elements of an n-vector, shape (size, K)."""

    def local_cost(self, k: int) -> float:
        """Relative cost per trial of drawing K elements through a Cholesky factor (inf: never)."""
        return math.inf


def _draw_circulant(rng: np.random.Generator, size: int, var: FloatArray, m: int) -> FloatArray:
    """``size`` real Gaussian vectors of length m whose rfft orders have E|c_q|² = var[q]."""
    c = rng.standard_normal((size, 2 * var.size)).view(np.complex128)  # re, im ~ N(0, 1)
    c *= np.sqrt(0.5 * var)
    c[:, 0] = c[:, 0].real * math.sqrt(2.0)  # order 0 and Nyquist of a real vector are real
    if m % 2 == 0:
        c[:, -1] = c[:, -1].real * math.sqrt(2.0)
    return np.fft.irfft(c, m, axis=-1)


@dataclasses.dataclass(frozen=True)
class CirculantError(ErrorProcess):
    """An error that is a stationary process on a circle of L elements: element i of the vector
    holds the process at position i mod L (L = N for a scale curve; L < N repeats it, e.g. the
    same scale lines in every revolution).

    Attributes
    ----------
    autocov : ndarray, shape (L,)
        c(k), k = 0 … L − 1 (circular; c(k) = c(L − k)), unit of the vector squared.
    """

    autocov: FloatArray = dataclasses.field(default_factory=lambda: np.zeros(1))

    def lags(self, n: int) -> FloatArray:
        c = self.autocov
        return c[np.arange(n) % c.size]

    def spectrum(self) -> FloatArray:
        """E|c_q|² of the rfft orders of one period (numpy's unnormalised rfft)."""
        c = self.autocov
        return np.maximum(np.fft.rfft(c).real, 0.0) * c.size

    def draw_full(self, rng: np.random.Generator, size: int) -> FloatArray:
        """``size`` draws of one whole period, shape (size, L)."""
        return _draw_circulant(rng, size, self.spectrum(), self.autocov.size)

    def draw_at(
        self, rng: np.random.Generator, size: int, positions: NDArray[np.int64], n: int
    ) -> FloatArray:
        period = self.autocov.size
        var = self.spectrum()
        where = positions % period
        chunk = max(1, _CHUNK_ELEMENTS // period)
        parts = []
        done = 0
        while done < size:
            step = min(chunk, size - done)
            parts.append(_draw_circulant(rng, step, var, period)[:, where])
            done += step
        return np.concatenate(parts, axis=0)

    def local_cost(self, k: int) -> float:
        # a whole period per trial (normals + FFT) against K² multiply-adds per trial
        return float(k * k) / (12.0 * 12.0 * self.autocov.size)


@dataclasses.dataclass(frozen=True)
class FilteredWhite(ErrorProcess):
    """e_i = σ·Σ_k h_k·w_{i+k} with w white N(0, 1): e.g. a rate over a block of pulses, whose
    error is the difference of the timing errors at the block's two ends (h = (−s, s)).

    Attributes
    ----------
    taps : ndarray, shape (r,)
        h_0 … h_{r−1} (unit of the vector per unit of σ).
    sigma : float
        Standard deviation of w (the input's unit).
    """

    taps: FloatArray = dataclasses.field(default_factory=lambda: np.ones(1))
    sigma: float = 0.0

    def lags(self, n: int) -> FloatArray:
        h = np.asarray(self.taps, dtype=np.float64)
        r = np.correlate(h, h, mode="full")[h.size - 1 :] * self.sigma**2
        out = np.zeros(n)
        out[: min(n, r.size)] = r[: min(n, r.size)]
        return out

    def draw_at(
        self, rng: np.random.Generator, size: int, positions: NDArray[np.int64], n: int
    ) -> FloatArray:
        h = np.asarray(self.taps, dtype=np.float64)
        need = (positions[:, None] + np.arange(h.size)[None, :]).ravel()
        uniq, inv = np.unique(need, return_inverse=True)
        w = rng.standard_normal((size, uniq.size))
        # Σ_k h_k·w[:, i + k] tap by tap, one (size, K) gather each: a third of the time of
        # gathering all (size, K, r) values and a stacked matrix–vector product, same sums.
        at = inv.reshape(positions.size, h.size)
        acc = h[0] * w[:, at[:, 0]]
        for j in range(1, h.size):
            acc += h[j] * w[:, at[:, j]]
        return self.sigma * acc


@dataclasses.dataclass(frozen=True)
class CovarianceCorrection(CirculantError):
    """A correction of the covariance of the errors, circulant like :class:`CirculantError` but
    not a process of its own: 2·Cov between two sources that are not independent (e.g. a rate
    head's timing noise and the self-calibration it is compensated with). It enters the closed
    forms (mean and variance of a mean square) exactly; a Monte Carlo draws it jointly with the
    other sources of its role when the covariance among the candidates can be factored, and
    otherwise leaves it out (a negative correction left out overstates the noise: the interval
    stays valid, the bias is overstated).
    """

    drawable: bool = dataclasses.field(default=False, init=False)

    def draw_at(
        self, rng: np.random.Generator, size: int, positions: NDArray[np.int64], n: int
    ) -> FloatArray:
        raise ConfigError(f"'{self.input.name}' is a covariance correction, not a process.")


@dataclasses.dataclass(frozen=True)
class Summary:
    """A summary's budget with its noise bias (None when no noise of known level is in the data).

    Attributes
    ----------
    budget : UncertaintyBudget
        ``value`` the plain summary, u, ``interval`` for the true value, U, k.
    bias : float or None
        How much the noise of known level raises the plain value (its unit).
    bias_corrected : float or None
        The plain value less that bias (its unit).
    """

    budget: UncertaintyBudget
    bias: float | None
    bias_corrected: float | None


def _check(data: FloatArray, sources: Sequence[ErrorProcess]) -> FloatArray:
    d = np.asarray(data, dtype=np.float64)
    if d.ndim != 1 or d.size < 2 or not np.all(np.isfinite(d)):
        raise ConfigError("a summary needs a finite vector of at least 2 values.")
    if not sources:
        raise ConfigError("a summary's budget needs at least one error source.")
    return d


def _role_notes(sources: Sequence[ErrorProcess]) -> list[str]:
    out = []
    names = {r: [s.input.name for s in sources if s.role == r] for r in _ROLES}
    if names["bound"]:
        out.append(
            "in the data but not corrected for (its level is only bounded or stated, so it must "
            f"not make the result look better): {', '.join(names['bound'])}; the interval's "
            "lower end allows for all of it."
        )
    if names["absent"]:
        out.append(
            f"part of the true curve that the data lack: {', '.join(names['absent'])}; the "
            "interval is for the true value including it."
        )
    return out


def _dof(sources: Sequence[ErrorProcess], var: Sequence[float]) -> float:
    """Welch–Satterthwaite ν of a variance made of the sources' parts ``var``."""
    if sum(var) <= 0:
        return math.inf
    return welch_satterthwaite(np.sqrt(np.maximum(var, 0.0)), [s.input.dof for s in sources])


# ------------------------------------------------------------------------------ peak / pp
def candidate_positions(
    data: FloatArray, g_total: FloatArray, statistic: Literal["pp", "peak"]
) -> tuple[NDArray[np.int64], NDArray[np.bool_], NDArray[np.bool_]]:
    """The elements that can hold the extremes of the true curve or of a re-measurement.

    With σ_D the largest standard deviation of the difference of two elements' errors and
    z = √(2 ln(N/10⁻³)) (a union bound over the elements), an element of the true curve within
    τ = z·σ_D of its peak lies within 2τ of the data's peak, and one farther off cannot become the
    peak. Returns the positions (sorted), and for each whether it is a candidate for the maximum
    ("hi") and for the minimum ("lo") — for ``"peak"`` of |d|, both the same.
    """
    n = data.size
    z = math.sqrt(2.0 * math.log(n / _CANDIDATE_RISK))
    sigma_d = math.sqrt(max(2.0 * (float(g_total[0]) - float(np.min(g_total))), 0.0))
    delta = 2.0 * z * sigma_d
    if statistic == "peak":
        a = np.abs(data)
        hi = a >= a.max() - delta
        lo = hi
    else:
        hi = data >= data.max() - delta
        lo = data <= data.min() + delta
    pos = np.flatnonzero(hi | lo).astype(np.int64)
    return pos, hi[pos], lo[pos]


def _factor(cov: FloatArray) -> FloatArray:
    """A matrix L with L·Lᵀ = cov (cov symmetric positive semi-definite)."""
    scale = float(np.trace(cov)) / max(cov.shape[0], 1)
    try:
        return np.linalg.cholesky(cov + np.eye(cov.shape[0]) * (1e-12 * scale))
    except np.linalg.LinAlgError:
        w, v = np.linalg.eigh(cov)
        return v * np.sqrt(np.maximum(w, 0.0))


def statistic_samples(
    positions: NDArray[np.int64],
    n: int,
    sources: Sequence[ErrorProcess],
    *,
    trials: int = MC_TRIALS,
    seed: int = MC_SEED,
) -> dict[str, FloatArray]:
    """Monte Carlo draws of the errors at the given elements of an n-vector, by role group.

    Returns ``{"noise": (M, K), "other": (M, K)}`` — the sum of the sources of role "noise", and
    of the others ("bound" and "absent"), independent of each other. Every source is drawn
    exactly: its own way (a whole circulant period, the white values a filter needs), or, when
    only a few of the many elements are needed, jointly with the others of its group through
    the Cholesky factor of their covariance among the K elements. The rows are those of
    :func:`iter_statistic_samples` (the same draws, batch by batch).

    References
    ----------
    JCGM 101:2008 §6.4.8 (multivariate Gaussian by a Cholesky factor), §7.2–7.4.
    """
    parts = list(iter_statistic_samples(positions, n, sources, trials=trials, seed=seed))
    return {g: np.concatenate([x[g] for x in parts], axis=0) for g in ("noise", "other")}


def iter_statistic_samples(
    positions: NDArray[np.int64],
    n: int,
    sources: Sequence[ErrorProcess],
    *,
    trials: int = MC_TRIALS,
    seed: int = MC_SEED,
    batch: int | None = None,
) -> Iterator[dict[str, FloatArray]]:
    """:func:`statistic_samples` in batches of ``batch`` trials (default: about
    :data:`_CHUNK_ELEMENTS` values per array): each source's generator carries on from batch to
    batch, so the rows are the same whatever the batch, and memory is bounded by the batch."""
    k = positions.size
    step = max(1, batch if batch is not None else _CHUNK_ELEMENTS // max(k, 1))
    streams = np.random.SeedSequence(seed).spawn(len(sources) + 2)
    plans = []
    for group, ss in zip(("noise", "other"), streams[-2:], strict=True):
        members = [
            (s, st)
            for s, st in zip(sources, streams, strict=False)
            if (s.role == "noise") == (group == "noise")
        ]
        exact = corrections_drawn([s for s, _ in members], k)
        if any(not s.drawable for s, _ in members) and exact:
            joint_ids = {id(s) for s, _ in members}  # the correction needs the joint factor
        else:
            joint_ids = {id(s) for s, _ in members if s.drawable and s.local_cost(k) < 1.0}
        own = [
            (s, np.random.default_rng(st))
            for s, st in members
            if id(s) not in joint_ids and s.drawable
        ]
        factor = None
        if joint_ids:
            lag = np.abs(positions[:, None] - positions[None, :])
            cov = np.zeros((k, k))
            for s, _ in members:
                if id(s) in joint_ids:
                    cov += s.lags(int(lag.max()) + 1)[lag]
            factor = (np.random.default_rng(ss), _factor(cov).T)
        plans.append((group, own, factor))
    for start in range(0, trials, step):
        size = min(step, trials - start)
        out = {}
        for group, own, factor in plans:
            acc = np.zeros((size, k))
            for s, rng in own:
                acc += s.draw_at(rng, size, positions, n)
            if factor is not None:
                acc += factor[0].standard_normal((size, k)) @ factor[1]
            out[group] = acc
        yield out


def corrections_drawn(sources: Sequence[ErrorProcess], k: int) -> bool:
    """Whether :func:`statistic_samples` draws the covariance corrections among ``sources``
    exactly (jointly with the rest, through a Cholesky factor: K ≤ 400 candidates)."""
    return all(s.drawable for s in sources) or k <= _JOINT_MAX


def monte_carlo_statistics(
    base: FloatArray,
    draws: FloatArray,
    statistic: Callable[[FloatArray], FloatArray],
    scales: Sequence[float] = (1.0,),
) -> list[FloatArray]:
    """The statistic of ``base + s·draws`` (trial by trial) for every scale s: one (M,) array each.

    References
    ----------
    JCGM 101:2008 §7.5 (model evaluation), §7.6 (estimate and standard uncertainty).
    """
    return [np.asarray(statistic(base + s * draws), dtype=np.float64) for s in scales]


def expected_periodogram(g: FloatArray) -> FloatArray:
    """E|X_q|² of the rfft orders of N samples of a stationary process with autocovariance
    g(ℓ), ℓ = 0 … N − 1: Σ_ℓ (N − |ℓ|)·g(|ℓ|)·e^(−2πiqℓ/N) (the Fejér-weighted spectrum)."""
    n = g.size
    a = (n - np.arange(n, dtype=np.float64)) * g
    return np.maximum(2.0 * np.fft.rfft(a).real - a[0], 0.0)


def denoised(data: FloatArray, g_noise: FloatArray, smooth: int = 8) -> FloatArray:
    """The vector with its noise shrunk away order by order (Wiener): each rfft order times
    max(0, 1 − E|noise_q|²/S_q), S_q the data's periodogram averaged over ±``smooth`` orders.

    A curve the noise dominates comes out near its mean, orders far above the noise are kept:
    the base on which a re-measurement (parametric bootstrap) sees the extremes compete as they
    do in the true curve, rather than with the data's own noise once more.

    References
    ----------
    N. Wiener, Extrapolation, Interpolation and Smoothing of Stationary Time Series (1949); the
    smoothed periodogram: P. Bloomfield, Fourier Analysis of Time Series, 2nd ed. (2000) §8.
    """
    n = data.size
    spec = np.fft.rfft(data)
    power = np.abs(spec) ** 2
    kernel = np.ones(2 * smooth + 1)
    padded = np.concatenate((power[smooth:0:-1], power, power[-2 : -smooth - 2 : -1]))
    s = np.convolve(padded, kernel, mode="valid") / kernel.size
    noise = expected_periodogram(g_noise)
    with np.errstate(divide="ignore", invalid="ignore"):
        gain = np.where(s > 0, np.clip(1.0 - noise / s, 0.0, 1.0), 0.0)
    gain[0] = 1.0
    return np.fft.irfft(spec * gain, n)


def _quantile_se(x: FloatArray, q: float) -> float:
    """Monte Carlo standard error of the q-quantile of x: half the distance between the order
    statistics one binomial standard deviation either side (David & Nagaraja §7.1)."""
    srt = np.sort(x)
    m = srt.size
    half = math.sqrt(m * q * (1.0 - q))
    lo = int(np.clip(math.floor(m * q - half), 0, m - 1))
    hi = int(np.clip(math.ceil(m * q + half), 0, m - 1))
    return 0.5 * float(srt[hi] - srt[lo])


def _support(s: ErrorProcess) -> int:
    """Lags beyond which a source's autocovariance only repeats (a period) or is zero (taps)."""
    if isinstance(s, CirculantError):
        return int(s.autocov.size) + 1
    if isinstance(s, FilteredWhite):
        return int(np.asarray(s.taps).size) + 1
    return 1 << 62


def noise_periodogram(sources: Sequence[ErrorProcess], n: int) -> FloatArray:
    """E|X_q|² of one Welch window (:func:`~rotacal.uncertainty.summaries_peak.window_length`)
    of the sum of ``sources`` over a vector of n elements."""
    size = window_length(n)
    g = sum((s.lags(size) for s in sources), np.zeros(size))
    return expected_periodogram(g)


def denoise_gain(
    d: FloatArray, sources: Sequence[ErrorProcess], group: Sequence[ErrorProcess]
) -> FloatArray:
    """The Wiener gain that shrinks the errors ``group`` away from d (Welch spectrum of d)."""
    welch = WelchSums(d.size)
    welch.update(d)
    return welch_gain(welch.power(), noise_periodogram(group, d.size))


def mc_budget(
    quantity: str,
    unit: str,
    data: FloatArray | PeakInputs,
    sources: Sequence[ErrorProcess],
    *,
    statistic: Literal["pp", "peak"],
    notes: Sequence[str] = (),
    trials: int = MC_TRIALS,
    seed: int = MC_SEED,
    p: float = COVERAGE,
) -> Summary:
    """Budget of the peak-to-peak (``"pp"``) or the peak |value| (``"peak"``) of a vector.

    Parameters
    ----------
    quantity, unit : str
        JSON key and unit (the vector's unit).
    data : ndarray, shape (N,), or PeakInputs
        The measured vector d, or (for ``"peak"``) what the budget needs of it, collected over
        a stream (:mod:`rotacal.uncertainty.summaries_peak`: the same numbers).
    sources : sequence of ErrorProcess
        Its errors, each with its role.
    statistic : {"pp", "peak"}
        max − min, or max |d|.
    notes : sequence of str
        Extra sentences for the budget.
    trials, seed : int
        Monte Carlo trials M and seed (reproducible).
    p : float
        Coverage probability (0.95).

    Returns
    -------
    Summary
        ``budget.method = "Monte Carlo"``, ``value`` the plain statistic, ``interval`` for the
        true value; the bias from the sources of role "noise" (None without one).

    References
    ----------
    JCGM 101:2008 §7.6 (u as the standard deviation of the model values), §7.7 (coverage
    interval); JCGM 102:2011 §9 (bias of a magnitude-type output near zero); Efron & Tibshirani
    (1993) §6, §10 (bootstrap standard error and bias); David & Nagaraja (2003) §7.1 (Monte Carlo
    error of a quantile).
    """
    if statistic not in ("pp", "peak"):
        raise ConfigError(f"statistic must be 'pp' or 'peak', got {statistic!r}.")
    if isinstance(data, PeakInputs):
        if statistic != "peak" or data.n < 2 or not sources:
            raise ConfigError("the candidates of a stream serve the peak of at least 2 values.")
        n = data.n
    else:
        d = _check(data, sources)
        n = d.size
    # the autocovariances as far as they are not periodic repeats or zeros (and one window)
    support = min(n, max([WINDOW, *(_support(s) for s in sources)]))
    g = {id(s): s.lags(support) for s in sources}
    drawable = [s for s in sources if s.drawable]
    # the processes alone (a negative correction left out: conservative bounds and candidates)
    g_total = sum((g[id(s)] for s in drawable), np.zeros(support))
    present = [s for s in sources if s.role != "absent"]
    noise_only = [s for s in sources if s.role == "noise"]
    if isinstance(data, PeakInputs):
        inputs = data
        is_hi = is_lo = np.ones(inputs.pos.size, dtype=bool)
    else:
        pos, is_hi, is_lo = candidate_positions(d, g_total, statistic)
        gains = [denoise_gain(d, sources, group) for group in (present, noise_only)]
        plain = float(np.ptp(d)) if statistic == "pp" else float(np.max(np.abs(d)))
        inputs = PeakInputs(n, plain, pos, d[pos], denoised_at(d, pos, gains))
    pos, base, plain = inputs.pos, inputs.base, inputs.plain

    # the candidates for the largest and the smallest value as index arrays, or all of them (no
    # gather: max and min are exact in any order, so the same numbers at a fraction of the cost)
    hi_at = slice(None) if np.all(is_hi) else np.flatnonzero(is_hi)
    lo_at = slice(None) if np.all(is_lo) else np.flatnonzero(is_lo)

    def stat(x: FloatArray) -> FloatArray:
        if statistic == "peak":
            return np.max(np.abs(x), axis=-1)
        return np.max(x[..., hi_at], axis=-1) - np.min(x[..., lo_at], axis=-1)

    # many candidates (a curve near zero): fewer trials, the Monte Carlo error is stated
    trials = min(trials, max(250, _CHUNK_ELEMENTS // (2 * pos.size)))
    noisy = any(s.role == "noise" for s in sources)
    # u: the spread of the statistic re-measured with every error — from the data themselves
    # (their noise then counts twice: too large where the noise sets the extremes) and from the
    # denoised curve (its extremes too flat: too small where single elements set them); their
    # geometric mean lies within the square root of either's error
    g_present = sum((g[id(s)] for s in present), np.zeros(support))
    f_all = inputs.denoised[0] if np.any(g_present) else base
    f_n = inputs.denoised[1]
    # per trial, batch by batch (memory bounded by a batch, whatever the candidates)
    per_trial: dict[str, list[FloatArray]] = {"den": [], "data": [], "worst": [], "noise": []}
    for draws in iter_statistic_samples(pos, n, sources, trials=trials, seed=seed):
        total = draws["noise"] + draws["other"]
        per_trial["den"].append(monte_carlo_statistics(f_all, total, stat)[0])
        per_trial["data"].append(monte_carlo_statistics(base, total, stat)[0])
        # upper error bound: the largest error the candidate elements carry
        if statistic == "peak":
            per_trial["worst"].append(np.max(np.abs(total), axis=-1))
        else:
            per_trial["worst"].append(stat(total))
        if noisy:
            per_trial["noise"].append(monte_carlo_statistics(f_n, draws["noise"], stat)[0])
    y_den, y_data, worst = (np.concatenate(per_trial[key]) for key in ("den", "data", "worst"))
    u_den, u_data = float(np.std(y_den, ddof=1)), float(np.std(y_data, ddof=1))
    u = math.sqrt(u_den * u_data)
    q_hi = float(np.quantile(worst, 0.5 + 0.5 * p))
    lo = max(plain - q_hi, 0.0)
    # lower error bound: the error at the true extreme(s), Gaussian with this variance
    var_one = float(g_total[0]) if statistic == "peak" else 2.0 * (g_total[0] - np.min(g_total))
    nu = _dof(drawable, [float(g[id(s)][0]) for s in drawable])
    t = coverage_factor(nu, p)
    hi = plain + t * math.sqrt(max(var_one, 0.0))
    big_u = 0.5 * (hi - lo)
    se_lo = _quantile_se(worst, 0.5 + 0.5 * p)
    bias = corrected = None
    text = [
        f"Monte Carlo with M = {trials} trials (seed {seed}) over the {pos.size} of {n} elements "
        "that can hold the extremes: u is the geometric mean of the statistic's spread "
        f"re-measured from the data ({u_data:.3g} {unit}: their noise counted twice) and from "
        f"the denoised curve ({u_den:.3g} {unit}: extremes too flat) — parametric bootstrap. "
        "95 % interval for the true value "
        f"[{lo:.6g}, {hi:.6g}] {unit}: the plain value less the 97.5 % quantile of the largest "
        "error those elements carry, and plus t·σ of the error at one extreme — each end holds "
        "with probability ≥ 97.5 % whatever the true curve (conservative when the extremes are "
        f"sharp); Monte Carlo standard error of the lower end ≈ {se_lo:.2g} {unit}. U is half "
        "the interval's width, k = U/u."
    ]
    if noisy:
        # the bias the known noise gives: re-measure the denoised curve with that noise alone
        y_n = np.concatenate(per_trial["noise"])
        bias = float(np.mean(y_n)) - float(stat(f_n))
        corrected = plain - bias
        se_b = float(np.std(y_n, ddof=1)) / math.sqrt(trials)
        text.append(
            f"bias from the noise of known level {bias:+.3g} {unit}: the mean rise of the "
            "statistic when the denoised curve is re-measured with that noise (Monte Carlo "
            f"standard error ≈ {se_b:.2g} {unit}); bias-corrected value {corrected:.6g} {unit}."
        )
        if abs(bias) > 0.1 * abs(plain):
            text.append(
                "the noise makes up much of the plain value: the bias-corrected value is "
                "approximate; the interval stays valid."
            )
    else:
        text.append(
            "no noise of known level in the data: the plain value is not corrected for bias; the "
            f"firm statement is the upper end, true value ≤ {hi:.6g} {unit} (p ≈ 97.5 %)."
        )
    for s in sources:
        if not s.drawable:
            text.append(
                f"{s.input.name} ({s.input.source}): a correlation between two of the errors; "
                + (
                    "drawn jointly with them."
                    if corrections_drawn(sources, pos.size)
                    else f"left out of the draws over {pos.size} elements (it lowers the noise: "
                    "the interval stays valid, the bias is somewhat overstated)."
                )
            )
    rows = []
    if statistic == "peak":
        weights = [float(g[id(s)][0]) for s in drawable]
    else:
        lag = abs(int(np.argmax(d)) - int(np.argmin(d)))
        weights = [2.0 * float(g[id(s)][0] - s.lags(lag + 1)[lag]) for s in drawable]
    w_sum = sum(weights)
    for s, w in zip(drawable, weights, strict=True):
        share = w / w_sum if w_sum > 0 else 0.0
        contrib = u * math.sqrt(share)
        rows.append(
            BudgetRow(
                source=s.input.name,
                value=s.input.value,
                unit=s.input.unit,
                distribution=s.input.description or s.input.distribution,
                u=s.input.u,
                sensitivity=contrib / s.input.u if s.input.u > 0 else 0.0,
                contribution=contrib,
                share=share,
                dof=s.input.dof,
                origin=s.input.source,
            )
        )
    if len(drawable) > 1:
        text.append(
            "u is split among the rows in proportion to each source's variance at the extremes "
            "(the statistic moves with the errors there)."
        )
    budget = UncertaintyBudget(
        quantity=quantity,
        unit=unit,
        value=plain,
        u=u,
        dof_eff=math.inf,
        k=big_u / u if u > 0 else coverage_factor(math.inf, p),
        p=p,
        U=big_u,
        rows=tuple(rows),
        method="Monte Carlo",
        notes=(*text, *_role_notes(sources), *notes),
        interval=(lo, hi),
    )
    return Summary(budget, bias, corrected)
