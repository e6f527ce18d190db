"""What a Monte Carlo of tables drawn within their tolerances states, with its coverage interval.

A Monte Carlo check draws N tables (and angles) and counts how many keep the orientation within
the requirement; the largest error of N draws depends on N and has no coverage interval without a
model of the distribution's tail. The statistics here are population quantities with
distribution-free coverage intervals, so a repeat with another seed falls inside them as often as
p says:

- :func:`fraction_interval` — the fraction of tables that keep a property (within the requirement,
  above a rate error), with its exact binomial (Clopper–Pearson) interval;
- :func:`quantile_interval` — the q-quantile of a sample (the error 99.9 % of tables stay within)
  from its order statistics, with the interval whose ranks come from the binomial distribution;
- :class:`TopValues` — the largest values of a stream of chunks (carried state), enough to state
  an upper quantile of a long Monte Carlo without keeping every draw.

References
----------
Clopper C. J., Pearson E. S. (1934), Biometrika 26(4), 404–413 (the exact binomial interval);
David H. A., Nagaraja H. N. (2003), Order Statistics, 3rd ed., §7.1 (distribution-free
confidence intervals for quantiles); JCGM 101:2008 (GUM Supplement 1) §7.7 (coverage intervals
from Monte Carlo draws).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import beta, binom

__all__ = [
    "COVERAGE",
    "QUANTILE",
    "TopValues",
    "fraction_interval",
    "quantile_interval",
    "top_values_needed",
]

#: Coverage probability of the intervals stated.
COVERAGE = 0.95
#: The upper quantile of |Δ| a turntable budget states: the error 99.9 % of tables stay within.
QUANTILE = 0.999


def fraction_interval(hits: int, n: int, p: float = COVERAGE) -> tuple[float, float, float]:
    """The fraction ``hits / n`` and its two-sided Clopper–Pearson interval for probability ``p``.

    Parameters
    ----------
    hits : int
        Draws with the property (0 ≤ hits ≤ n).
    n : int
        Draws (≥ 1).
    p : float
        Coverage probability (0.95).

    Returns
    -------
    (fraction, low, high)
        With ``hits == n`` the interval is [(1 − p)/2 ^ (1/n), 1]; with 0 hits, [0, 1 − that].

    References
    ----------
    Clopper & Pearson (1934): the limits are the (1 − p)/2 and (1 + p)/2 quantiles of
    Beta(hits, n − hits + 1) and Beta(hits + 1, n − hits).
    """
    tail = 0.5 * (1.0 - p)
    low = 0.0 if hits == 0 else float(beta.ppf(tail, hits, n - hits + 1))
    high = 1.0 if hits == n else float(beta.ppf(1.0 - tail, hits + 1, n - hits))
    return hits / n, low, high


def _ranks(n: int, q: float, p: float) -> tuple[int, int]:
    """1-based ascending ranks (l, u) with P(X_(l) ≤ ξ_q ≤ X_(u)) ≥ p (David & Nagaraja §7.1)."""
    tail = 0.5 * (1.0 - p)
    low = int(binom.ppf(tail, n, q))  # P(B ≤ low − 1) ≤ tail
    high = int(binom.ppf(1.0 - tail, n, q)) + 1  # P(B ≥ high) ≤ tail
    return max(low, 0), high


def top_values_needed(n: int, q: float = QUANTILE, p: float = COVERAGE) -> int:
    """How many of the largest of ``n`` values :func:`quantile_interval` reads (its lowest rank)."""
    low, high = _ranks(n, q, p)
    return n - low + 1 if 1 <= low and high <= n else 0


def quantile_interval(
    largest: np.ndarray, n: int, q: float = QUANTILE, p: float = COVERAGE
) -> tuple[float, float, float] | None:
    """The q-quantile of ``n`` draws and its distribution-free coverage interval for probability p.

    Parameters
    ----------
    largest : ndarray
        The largest values of the ``n`` draws (any order; at least :func:`top_values_needed` of
        them, or all ``n``), in the unit of the result.
    n : int
        Number of draws.
    q : float
        The quantile (0.999: the value 99.9 % of the draws stay within).
    p : float
        Coverage probability of the interval.

    Returns
    -------
    (value, low, high) or None
        The order statistic of rank ⌈n·q⌉ and the order statistics X_(l), X_(u) whose ranks come
        from Binomial(n, q); ``None`` when n is too small for an interval (qⁿ > (1 − p)/2, about
        3.7/(1 − q) draws for p = 95 %: the upper rank would lie beyond the largest draw).

    References
    ----------
    David & Nagaraja (2003) §7.1: P(X_(l) ≤ ξ_q ≤ X_(u)) = Σ_{i=l}^{u−1} C(n, i) qⁱ (1 − q)ⁿ⁻ⁱ,
    whatever the distribution (continuous).
    """
    low, high = _ranks(n, q, p)
    if low < 1 or high > n:
        return None
    values = np.sort(np.asarray(largest, dtype=float))
    first_rank = n - values.size + 1  # ascending rank of values[0]
    if low < first_rank:
        raise ValueError(f"quantile_interval needs the {n - low + 1} largest values")
    rank = max(math.ceil(n * q), 1)

    def at(r: int) -> float:
        return float(values[r - first_rank])

    return at(rank), at(low), at(high)


class TopValues:
    """The ``keep`` largest values of each column seen so far, over a stream of chunks.

    The result does not depend on how the stream is cut into chunks (the largest values of a
    union are the largest of the parts' largest).
    """

    def __init__(self, keep: int, columns: int) -> None:
        self.keep = int(keep)
        self.values = np.empty((0, columns))

    def add(self, chunk: np.ndarray) -> None:
        """Merge the rows of ``chunk`` (shape (m, columns)) into the largest values kept."""
        if self.keep == 0:
            return
        if self.values.shape[0] == self.keep:  # full: only values above a column's least can enter
            floor = self.floor()
            self.add_columns([chunk[:, j][chunk[:, j] > floor[j]] for j in range(chunk.shape[1])])
            return
        both = np.concatenate((self.values, chunk), axis=0)
        if both.shape[0] > self.keep:
            both = np.partition(both, both.shape[0] - self.keep, axis=0)[-self.keep :]
        self.values = both

    def floor(self) -> np.ndarray:
        """Per column, the value a new one must exceed to enter: the least kept once ``keep``
        values are kept, −∞ before (+∞ when none are kept)."""
        columns = self.values.shape[1]
        if self.keep == 0:
            return np.full(columns, np.inf)
        if self.values.shape[0] < self.keep:
            return np.full(columns, -np.inf)
        return self.values.min(axis=0)

    def add_columns(self, candidates: list[np.ndarray]) -> None:
        """Merge, per column, the values of ``candidates[j]`` that exceed :meth:`floor` (all of
        them before ``keep`` are kept: then every column gets the same number)."""
        if self.keep == 0:
            return
        if self.values.shape[0] < self.keep:
            self.add(np.stack(candidates, axis=1))
            return
        columns = []
        for j, column in enumerate(candidates):
            both = np.concatenate((self.values[:, j], column))
            columns.append(np.partition(both, both.size - self.keep)[-self.keep :])
        self.values = np.stack(columns, axis=1)
