"""Time and peak memory of ``inspect_capture`` against reading the same file once.

Writes a capture of N rows (time_s with jitter and one gap, two quantised channels a and b) as an
uncompressed NPZ (memory-mapped by the reader), a compressed NPZ and a CSV, and runs in child
processes, one case each:

- ``read``: ``read_capture`` of every column and one sum over each (every byte touched once) —
  the baseline;
- ``inspect``: ``inspect_capture`` (streams in chunks of ``CHUNK_ROWS`` rows).

It prints each child's wall time and peak RSS (its own VmHWM), the ratios inspect/read, and the
ratio of inspect's peak at N and at N/10 (flat memory ⇒ ≈ 1; meaningful when N/10 exceeds
``rotacal.inspect.files.CHUNK_ROWS``, 262 144 rows, so both sizes stream). Pages of a memory-mapped
file count into RSS while they are mapped; they are page cache, not allocated memory. The files go to ``--dir`` (default: a temporary folder) and are removed after.

    python benchmarks/bench_inspect.py                  # N = 1e7 (NPZ), 2e6 (CSV)
    python benchmarks/bench_inspect.py --rows 1e6 --csv-rows 2e5   # quicker
"""

from __future__ import annotations

import argparse
import json
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def columns(n: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(5)
    dt = 1e-3 * (1 + rng.normal(0.0, 1e-3, n))
    dt[n // 2] = 0.5  # one gap
    t = np.cumsum(dt)
    lsb = 2.5 / 2**16
    a = np.round(np.cos(2 * np.pi * 3 * t) / lsb) * lsb
    b = np.round(np.sin(2 * np.pi * 3 * t) / lsb) * lsb
    return {"time_s": t, "a": a, "b": b}


def write(path: Path, n: int) -> None:
    from rotacal.io import write_capture

    cols = columns(n)
    if path.suffix == ".npz" and "compressed" in path.name:
        np.savez_compressed(path, **cols)
    else:
        write_capture(path, cols)


def _peak_rss_mb() -> float:
    """This process's peak resident memory (VmHWM: the high-water mark of its own address
    space; ru_maxrss would carry the parent's size over fork and exec)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def child(mode: str, path: str) -> None:
    from rotacal.inspect import inspect_capture
    from rotacal.io import read_capture

    start = time.perf_counter()
    if mode == "read":
        cap = read_capture(path)
        total = sum(float(np.sum(c)) for c in cap.columns.values())
        rows = len(cap)
    else:
        result = inspect_capture(path)
        total = float(result.gap_count)
        rows = result.rows
    seconds = time.perf_counter() - start
    peak_mb = _peak_rss_mb()
    print(json.dumps({"seconds": seconds, "peak_mb": peak_mb, "rows": rows, "check": total}))


def run(mode: str, path: Path) -> tuple[float, float]:
    """One case in a fresh process: (wall time in s, that process's peak RSS in MB)."""
    out = subprocess.run(
        [sys.executable, __file__, "--child", mode, str(path)],
        check=True,
        capture_output=True,
        text=True,
    )
    found = json.loads(out.stdout)
    return found["seconds"], found["peak_mb"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--rows", type=float, default=1e7)
    parser.add_argument("--csv-rows", type=float, default=2e6)
    parser.add_argument("--dir", default=None)
    parser.add_argument("--child", nargs=2, metavar=("MODE", "PATH"))
    args = parser.parse_args()
    if args.child:
        child(*args.child)
        return
    folder = Path(tempfile.mkdtemp(dir=args.dir))
    try:
        print(
            f"{'file':<24}{'rows':>11}{'read s':>9}{'inspect s':>11}{'ratio':>7}"
            f"{'read MB':>9}{'inspect MB':>12}"
        )
        for name, n in (
            ("plain.npz", int(args.rows)),
            ("compressed.npz", int(args.rows)),
            ("capture.csv", int(args.csv_rows)),
        ):
            peaks = []
            for rows in (n // 10, n):
                path = folder / f"{rows}_{name}"
                write(path, rows)
                read_s, read_mb = run("read", path)
                look_s, look_mb = run("inspect", path)
                peaks.append(look_mb)
                print(
                    f"{path.name:<24}{rows:>11}{read_s:>9.2f}{look_s:>11.2f}"
                    f"{look_s / read_s:>7.2f}{read_mb:>9.0f}{look_mb:>12.0f}"
                )
                path.unlink()
            print(f"  inspect peak at N / at N/10: {peaks[1] / peaks[0]:.2f}")
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
