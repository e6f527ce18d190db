"""Gyro scale factor (seed 004) and multiposition drift coefficients (seed 001) against the twins'
truth over many noise draws, against the bars of issue 4; and their speed against a bare baseline.

    python benchmarks/bench_gyro_accuracy.py [--draws 200]

Scale factor: the default twin (11 rates ±100 °/s, 12.5 mV/(°/s), 0.05 °/s rms noise, 5000 samples
per point, 0.0195 %FS nonlinearity); bar: |S/S_true − 1| < 2·10⁻⁵ with S_true the least-squares
line of the noise-free response. Multiposition: seed 001 Table 1 coefficients, 64 positions × 4
readings of 0.005 °/h noise, both axes; bar: every coefficient within 0.01 °/h (/g, /g²).
Speed: rotacal's calibration against grouping + ``np.polyfit`` / ``np.linalg.lstsq`` alone on the
same data, as a ratio measured in this run.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rotacal.gyro.multiposition import calibrate_multiposition, earth_rate_and_gravity
from rotacal.gyro.scale_factor import calibrate_scale_factor
from rotacal.sim.gyro_rates import simulate_gyro_rates
from rotacal.sim.multiposition import simulate_multiposition


def _best(fn, repeat: int = 7) -> float:
    t = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return min(t)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--draws", type=int, default=200)
    n = ap.parse_args().draws

    rel, dnl = [], []
    for seed in range(n):
        cap = simulate_gyro_rates(seed=seed)
        r = calibrate_scale_factor(cap.columns["rate_deg_s"], cap.columns["output"])
        rel.append(r.scale_factor / cap.truth["ls_scale_factor"] - 1)
        dnl.append(r.nonlinearity_percent_fs - cap.truth["nonlinearity_percent_fs"])
    rel_a, dnl_a = np.abs(rel), np.abs(dnl)
    print(f"scale factor over {n} draws (bar 2e-5 relative)")
    print(f"  |S/S_true - 1|: max {rel_a.max():.2e}  rms {np.sqrt(np.mean(np.square(rel))):.2e}")
    print(f"  NL error (%FS): max {dnl_a.max():.2e}  rms {np.sqrt(np.mean(np.square(dnl))):.2e}")
    print(f"  within bar: {np.mean(rel_a < 2e-5) * 100:.1f} %")

    for axis in ("x", "y"):
        worst, ratio = 0.0, 0.0
        for seed in range(n):
            cap = simulate_multiposition(axis=axis, seed=seed)
            c = cap.columns
            r = calibrate_multiposition(
                c["phi1_deg"], c["phi2_deg"], c["output_deg_h"], axis=axis, latitude_deg=45.75
            )
            for k, v in cap.truth["drift_coefficients"].items():
                e = abs(r.drift_coefficients[k] - v)
                worst = max(worst, e)
                ratio = max(ratio, e / r.drift_coefficients_u[k])
        print(
            f"multiposition {axis} axis over {n} draws (bar 0.01): max |error| {worst:.4f}, "
            f"max |error|/u {ratio:.2f}"
        )

    # speed against a bare baseline on the same data
    big = simulate_gyro_rates(samples_per_point=200_000, seed=1)
    rate, out = big.columns["rate_deg_s"], big.columns["output"]

    def baseline() -> None:
        u, inv = np.unique(rate, return_inverse=True)
        means = np.bincount(inv, weights=out) / np.bincount(inv)
        np.polyfit(u, means, 1)

    t_base = _best(baseline)
    t_rot = _best(lambda: calibrate_scale_factor(rate, out))
    print(
        f"scale factor on {rate.size} rows: rotacal {t_rot * 1e3:.1f} ms, baseline "
        f"(np.unique + bincount + polyfit) {t_base * 1e3:.1f} ms, ratio {t_rot / t_base:.2f}"
    )
    cap = simulate_multiposition(repeats=1000, seed=1)
    c = cap.columns

    def base_mp() -> None:
        w, a = earth_rate_and_gravity(c["phi1_deg"], c["phi2_deg"], 45.75)
        ax, ay, az = a.T
        m = np.column_stack([np.ones_like(ax), ax, ay, az, ax**2, az**2, ax * ay])
        np.linalg.lstsq(m, c["output_deg_h"] - w[:, 0], rcond=None)

    t_base = _best(base_mp)
    t_rot = _best(
        lambda: calibrate_multiposition(
            c["phi1_deg"], c["phi2_deg"], c["output_deg_h"], latitude_deg=45.75
        )
    )
    print(
        f"multiposition on {c['phi1_deg'].size} rows: rotacal {t_rot * 1e3:.1f} ms, baseline "
        f"(eq. 3 + lstsq) {t_base * 1e3:.1f} ms, ratio {t_rot / t_base:.2f}"
    )


if __name__ == "__main__":
    main()
