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
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.results import Result
from rotacal.turntable.chain import ARCMIN_PER_RAD, COMPONENTS
from rotacal.turntable.draws import QUANTILE, TopValues, quantile_interval, top_values_needed
from rotacal.turntable.fast import compiled_draws, compiled_tally, use_compiled
from rotacal.turntable.geometry import Turntable
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
        Number of draws and the seed of ``numpy.random.Generator(PCG64(seed))``.
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


def monte_carlo_check(
    table: Turntable,
    allocation: Allocation,
    *,
    runs: int = 1_000_000,
    seed: int = 2026,
    signs: str = "random",
    chunk: int = 262_144,
    progress: Callable[[int, int], None] | None = None,
) -> MonteCarloCheck:
    """Monte Carlo check of an allocation with the full orientation-error model (Figure 9).

    Each draw takes every angle uniform on [0, 2π) and every angular error χ_i = s_i·U(LB_i, UB_i)
    (s_i = ±1 with equal odds for ``signs="random"``; +1 for ``"positive"``, the paper's literal
    Ω_χ), and evaluates the full model ``table.fast_orientation_error`` (eqs. (17)–(24)). The draws
    come from ``numpy.random.Generator(PCG64(seed))``, one row of uniforms per draw (errors first,
    then angles; for random signs one uniform v on [−1, 1) gives both sign and magnitude |v|), in
    chunks of ``chunk`` rows: memory stays flat and the result is the same for any chunk size.

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

    Returns
    -------
    MonteCarloCheck
        Largest |Δψ|, |Δθ|, |Δγ| (rad and arcmin), whether all draws are within the requirement,
        how many are not, the throughput, 60-bin histograms over ±I_j, and the 99.9 % quantile
        of each |Δ_j| with its 95 % coverage interval (from the largest draws, kept chunk by chunk).

    Raises
    ------
    ConfigError
        runs or chunk not an integer ≥ 1, seed not an integer ≥ 0 (booleans and floats such as
        1.5 are refused, not truncated), an unknown ``signs``, LB_i > UB_i.

    References
    ----------
    Seed 001, §4.3 (Monte Carlo verification, 10 000 runs), Figure 9; eqs. (17)–(25).
    """
    _require_angular(table)
    runs_i, seed_i = check_draws(runs, seed)
    chunk_i = _integer("chunk", chunk, 1)
    if signs not in ("random", "positive"):
        raise ConfigError(f"signs must be 'random' or 'positive', got {signs!r}.")
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
    n_err = len(names)
    n_angles = len(tuple(table.angle_names))
    width = ub - lb
    rng = np.random.Generator(np.random.PCG64(seed_i))
    max_abs = np.zeros(3)
    counts = np.zeros((3, _HIST_BINS), dtype=np.int64)
    outside = 0
    bins_per_rad = _HIST_BINS / (2.0 * req_v)
    largest = TopValues(top_values_needed(runs_i), 3)  # for the 99.9 % quantile of |Δ|
    t0 = time.perf_counter()
    done = 0
    compiled = use_compiled(runs_i)
    if compiled:  # the same numbers, each chunk's draws and tallies in one pass
        draws, tally = compiled_draws(), compiled_tally()
        rows = min(chunk_i, runs_i)  # buffers filled again for every chunk
        chi_buffer, angle_buffer = np.empty((rows, n_err)), np.empty((rows, n_angles))
        uniforms = np.empty((rows, n_err + n_angles))
    while done < runs_i:
        m = min(chunk_i, runs_i - done)
        if compiled:
            u = rng.random(out=uniforms[:m])  # the same numbers as rng.random((m, ·))
            chi, angles = chi_buffer[:m], angle_buffer[:m]
            draws(u, lb, width, signs == "random", chi, angles)
            d = _fast(table, angles, chi)
            outside += tally(d, req_v, bins_per_rad, max_abs, counts)
            largest.add(np.abs(d))
            done += m
            if progress is not None:
                progress(done, runs_i)
            continue
        u = rng.random((m, n_err + n_angles))
        if signs == "random":
            v = 2.0 * u[:, :n_err] - 1.0
            chi = np.copysign(lb + width * np.abs(v), v)
        else:
            chi = lb + width * u[:, :n_err]
        angles = _TWO_PI * u[:, n_err:]
        d = _fast(table, angles, chi)
        a = np.abs(d)
        np.maximum(max_abs, a.max(axis=0), out=max_abs)
        largest.add(a)
        out_mask = a > req_v
        outside += int(np.count_nonzero(out_mask.any(axis=1)))
        idx = np.floor((d + req_v) * bins_per_rad).astype(np.int64)
        idx = np.minimum(idx, _HIST_BINS - 1)  # +I_j exactly falls in the last bin
        for j in range(3):
            keep = idx[~out_mask[:, j], j]
            counts[j] += np.bincount(keep, minlength=_HIST_BINS)[:_HIST_BINS]
        done += m
        if progress is not None:
            progress(done, runs_i)
    elapsed = time.perf_counter() - t0
    histograms = {
        c: {
            "edges_rad": np.linspace(-req_v[j], req_v[j], _HIST_BINS + 1).tolist(),
            "counts": counts[j].tolist(),
        }
        for j, c in enumerate(COMPONENTS)
    }
    quantiles = {
        c: quantile_interval(largest.values[:, j], runs_i) for j, c in enumerate(COMPONENTS)
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
