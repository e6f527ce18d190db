"""Speed of the overlapping Allan deviation (rotacal.signal.allan) against allantools, one core.

A gyro-like rate record (white rate noise + a small rate random walk, 100 Hz) of ``--samples``
points (default 10⁷):

1. octave τ: ``overlapping_adev(y, fs, taus="octave")`` and ``allantools.oadev(..., taus="octave")``
   on the same data in the same run — times, their ratio and the largest relative difference;
2. every τ (m = 1 … ⌊N/2⌋): ``overlapping_adev(y, fs, taus="all")`` timed, also with a rate ramp
   added (the case that used to fall back to the direct method), each checked against the
   literal sum at 40 cluster sizes (NumPy, the plain path); with ``--numpy-twin`` also without
   Numba (``ROTACAL_NUMBA=0``); with ``--cli`` the whole
   ``rotacal allan --taus all`` command on an NPZ of the record; allantools is not run
   at that size (O(N²)): its ``taus="all"`` cost is measured at 10⁴ and 10⁵ samples and
   extrapolated both with the exponent those two give (≈ 1.5: overheads still count there) and
   with N², its asymptotic cost (N/2 values of τ at O(N) each).

Best of ``--repeat`` (default 1 for the big runs): wall time (``time.perf_counter``) and, in
the ``cpu`` column, the CPU time of this process (user + system, ``time.process_time``; for the
command, of the child) — on a shared machine the CPU time is the steadier figure. No asserts.

Run: ``python benchmarks/bench_allan.py [--samples N] [--repeat R] [--quick] [--cli]``
"""

from __future__ import annotations

import argparse
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import math  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from rotacal.signal.allan import overlapping_adev  # noqa: E402

FS_HZ = 100.0
#: Rate ramp of the ramp case (°/s²): dominates the curve from τ of a few seconds.
RAMP_DEG_S2 = 1e-2


#: CPU seconds (user + system) of the last :func:`best_of` (its best run) or :func:`time_cli`.
LAST_CPU = [0.0]


