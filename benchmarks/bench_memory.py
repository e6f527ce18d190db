"""Peak memory of the chunked encoder calibration: flat in the capture length.

Writes an uncompressed NPZ encoder capture of N samples (time_s, a, b as float64: 24·N bytes on
disk) piece by piece, so that writing stays flat too, then runs in child processes:

- ``calibrate_encoder_motion_chunked(encoder_chunks_from_file(...))`` on N and on N/10 samples,
- ``calibrate_encoder_motion`` (in memory, on the memory-mapped columns) on N/10 samples,

and prints each child's peak RSS (``getrusage(RUSAGE_CHILDREN).ru_maxrss`` of a child that runs
exactly one case), the wall time and the throughput, and the ratio of the chunked peaks for N and
N/10 (flat memory ⇒ ≈ 1). The files are written to ``--dir`` (default /tmp) and removed after.

    python benchmarks/bench_memory.py                 # N = 1e8 (2.4 GB + 0.24 GB on disk)
    python benchmarks/bench_memory.py --samples 2e7   # quicker
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bench_motion_stream import LINES
from bench_motion_stream import write_npz as _write_npz


def write_npz(path: Path, n: int) -> None:
    """An uncompressed NPZ encoder capture (1 MHz, 2 Hz motion), written piece by piece."""
    _write_npz(path, "encoder", n)


def child(mode: str, path: str) -> None:
    """Run one case and print its result as JSON (peak RSS is read by the parent)."""
    from rotacal.io import read_capture
    from rotacal.table import (
        calibrate_encoder_motion,
        calibrate_encoder_motion_chunked,
        encoder_chunks_from_file,
    )

    t0 = time.perf_counter()
    if mode == "chunked":
        r = calibrate_encoder_motion_chunked(encoder_chunks_from_file(path), lines=LINES)
    elif mode == "memory":
        cap = read_capture(path, columns=["time_s", "a", "b"])
        c = cap.columns
        r = calibrate_encoder_motion(c["time_s"], c["a"], c["b"], lines=LINES)
    else:  # "idle": interpreter + imports only
        r = None
    wall = time.perf_counter() - t0
    out = {"wall_s": wall}
    if r is not None:
        out.update(thd_percent=r.thd_percent, amplitude_deg=r.amplitude_deg, periods=r.periods_used)
    print(json.dumps(out))


def run_child(mode: str, path: Path) -> dict:
    """Run a case in a fresh process that itself runs it in one grandchild, so that
    RUSAGE_CHILDREN.ru_maxrss belongs to that case alone."""
    code = (
        "import json, resource, subprocess, sys\n"
        f"p = subprocess.run([sys.executable, {__file__!r}, '--child', {mode!r}, {str(path)!r}],"
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
    ap.add_argument("--samples", type=float, default=1e8, help="N (default 1e8)")
    ap.add_argument("--dir", default="/tmp", help="where the captures are written")
    ap.add_argument("--child", nargs=2, metavar=("MODE", "PATH"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(*args.child)
        return
    n = int(args.samples)
    need = 24 * (n + n // 10) * 1.05
    free = shutil.disk_usage(args.dir).free
    if free < need:
        sys.exit(f"{args.dir} has {free / 1e9:.1f} GB free, {need / 1e9:.1f} GB needed")
    work = Path(tempfile.mkdtemp(prefix="rotacal-bench-mem-", dir=args.dir))
    try:
        paths = {}
        for size in (n // 10, n):
            p = work / f"enc_{size}.npz"
            t0 = time.perf_counter()
            write_npz(p, size)
            print(
                f"wrote {p.name}: {size:.3g} samples, {p.stat().st_size / 1e9:.2f} GB "
                f"in {time.perf_counter() - t0:.1f} s"
            )
            paths[size] = p
        rows = [
            ("idle (python + imports)", "idle", n // 10),
            ("in-memory, N/10", "memory", n // 10),
            ("chunked, N/10", "chunked", n // 10),
            ("chunked, N", "chunked", n),
        ]
        results = {}
        print(
            f"\n{'case':26s} {'samples':>10s} {'peak RSS MB':>12s} {'time s':>8s} {'Msa/s':>7s}"
            f" {'THD %':>10s}"
        )
        for label, mode, size in rows:
            out = run_child(mode, paths[size])
            results[label] = out
            rate = size / out["wall_s"] / 1e6 if mode != "idle" else float("nan")
            thd = out.get("thd_percent", float("nan"))
            print(
                f"{label:26s} {size:10.3g} {out['peak_rss_mb']:12.0f} {out['wall_s']:8.2f} "
                f"{rate:7.1f} {thd:10.6f}"
            )
        small, big = results["chunked, N/10"], results["chunked, N"]
        print(
            f"\npeak RSS ratio chunked N / chunked N/10: {big['peak_rss_mb'] / small['peak_rss_mb']:.3f}"
        )
        mem = results["in-memory, N/10"]
        print(
            f"peak RSS ratio in-memory N/10 / chunked N/10: "
            f"{mem['peak_rss_mb'] / small['peak_rss_mb']:.2f}"
        )
        print(
            f"THD chunked − in-memory at N/10: {small['thd_percent'] - mem['thd_percent']:.3g} pp"
        )
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
