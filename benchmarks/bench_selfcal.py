"""Speed and accuracy of the multi-head encoder self-calibration and rate analysis (seed 004).

The issue's case: 12 heads × 18000 pulses × 3 revolutions (the twin, 1 ns jitter, 0.01 % rate
fluctuation, eccentricity, random graduation errors, head placement errors). Times, best of 5:
- ``self_calibrate`` (checks, pairing in time, local rate, per-order least squares per revolution,
  period check, repeatability);
- in the same run, a naive equal-division average: ``np.interp`` of every head's pulse count at head
  0's pulse times, averaged over heads — the minimal work of any EDA on timestamps — as a baseline;
- ``calibrate_rate`` on the same capture (self-calibration included).
Prints the times, the ratio to the baseline and both methods' rms error against the twin's truth.
No asserts on time.

Run: ``python benchmarks/bench_selfcal.py [--heads N] [--pulses M] [--revolutions R]``
"""

from __future__ import annotations

import argparse
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import math  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from rotacal.encoder import self_calibrate  # noqa: E402
from rotacal.sim import simulate_pulses  # noqa: E402
from rotacal.table import calibrate_rate  # noqa: E402


def best_of(fn: Callable[[], Any], repeat: int = 5) -> tuple[float, Any]:
    best, out = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def naive_eda(heads: list[np.ndarray], m: int) -> np.ndarray:
    """Interpolate each head's count at head 0's times, average the n readings, fold by revolution."""
    t0 = heads[0]
    lo = max(h[0] for h in heads)
    hi = min(h[-1] for h in heads)
    j = np.flatnonzero((t0 >= lo) & (t0 <= hi))
    revs = j.size // m
    j = j[: revs * m]
    pitch = 360.0 / m * 3600.0
    diffs = np.zeros(j.size)
    for h in heads[1:]:
        d = (np.interp(t0[j], h, np.arange(h.size)) - j) * pitch
        diffs += d - d.mean()
    dev = (diffs / len(heads)).reshape(revs, m).mean(axis=0)
    return np.roll(dev - dev.mean(), j[0] % m)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--heads", type=int, default=12)
    ap.add_argument("--pulses", type=int, default=18000)
    ap.add_argument("--revolutions", type=float, default=3.3)
    args = ap.parse_args()
    cap = simulate_pulses(
        heads=args.heads, pulses_per_rev=args.pulses, revolutions=args.revolutions, seed=4
    )
    heads = [cap.columns[f"head_{i}"] for i in range(args.heads)]
    m = args.pulses
    truth = np.asarray(cap.truth["deviation_detectable_arcsec"])
    total = sum(h.size for h in heads)
    print(f"capture: {args.heads} heads x {m} pulses/rev, {total:,} timestamps")

    t_sc, sc = best_of(lambda: self_calibrate(heads, pulses_per_rev=m))
    t_nv, nv = best_of(lambda: naive_eda(heads, m))
    t_rt, rt = best_of(lambda: calibrate_rate(heads, pulses_per_rev=m))

    def rms(x: np.ndarray) -> float:
        return float(np.sqrt(np.mean(x**2)))

    print(
        f"self_calibrate            {t_sc * 1e3:8.1f} ms   {sc.revolutions_used} revolutions, "
        f"rms error vs truth {rms(sc.deviation_arcsec - truth):.2e} arcsec"
    )
    print(
        f"naive interp EDA baseline {t_nv * 1e3:8.1f} ms   "
        f"rms error vs truth {rms(nv - truth):.2e} arcsec (interpolates between lines)"
    )
    print(f"ratio self_calibrate / baseline: {t_sc / t_nv:.2f}")
    print(
        f"calibrate_rate (with self-calibration, s(phi) at {len(rt.allan_angle_deg)} angles): "
        f"{t_rt * 1e3:8.1f} ms"
    )


if __name__ == "__main__":
    main()
