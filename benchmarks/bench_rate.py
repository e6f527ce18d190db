"""Throughput and peak memory of the pulse-timing rate analysis and of the self-calibration.

Each case runs in a child process of its own (peak RSS = that child's ``ru_maxrss``, the pulse
times included: 8 bytes per timestamp), on a twin made in the child:

- ``rate N``: ``calibrate_rate`` of one head of N timestamps (18,000 pulses per revolution,
  300 °/s, the issue's case: no self-calibration, so every part of the analysis is the rate's);
- ``selfcal R``: ``self_calibrate`` of 12 heads × 18,000 pulses × R revolutions.

Printed per case: timestamps, seconds (wall, and the child's CPU time: on a shared machine the
steadier figure), timestamps/s (wall), peak RSS (MB) and bytes per timestamp
above the idle child's (the interpreter and the imports), and the ratio of the analysis's time
to the baseline measured in the same child — the rate points ``360·A/m / (t[i+A] − t[i])`` over
the whole record for ``rate`` (the least any rate analysis does), the nearest-pulse search of
every head against head 0 (``np.searchsorted``) for ``selfcal``. No asserts on time.

    python benchmarks/bench_rate.py            # rate 1e6, 1e7; selfcal 10, 30 revolutions
    python benchmarks/bench_rate.py --quick    # rate 1e6; selfcal 10 revolutions
    python benchmarks/bench_rate.py --big      # adds rate 1e8 and selfcal 100 revolutions
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

PULSES_PER_REV = 18000
RATE_DEG_S = 300.0
AVERAGE = 10


def one_head(n: int) -> np.ndarray:
    """n pulse times of one head: 300 °/s with a 0.01 % rate fluctuation, a 3″ eccentricity and
    0.03″ random graduation errors, 1 ns jitter (the twin of ``simulate_pulses``, one head)."""
    rng = np.random.default_rng(17)
    m = PULSES_PER_REV
    pitch = 360.0 / m
    line = np.arange(n) % m
    grad = rng.normal(0.0, 0.03, m)[line] + 3.0 * np.cos(2 * np.pi * line / m + 0.3)
    angle = np.arange(n) * pitch + grad / 3600.0
    t = angle / RATE_DEG_S
    t += 1e-4 / (2 * np.pi * 0.5) * np.sin(2 * np.pi * 0.5 * t)  # 0.01 % at 0.5 Hz
    return t + rng.normal(0.0, 1e-9, n)


def child(case: str, size: float) -> None:
    from rotacal.encoder.selfcal import self_calibrate
    from rotacal.sim.pulses import simulate_pulses
    from rotacal.table.rate import calibrate_rate

    out: dict[str, float] = {}
    if case == "rate":
        t = one_head(int(size))
        t0, c0 = time.perf_counter(), time.process_time()
        r = calibrate_rate([t], pulses_per_rev=PULSES_PER_REV, average=AVERAGE)
        out["seconds"], out["cpu_s"] = time.perf_counter() - t0, time.process_time() - c0
        t0 = time.perf_counter()
        _ = (360.0 * AVERAGE / PULSES_PER_REV) / (t[AVERAGE:] - t[:-AVERAGE])
        out["baseline_s"] = time.perf_counter() - t0
        out["timestamps"] = t.size
        out["mean_rate_deg_s"] = r.mean_rate_deg_s
    elif case == "selfcal":
        cap = simulate_pulses(heads=12, pulses_per_rev=PULSES_PER_REV, revolutions=size, seed=2)
        heads = [np.asarray(cap.columns[f"head_{i}"]) for i in range(12)]
        del cap
        t0, c0 = time.perf_counter(), time.process_time()
        self_calibrate(heads, pulses_per_rev=PULSES_PER_REV)
        out["seconds"], out["cpu_s"] = time.perf_counter() - t0, time.process_time() - c0
        t0 = time.perf_counter()
        for h in heads[1:]:
            np.searchsorted(h, heads[0])
        out["baseline_s"] = time.perf_counter() - t0
        out["timestamps"] = sum(h.size for h in heads)
    print(json.dumps(out))


def run(case: str, size: float) -> dict[str, float]:
    """One case in a fresh process that runs it in one grandchild (RUSAGE_CHILDREN is its own)."""
    code = (
        "import json, resource, subprocess, sys\n"
        f"p = subprocess.run([sys.executable, {__file__!r}, '--child', {case!r}, {str(size)!r}],"
        " capture_output=True, text=True)\n"
        "if p.returncode: sys.stderr.write(p.stderr); sys.exit(p.returncode)\n"
        "out = json.loads(p.stdout.strip().splitlines()[-1])\n"
        "out['peak_rss_mb'] = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024\n"
        "print(json.dumps(out))\n"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="rate 1e6 and selfcal 10 revolutions")
    ap.add_argument("--big", action="store_true", help="add rate 1e8 and selfcal 100 revolutions")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child[0], float(args.child[1]))
        return
    cases: list[tuple[str, float]] = [("rate", 1e6), ("selfcal", 10.0)]
    if not args.quick:
        cases[1:1] = [("rate", 1e7)]
        cases.append(("selfcal", 30.0))
    if args.big:
        cases.insert(2, ("rate", 1e8))
        cases.append(("selfcal", 100.0))
    idle = run("idle", 0.0)["peak_rss_mb"]
    print(f"idle child (interpreter + imports): {idle:.0f} MB")
    print(
        f"{'case':>16} {'timestamps':>12} {'seconds':>9} {'cpu s':>7} {'ts/s':>10} {'peak MB':>8} "
        f"{'B/ts':>6} {'× baseline':>11}"
    )
    for case, size in cases:
        r = run(case, size)
        label = f"{case} {size:g}" + (" rev" if case == "selfcal" else "")
        per_ts = (r["peak_rss_mb"] - idle) * 2**20 / r["timestamps"]
        print(
            f"{label:>16} {r['timestamps']:>12.3g} {r['seconds']:>9.2f} {r['cpu_s']:>7.2f} "
            f"{r['timestamps'] / r['seconds']:>10.3g} {r['peak_rss_mb']:>8.0f} {per_ts:>6.0f} "
            f"{r['seconds'] / r['baseline_s']:>11.0f}"
        )
    print(
        "baselines: rate — the rate points over the whole record; selfcal — np.searchsorted of "
        "every head at head 0's times (same child, same run)."
    )


if __name__ == "__main__":
    main()