def best_of(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    """Best wall time of ``repeat`` calls and the last result; the best CPU time in LAST_CPU."""
    best = math.inf
    cpu = math.inf
    out = None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        cpu = min(cpu, time.process_time() - c0)
        best = min(best, time.perf_counter() - t0)
    LAST_CPU[0] = cpu
    return best, out


def fmt_cpu() -> str:
    return f"cpu {LAST_CPU[0]:7.3f} s"


def gyro_rate(n: int, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    white = 0.3 * rng.standard_normal(n)
    walk = np.cumsum(2e-5 * rng.standard_normal(n))
    return 0.1 + white + walk


def fmt(seconds: float) -> str:
    if seconds < 120:
        return f"{seconds:10.3f} s"
    if seconds < 2 * 3600:
        return f"{seconds / 60:10.1f} min"
    return f"{seconds / 3600:10.1f} h"


def literal_check(y: np.ndarray, res: Any, count: int = 40) -> float:
    """Largest relative difference of σ at ``count`` cluster sizes (the first and last ten, and
    twenty log-spaced between) from the literal sum of squared second differences."""
    from rotacal.signal._allan_fast import direct_sums
    from rotacal.signal._phase import phase_record

    x = phase_record(y, FS_HZ, "rate")
    ms = np.asarray(res.cluster_sizes)
    pick = np.unique(
        np.concatenate(
            [
                np.arange(10),
                np.geomspace(10, ms.size - 11, count - 20).astype(int),
                ms.size - 1 - np.arange(10),
            ]
        )
    )
    ref = direct_sums(x, ms[pick], jit=False)
    adev = np.sqrt(ref / (2.0 * (x.size - 2 * ms[pick]))) / (ms[pick] / FS_HZ)
    return float(np.max(np.abs(res.adev[pick] / adev - 1.0)))


def time_cli(y: np.ndarray) -> tuple[float, float]:
    """Seconds of ``rotacal allan FILE --taus all --json OUT`` in a subprocess (NPZ input; its
    CPU time in LAST_CPU), and of ``np.load`` of the same file's rate column in this process."""
    with tempfile.TemporaryDirectory() as folder:
        capture = os.path.join(folder, "gyro.npz")
        np.savez(capture, rate_deg_s=y, time_s=np.arange(y.size) / FS_HZ)
        t0 = time.perf_counter()
        with np.load(capture) as data:
            loaded = data["rate_deg_s"]
        t_load = time.perf_counter() - t0
        del loaded
        command = [sys.executable, "-m", "rotacal", "allan", capture, "--taus", "all"]
        command += ["--json", os.path.join(folder, "out.json")]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        LAST_CPU[0] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        return wall, t_load


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=10_000_000)
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--quick", action="store_true", help="10⁶ samples")
    ap.add_argument("--cli", action="store_true", help="also time the whole rotacal allan command")
    ap.add_argument(
        "--numpy-twin", action="store_true", help="also every τ with ROTACAL_NUMBA=0 (NumPy only)"
    )
    args = ap.parse_args()
    n = 1_000_000 if args.quick else args.samples
    try:
        import allantools
    except ImportError:  # pragma: no cover - dev extra
        raise SystemExit(
            "allantools is needed for the comparison: pip install allantools"
        ) from None

    y = gyro_rate(n)
    print(f"overlapping ADEV, {n:,} rate samples at {FS_HZ:g} Hz, one core")
    print(f"{'case':44s} {'time':>13s}  {'ratio':>8s}  note")

    t_rc, res = best_of(lambda: overlapping_adev(y, fs=FS_HZ, taus="octave"), args.repeat)
    cpu_rc = LAST_CPU[0]
    t_at, ref = best_of(
        lambda: allantools.oadev(y, rate=FS_HZ, data_type="freq", taus="octave"), args.repeat
    )
    diff = float(np.max(np.abs(res.adev / ref[1] - 1.0)))
    print(
        f"{'octave τ: rotacal overlapping_adev':44s} {fmt(t_rc)}  {1.0:8.2f}  {res.tau_s.size} τ, "
        f"cpu {cpu_rc:7.3f} s"
    )
    print(
        f"{'octave τ: allantools.oadev':44s} {fmt(t_at)}  {t_at / t_rc:8.2f}  "
        f"max |rel diff| {diff:.1e}, {fmt_cpu()} ({LAST_CPU[0] / cpu_rc:.2f}× rotacal's)"
    )

    t_all, res_all = best_of(lambda: overlapping_adev(y, fs=FS_HZ, taus="all"), args.repeat)
    print(
        f"{'every τ: rotacal overlapping_adev(taus=all)':44s} {fmt(t_all)}  {t_all / t_rc:8.2f}  "
        f"{res_all.tau_s.size:,} τ, {res_all._n_direct} computed directly, {fmt_cpu()}; "
        f"max |rel diff| from the literal sum {literal_check(y, res_all):.1e}"
    )
    ramp = y + RAMP_DEG_S2 * np.arange(n) / FS_HZ
    t_ramp, res_ramp = best_of(lambda: overlapping_adev(ramp, fs=FS_HZ, taus="all"), args.repeat)
    print(
        f"{'every τ, with a rate ramp':44s} {fmt(t_ramp)}  {t_ramp / t_rc:8.2f}  "
        f"{res_ramp._n_direct} computed directly, {fmt_cpu()}; "
        f"max |rel diff| {literal_check(ramp, res_ramp):.1e}"
    )
    if args.numpy_twin:
        os.environ["ROTACAL_NUMBA"] = "0"
        t_np, _ = best_of(lambda: overlapping_adev(y, fs=FS_HZ, taus="all"), args.repeat)
        del os.environ["ROTACAL_NUMBA"]
        print(
            f"{'every τ, ROTACAL_NUMBA=0 (NumPy direct sums)':44s} {fmt(t_np)}  {t_np / t_rc:8.2f}"
        )
    if args.cli:
        t_cli, t_load = time_cli(y)
        print(
            f"{'rotacal allan --taus all (NPZ → JSON)':44s} {fmt(t_cli)}  {t_cli / t_rc:8.2f}  "
            f"{fmt_cpu()}; {t_cli / (t_load + t_all):.2f}× np.load ({t_load:.2f} s) + the "
            "in-process every-τ time"
        )
    sizes = (10_000, 100_000)
    times = []
    for small in sizes:
        ys = gyro_rate(small, seed=2)
        t, _ = best_of(
            lambda ys=ys: allantools.oadev(ys, rate=FS_HZ, data_type="freq", taus="all"), 1
        )
        times.append(t)
        print(f"{f'every τ: allantools.oadev(taus=all), N={small:,}':44s} {fmt(t)}")
    expo = math.log(times[1] / times[0]) / math.log(sizes[1] / sizes[0])
    for label, power in ((f"N^{expo:.2f}, measured", expo), ("N², its asymptotic cost", 2.0)):
        estimate = times[1] * (n / sizes[1]) ** power
        print(
            f"{f'every τ: allantools, N={n:,} (extrapolated)':44s} {fmt(estimate)}  "
            f"{estimate / t_all:8.0f}  cost ∝ {label}"
        )
    print(
        "ratio: time / rotacal octave time (rotacal rows); allantools estimate / rotacal every-τ time"
    )


if __name__ == "__main__":
    main()
