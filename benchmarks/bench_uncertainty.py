"""Throughput of the Monte Carlo method (rotacal.uncertainty.montecarlo.monte_carlo) on one core.

Times ``monte_carlo`` with 10⁶ trials (fixed) for

(a) the JCGM 101 §9.3 mass-calibration model (5 inputs), and
(b) a calibration-sized model: a gyro scale-factor/bias straight-line fit of 11 rate points,
    each with a Normal output reading and a rectangular set-rate error (22 inputs), solved per
    trial by the closed-form least squares (whole-array), giving 2 outputs;

and, in the same run, a baseline for (b): the same inputs drawn as arrays, then a per-trial Python
loop calling ``numpy.polyfit`` on 10⁴ trials (trials/s scaled). Prints trials/s and the ratios, and
checks that the baseline and the Monte Carlo agree on K and u(K). Best of 3, ``time.perf_counter``;
no asserts on time.

Run: ``python benchmarks/bench_uncertainty.py [--trials N] [--baseline-trials N]``
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

from rotacal.uncertainty.distributions import Distribution, Normal, Rectangular  # noqa: E402
from rotacal.uncertainty.montecarlo import MonteCarloResult, monte_carlo  # noqa: E402

# ---------------------------------------------------------------- (a) JCGM 101 §9.3 mass model
MASS_INPUTS: dict[str, Distribution] = {
    "m_rc": Normal(100_000.000, 0.050),  # mg
    "dm_rc": Normal(1.234, 0.020),  # mg
    "rho_a": Rectangular(1.10, 1.30),  # kg/m³
    "rho_w": Rectangular(7000.0, 9000.0),  # kg/m³
    "rho_r": Rectangular(7950.0, 8050.0),  # kg/m³
}


def mass(m_rc: Any, dm_rc: Any, rho_a: Any, rho_w: Any, rho_r: Any) -> Any:
    return (m_rc + dm_rc) * (1.0 + (rho_a - 1.2) * (1.0 / rho_w - 1.0 / rho_r)) - 100_000.0


# ------------------------------------------------------ (b) 11-point scale-factor / bias fit
RATES = np.linspace(-100.0, 100.0, 11)  # set rates, deg/s
K_TRUE, B_TRUE = 1.0025, 0.03  # scale factor (V per deg/s), bias (V)
U_READ = 2e-3  # u of each averaged reading, V
RATE_ERR = 0.01  # set-rate error half-width, deg/s

FIT_INPUTS: dict[str, Distribution] = {}
for _k, _w in enumerate(RATES):
    FIT_INPUTS[f"y{_k}"] = Normal(K_TRUE * _w + B_TRUE, U_READ)
    FIT_INPUTS[f"e{_k}"] = Rectangular.centered(0.0, RATE_ERR)


def line_fit(**v: np.ndarray) -> dict[str, np.ndarray]:
    """Closed-form least squares y = K·x + b per trial, x = set rate + its error."""
    n = len(RATES)
    y = np.stack([v[f"y{k}"] for k in range(n)])
    x = RATES[:, None] + np.stack([v[f"e{k}"] for k in range(n)])
    xm = x.mean(axis=0)
    ym = y.mean(axis=0)
    dx = x - xm
    slope = np.einsum("ij,ij->j", dx, y - ym) / np.einsum("ij,ij->j", dx, dx)
    return {"K": slope, "b": ym - slope * xm}


def baseline(trials: int, seed: int = 1) -> tuple[float, float]:
    """Per-trial Python loop with numpy.polyfit; returns (mean K, u(K))."""
    rng = np.random.default_rng(seed)
    n = len(RATES)
    y = (K_TRUE * RATES + B_TRUE)[None, :] + U_READ * rng.standard_normal((trials, n))
    x = RATES[None, :] + rng.uniform(-RATE_ERR, RATE_ERR, (trials, n))
    ks = np.empty(trials)
    bs = np.empty(trials)
    for i in range(trials):
        ks[i], bs[i] = np.polyfit(x[i], y[i], 1)
    return float(ks.mean()), float(ks.std(ddof=1))


def best_of(fn: Callable[[], Any], repeat: int = 3) -> tuple[float, Any]:
    best = math.inf
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=1_000_000)
    ap.add_argument("--baseline-trials", type=int, default=10_000)
    args = ap.parse_args()
    m = args.trials

    t_mass, r_mass = best_of(lambda: monte_carlo(mass, MASS_INPUTS, trials=m))
    assert isinstance(r_mass, MonteCarloResult)
    print(
        f"(a) JCGM 101 §9.3 mass, 5 inputs:       {t_mass:6.2f} s  {m / t_mass / 1e6:6.2f} M trials/s"
        f"  (δm = {r_mass.value:.4f} mg, u = {r_mass.u:.4f} mg)"
    )

    t_fit, r_fit = best_of(lambda: monte_carlo(line_fit, FIT_INPUTS, trials=m))
    assert isinstance(r_fit, dict)
    k_mc = r_fit["K"]
    print(
        f"(b) 11-point line fit, 22 inputs:       {t_fit:6.2f} s  {m / t_fit / 1e6:6.2f} M trials/s"
        f"  (K = {k_mc.value:.6f}, u(K) = {k_mc.u:.3e})"
    )

    nb = args.baseline_trials
    t_base, (k_mean, k_u) = best_of(lambda: baseline(nb), repeat=1)
    rate_base = nb / t_base
    print(
        f"    baseline: np.polyfit per trial ({nb:.0e}): {t_base:6.2f} s  "
        f"{rate_base / 1e3:6.1f} k trials/s  (K = {k_mean:.6f}, u(K) = {k_u:.3e})"
    )
    print(f"ratio (b) monte_carlo / per-trial polyfit loop: {(m / t_fit) / rate_base:.0f}x")
    print(f"ratio (a) / (b) trials/s: {(m / t_mass) / (m / t_fit):.1f}")
    print(
        f"agreement: |ΔK| = {abs(k_mc.value - k_mean):.1e} (baseline SE {k_u / math.sqrt(nb):.1e}), "
        f"u(K) ratio = {k_mc.u / k_u:.3f}"
    )


if __name__ == "__main__":
    main()
