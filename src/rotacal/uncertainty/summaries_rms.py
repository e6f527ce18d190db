"""The rms of a measured vector and its budget from sufficient statistics (closed form).

What :func:`rms_budget` needs of the vector d (N elements) is only ms(d), dᵀG d for the Toeplitz
covariance G of each error source, and traces tr(G₁G₂) that do not depend on d at all. Every
source here is either short (:class:`~rotacal.uncertainty.summaries.FilteredWhite`: g(ℓ) = 0 from
its number of taps r on; dᵀGd needs the lagged sums Σd_i·d_{i+ℓ}, ℓ < r) or periodic
(:class:`~rotacal.uncertainty.summaries.CirculantError`: g(ℓ) = c(ℓ mod P), c symmetric on the
circle; then dᵀGd = Σ_j c(j)·T_j exactly, T the circular autocorrelation of the folded sums
S_c = Σ_{i ≡ c (mod P)} d_i). :class:`SeriesStats` holds those sums: from an array, or added up
chunk by chunk over a stream (carrying the global index), or mapped through d → a·d + b (a
series kept about a provisional reference). Memory: P + r values, whatever N.

References
----------
Mathai & Provost (1992) Thm 3.2b.2 (mean and variance of a quadratic form in Gaussian
variables); R. M. Gray, "Toeplitz and circulant matrices: a review", Found. Trends Commun. Inf.
Theory 2 (2006) §3 (a periodic Toeplitz form as a circular one on the folded vector).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from rotacal.errors import ConfigError
from rotacal.uncertainty.budget import BudgetRow, UncertaintyBudget
from rotacal.uncertainty.gum import coverage_factor

if TYPE_CHECKING:
    from rotacal.uncertainty.summaries import ErrorProcess, Summary

__all__ = ["SeriesStats", "rms_budget", "series_periods"]

FloatArray = NDArray[np.float64]

#: Lagged sums kept: enough for every short source (a two-tap difference needs lags 0 and 1).
MAX_LAG = 4


def series_periods(sources: Iterable[ErrorProcess]) -> tuple[int, ...]:
    """The periods P of the periodic sources among ``sources`` (what :class:`SeriesStats` folds)."""
    return tuple(sorted({int(p) for s in sources if (p := _period(s)) is not None}))


def _period(source: object) -> int | None:
    autocov = getattr(source, "autocov", None)
    return None if autocov is None else int(np.asarray(autocov).size)


def _taps(source: object) -> int:
    taps = getattr(source, "taps", None)
    if taps is None:
        raise ConfigError(f"{type(source).__name__}: neither periodic nor a short filter.")
    r = int(np.asarray(taps).size)
    if r > MAX_LAG:
        raise ConfigError(f"a filter of {r} taps is longer than the {MAX_LAG} lags kept.")
    return r


@dataclasses.dataclass
class SeriesStats:
    """Sufficient statistics of a vector d for :func:`rms_budget` (unit of d, squared).

    Attributes
    ----------
    n : int
        Elements seen.
    total : float
        Σd_i.
    lagged : ndarray, shape (MAX_LAG,)
        Σ_i d_i·d_{i+ℓ}, ℓ = 0 … MAX_LAG − 1 (pairs inside the vector).
    folded : dict of int -> ndarray
        For each period P, S_c = Σ_{i ≡ c (mod P)} d_i, c = 0 … P − 1.
    head, tail : ndarray
        The first and the last MAX_LAG − 1 elements (the sums that leave out a few edges).
    """

    n: int
    total: float
    lagged: FloatArray
    folded: dict[int, FloatArray]
    head: FloatArray
    tail: FloatArray

    @classmethod
    def empty(cls, periods: Sequence[int]) -> SeriesStats:
        """No element yet, folding over ``periods``."""
        return cls(
            0,
            0.0,
            np.zeros(MAX_LAG),
            {int(p): np.zeros(int(p)) for p in periods},
            np.zeros(0),
            np.zeros(0),
        )

    @classmethod
    def of(cls, data: FloatArray, periods: Sequence[int]) -> SeriesStats:
        """The statistics of a whole vector."""
        out = cls.empty(periods)
        out.update(np.asarray(data, dtype=np.float64))
        return out

    def update(self, d: FloatArray) -> None:
        """Add the next elements (global index carried)."""
        if d.size == 0:
            return
        keep = MAX_LAG - 1
        joined = np.concatenate((self.tail, d))  # the pairs across the boundary
        off = self.tail.size
        for lag in range(MAX_LAG):
            # pairs (i, i + lag) whose second element is new
            first = max(off - lag, 0)
            a = joined[first : joined.size - lag]
            b = joined[first + lag :]
            self.lagged[lag] += float(np.dot(a, b))
        for period, sums in self.folded.items():
            start = self.n % period
            # whole turns of the circle from the first element at residue `start`
            pad = np.concatenate((np.zeros(start), d))
            turns = -(-pad.size // period)
            full = np.zeros(turns * period)
            full[: pad.size] = pad
            sums += full.reshape(turns, period).sum(axis=0)
        self.total += float(np.sum(d))
        if self.head.size < keep:
            self.head = np.concatenate((self.head, d[: keep - self.head.size]))
        self.tail = joined[-keep:].copy() if keep else np.zeros(0)
        self.n += int(d.size)

    def affine(self, scale: float, shift: float) -> SeriesStats:
        """The statistics of scale·d + shift (exact algebra; d kept about a provisional
        reference is moved onto the final one without a second pass)."""
        a, b, n = float(scale), float(shift), self.n
        lagged = np.empty(MAX_LAG)
        for lag in range(MAX_LAG):
            pairs = max(n - lag, 0)
            if pairs == 0:
                lagged[lag] = 0.0
                continue
            # Σ_{i < n−ℓ} d_i and Σ_{i ≥ ℓ} d_i: the total less the last / first ℓ elements
            lead = self.total - float(np.sum(self.tail[self.tail.size - lag :]))
            trail = self.total - float(np.sum(self.head[:lag]))
            lagged[lag] = a * a * self.lagged[lag] + a * b * (lead + trail) + pairs * b * b
        folded = {}
        for period, sums in self.folded.items():
            counts = np.full(period, n // period, dtype=np.float64)
            counts[: n % period] += 1.0
            folded[period] = a * sums + b * counts
        return SeriesStats(
            n, a * self.total + n * b, lagged, folded, a * self.head + b, a * self.tail + b
        )

    def quadratic(self, source: ErrorProcess) -> float:
        """dᵀG d for the source's Toeplitz covariance G (first column its autocovariance)."""
        period = _period(source)
        if period is None:
            g = source.lags(_taps(source))
            return float(g[0] * self.lagged[0] + 2.0 * np.dot(g[1:], self.lagged[1 : g.size]))
        if period not in self.folded:
            raise ConfigError(f"the statistics were not folded over the period {period}.")
        s = self.folded[period]
        f = np.fft.rfft(s)
        circular = np.fft.irfft(f * np.conj(f), period)  # T_j = Σ_c S_c·S_{c+j}
        c = np.asarray(getattr(source, "autocov"), dtype=np.float64)  # noqa: B009 (a CirculantError)
        return float(np.dot(c, circular))


