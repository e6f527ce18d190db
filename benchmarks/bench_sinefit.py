"""Throughput of the multi-harmonic sine fit (rotacal.signal.fit_harmonics) on one core.

Generates 10⁷ uniformly spaced samples (10 periods, or ``--periods``; 10 harmonics, white noise), times
``fit_harmonics(..., harmonics=10, refine_frequency=True)`` and, in the same run, a naive baseline:
``numpy.linalg.lstsq`` on an explicit 10⁶ × 21 design matrix at the known frequency (no
refinement, a tenth of the samples). Prints samples/s for both and their ratio, plus the accuracy
of the fit against the known truth. Best of 3 with ``time.perf_counter``; no asserts on time.

Run: ``python benchmarks/bench_sinefit.py [--samples N] [--periods 10,1000,10000] [--cpu]`` (one block of
lines per number of periods; the issue's bar: under 0.3 s for 10⁷ samples at any of them)
"""

from __future__ import annotations

import argparse
import os

# one core: pin the BLAS thread pools before NumPy loads
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import math  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from rotacal.signal import HarmonicFitAccumulator, fit_harmonics, thd_percent  # noqa: E402

H = 10
FS_HZ = 500_000.0
NOISE = 1e-3


#: Wall time, or with --cpu this process's CPU time (steadier on a shared machine).
CLOCK = time.perf_counter


def best_of(fn: Callable[[], Any], repeat: int = 3) -> tuple[float, Any]:
    best = math.inf
    out = None
    for _ in range(repeat):
        t0 = CLOCK()
        out = fn()
        best = min(best, CLOCK() - t0)
    return best, out


def make_signal(
    n: int, f_hz: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(n) / FS_HZ
    amps = np.array([2.0] + [0.02 / h for h in range(2, H + 1)])
    phases = rng.uniform(-math.pi, math.pi, H)
    y = np.full(n, 0.25)
    for h in range(1, H + 1):
        y += amps[h - 1] * np.sin(2 * math.pi * h * f_hz * t + phases[h - 1])
    y += NOISE * rng.standard_normal(n)
    return t, y, amps


def naive_lstsq(t: np.ndarray, y: np.ndarray, f_hz: float) -> np.ndarray:
    th = 2 * math.pi * f_hz * (t - t.mean())
    ang = np.outer(th, np.arange(1, H + 1))
    design = np.hstack([np.ones((t.size, 1)), np.cos(ang), np.sin(ang)])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    return coef


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=10_000_000)
    ap.add_argument("--periods", default="10", help="comma-separated periods in the record")
    ap.add_argument("--baseline-samples", type=int, default=1_000_000)
    ap.add_argument("--chunks", type=int, default=10, help="chunks for the accumulator run")
    ap.add_argument("--cpu", action="store_true", help="time by CPU time, not wall time")
    args = ap.parse_args()
    global CLOCK
    if args.cpu:
        CLOCK = time.process_time
    for periods in (float(p) for p in args.periods.split(",")):
        run(args, periods)


def run(args: argparse.Namespace, periods: float) -> None:
    """Time the fit, the chunked accumulator and the naive baseline on one record."""
    rng = np.random.default_rng(2023)
    f_hz = periods * FS_HZ / args.samples
    t, y, amps = make_signal(args.samples, f_hz, rng)
    n = t.size
    print(f"signal: {n:.3g} samples, {f_hz * n / FS_HZ:.1f} periods, {H} harmonics, noise {NOISE}")

    t_fit, fit = best_of(lambda: fit_harmonics(t, y, harmonics=H, refine_frequency=True))
    print(
        f"fit_harmonics (refine f):        {t_fit * 1e3:8.1f} ms  {n / t_fit / 1e6:8.1f} M samples/s"
        f"  ({fit.iterations} iterations)"
    )
    print(
        f"  |f/f0 - 1| = {abs(fit.frequency_hz / f_hz - 1):.2e}  (u = "
        f"{fit.frequency_u_hz / f_hz:.1e});  max |A_h/A_h0 - 1| = "
        f"{np.max(np.abs(fit.amplitudes / amps - 1)):.2e};  THD = {thd_percent(fit):.6f} % "
        f"(true {thd_percent(amps):.6f} %);  residual rms = {fit.residual_rms:.3e}"
    )

    def chunked() -> Any:
        acc = HarmonicFitAccumulator(frequency_hz=f_hz, harmonics=H)
        for tc, yc in zip(
            np.array_split(t, args.chunks), np.array_split(y, args.chunks), strict=True
        ):
            acc.add(tc, yc)
        return acc.fit(harmonics=H)

    t_acc, fit_c = best_of(chunked)
    print(
        f"HarmonicFitAccumulator, {args.chunks} chunks: {t_acc * 1e3:8.1f} ms  "
        f"{n / t_acc / 1e6:8.1f} M samples/s  (|Δf|/f vs one-shot = "
        f"{abs(fit_c.frequency_hz / fit.frequency_hz - 1):.1e})"
    )

    nb = min(args.baseline_samples, n)
    t_naive, coef = best_of(lambda: naive_lstsq(t[:nb], y[:nb], f_hz))
    print(
        f"naive lstsq, explicit {nb:.0e} x {2 * H + 1} design (f known): {t_naive * 1e3:8.1f} ms  "
        f"{nb / t_naive / 1e6:8.2f} M samples/s"
    )
    print(f"throughput ratio fit_harmonics / naive lstsq: {(n / t_fit) / (nb / t_naive):.0f}x")
    _ = coef


if __name__ == "__main__":
    main()
