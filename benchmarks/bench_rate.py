"""Throughput and peak memory of the pulse-timing rate analysis and of the self-calibration.

Each case runs in a child process of its own (peak RSS = that child's ``ru_maxrss``, the pulse
times included: 8 bytes per timestamp), on a twin made in the child:

- ``rate N``: ``calibrate_rate`` of one head of N timestamps (18,000 pulses per revolution,
  300 °/s, the issue's case: no self-calibration, so every part of the analysis is the rate's);
- ``selfcal R``: ``self_calibrate`` of 12 heads × 18,000 pulses × R revolutions;
- ``command N``: the whole ``python -m rotacal rate cap.npz --pulses-per-rev 18000 --json …``
  on the same N timestamps written to ``/tmp/bench-pulses/`` (deleted after the case), against
  ``np.load`` plus the bare rate points of the file in a child of its own (same run).

- ``stream N``: ``calibrate_rate_file`` of one head of N timestamps streamed from an HDF5 file
  (written chunk by chunk to ``/tmp/bench-pulses/``, deleted after the case; the same twin,
  its jitter drawn per chunk), against the same child reading the file through the same chunk
  reader and computing the bare rate points of every chunk (best of three, same run). The
  peak RSS is the whole child's: the flat-memory claim of issue 17 (< 1 GB at 6.5·10⁸).
  Two lines: ``1st``, the first call in the fresh child with the analysis's imports and
  Numba's load (what one ``rotacal rate`` command pays), and ``2nd``, the least of two further
  calls in the same child (the throughput once those are paid; each result must equal the
  first's).

Printed per case: timestamps, seconds (wall, and the child's CPU time: on a shared machine the
steadier figure), timestamps/s (wall), peak RSS (MB) and bytes per timestamp
above the idle child's (the interpreter and the imports), and the ratio of the analysis's time
(wall, and CPU) to the baseline measured in the same child (best of three) — the rate points ``360·A/m / (t[i+A] − t[i])`` over
the whole record for ``rate`` (the least any rate analysis does), the nearest-pulse search of
every head against head 0 (``np.searchsorted``) for ``selfcal``. No asserts on time.

    python benchmarks/bench_rate.py            # rate 1e6, 1e7; command 1e7; selfcal 10, 30 rev
    python benchmarks/bench_rate.py --quick    # rate 1e6; selfcal 10 revolutions
    python benchmarks/bench_rate.py --big      # adds rate and command 1e8, selfcal 100 rev
    python benchmarks/bench_rate.py --stream   # stream 1e7, 1e8, 6.5e8 (a 5.2 GB file)
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from typing import Any

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


def write_h5(path: str, n: int) -> None:
    """:func:`one_head`'s twin written chunk by chunk (bounded memory): the same graduation,
    fluctuation and 1 ns jitter (drawn per chunk)."""
    import h5py

    m = PULSES_PER_REV
    pitch = 360.0 / m
    rng = np.random.default_rng(17)
    err = rng.normal(0.0, 0.03, m)
    step = 1 << 23
    with h5py.File(path, "w") as f:
        ds = f.create_dataset("head_0", shape=(n,), dtype="f8")
        for start in range(0, n, step):
            idx = np.arange(start, min(start + step, n))
            line = idx % m
            grad = err[line] + 3.0 * np.cos(2 * np.pi * line / m + 0.3)
            t = (idx * pitch + grad / 3600.0) / RATE_DEG_S
            t += 1e-4 / (2 * np.pi * 0.5) * np.sin(2 * np.pi * 0.5 * t)
            ds[start : start + idx.size] = t + np.random.default_rng(start).normal(
                0, 1e-9, idx.size
            )


def read_rate_points(path: str) -> None:
    """The stream baseline: every chunk of the file through the same reader, its rate points."""
    from rotacal.io import iter_capture_chunks

    for part in iter_capture_chunks(path, ["head_0"], chunk_rows=1 << 22):
        t = part["head_0"]
        _ = (360.0 * AVERAGE / PULSES_PER_REV) / (t[AVERAGE:] - t[:-AVERAGE])


def best_of_three(work: Any) -> tuple[float, float]:
    """Least wall and CPU seconds of three runs of ``work()`` (the baseline; a shared machine
    makes single wall times unsteady)."""
    walls, cpus = [], []
    for _ in range(3):
        t0, c0 = time.perf_counter(), time.process_time()
        work()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return min(walls), min(cpus)


def child(case: str, size: float) -> None:
    out: dict[str, float] = {}
    if case == "rate":
        from rotacal.table.rate import calibrate_rate

        t = one_head(int(size))
        t0, c0 = time.perf_counter(), time.process_time()
        r = calibrate_rate([t], pulses_per_rev=PULSES_PER_REV, average=AVERAGE)
        out["seconds"], out["cpu_s"] = time.perf_counter() - t0, time.process_time() - c0
        out["baseline_s"], out["baseline_cpu_s"] = best_of_three(
            lambda: (360.0 * AVERAGE / PULSES_PER_REV) / (t[AVERAGE:] - t[:-AVERAGE])
        )
        out["timestamps"] = t.size
        out["mean_rate_deg_s"] = r.mean_rate_deg_s
    elif case == "selfcal":
        from rotacal.encoder.selfcal import self_calibrate
        from rotacal.sim.pulses import simulate_pulses

        cap = simulate_pulses(heads=12, pulses_per_rev=PULSES_PER_REV, revolutions=size, seed=2)
        heads = [np.asarray(cap.columns[f"head_{i}"]) for i in range(12)]
        del cap
        t0, c0 = time.perf_counter(), time.process_time()
        self_calibrate(heads, pulses_per_rev=PULSES_PER_REV)
        out["seconds"], out["cpu_s"] = time.perf_counter() - t0, time.process_time() - c0
        out["baseline_s"], out["baseline_cpu_s"] = best_of_three(
            lambda: [np.searchsorted(h, heads[0]) for h in heads[1:]]
        )
        out["timestamps"] = sum(h.size for h in heads)
    elif case == "stream":
        path = path_of(size).replace(".npz", ".h5")
        # first call: the analysis's imports, Numba's load and its cached kernels included
        t0, c0 = time.perf_counter(), time.process_time()
        from rotacal.table.rate_file import calibrate_rate_file

        r = calibrate_rate_file(path, pulses_per_rev=PULSES_PER_REV, average=AVERAGE)
        out["first_s"], out["first_cpu_s"] = time.perf_counter() - t0, time.process_time() - c0
        # two more calls, same process: the throughput once the fixed costs are paid (the least
        # of two, as the baseline's best of three: a shared machine makes single times unsteady)
        walls, cpus = [], []
        for _ in range(2):
            t0, c0 = time.perf_counter(), time.process_time()
            again = calibrate_rate_file(path, pulses_per_rev=PULSES_PER_REV, average=AVERAGE)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
            if json.dumps(again.to_dict(), default=str) != json.dumps(r.to_dict(), default=str):
                raise SystemExit("a warm call's result differs from the first call's")
        out["warm_s"], out["warm_cpu_s"] = min(walls), min(cpus)
        out["baseline_s"], out["baseline_cpu_s"] = best_of_three(lambda: read_rate_points(path))
        out["timestamps"] = int(size)
        out["first_ts_per_s"] = size / out["first_s"]
        out["warm_ts_per_s"] = size / out["warm_s"]
        out["mean_rate_deg_s"] = r.mean_rate_deg_s
    elif case == "write_h5":
        write_h5(path_of(size).replace(".npz", ".h5"), int(size))
        out["timestamps"] = int(size)
    elif case == "idle":  # the interpreter and the imports of the analysis cases
        import rotacal.encoder.selfcal
        import rotacal.sim.pulses
        import rotacal.table.rate  # noqa: F401
    elif case == "write":  # the capture file of a command case: size, path
        np.savez(path_of(size), head_0=one_head(int(size)))
        out["timestamps"] = int(size)
    elif case == "load":  # the command's baseline: read the file, the bare rate points
        t0, c0 = time.perf_counter(), time.process_time()
        t = np.load(path_of(size))["head_0"]
        _ = (360.0 * AVERAGE / PULSES_PER_REV) / (t[AVERAGE:] - t[:-AVERAGE])
        out["seconds"], out["cpu_s"] = time.perf_counter() - t0, time.process_time() - c0
        out["timestamps"] = t.size
    print(json.dumps(out))


def path_of(size: float) -> str:
    return os.path.join(BENCH_DIR, f"rate-{int(size)}.npz")


BENCH_DIR = os.path.join(tempfile.gettempdir(), "bench-pulses")


def run(case: str, size: float, argv: list[str] | None = None) -> dict[str, float]:
    """One case in a fresh process that runs it in one grandchild (RUSAGE_CHILDREN is its own);
    ``argv``: a whole command instead, timed from start to exit."""
    args = argv if argv is not None else [__file__, "--child", case, str(size)]
    code = (
        "import json, resource, subprocess, sys, time\n"
        "t0 = time.perf_counter()\n"
        f"p = subprocess.run([sys.executable, *{args!r}], capture_output=True, text=True)\n"
        "wall = time.perf_counter() - t0\n"
        "if p.returncode: sys.stderr.write(p.stderr); sys.exit(p.returncode)\n"
        f"out = json.loads(p.stdout.strip().splitlines()[-1]) if {argv is None!r} else {{}}\n"
        "out.setdefault('seconds', wall)\n"
        "ru = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
        "out['peak_rss_mb'] = ru.ru_maxrss / 1024\n"
        "out.setdefault('cpu_s', ru.ru_utime + ru.ru_stime)\n"
        "print(json.dumps(out))\n"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="rate 1e6 and selfcal 10 revolutions")
    ap.add_argument("--big", action="store_true", help="add rate 1e8 and selfcal 100 revolutions")
    ap.add_argument(
        "--stream", action="store_true", help="only the streamed cases: 1e7, 1e8, 6.5e8 timestamps"
    )
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child[0], float(args.child[1]))
        return
    cases: list[tuple[str, float]] = [("rate", 1e6), ("selfcal", 10.0)]
    if not args.quick:
        cases[1:1] = [("rate", 1e7), ("command", 1e7)]
        cases.append(("selfcal", 30.0))
    if args.big:
        cases[3:3] = [("rate", 1e8), ("command", 1e8)]
        cases.append(("selfcal", 100.0))
    if args.stream:
        cases = [("stream", 1e7), ("stream", 1e8), ("stream", 6.5e8)]
    idle = run("idle", 0.0)["peak_rss_mb"]
    print(f"idle child (interpreter + imports): {idle:.0f} MB")
    print(
        f"{'case':>16} {'timestamps':>12} {'seconds':>9} {'cpu s':>7} {'ts/s':>10} {'peak MB':>8} "
        f"{'B/ts':>6} {'× baseline':>11} {'× (cpu)':>8}"
    )
    for case, size in cases:
        if case == "command":
            command_case(size, idle)
            continue
        if case == "stream":
            r = stream_case(size)
            if r is None:
                continue
            print_row(
                f"stream {size:g} 1st",
                {**r, "seconds": r["first_s"], "cpu_s": r["first_cpu_s"]},
                idle,
            )
            print_row(
                f"stream {size:g} 2nd",
                {**r, "seconds": r["warm_s"], "cpu_s": r["warm_cpu_s"]},
                idle,
            )
            continue
        r = run(case, size)
        print_row(f"{case} {size:g}" + (" rev" if case == "selfcal" else ""), r, idle)
    print(
        "baselines: rate — the rate points over the whole record; selfcal — np.searchsorted of "
        "every head at head 0's times (same child, same run); command — np.load of the file and "
        "the rate points, in a child of its own (same run); stream — reading the HDF5 file in "
        "chunks and the bare rate points of each (same child, same run)."
    )
    if args.stream:
        print(
            "stream 1st: the first call in a fresh process, its imports and Numba's load "
            "included (what one `rotacal rate` pays); stream 2nd: the least of two further "
            "calls in the same process (the throughput once those are paid). Peak RSS: the "
            "child's, all calls."
        )


def print_row(label: str, r: dict[str, float], idle: float) -> None:
    """One case's line of the table (columns as in the heading)."""
    per_ts = (r["peak_rss_mb"] - idle) * 2**20 / r["timestamps"]
    print(
        f"{label:>16} {r['timestamps']:>12.3g} {r['seconds']:>9.2f} {r['cpu_s']:>7.2f} "
        f"{r['timestamps'] / r['seconds']:>10.3g} {r['peak_rss_mb']:>8.0f} {per_ts:>6.0f} "
        f"{r['seconds'] / r['baseline_s']:>11.1f} "
        f"{r['cpu_s'] / max(r['baseline_cpu_s'], 1e-6):>8.1f}"
    )