def _residue_weights(n: int, period: int) -> FloatArray:
    """w_c = Σ (n − ℓ) over 1 ≤ ℓ ≤ n − 1 with ℓ ≡ c (mod P), c = 0 … P − 1 (arithmetic
    progressions: no length-n array)."""
    c = np.arange(period, dtype=np.float64)
    count = np.where(c <= n - 1, np.floor((n - 1 - c) / period) + 1.0, 0.0)
    count[0] -= 1.0  # ℓ = 0 is not a lag of the sum
    first = np.where(c == 0, float(period), c)  # the smallest ℓ ≥ 1 of each residue
    sum_l = count * first + period * count * (count - 1.0) / 2.0
    return np.asarray(count * n - sum_l, dtype=np.float64)


def trace_product(s1: ErrorProcess, s2: ErrorProcess, n: int) -> float:
    """tr(G₁G₂) = N·g₁(0)g₂(0) + 2·Σ_{ℓ=1}^{N−1}(N − ℓ)·g₁(ℓ)g₂(ℓ) for two sources over N
    elements: a short sum when either is short, a sum over the residues of a common period
    otherwise."""
    p1, p2 = _period(s1), _period(s2)
    if p1 is None or p2 is None:
        r = min(_taps(s1) if p1 is None else n, _taps(s2) if p2 is None else n, n)
        g1, g2 = s1.lags(r), s2.lags(r)
        w = n - np.arange(1, r, dtype=np.float64)
        return float(n * g1[0] * g2[0] + 2.0 * np.dot(w, g1[1:] * g2[1:]))
    period = math.lcm(p1, p2)
    if period > max(n, p1, p2):  # no common period within the vector: the lags themselves
        period = n
    f = s1.lags(period) * s2.lags(period)
    return float(n * f[0] + 2.0 * np.dot(_residue_weights(n, period), f))


