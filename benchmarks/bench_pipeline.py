"""Speed of the whole encoder pipeline against bare ``np.unwrap(np.arctan2(b, a))``, one run.

    python benchmarks/bench_pipeline.py [--samples 10000000]

The pipeline is everything `rotacal motion encoder` does after reading the file: Heydemann
correction, phase with carried cycle count, 12-subinterval subdivision, reversing moments, angle,
interception of whole periods and the 10-harmonic fit with the frequency refined (and the check
for an unfitted drift); then the same with ``--drift`` (a linear term in the fit). Prints times,
throughput and the ratio to the baseline measured in the same run (machines here are noisy: the
ratio is the figure that counts, never a timed assertion).
"""

from __future__ import annotations

import argparse
import os
import time

# "on one core": keep BLAS to one thread (set before NumPy loads)
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from rotacal import sim  # noqa: E402
from rotacal.table import calibrate_encoder_motion  # noqa: E402


def best_of(n: int, func):
    best = np.inf
    out = None
    for _ in range(n):
        t0 = time.perf_counter()
        out = func()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=int, default=10_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()

    fs = 200_000.0
    duration = args.samples / fs
    motion = sim.SineMotion(
        amplitude_deg=0.5, frequency_hz=8.3 / duration, harmonics={2: (0.01, 0.3), 3: (0.005, 1.0)}
    )
    cap = sim.simulate_encoder(
        motion,
        fs_hz=fs,
        duration_s=duration,
        offset_a=0.02,
        amplitude_b=0.98,
        phase_error_rad=0.01,
        noise_rms=0.003,
        seed=0,
    )
    t, a, b = (cap.columns[k] for k in ("time_s", "a", "b"))
    n = t.size
    # warm up both (page faults, caches)
    np.unwrap(np.arctan2(b[:100_000], a[:100_000]))
    calibrate_encoder_motion(t[: n // 3], a[: n // 3], b[: n // 3], lines=36000)

    t_base, _ = best_of(args.repeat, lambda: np.unwrap(np.arctan2(b, a)))
    t_pipe, r = best_of(args.repeat, lambda: calibrate_encoder_motion(t, a, b, lines=36000))
    truth = motion.truth(r.analysis_start_s, r.analysis_stop_s)

    print(f"samples                         {n:,}")
    print(f"baseline np.unwrap(np.arctan2)  {t_base * 1e3:8.1f} ms")
    print(
        f"rotacal encoder pipeline        {t_pipe * 1e3:8.1f} ms   ({n / t_pipe / 1e6:.1f} M samples/s)"
    )
    print(f"ratio pipeline / baseline       {t_pipe / t_base:8.2f}   (bar: <= 2)")
    print(f"THD error vs truth              {r.thd_percent - truth['thd_percent']:+.2e} pp")
    print(
        f"amplitude error vs truth        {r.amplitude_deg / truth['amplitude_deg'] - 1:+.2e} (relative)"
    )
    print(
        f"frequency error vs truth        {r.frequency_hz / truth['frequency_hz'] - 1:+.2e} (relative)"
    )
    # --drift: the same pipeline with the linear drift term in the fit (no extra pass in memory)
    t_drift, r_d = best_of(
        args.repeat, lambda: calibrate_encoder_motion(t, a, b, lines=36000, drift=True)
    )
    print(
        f"with --drift                    {t_drift * 1e3:8.1f} ms   "
        f"(ratio to without: {t_drift / t_pipe:.2f})"
    )
    print(f"THD error vs truth, --drift     {r_d.thd_percent - truth['thd_percent']:+.2e} pp")


if __name__ == "__main__":
    main()
