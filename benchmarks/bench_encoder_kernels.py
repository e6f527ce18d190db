"""Throughput of the quadrature-encoder kernels against bare ``np.unwrap(np.arctan2(b, a))``.

Run: ``python benchmarks/bench_encoder_kernels.py [n_samples]`` (default 10⁷). Both are timed in
the same run, best of 3 after a warm-up; the ratio is what matters, not the absolute times.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from rotacal.encoder import (
    angle_deg,
    correct_quadrature,
    demodulate,
    find_reversals,
    fit_quadrature_correction,
    unwrapped_phase,
)

LINES = 36000


def capture(n: int, fs: float = 1e6) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """5° at 0.5 Hz with 1 % offsets, 2 % gain mismatch, 1° phase error, noise, 16-bit ADC."""
    rng = np.random.default_rng(0)
    t = np.arange(n) / fs
    theta = 5.0 * np.sin(2 * np.pi * 0.5 * t) + 0.05 * np.sin(2 * np.pi * 1.0 * t + 0.3)
    phi = 2 * np.pi * LINES * theta / 360.0
    a = 0.01 + np.cos(phi) + 0.002 * rng.standard_normal(n)
    b = -0.01 + 1.02 * np.sin(phi + np.radians(1.0)) + 0.002 * rng.standard_normal(n)
    lsb = 2.5 / 2**15
    return t, np.round(a / lsb) * lsb, np.round(b / lsb) * lsb, theta


def best_of(fn: Callable[[], Any], repeats: int = 3) -> tuple[float, Any]:
    out = fn()  # warm-up
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    n = int(float(sys.argv[1])) if len(sys.argv) > 1 else 10_000_000
    t, a, b, theta = capture(n)
    correction = fit_quadrature_correction(a, b)

    def baseline() -> np.ndarray:
        return np.unwrap(np.arctan2(b, a))

    def kernels() -> tuple[np.ndarray, Any]:
        u, v = correct_quadrature(a, b, correction)
        phase, _ = unwrapped_phase(u, v)
        rev = find_reversals(t, u, v, phase)
        return angle_deg(phase, LINES), rev

    def full() -> Any:
        return demodulate(t, a, b, LINES)

    t_base, _ = best_of(baseline)
    t_fit, _ = best_of(lambda: fit_quadrature_correction(a, b))
    t_kern, (theta_est, rev) = best_of(kernels)
    t_full, demod = best_of(full)

    err = theta_est - theta
    err -= err.mean()
    print(f"samples: {n:,}   reversals found: {len(rev)}   transitions: {rev.transitions:,}")
    print(f"angle error after correction: rms {err.std():.2e} deg, max {np.abs(err).max():.2e} deg")
    rows = [
        ("np.unwrap(np.arctan2(b, a))  [baseline]", t_base),
        ("fit_quadrature_correction (1e6 pts)", t_fit),
        ("correct + unwrapped_phase + find_reversals + angle", t_kern),
        ("demodulate (checks + fit + all of the above)", t_full),
    ]
    for name, sec in rows:
        print(
            f"{name:<52s} {sec * 1e3:8.1f} ms  {n / sec / 1e6:7.1f} M samples/s  "
            f"ratio {sec / t_base:5.2f}"
        )
    print(
        f"correction used: {demod.correction.method}, coverage {demod.correction.coverage_rad:.2f}"
    )


if __name__ == "__main__":
    main()
