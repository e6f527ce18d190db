"""Rate accuracy and stability over angle windows (``rotacal rate --window-deg``): time, memory,
and the streamed path against the in-memory one.

The record: one head of an 18,000-line encoder on a table at 300 °/s with a once-per-revolution
and a 10-per-revolution rate ripple (0.01 % each) and 1 ns timing jitter, written chunk by chunk
to an HDF5 file under ``/tmp/bench-window20`` (deleted after each size): 10⁷ timestamps (9.3
minutes) and 5.4·10⁷ (one hour, the issue's case; a 432 MB file).

Every case runs in a child process of its own (peak RSS = that child's ``ru_maxrss``):

- ``stream N``: :func:`rotacal.table.rate_windows.rate_windows_stream` over the file's chunks
  (windows 1°, 10°, 360°, the timing jitter estimated in the same pass): the first call in the
  fresh child (imports and Numba's load included), then the least of two warm calls (the pulse
  times checked as they come, the API's default), one warm call with ``check=False`` (as the
  rate command runs it, its analysis having checked the train), against
  the same child reading the file through the same chunk reader (best of three; the least any
  streamed analysis does). Printed: seconds (wall and CPU), timestamps/s, peak RSS (measured
  before the in-memory check below loads the whole array), the ratio to the baseline, and the
  largest relative difference of the mean rate, stability and peak from the in-memory path
  (every window rate of the whole array by :func:`rotacal.table.rate_windows.window_rates`,
  then NumPy's mean and standard deviation);
- ``command N``: the whole ``python -m rotacal rate FILE --pulses-per-rev 18000 --no-compensation
  --set-rate-deg-s 300`` with and without ``--window-deg 1,10,360`` (what the windows add to the
  command), seconds and peak RSS of each.

    python benchmarks/bench_rate_windows.py            # 1e7 and 5.4e7 timestamps
    python benchmarks/bench_rate_windows.py --quick    # 1e7 only
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from bench_rate import best_of_three  # noqa: E402  (least wall and CPU seconds of three runs)

M = 18_000
RATE = 300.0
WINDOWS = (1.0, 10.0, 360.0)
HOUR = 54_000_000  # 3600 s × 300 °/s × 18,000 / 360°
DIR = "/tmp/bench-window20"


def path_of(n: int) -> str:
    return os.path.join(DIR, f"windows-{n}.h5")


def write_h5(path: str, n: int) -> None:
    """The record, chunk by chunk: time as a function of the line's angle θ_j = j·360/m,
    t = θ/ω − Σ a·sin(q·θ)/(q·ω·2π/360) (rate ripple of relative amplitude a at q per revolution,
    to first order), plus 1 ns jitter drawn per chunk."""
    import h5py

    step = 1 << 22
    with h5py.File(path, "w") as f:
        ds = f.create_dataset("head_0", shape=(n,), dtype="f8")
        for start in range(0, n, step):
            j = np.arange(start, min(start + step, n), dtype=np.float64)
            theta = np.deg2rad(j * (360.0 / M))
            t = theta / np.deg2rad(RATE)
            for q, a in ((1, 1e-4), (10, 1e-4)):
                t -= a * np.sin(q * theta + 0.4 * q) / (q * np.deg2rad(RATE))
            noise = np.random.default_rng(start).normal(0.0, 1e-9, j.size)
            ds[start : start + j.size] = t + noise


def _chunks(path: str):
    from rotacal.io import iter_capture_chunks

    def chunks():
        for part in iter_capture_chunks(path, ["head_0"], chunk_rows=1 << 22):
            yield part["head_0"]

    return chunks


def child(case: str, n: int) -> None:
    out: dict[str, float] = {"timestamps": n}
    path = path_of(n)
    if case == "write":
        write_h5(path, n)
    elif case == "stream":
        t0, c0 = time.perf_counter(), time.process_time()
        from rotacal.table.rate_windows import rate_windows_stream, window_rates

        kw = dict(pulses_per_rev=M, windows_deg=WINDOWS, set_rate_deg_s=RATE)
        streamed = rate_windows_stream(_chunks(path), pulses=n, **kw).to_dict()
        out["first_s"], out["first_cpu_s"] = time.perf_counter() - t0, time.process_time() - c0
        walls, cpus = [], []
        for _ in range(2):  # once the imports and Numba's load (the jitter's kernel) are paid
            t0, c0 = time.perf_counter(), time.process_time()
            again = rate_windows_stream(_chunks(path), pulses=n, **kw).to_dict()
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
            if again != streamed:
                raise SystemExit("a warm call's result differs from the first call's")
        out["seconds"], out["cpu_s"] = min(walls), min(cpus)
        # as the rate command runs it: its analysis has checked the pulse times already
        t0, c0 = time.perf_counter(), time.process_time()
        unchecked = rate_windows_stream(_chunks(path), pulses=n, check=False, **kw).to_dict()
        out["unchecked_s"], out["unchecked_cpu_s"] = (
            time.perf_counter() - t0,
            time.process_time() - c0,
        )
        if unchecked != streamed:
            raise SystemExit("the unchecked call's result differs from the checked one's")
        out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

        def read() -> None:
            for _ in _chunks(path)():
                pass

        out["baseline_s"], out["baseline_cpu_s"] = best_of_three(read)
        # the in-memory path: every window rate of the whole array, then NumPy's mean and std
        whole = np.concatenate(list(_chunks(path)()))
        worst = 0.0
        for w in WINDOWS:
            key = f"{w:g}"
            _, r = window_rates(whole, pulses_per_rev=M, window_deg=w)
            mean = r.mean()
            plain = {
                "window_mean_rate_deg_s": mean,
                "rate_stability_percent": 100 * r.std(ddof=1) / mean,
                "rate_stability_peak_percent": 100 * np.max(np.abs(r - mean)) / mean,
            }
            for name, value in plain.items():
                worst = max(worst, abs(streamed[name][key] / value - 1.0))
        out["max_rel_diff"] = worst
        out["stability_1_percent"] = streamed["rate_stability_percent"]["1"]
        out["stability_360_percent"] = streamed["rate_stability_percent"]["360"]
    print(json.dumps(out))


def run(argv: list[str]) -> dict[str, float]:
    """``python argv`` in a fresh process that runs it in one grandchild: its stdout's last
    JSON line (if any), wall seconds, the grandchild's CPU seconds and peak RSS."""
    code = (
        "import json, resource, subprocess, sys, time\n"
        "t0 = time.perf_counter()\n"
        f"p = subprocess.run([sys.executable, *{argv!r}], capture_output=True, text=True)\n"
        "wall = time.perf_counter() - t0\n"
        "if p.returncode: sys.stderr.write(p.stderr); sys.exit(p.returncode)\n"
        "lines = [x for x in p.stdout.strip().splitlines() if x.startswith('{')]\n"
        "out = json.loads(lines[-1]) if lines else {}\n"
        "out.setdefault('seconds', wall)\n"
        "ru = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
        "out.setdefault('peak_rss_mb', ru.ru_maxrss / 1024)\n"
        "out.setdefault('cpu_s', ru.ru_utime + ru.ru_stime)\n"
        "print(json.dumps(out))\n"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def one_size(n: int) -> None:
    os.makedirs(DIR, exist_ok=True)
    if shutil.disk_usage(DIR).free < 3 * n * 8:
        print(f"{n:>10.3g} skipped: too little space in {DIR}")
        return
    path = path_of(n)
    try:
        run([__file__, "--child", "write", str(n)])
        r = run([__file__, "--child", "stream", str(n)])
        print(
            f"stream  {n:>10.3g} {r['first_s']:>8.2f} {r['first_cpu_s']:>7.2f} "
            f"{n / r['first_s']:>10.3g} {'':>8} {'':>8} {'':>8} {'':>10}   1st call (imports)"
        )
        print(
            f"stream  {n:>10.3g} {r['seconds']:>8.2f} {r['cpu_s']:>7.2f} "
            f"{n / r['seconds']:>10.3g} {r['peak_rss_mb']:>8.0f} "
            f"{r['seconds'] / r['baseline_s']:>8.2f} {r['cpu_s'] / r['baseline_cpu_s']:>8.2f} "
            f"{r['max_rel_diff']:>10.1e}   s(1°) {r['stability_1_percent']:.5f} %, "
            f"s(360°) {r['stability_360_percent']:.2e} %"
        )
        print(
            f"stream  {n:>10.3g} {r['unchecked_s']:>8.2f} {r['unchecked_cpu_s']:>7.2f} "
            f"{n / r['unchecked_s']:>10.3g} {'':>8} "
            f"{r['unchecked_s'] / r['baseline_s']:>8.2f} "
            f"{r['unchecked_cpu_s'] / r['baseline_cpu_s']:>8.2f} {'':>10}   check=False (as in "
            "`rotacal rate`)"
        )
        base = ["-m", "rotacal", "rate", path, "--pulses-per-rev", str(M), "--no-compensation"]
        base += ["--set-rate-deg-s", str(RATE), "--json", path + ".json", "--overwrite"]
        runs: dict[str, list[dict[str, float]]] = {"plain": [], "windows": []}
        for _ in range(2):  # alternated, the least of two: a shared machine is unsteady
            runs["plain"].append(run(base))
            runs["windows"].append(run([*base, "--window-deg", "1,10,360"]))
        plain, windows = (
            {
                "seconds": min(x["seconds"] for x in runs[k]),
                "cpu_s": min(x["cpu_s"] for x in runs[k]),
                "peak_rss_mb": max(x["peak_rss_mb"] for x in runs[k]),
            }
            for k in ("plain", "windows")
        )
        print(
            f"command {n:>10.3g} {windows['seconds']:>8.2f} {windows['cpu_s']:>7.2f} "
            f"{n / windows['seconds']:>10.3g} {windows['peak_rss_mb']:>8.0f} "
            f"{windows['seconds'] / plain['seconds']:>8.2f} "
            f"{windows['cpu_s'] / plain['cpu_s']:>8.2f}   (without windows: "
            f"{plain['seconds']:.2f} s, {plain['peak_rss_mb']:.0f} MB)"
        )
    finally:
        for leftover in (path, path + ".json"):
            if os.path.exists(leftover):
                os.remove(leftover)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="10⁷ timestamps only")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child[0], int(args.child[1]))
        return
    print(
        f"{'case':<7} {'timestamps':>10} {'seconds':>8} {'cpu s':>7} {'ts/s':>10} {'peak MB':>8} "
        f"{'× base':>8} {'× (cpu)':>8} {'vs memory':>10}"
    )
    for n in (10_000_000,) if args.quick else (10_000_000, HOUR):
        one_size(n)
    print(
        "stream: × base = the windows' time over reading the same file's chunks (best of three, "
        "same child); vs memory = the largest relative difference of the mean rate, stability and "
        "peak from the in-memory path. command: × base = `rotacal rate … --window-deg 1,10,360` over the same command "
        "without windows (same run)."
    )


if __name__ == "__main__":
    main()