def rms_budget(
    quantity: str,
    unit: str,
    data: FloatArray | SeriesStats,
    sources: Sequence[ErrorProcess],
    *,
    notes: Sequence[str] = (),
    p: float = 0.95,
) -> Summary:
    """Budget of the rms of a measured vector: closed-form bias, u and interval for the truth.

    Parameters
    ----------
    quantity, unit : str
        JSON key and unit of the rms (the vector's unit).
    data : ndarray, shape (N,), or SeriesStats
        The measured vector d (unit), or its sufficient statistics (folded over the periods of
        the periodic sources: :func:`series_periods`).
    sources : sequence of ErrorProcess
        Its errors, each with its role.
    notes : sequence of str
        Extra sentences for the budget.
    p : float
        Coverage probability.

    Returns
    -------
    Summary
        ``budget.method`` = "GUM" (exact mean and variance of the mean square, normal
        approximation for its interval); the bias and the bias-corrected value when a source of
        role "noise" is present.

    References
    ----------
    Mathai & Provost (1992) Thm 3.2b.2: for x ~ N(μ, C), E xᵀx = μᵀμ + tr C and
    Var xᵀx = 4μᵀCμ + 2 tr C²; JCGM 100:2008 §4.2 (variance of a Type A variance estimate,
    2σ⁴/ν); JCGM 101:2008 §7.7 (coverage interval).
    """
    from rotacal.uncertainty.summaries import Summary, _check, _dof, _role_notes

    if isinstance(data, SeriesStats):
        st = data
        if st.n < 2 or not math.isfinite(st.lagged[0]):
            raise ConfigError("a summary needs a finite vector of at least 2 values.")
        _check(np.zeros(2), sources)  # the sources' own check
    else:
        st = SeriesStats.of(_check(data, sources), series_periods(sources))
    n = st.n
    ms = float(st.lagged[0]) / n
    rms = math.sqrt(ms)
    present = [s for s in sources if s.role != "absent"]
    absent = [s for s in sources if s.role == "absent"]
    mean_sq = {id(s): float(s.lags(1)[0]) for s in sources}
    e_noise = sum(mean_sq[id(s)] for s in sources if s.role == "noise")
    e_bound = sum(mean_sq[id(s)] for s in sources if s.role == "bound")
    e_absent = sum(mean_sq[id(s)] for s in absent)
    # each source's part of Var ms(d) − ms(f) (the parts add up to the whole, cross terms shared)
    parts = []
    for s in sources:
        role = s.role
        other = present if role != "absent" else absent
        cross = sum(trace_product(s, o, n) for o in present)
        signal = st.quadratic(s) - cross
        if s.drawable:
            signal = max(signal, 0.0)
        v = (4.0 * signal + 2.0 * sum(trace_product(s, o, n) for o in other)) / n**2
        inp = s.input
        if role == "noise" and s.drawable and math.isfinite(inp.dof):
            # the level is itself estimated: 2E²/ν, E the mean square of all it scales
            level = s.level
            shared = sum(mean_sq[id(o)] for o in sources if o is s or (level and o.level == level))
            v += 2.0 * shared**2 / inp.dof
        parts.append(v)
    var = max(float(sum(parts)), 1e-300)
    sd = math.sqrt(var)
    centre = ms - e_noise + e_absent
    nu = _dof(sources, parts)
    z = coverage_factor(nu, p)
    lo_ms = centre - e_bound - z * sd
    hi_ms = centre + z * sd
    lo, hi = math.sqrt(max(lo_ms, 0.0)), math.sqrt(max(hi_ms, 0.0))
    # u: the error of the rms, ≈ that of the mean square over 2·rms (√ of the centre, kept off
    # zero by its own spread: near zero the rms is known to about √(z·sd))
    scale = 2.0 * math.sqrt(max(centre, sd, 1e-300))
    u = sd / scale
    big_u = 0.5 * (hi - lo)
    rows = tuple(
        BudgetRow(
            source=s.input.name,
            value=s.input.value,
            unit=s.input.unit,
            distribution=s.input.description or s.input.distribution,
            u=s.input.u,
            sensitivity=(math.sqrt(max(v, 0.0)) / scale) / s.input.u if s.input.u > 0 else 0.0,
            contribution=math.sqrt(max(v, 0.0)) / scale,
            share=v / var,
            dof=s.input.dof,
            origin=s.input.source,
        )
        for s, v in zip(sources, parts, strict=True)
        if s.drawable
    )
    bias = corrected = None
    text = [
        f"closed form: the mean square of the data is {ms:.6g} {unit}²; "
        + (
            f"the noise of known level adds {e_noise:.3g} {unit}² to it on average; "
            if e_noise
            else ""
        )
        + (f"the bounded errors up to {e_bound:.3g} {unit}²; " if e_bound else "")
        + (f"the parts the data lack add {e_absent:.3g} {unit}² to the truth; " if e_absent else "")
        + f"its standard deviation is {sd:.3g} {unit}² (4fᵀCf/N² + 2tr C²/N², the level's own "
        f"uncertainty included). 95 % interval for the true rms: [{lo:.6g}, {hi:.6g}] {unit} "
        "(the square root of the mean square's normal interval, clipped at 0); u is the spread "
        "of the rms's error, U half the interval's width, k = U/u."
    ]
    if e_noise:
        corrected = math.sqrt(max(ms - e_noise, 0.0))
        bias = rms - corrected
        text.append(
            f"bias from the noise of known level {bias:+.3g} {unit} (exact for a mean square); "
            f"bias-corrected rms {corrected:.6g} {unit}."
        )
    else:
        text.append(
            "no noise of known level in the data: the plain value is not corrected for bias; the "
            f"firm statement is the upper end, true rms ≤ {hi:.6g} {unit} (p ≈ 97.5 %)."
        )
    corrections = [(s, v) for s, v in zip(sources, parts, strict=True) if not s.drawable]
    for s, v in corrections:
        text.append(
            f"{s.input.name}: a correlation between two of the errors, in the mean square "
            f"({s.input.source}; it changes the noise's mean square by {mean_sq[id(s)]:+.3g} "
            f"{unit}² and its variance by {v:+.3g} {unit}⁴), so it has no row of its own."
        )
    if len(sources) > 1:
        text.append(
            "each row's contribution is its part of the mean square's variance (cross terms "
            "shared), so the shares add up to 100 %"
            + (" with the correlation's part." if corrections else ".")
        )
    budget = UncertaintyBudget(
        quantity=quantity,
        unit=unit,
        value=rms,
        u=u,
        dof_eff=nu,
        k=big_u / u if u > 0 else coverage_factor(math.inf, p),
        p=p,
        U=big_u,
        rows=rows,
        method="GUM",
        notes=(*text, *_role_notes(sources), *notes),
        interval=(lo, hi),
    )
    return Summary(budget, bias, corrected)