def stream_case(size: float) -> dict[str, float] | None:
    """The streamed analysis of an HDF5 file of ``size`` timestamps (made first, deleted after)."""
    os.makedirs(BENCH_DIR, exist_ok=True)
    if shutil.disk_usage(BENCH_DIR).free < 2 * size * 8:
        print(f"{'stream ' + format(size, 'g'):>16} skipped: too little space in {BENCH_DIR}")
        return None
    path = path_of(size).replace(".npz", ".h5")
    try:
        run("write_h5", size)
        return run("stream", size)
    finally:
        if os.path.exists(path):
            os.remove(path)


def command_case(size: float, idle: float) -> None:
    """The whole ``rotacal rate`` command on a capture file of ``size`` timestamps (made first,
    deleted after, also on failure)."""
    os.makedirs(BENCH_DIR, exist_ok=True)
    need = size * 8 * 1.1
    if shutil.disk_usage(BENCH_DIR).free < 4 * need:
        print(f"{'command ' + format(size, 'g'):>16} skipped: too little space in {BENCH_DIR}")
        return
    path = path_of(size)
    try:
        run("write", size)
        loads = [run("load", size) for _ in range(3)]
        base = min(x["seconds"] for x in loads)
        base_cpu = min(x["cpu_s"] for x in loads)
        argv = ["-m", "rotacal", "rate", path, "--pulses-per-rev", str(PULSES_PER_REV)]
        argv += ["--average", str(AVERAGE), "--json", path + ".json", "--overwrite"]
        r = run("command", size, argv)
        per_ts = (r["peak_rss_mb"] - idle) * 2**20 / size
        print(
            f"{'command ' + format(size, 'g'):>16} {size:>12.3g} {r['seconds']:>9.2f} "
            f"{r['cpu_s']:>7.2f} {size / r['seconds']:>10.3g} {r['peak_rss_mb']:>8.0f} "
            f"{per_ts:>6.0f} {r['seconds'] / base:>11.1f} {r['cpu_s'] / base_cpu:>8.1f}"
        )
    finally:
        for leftover in (path, path + ".json"):
            if os.path.exists(leftover):
                os.remove(leftover)


if __name__ == "__main__":
    main()
