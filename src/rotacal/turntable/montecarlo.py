"""The Monte Carlo check of a turntable's allocation (GyroWheel study, §4.3, Figure 9).

Draws tables within their tolerances and angles on [0, 2π), evaluates the full model of
eqs. (17)–(24) (:meth:`Turntable.fast_orientation_error <rotacal.turntable.geometry.Turntable>`)
and states the largest errors, the draws outside the requirement, histograms and the 99.9 %
quantile with its coverage interval (:mod:`rotacal.turntable.draws`), in chunks with carried
state.

References
----------
Seed 001 (``../shared/seeds/001_4a387eb674e238f2.txt``), §4.3, Figure 9; JCGM 101:2008 §7.7.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.results import Result
from rotacal.turntable.chain import _FAST_CHUNK, ARCMIN_PER_RAD, COMPONENTS
from rotacal.turntable.draws import QUANTILE, TopValues, quantile_interval, top_values_needed
from rotacal.turntable.fast import (
    _chain_arrays,
    compiled_draws,
    compiled_monte_carlo,
    compiled_tally,
    use_compiled,
)
from rotacal.turntable.geometry import Turntable
from rotacal.turntable.stream import STREAMS, philox_key, turn_sin_cos
from rotacal.turntable.worstcase import (
    _TWO_PI,
    _bounds_vector,
    _fast,
    _require_angular,
    _requirement,
)

if TYPE_CHECKING:
    from rotacal.turntable.allocation import Allocation

__all__ = ["MonteCarloCheck", "check_draws", "monte_carlo_check"]

_HIST_BINS = 60


@dataclasses.dataclass(frozen=True)
class MonteCarloCheck(Result):
    """Monte Carlo check of an allocation with the full model (GyroWheel study, §4.3, Figure 9).

    Attributes
    ----------
    runs, seed : int
        Number of draws and the seed of the stream.
    signs : str
        ``"random"`` (χ_i = ±U(LB_i, UB_i)) or ``"positive"`` (the paper's literal Ω_χ).
    max_abs_rad, max_abs_arcmin : dict
        Largest |Δψ|, |Δθ|, |Δγ| over the draws.
    requirement_rad : dict
        I_j (rad).
    all_within : bool
        No draw exceeds any requirement.
    outside : int
        Draws with at least one component beyond its requirement.
    draws_per_second : float
        Throughput of this run (wall clock; not reproducible, unlike everything else).
    histograms : dict
        ``{j: {"edges_rad": [61 edges over ±I_j], "counts": [60]}}`` (values beyond ±I_j are not
        counted; see ``outside``).
    quantile : float
        The quantile q of |Δ_j| stated in ``quantile_abs_rad`` (0.999).
    quantile_abs_rad : dict or None
        ``{j: (value, low, high)}``: the q-quantile of |Δ_j| over the draws and its
        distribution-free 95 % coverage interval (:func:`rotacal.turntable.draws.quantile_interval`);
        ``None`` when there are too few draws for one.
    stream : str
        The random stream: ``"philox"`` (``Generator(Philox(seed))``, counter-based) or
        ``"pcg64"`` (``Generator(PCG64(seed))``, the stream of earlier versions).
    """

    runs: int
    seed: int
    signs: str
    max_abs_rad: dict[str, float]
    max_abs_arcmin: dict[str, float]
    requirement_rad: dict[str, float]
    all_within: bool
    outside: int
    draws_per_second: float
    histograms: dict[str, dict[str, list[float]]]
    quantile: float = QUANTILE
    quantile_abs_rad: dict[str, tuple[float, float, float]] | None = None
    stream: str = "philox"


def monte_carlo_check(
    table: Turntable,
    allocation: Allocation,
    *,
    runs: int = 1_000_000,
    seed: int = 2026,
    signs: str = "random",
    chunk: int = 262_144,
    progress: Callable[[int, int], None] | None = None,
    stream: str = "philox",
    threads: int = 1,
) -> MonteCarloCheck:
    """Monte Carlo check of an allocation with the full orientation-error model (Figure 9).

    Each draw takes every angle uniform on [0, 2π) and every angular error χ_i = s_i·U(LB_i, UB_i)
    (s_i = ±1 with equal odds for ``signs="random"``; +1 for ``"positive"``, the paper's literal
    Ω_χ), and evaluates the full model of eqs. (17)–(24) (the recursion of
    ``table.fast_orientation_error``). The draws come from ``numpy.random.Generator(Philox(seed))``
    (or, with ``stream="pcg64"``, ``Generator(PCG64(seed))`` as in earlier versions), one row of
    uniforms per draw (errors first, then angles; for random signs one uniform v = 2u − 1 on
    [−1, 1) gives both sign and magnitude |v|; φ = 2π·u), in chunks of ``chunk`` rows: memory
    stays flat and the result is the same for any chunk size.

    The Philox stream is counter-based (:mod:`rotacal.turntable.stream`): from
    :data:`~rotacal.turntable.fast.COMPILE_FROM_DRAWS` draws (``ROTACAL_NUMBA``) one compiled pass
    makes each block's numbers, model and tallies on every core
    (:mod:`rotacal.turntable._mc_jit`), and gives the NumPy path's result to the last bit on any
    number of threads. With it cos φ and sin φ come from
    :func:`rotacal.turntable.stream.turn_sin_cos` (within 2.3·10⁻¹⁶ of the exact values; the
    PCG64 path takes the C library's of 2π·u).

    Parameters
    ----------
    table : Turntable
        The table.
    allocation : Allocation
        Its ``upper_bounds_rad`` and ``lower_bounds_rad`` (rad) and ``requirement_rad`` are used
        (``None`` bounds: the error is held at 0).
    runs : int
        Number of draws (the paper used 10 000); an integer ≥ 1.
    seed : int
        Seed of the generator; an integer ≥ 0.
    signs : {"random", "positive"}
        Sign of the errors.
    chunk : int
        Draws per chunk.
    progress : callable, optional
        ``progress(done, total)`` after every chunk.
    stream : {"philox", "pcg64"}
        The random stream (:data:`rotacal.turntable.stream.STREAMS`).
    threads : int
        Threads the compiled Philox path runs each chunk on (≥ 1; the result is the same for
        any number). One by default: on a machine whose cores are busy, more only wait.

    Returns
    -------
    MonteCarloCheck
        Largest |Δψ|, |Δθ|, |Δγ| (rad and arcmin), whether all draws are within the requirement,
        how many are not, the throughput, 60-bin histograms over ±I_j, and the 99.9 % quantile
        of each |Δ_j| with its 95 % coverage interval (from the largest draws, kept chunk by chunk).

    Raises
    ------
    ConfigError
        runs, chunk or threads not an integer ≥ 1, seed not an integer ≥ 0 (booleans and floats such as
        1.5 are refused, not truncated), an unknown ``signs`` or ``stream``, LB_i > UB_i.

    References
    ----------
    Seed 001, §4.3 (Monte Carlo verification, 10 000 runs), Figure 9; eqs. (17)–(25).
    """
    _require_angular(table)
    runs_i, seed_i = check_draws(runs, seed)
    chunk_i = _integer("chunk", chunk, 1)
    threads_i = _integer("threads", threads, 1)
    if signs not in ("random", "positive"):
        raise ConfigError(f"signs must be 'random' or 'positive', got {signs!r}.")
    if stream not in STREAMS:
        raise ConfigError(f"stream must be 'philox' or 'pcg64', got {stream!r}.")
    names = tuple(table.angular_error_names)
    ub = _bounds_vector(table, allocation.upper_bounds_rad, "the upper bound")
    lb = _bounds_vector(table, allocation.lower_bounds_rad, "the lower bound")
    lb = np.where(ub > 0, lb, 0.0)
    bad = np.flatnonzero(lb > ub)
    if bad.size:
        raise ConfigError(
            f"the lower bound of {names[int(bad[0])]} exceeds its upper bound: fix the allocation."
        )
    req = _requirement(table, allocation.requirement_rad)
    req_v = np.array([req[c] for c in COMPONENTS])
    tallies = _Tallies(req_v, top_values_needed(runs_i))
    t0 = time.perf_counter()
    run = _Run(table, runs_i, seed_i, lb, ub - lb, signs == "random", chunk_i, progress)
    if stream == "philox" and use_compiled(runs_i):
        _philox_compiled(run, tallies, threads_i)
    else:
        _numpy_generator(run, tallies, stream)
    elapsed = time.perf_counter() - t0
    max_abs, counts, outside = tallies.max_abs, tallies.counts, tallies.outside
    histograms = {
        c: {
            "edges_rad": np.linspace(-req_v[j], req_v[j], _HIST_BINS + 1).tolist(),
            "counts": counts[j].tolist(),
        }
        for j, c in enumerate(COMPONENTS)
    }
    quantiles = {
        c: quantile_interval(tallies.largest.values[:, j], runs_i) for j, c in enumerate(COMPONENTS)
    }
    return MonteCarloCheck(
        runs=runs_i,
        seed=seed_i,
        signs=signs,
        max_abs_rad={c: float(max_abs[j]) for j, c in enumerate(COMPONENTS)},
        max_abs_arcmin={c: float(max_abs[j] * ARCMIN_PER_RAD) for j, c in enumerate(COMPONENTS)},
        requirement_rad=req,
        all_within=outside == 0,
        outside=outside,
        draws_per_second=runs_i / elapsed if elapsed > 0 else math.inf,
        histograms=histograms,
        stream=stream,
        quantile_abs_rad=(
            None if any(v is None for v in quantiles.values()) else quantiles  # type: ignore[arg-type]
        ),
    )


def check_draws(runs: Any, seed: Any) -> tuple[int, int]:
    """``runs`` (an integer ≥ 1) and ``seed`` (an integer ≥ 0) of :func:`monte_carlo_check` as
    ints; anything else is one ConfigError line naming it. A caller that allocates first checks
    them before the allocation's seconds of work."""
    return _integer("runs", runs, 1), _integer("seed", seed, 0)


def _integer(name: str, value: Any, minimum: int) -> int:
    """``value`` as an int ≥ ``minimum``; bools, floats and strings are one ConfigError line."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise ConfigError(f"{name} must be an integer ≥ {minimum}, got {value!r}.")
    if int(value) < minimum:
        raise ConfigError(f"{name} must be an integer ≥ {minimum}, got {value!r}.")
    return int(value)


@dataclasses.dataclass(frozen=True)
class _Run:
    """What every chunk of one run needs: the table, the number of draws and the seed, the errors'
    lower bounds and widths UB − LB (rad), the signs, the chunk size and the progress callback."""

    table: Turntable
    runs: int
    seed: int
    lower: np.ndarray
    width: np.ndarray
    random_signs: bool
    chunk: int
    progress: Callable[[int, int], None] | None

    def report(self, done: int) -> None:
        """Tell the progress callback, if any, that ``done`` draws are done."""
        if self.progress is not None:
            self.progress(done, self.runs)


class _Tallies:
    """What the Monte Carlo keeps of its draws, chunk by chunk: the largest |Δ_j|, the
    histograms over ±I_j, the draws outside the requirement and the largest values for the
    quantile (carried state; the same whatever the chunks)."""

    def __init__(self, requirement: np.ndarray, keep: int) -> None:
        self.requirement = requirement
        self.bins_per_rad = _HIST_BINS / (2.0 * requirement)
        self.max_abs = np.zeros(3)
        self.counts = np.zeros((3, _HIST_BINS), dtype=np.int64)
        self.outside = 0
        self.largest = TopValues(keep, 3)

    def add(self, d: np.ndarray) -> None:
        """Tally the (Δψ, Δθ, Δγ) rows of ``d`` (rad) with NumPy."""
        a = np.abs(d)
        np.maximum(self.max_abs, a.max(axis=0), out=self.max_abs)
        self.largest.add(a)
        out_mask = a > self.requirement
        self.outside += int(np.count_nonzero(out_mask.any(axis=1)))
        idx = np.floor((d + self.requirement) * self.bins_per_rad).astype(np.int64)
        idx = np.minimum(idx, _HIST_BINS - 1)  # +I_j exactly falls in the last bin
        for j in range(3):
            keep = idx[~out_mask[:, j], j]
            self.counts[j] += np.bincount(keep, minlength=_HIST_BINS)[:_HIST_BINS]


def _philox_compiled(run: _Run, tallies: _Tallies, threads: int) -> None:
    """The Philox stream's draws, model and tallies in the fused compiled kernel, chunk by chunk,
    each chunk cut into ``threads`` ranges run at once (the kernel releases the GIL), each with
    its own maxima and histograms; only the candidates for the largest values come back."""
    kernel = compiled_monte_carlo()
    key = philox_key(run.seed)
    chain = _chain_arrays(run.table._p.links)
    n_angles = len(tuple(run.table.angle_names))
    rows = -(-min(run.chunk, run.runs) // threads)  # the longest range of a chunk
    parts = [
        (np.zeros(3), np.zeros_like(tallies.counts), np.empty((3, rows)), np.zeros(3, np.int64))
        for _ in range(threads)
    ]
    common = (n_angles, run.lower, run.width, run.random_signs, *chain)
    pool = ThreadPoolExecutor(threads) if threads > 1 else None
    try:
        done = 0
        while done < run.runs:
            m = min(run.chunk, run.runs - done)
            floor = tallies.largest.floor()
            cuts = [done + m * p // threads for p in range(threads + 1)]
            calls = [
                (key, cuts[p], cuts[p + 1] - cuts[p], *common, tallies.requirement,
                 tallies.bins_per_rad, floor, *parts[p])
                for p in range(threads)
            ]  # fmt: skip
            if pool is None:
                tallies.outside += kernel(*calls[0])
            else:
                tallies.outside += sum(pool.map(lambda args: kernel(*args), calls))
            tallies.largest.add_columns(
                [np.concatenate([c[j, : f[j]] for _, _, c, f in parts]) for j in range(3)]
            )
            done += m
            run.report(done)
    finally:
        if pool is not None:
            pool.shutdown()
    for part_max, part_counts, _, _ in parts:
        np.maximum(tallies.max_abs, part_max, out=tallies.max_abs)
        tallies.counts += part_counts


def _numpy_generator(run: _Run, tallies: _Tallies, stream: str) -> None:
    """Rows of uniforms from NumPy's generator of ``stream``, chunk by chunk: the NumPy twin of
    :func:`_philox_compiled` (Philox; angles' cos and sin by
    :func:`rotacal.turntable.stream.turn_sin_cos`), or the PCG64 stream of earlier versions
    (angles 2π·u through :meth:`Turntable.fast_orientation_error`; its draws and tallies
    compiled from :data:`rotacal.turntable.fast.COMPILE_FROM_DRAWS` draws, the same numbers)."""
    table, lower, width = run.table, run.lower, run.width
    n_err = lower.shape[0]
    n_angles = len(tuple(table.angle_names))
    bit_generator = np.random.Philox(run.seed) if stream == "philox" else np.random.PCG64(run.seed)
    rng = np.random.Generator(bit_generator)
    compiled = stream == "pcg64" and use_compiled(run.runs)
    rows = min(run.chunk, run.runs)  # buffers filled again for every chunk
    uniforms = np.empty((rows, n_err + n_angles))
    if compiled:
        draws, tally = compiled_draws(), compiled_tally()
        chi_buffer, angle_buffer = np.empty((rows, n_err)), np.empty((rows, n_angles))
    done = 0
    while done < run.runs:
        m = min(run.chunk, run.runs - done)
        u = rng.random(out=uniforms[:m])  # the same numbers as rng.random((m, ·))
        if compiled:
            chi, angles = chi_buffer[:m], angle_buffer[:m]
            draws(u, lower, width, run.random_signs, chi, angles)
            d = _fast(table, angles, chi)
            tallies.outside += tally(d, tallies.requirement, tallies.bins_per_rad,
                                     tallies.max_abs, tallies.counts)  # fmt: skip
            tallies.largest.add(np.abs(d))
        else:
            if run.random_signs:
                v = 2.0 * u[:, :n_err] - 1.0
                chi = np.copysign(lower + width * np.abs(v), v)
            else:
                chi = lower + width * u[:, :n_err]
            if stream == "philox":
                d = np.empty((m, 3))
                for lo in range(0, m, _FAST_CHUNK):  # cache-sized: sin and cos are 25 passes
                    hi = min(m, lo + _FAST_CHUNK)
                    trig = {}
                    for k in table._fast_angles():
                        sin, cos = turn_sin_cos(u[lo:hi, n_err + k])
                        trig[k] = (cos, sin)
                    d[lo:hi] = table.fast_orientation_error_trig(trig, chi[lo:hi])
            else:
                d = _fast(table, _TWO_PI * u[:, n_err:], chi)
            tallies.add(d)
        done += m
        run.report(done)
