"""Propagation of distributions by the Monte Carlo method (JCGM 101:2008, GUM Supplement 1).

:func:`monte_carlo` draws M values of every input quantity from its distribution
(:mod:`rotacal.uncertainty.distributions`), evaluates a vectorised measurement model on them in
batches, and summarises the M values of the output quantity: estimate (mean), standard uncertainty
(standard deviation), and the probabilistically symmetric and shortest coverage intervals of
:func:`coverage_interval`. With ``trials=None`` the adaptive procedure of JCGM 101 §7.9 chooses M:
batches of M₀ = max(100/(1 − p), 10⁴) trials are added until twice the standard deviation of the
batch averages of y, u(y) and of both interval endpoints is within the numerical tolerance δ of
u(y) at ``ndigits`` significant digits. :func:`validate_gum` compares a GUM result with a Monte
Carlo one as JCGM 101 §8 prescribes.

Reproducibility: the trials are drawn in fixed blocks of 10⁴, each from its own random stream
``SeedSequence(seed, spawn_key=(block,))``; the result for a seed is therefore the same for every
evaluation ``batch`` size (the batch only sets how many trials are held in memory at once).

Correlated inputs: a correlation matrix is accepted among Normal inputs only; those are drawn as
one multivariate Gaussian through the Cholesky factor of their correlation matrix (JCGM 101
§6.4.8). Other correlated quantities can be given as one :class:`MultivariateNormal` input.

References
----------
JCGM 101:2008, Evaluation of measurement data — Supplement 1 to the GUM — Propagation of
distributions using a Monte Carlo method: §5.9 and §7 (the method), §7.5–§7.7 (estimate, standard
uncertainty, coverage intervals), §7.9 (adaptive procedure), §8 (validation of the GUM uncertainty
framework), §9 (examples).
JCGM 102:2011 (Supplement 2), §7 (models with any number of output quantities).
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.results import Result
from rotacal.uncertainty.distributions import Distribution, Normal, _psd_factor

if TYPE_CHECKING:
    from rotacal.uncertainty.gum import GUMResult

__all__ = [
    "MonteCarloResult",
    "coverage_interval",
    "monte_carlo",
    "numerical_tolerance",
    "validate_gum",
]

#: Trials per random stream: trials [k·B, (k + 1)·B) always come from stream k.
_BLOCK = 10_000
#: Output values kept in the result for histograms.
_KEEP = 1_000_000
#: Input values listed in the message about a non-finite model output.
_SHOW_INPUTS = 6

Model = Callable[..., Any]
Progress = Callable[[int, int], None]


# ------------------------------------------------------------------------------------ the result
@dataclasses.dataclass(frozen=True)
class MonteCarloResult(Result):
    """Summary of the Monte Carlo values of one output quantity (unit of the model output).

    Attributes
    ----------
    value : float
        Estimate y: the average of the M model values (JCGM 101 §7.6, eq. (14)).
    u : float
        Standard uncertainty u(y): their standard deviation (JCGM 101 §7.6, eq. (15)).
    p : float
        Coverage probability of the intervals.
    trials : int
        Number M of Monte Carlo trials.
    seed : int
        Seed of the random streams (the same seed gives the same result).
    interval_symmetric : tuple of float
        Probabilistically symmetric 100p % coverage interval (JCGM 101 §7.7.1).
    interval_shortest : tuple of float
        Shortest 100p % coverage interval (JCGM 101 §7.7.2).
    converged : bool
        Adaptive run: the §7.9 stopping rule was met within ``max_trials``. Fixed run: True.
    output : str
        Name of the output quantity (``"y"`` for a model returning one array).
    tolerance : float
        Numerical tolerance δ of u(y) at ``ndigits`` significant digits (JCGM 101 §7.9.2).
    _samples : ndarray
        The first ≤ 10⁶ model values, for histograms (not in the JSON).
    """

    value: float
    u: float
    p: float
    trials: int
    seed: int
    interval_symmetric: tuple[float, float]
    interval_shortest: tuple[float, float]
    converged: bool
    output: str = "y"
    tolerance: float = math.nan
    _samples: np.ndarray = dataclasses.field(
        default_factory=lambda: np.empty(0), repr=False, compare=False
    )

    @property
    def samples(self) -> np.ndarray:
        """The first ≤ 10⁶ model values (unit of the output), in trial order."""
        return self._samples


# ------------------------------------------------------------------------------ small helpers
def numerical_tolerance(z: float, ndigits: int = 2) -> float:
    """Numerical tolerance δ of a value z held to ``ndigits`` significant decimal digits.

    z is written c·10^l with c an ``ndigits``-digit integer; δ = ½·10^l. (0 for z = 0.)

    Parameters
    ----------
    z : float
        The value (any unit), usually a standard uncertainty u(y).
    ndigits : int
        Number of significant decimal digits regarded as meaningful (≥ 1).

    Returns
    -------
    float
        δ, in the unit of z.

    References
    ----------
    JCGM 101:2008, §7.9.2 (numerical tolerance associated with a numerical value).
    """
    nd = _int_setting("ndigits", ndigits, minimum=1)
    a = abs(float(z))
    if a == 0.0 or not math.isfinite(a):
        return 0.0 if a == 0.0 else math.inf
    c = f"{a:.{nd - 1}e}"  # the value rounded to nd significant digits
    exponent = int(c.split("e")[1])
    return 0.5 * 10.0 ** (exponent - nd + 1)


def _int_setting(name: str, value: Any, *, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ConfigError(f"{name} must be an integer, got {value!r}.")
    v = int(value)
    if v < minimum:
        raise ConfigError(f"{name} must be at least {minimum}, got {v}.")
    return v


def _check_p(p: Any) -> float:
    if isinstance(p, bool) or not isinstance(p, numbers.Real):
        raise ConfigError(f"p (coverage probability) must be a number in (0, 1), got {p!r}.")
    pf = float(p)
    if not 0.0 < pf < 1.0:
        raise ConfigError(f"p (coverage probability) must lie strictly between 0 and 1, got {p!r}.")
    return pf


def _q_index(m: int, p: float) -> int:
    """q of JCGM 101 §7.7.1: pM if that is an integer, else the integer part of pM + ½."""
    pm = p * m
    q = round(pm)
    if abs(pm - q) <= 1e-9 * max(1.0, pm):
        return int(q)
    return math.floor(pm + 0.5)


def _intervals_sorted(
    ys: np.ndarray, p: float, *, shortest: bool = True
) -> tuple[tuple[float, float], tuple[float, float] | None]:
    """(symmetric, shortest) coverage intervals from sorted values (JCGM 101 §7.7)."""
    m = ys.size
    q = _q_index(m, p)
    if m - q < 1:
        raise CaptureError(
            f"{m} values are too few for a {100 * p:g} % coverage interval; "
            f"use at least {math.ceil(100 / (1 - p))} trials."
        )
    # 1-based r of JCGM 101 §7.7.1 → 0-based index r − 1
    r = (m - q) // 2 if (m - q) % 2 == 0 else (m - q + 1) // 2
    r = max(r, 1)
    sym = (float(ys[r - 1]), float(ys[r - 1 + q]))
    if not shortest:
        return sym, None
    widths = ys[q:] - ys[: m - q]
    i = int(np.argmin(widths))
    return sym, (float(ys[i]), float(ys[i + q]))


def coverage_interval(
    samples: Any, p: float = 0.95, *, shortest: bool = False
) -> tuple[float, float]:
    """Coverage interval for a quantity from M Monte Carlo values of it.

    With the values sorted, y₍₁₎ ≤ … ≤ y₍M₎, and q = pM (or the integer part of pM + ½ when pM
    is not an integer), every [y₍r₎, y₍r+q₎] is a 100p % coverage interval. The probabilistically
    symmetric one has r = (M − q)/2 (or the integer part of (M − q + 1)/2); the shortest one has
    the r that minimises y₍r+q₎ − y₍r₎.

    Parameters
    ----------
    samples : array_like, shape (M,)
        Values of the quantity (any unit), finite.
    p : float
        Coverage probability, 0 < p < 1.
    shortest : bool
        True: the shortest interval (§7.7.2); False: the probabilistically symmetric one (§7.7.1).

    Returns
    -------
    (float, float)
        Lower and upper endpoints (unit of the samples).

    References
    ----------
    JCGM 101:2008, §7.7 (coverage interval for the output quantity), §7.7.1 (probabilistically
    symmetric), §7.7.2 (shortest).
    """
    pf = _check_p(p)
    y = np.asarray(samples, dtype=np.float64)
    if y.ndim != 1:
        raise CaptureError(f"samples must be one-dimensional, got shape {y.shape}.")
    if not np.all(np.isfinite(y)):
        raise CaptureError("samples contain NaN or infinite values; remove them first.")
    m = y.size
    q = _q_index(m, pf)
    if m - q < 1:
        raise CaptureError(
            f"{m} values are too few for a {100 * pf:g} % coverage interval; "
            f"use at least {math.ceil(100 / (1 - pf))}."
        )
    if shortest:
        sym_short = _intervals_sorted(np.sort(y), pf, shortest=True)[1]
        assert sym_short is not None
        return sym_short
    r = (m - q) // 2 if (m - q) % 2 == 0 else (m - q + 1) // 2
    r = max(r, 1)
    part = np.partition(y, (r - 1, r - 1 + q))
    return float(part[r - 1]), float(part[r - 1 + q])


# ------------------------------------------------------------------------------------- sampling
@dataclasses.dataclass(frozen=True)
class _Sampler:
    names: tuple[str, ...]
    dists: tuple[Distribution, ...]
    seed: int
    group: tuple[int, ...]  # indices of correlated Normal inputs (drawn jointly), may be empty
    group_factor: np.ndarray  # Cholesky factor of their correlation matrix

    def block(self, k: int) -> list[np.ndarray]:
        """The values of every input for trials [k·B, (k + 1)·B)."""
        rng = np.random.Generator(
            np.random.PCG64(np.random.SeedSequence(self.seed, spawn_key=(k,)))
        )
        out: list[np.ndarray] = [np.empty(0)] * len(self.dists)
        first = self.group[0] if self.group else -1
        for i, dist in enumerate(self.dists):
            if i == first:
                z = rng.standard_normal((_BLOCK, len(self.group))) @ self.group_factor.T
                for col, j in enumerate(self.group):
                    d = self.dists[j]
                    out[j] = d.mean + d.std * z[:, col]
            elif i in self.group:
                continue
            else:
                out[i] = np.asarray(dist.sample(rng, _BLOCK), dtype=np.float64)
        return out

    def draw(self, start: int, stop: int) -> dict[str, np.ndarray]:
        """The values of every input for trials [start, stop) (start a multiple of B)."""
        k0, k1 = start // _BLOCK, -(-stop // _BLOCK)
        blocks = [self.block(k) for k in range(k0, k1)]
        n = stop - start
        return {
            name: np.concatenate([b[i] for b in blocks])[:n] for i, name in enumerate(self.names)
        }


def _normalise_inputs(
    inputs: Mapping[str, Distribution] | Sequence[tuple[str, Distribution]],
) -> tuple[tuple[str, ...], tuple[Distribution, ...]]:
    if isinstance(inputs, Mapping):
        pairs = list(inputs.items())
    else:
        try:
            pairs = [(name, dist) for name, dist in inputs]
        except (TypeError, ValueError):
            raise ConfigError(
                "inputs must be a mapping {name: Distribution} or a sequence of (name, Distribution) pairs."
            ) from None
    if not pairs:
        raise ConfigError("inputs is empty; give at least one input quantity.")
    names: list[str] = []
    for name, dist in pairs:
        if not isinstance(name, str) or not name.isidentifier():
            raise ConfigError(
                f"input name {name!r} is not a Python identifier; the model receives the inputs "
                "as keyword arguments."
            )
        if name in names:
            raise ConfigError(f"input {name!r} is given twice; give each input once.")
        if not isinstance(dist, Distribution):
            raise ConfigError(
                f"input {name!r} is a {type(dist).__name__}, not a Distribution; use e.g. "
                "Normal(value, u) or Rectangular.centered(value, half_width)."
            )
        names.append(name)
    return tuple(names), tuple(d for _, d in pairs)


def _correlated_group(
    correlation: Any, names: tuple[str, ...], dists: tuple[Distribution, ...]
) -> tuple[tuple[int, ...], np.ndarray]:
    if correlation is None:
        return (), np.empty((0, 0))
    from rotacal.uncertainty.gum import correlation_matrix

    n = len(names)
    r = np.asarray(correlation_matrix(correlation, n, names=list(names)), dtype=np.float64)
    off = r - np.diag(np.diag(r))
    involved = [i for i in range(n) if np.any(off[i] != 0.0)]
    for i in involved:
        if type(dists[i]) is not Normal:
            j = next(j for j in range(n) if off[i, j] != 0.0)
            raise ConfigError(
                f"input {names[i]!r} ({dists[i].name}) is correlated with {names[j]!r}; the Monte "
                "Carlo method supports correlation only among Normal inputs — make them Normal "
                "or give the correlated quantities as one MultivariateNormal input."
            )
    group = tuple(involved)
    if not group:
        return (), np.empty((0, 0))
    sub = r[np.ix_(group, group)]
    return group, _psd_factor(sub)


# ------------------------------------------------------------------------------ model evaluation
def _evaluate(
    model: Model, values: dict[str, np.ndarray], n: int, names: tuple[str, ...]
) -> tuple[dict[str, np.ndarray], bool]:
    """Call the model once; return ({output: values}, the model returned a mapping)."""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        try:
            raw = model(**values)
        except TypeError as exc:
            raise ConfigError(
                f"the model could not be called with the keyword arguments "
                f"({', '.join(names)}): {exc}"
            ) from None
    is_map = isinstance(raw, Mapping)
    outs = dict(raw) if is_map else {"y": raw}
    if not outs:
        raise ConfigError("the model returned an empty mapping; return at least one output.")
    result: dict[str, np.ndarray] = {}
    for key, val in outs.items():
        try:
            arr = np.asarray(val, dtype=np.float64)
        except (TypeError, ValueError):
            raise ConfigError(
                f"the model output {key!r} is not numeric ({type(val).__name__}); "
                "return a float array with one value per trial."
            ) from None
        if arr.shape != (n,):
            raise ConfigError(
                f"the model output {key!r} has shape {arr.shape}, expected ({n},) — one value "
                "per trial; write the model with NumPy array operations on its keyword arguments."
            )
        bad = ~np.isfinite(arr)
        if bad.any():
            i = int(np.argmax(bad))
            shown = ", ".join(
                f"{name}={_fmt_value(values[name][i])}" for name in names[:_SHOW_INPUTS]
            )
            more = ", …" if len(names) > _SHOW_INPUTS else ""
            raise ConfigError(
                f"the model output {key!r} is NaN or infinite in {int(bad.sum())} of {n} trials "
                f"(first at {shown}{more}); make the model defined over the whole range of its "
                "input distributions."
            )
        result[str(key)] = arr
    return result, is_map


def _fmt_value(v: Any) -> str:
    a = np.asarray(v)
    if a.ndim == 0:
        return f"{float(a):.6g}"
    return "[" + ", ".join(f"{float(x):.4g}" for x in a.ravel()[:4]) + ("…]" if a.size > 4 else "]")


# ------------------------------------------------------------------------- adaptive bookkeeping
@dataclasses.dataclass
class _Running:
    """Running count, mean and sum of squared deviations (Chan et al. pairwise update)."""

    n: int = 0
    mean: float = 0.0
    m2: float = 0.0

    def add(self, y: np.ndarray) -> None:
        nb = y.size
        mb = float(np.mean(y))
        m2b = float(np.sum((y - mb) ** 2))
        n = self.n + nb
        delta = mb - self.mean
        self.mean += delta * nb / n
        self.m2 += m2b + delta * delta * self.n * nb / n
        self.n = n

    @property
    def std(self) -> float:
        return math.sqrt(self.m2 / (self.n - 1)) if self.n > 1 else 0.0


def _batch_stats(y: np.ndarray, p: float) -> tuple[float, ...]:
    """(mean, std, symmetric low, high, shortest low, high) of one adaptive batch."""
    ys = np.sort(y)
    sym, short = _intervals_sorted(ys, p, shortest=True)
    assert short is not None
    return (float(np.mean(y)), float(np.std(y, ddof=1)), *sym, *short)


# ---------------------------------------------------------------------------------- monte carlo
def monte_carlo(
    model: Model,
    inputs: Mapping[str, Distribution] | Sequence[tuple[str, Distribution]],
    *,
    correlation: Any = None,
    trials: int | None = None,
    p: float = 0.95,
    seed: int = 2026,
    ndigits: int = 2,
    batch: int = 100_000,
    max_trials: int = 10_000_000,
    progress: Progress | None = None,
) -> MonteCarloResult | dict[str, MonteCarloResult]:
    """Propagate the input distributions through a measurement model by Monte Carlo.

    Parameters
    ----------
    model : callable
        ``model(**arrays)``: receives one array per input, keyword named as the input, of shape
        (n,) (or (n, k) for a :class:`MultivariateNormal` input), and returns an array of shape
        (n,) — or a mapping {output name: array (n,)} for several outputs. Vectorised over the
        trials; units are those of the inputs and outputs.
    inputs : mapping or sequence of (name, Distribution)
        The input quantities and their distributions, in the order of ``correlation``.
    correlation : array_like (n, n) or None
        Correlation matrix of the inputs (validated by
        :func:`rotacal.uncertainty.gum.correlation_matrix`). Non-zero correlations are allowed
        only among :class:`Normal` inputs.
    trials : int or None
        Fixed number M of trials; None for the adaptive procedure of JCGM 101 §7.9.
    p : float
        Coverage probability of the intervals (dimensionless), 0 < p < 1.
    seed : int
        Seed (≥ 0) of the random streams; the result for a seed does not depend on ``batch``.
    ndigits : int
        Significant digits of u(y) to be stabilised by the adaptive procedure (§7.9.2); also sets
        the ``tolerance`` reported.
    batch : int
        Trials evaluated per model call (memory; rounded up to a multiple of 10⁴).
    max_trials : int
        Limit of the adaptive procedure; when reached, ``converged`` is False.
    progress : callable or None
        ``progress(trials_done, trials_target)`` after every batch (target = ``max_trials`` when
        adaptive).

    Returns
    -------
    MonteCarloResult or dict of str to MonteCarloResult
        One result, or one per output when the model returns a mapping.

    Raises
    ------
    ConfigError
        A bad setting or input, a correlation involving a non-Normal input or a matrix that is
        not a valid correlation matrix, a model output of the wrong shape or not finite.

    References
    ----------
    JCGM 101:2008, §7.2–§7.7 (number of trials, sampling, model evaluation, estimate eq. (14),
    standard uncertainty eq. (15), coverage intervals), §7.9.4 (adaptive procedure: batches of
    M = max(J, 10⁴), J the smallest integer ≥ 100/(1 − p); stop when 2·s of the batch averages of
    y, u(y), y_low and y_high are all ≤ δ), §6.4.8 (correlated Gaussian inputs).
    JCGM 102:2011, §7 (several output quantities).
    """
    if not callable(model):
        raise ConfigError(f"model must be callable, got {type(model).__name__}.")
    names, dists = _normalise_inputs(inputs)
    pf = _check_p(p)
    seed_i = _int_setting("seed", seed, minimum=0)
    nd = _int_setting("ndigits", ndigits, minimum=1)
    batch_i = _int_setting("batch", batch, minimum=1)
    batch_i = -(-batch_i // _BLOCK) * _BLOCK
    j_min = math.ceil(100.0 / (1.0 - pf) - 1e-9)
    group, factor = _correlated_group(correlation, names, dists)
    sampler = _Sampler(names, dists, seed_i, group, factor)

    if trials is not None:
        m_total = _int_setting("trials", trials, minimum=1)
        if m_total < j_min:
            raise ConfigError(
                f"trials={m_total} is too few for a {100 * pf:g} % coverage interval; use at "
                f"least {j_min} (100/(1 − p); JCGM 101 recommends ≥ 10⁶)."
            )
        chunks: dict[str, list[np.ndarray]] = {}
        is_map = False
        done = 0
        while done < m_total:
            stop = min(done + batch_i, m_total)
            outs, is_map = _evaluate(model, sampler.draw(done, stop), stop - done, names)
            for key, arr in outs.items():
                chunks.setdefault(key, []).append(arr)
            done = stop
            if progress is not None:
                progress(done, m_total)
        ys = {key: np.concatenate(parts) for key, parts in chunks.items()}
        converged = {key: True for key in ys}
    else:
        max_i = _int_setting("max_trials", max_trials, minimum=1)
        m_batch = -(-max(j_min, 10_000) // _BLOCK) * _BLOCK
        if max_i < 2 * m_batch:
            raise ConfigError(
                f"max_trials={max_i} is below two adaptive batches of {m_batch} trials; "
                f"raise it to at least {2 * m_batch}."
            )
        ys, converged, is_map = _adaptive(
            model, sampler, names, pf, nd, m_batch, max(batch_i, m_batch), max_i, progress
        )

    results: dict[str, MonteCarloResult] = {}
    for key, y in ys.items():
        srt = np.sort(y)
        sym, short = _intervals_sorted(srt, pf, shortest=True)
        assert short is not None
        u = float(np.std(y, ddof=1))
        results[key] = MonteCarloResult(
            value=float(np.mean(y)),
            u=u,
            p=pf,
            trials=int(y.size),
            seed=seed_i,
            interval_symmetric=sym,
            interval_shortest=short,
            converged=bool(converged[key]),
            output=key,
            tolerance=numerical_tolerance(u, nd),
            _samples=y[:_KEEP].copy() if y.size > _KEEP else y,
        )
    if is_map:
        return results
    return results["y"]


def _adaptive(
    model: Model,
    sampler: _Sampler,
    names: tuple[str, ...],
    p: float,
    ndigits: int,
    m_batch: int,
    eval_size: int,
    max_trials: int,
    progress: Progress | None,
) -> tuple[dict[str, np.ndarray], dict[str, bool], bool]:
    """JCGM 101 §7.9.4, with batches of ``m_batch`` trials checked one by one."""
    eval_size = -(-eval_size // m_batch) * m_batch  # whole adaptive batches per model call
    chunks: dict[str, list[np.ndarray]] = {}
    stats: dict[str, list[tuple[float, ...]]] = {}
    running: dict[str, _Running] = {}
    is_map = False
    done = 0  # trials evaluated
    h = 0  # adaptive batches accepted
    stopped = False
    limit = (max_trials // m_batch) * m_batch
    while not stopped and done < limit:
        stop = min(done + eval_size, limit)
        outs, is_map = _evaluate(model, sampler.draw(done, stop), stop - done, names)
        for key, arr in outs.items():
            chunks.setdefault(key, []).append(arr)
        for start in range(0, stop - done, m_batch):
            h += 1
            ok = True
            for key, arr in outs.items():
                part = arr[start : start + m_batch]
                stats.setdefault(key, []).append(_batch_stats(part, p))
                run = running.setdefault(key, _Running())
                run.add(part)
                if h < 2:
                    ok = False
                    continue
                s = np.std(np.asarray(stats[key]), axis=0, ddof=1) / math.sqrt(h)
                delta = numerical_tolerance(run.std, ndigits)
                if np.any(2.0 * s > delta):
                    ok = False
            if ok:
                stopped = True
                break
        done = stop
        if progress is not None:
            progress(min(done, h * m_batch), max_trials)
    n_used = h * m_batch
    ys = {key: np.concatenate(parts)[:n_used] for key, parts in chunks.items()}
    return ys, {key: stopped for key in ys}, is_map


# ---------------------------------------------------------------------------------- validation
def validate_gum(
    gum: GUMResult,
    mc: MonteCarloResult | Mapping[str, MonteCarloResult],
    *,
    ndigits: int = 2,
    j: int = 0,
    shortest: bool = True,
) -> dict[str, Any]:
    """Validate the GUM uncertainty framework against a Monte Carlo result (JCGM 101 §8).

    With the GUM estimate y, expanded uncertainty U_p and the Monte Carlo coverage interval
    [y_low, y_high] for the same p: d_low = |y − U_p − y_low|, d_high = |y + U_p − y_high|.
    The GUM result is validated when both are ≤ δ, the numerical tolerance of the GUM u(y) at
    ``ndigits`` significant digits. JCGM 101 §8.2 asks for a Monte Carlo run whose own tolerance
    is δ/5 or better (e.g. ``monte_carlo(..., ndigits=ndigits + 1)`` or ≥ 10⁶ trials).

    Parameters
    ----------
    gum : GUMResult
        Result of :func:`rotacal.uncertainty.gum.propagate`.
    mc : MonteCarloResult or mapping of them
        Monte Carlo result for the same output (a mapping is indexed by ``gum.names_out[j]``).
    ndigits : int
        Significant digits of u(y) that must agree (≥ 1).
    j : int
        Index of the output quantity in ``gum``.
    shortest : bool
        Compare with the shortest (default, as in JCGM 101 §9) or the probabilistically symmetric
        Monte Carlo interval.

    Returns
    -------
    dict
        ``d_low``, ``d_high``, ``delta`` (unit of the output), ``passed`` (bool),
        ``gum_interval``, ``mc_interval`` (tuples), ``interval`` ("shortest"/"symmetric"),
        ``ndigits``.

    References
    ----------
    JCGM 101:2008, §8.1 (validation of the GUM uncertainty framework using the Monte Carlo
    method), §8.2 (obtaining Monte Carlo results for validation purposes), §7.9.2 (δ).
    """
    nd = _int_setting("ndigits", ndigits, minimum=1)
    m_out = len(gum.value)
    if isinstance(j, bool) or not isinstance(j, numbers.Integral) or not 0 <= j < m_out:
        raise ConfigError(f"j must be an output index in 0…{m_out - 1}, got {j!r}.")
    if isinstance(mc, Mapping):
        name = gum.names_out[j]
        if name not in mc:
            raise ConfigError(
                f"the Monte Carlo results have no output {name!r} (they have "
                f"{', '.join(map(str, mc))}); pass the matching result."
            )
        mc = mc[name]
    if abs(float(gum.p) - mc.p) > 1e-9:
        raise ConfigError(
            f"the GUM result is for p = {gum.p:g} but the Monte Carlo one for p = {mc.p:g}; "
            "compare intervals of the same coverage probability."
        )
    y = float(gum.value[j])
    big_u = float(gum.U[j])
    lo, hi = mc.interval_shortest if shortest else mc.interval_symmetric
    delta = numerical_tolerance(float(gum.u[j]), nd)
    d_low = abs(y - big_u - lo)
    d_high = abs(y + big_u - hi)
    return {
        "d_low": d_low,
        "d_high": d_high,
        "delta": delta,
        "passed": bool(d_low <= delta and d_high <= delta),
        "gum_interval": (y - big_u, y + big_u),
        "mc_interval": (lo, hi),
        "interval": "shortest" if shortest else "symmetric",
        "ndigits": nd,
    }
