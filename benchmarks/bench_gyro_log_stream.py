"""`rotacal gyro scale-factor` on a continuous log (time_s, rate_deg_s, output): seconds and peak
memory of the whole command at 10⁷, 10⁸ and 10⁹ rows, as a ratio to reading the file.

For each N an uncompressed NPZ log is written to ``--dir`` piece by piece (three float64 columns:
24·N bytes, 24 GB at 10⁹): 1 kHz, eleven set rates from 0 to ±100 °/s held for N/11 rows each
with 50 °/s² ramps between, the table rate measured with 0.02 °/s noise, the output
2.5 V + 0.0125 V/(°/s)·Ω + 4·10⁻⁸·Ω³ + 0.6 mV noise. Then, each in a fresh process whose peak
RSS (``os.wait4``'s ``ru_maxrss``) is that case's alone:

- **baseline**: read the three columns in chunks of 2·10⁶ rows
  (``rotacal.io.iter_capture_chunks``, pages handed back as the command does) and sum them;
- **command**: ``python -m rotacal gyro scale-factor LOG --json OUT`` as a user runs it (it
  streams by itself above 10⁶ rows); at 10⁷ rows ``--in-memory`` too, and the two JSONs are
  compared (largest relative difference of every number; must be ≤ 1e-9).

It prints seconds, M rows/s, peak RSS (MB) and the ratio command/baseline of the same N, best of
``--repeat`` interleaved runs (one at 10⁹). The log is deleted after its cases (also on failure).

    python benchmarks/bench_gyro_log_stream.py                      # 1e7, 1e8, 1e9 (24 GB)
    python benchmarks/bench_gyro_log_stream.py --rows 1e7 1e8       # quicker
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_gyro_stream import measure_logs

PIECE = 4_000_000
FS_HZ = 1000.0
RATES = np.array([0.0, 20, -20, 40, -40, 60, -60, 80, -80, 100, -100])
ACCEL = 50.0


def _knots(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Corners (time, rate) of the table's profile: each rate held N/11 rows, ramps between."""
    hold = n / RATES.size / FS_HZ
    ramp = np.r_[0.0, np.abs(np.diff(RATES)) / ACCEL]
    starts = np.cumsum(ramp + np.r_[0.0, np.full(RATES.size - 1, hold - 0.0)])
    starts -= np.cumsum(np.r_[0.0, ramp[1:]])  # ramps eat into the holds: N rows in all
    return np.column_stack([starts + np.r_[0.0, ramp[1:]], starts + hold]).reshape(-1), np.repeat(
        RATES, 2
    )


def write_log(path: Path, n: int) -> None:
    kt, kr = _knots(n)
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name in ("time_s", "rate_deg_s", "output"):
            with zf.open(name + ".npy", "w", force_zip64=True) as fp:
                np.lib.format.write_array_header_1_0(
                    fp, {"descr": "<f8", "fortran_order": False, "shape": (n,)}
                )
                for lo in range(0, n, PIECE):
                    t = np.arange(lo, min(n, lo + PIECE)) / FS_HZ
                    if name == "time_s":
                        fp.write(t.tobytes())
                        continue
                    omega = np.interp(t, kt, kr)
                    rng = np.random.default_rng([17, lo])
                    if name == "rate_deg_s":
                        fp.write((omega + rng.normal(0.0, 0.02, t.size)).tobytes())
                        continue
                    rng = np.random.default_rng([18, lo])
                    y = 2.5 + 0.0125 * omega + 4e-8 * omega**3 + rng.normal(0.0, 6e-4, t.size)
                    fp.write(y.tobytes())


def child(mode: str, path: str) -> None:
    """One case; prints its wall and CPU time as JSON (the parent reads the peak RSS)."""
    t0, c0 = time.perf_counter(), time.process_time()
    if mode == "baseline":
        from rotacal.io import iter_capture_chunks

        total = 0.0
        names = ["time_s", "rate_deg_s", "output"]
        for chunk in iter_capture_chunks(path, names, chunk_rows=2_000_000):
            total += sum(float(chunk[k].sum()) for k in names)
        extra: dict = {"sum": total}
    else:
        out = path + f".{mode}.json"
        args = [sys.executable, "-m", "rotacal", "gyro", "scale-factor", path, "--json", out]
        args += ["--overwrite"] + (["--in-memory"] if mode == "in-memory" else [])
        subprocess.run(args, check=True, capture_output=True, text=True)
        extra = {"json": json.loads(Path(out).read_text())}
        os.unlink(out)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0 + sum(os.times()[2:4])  # with the CLI child's CPU
    print(json.dumps({"wall_s": wall, "cpu_s": cpu, **extra}))


def _largest_difference(a, b, key: str = "") -> float:
    """Largest relative difference between the numbers of two JSON trees (inf: shapes differ;
    the provenance, which names the path taken, left out). A value in ppm is a difference of
    two nearly equal numbers (the asymmetry of S): its difference is taken relative to 10⁶ ppm."""
    if isinstance(a, dict):
        if a.keys() != b.keys():
            return float("inf")
        keys = [k for k in a if k != "provenance"]
        return max((_largest_difference(a[k], b[k], k) for k in keys), default=0.0)
    if isinstance(a, list):
        if len(a) != len(b):
            return float("inf")
        pairs = zip(a, b, strict=True)
        return max((_largest_difference(x, y, key) for x, y in pairs), default=0.0)
    if isinstance(a, float) and isinstance(b, float):
        scale = max(abs(a), abs(b), 1e6 if key.endswith("_ppm") else 0.0)
        return 0.0 if a == b else abs(a - b) / scale
    return 0.0 if a == b else float("inf")


def _show(n: int, rows: dict) -> None:
    base = rows["baseline"]
    for m, r in rows.items():
        label = {"command": "command (auto)", "in-memory": "command --in-memory"}
        print(
            f"  {label.get(m, m):<20} {r['wall_s']:7.1f} s wall {r['cpu_s']:7.1f} s CPU"
            f"  {n / r['wall_s'] / 1e6:6.1f} M rows/s  peak RSS "
            f"{r['peak_rss_mb']:6.0f} MB  ratio to baseline wall "
            f"{r['wall_s'] / base['wall_s']:5.2f} CPU {r['cpu_s'] / base['cpu_s']:5.2f}",
            flush=True,
        )
    if "in-memory" in rows:
        d = _largest_difference(rows["command"]["json"], rows["in-memory"]["json"])
        print(f"  streamed vs in-memory: largest relative difference {d:.2e}")
    sf = rows["command"]["json"]
    print(
        f"  S = {sf['scale_factor']:.9g} V/(°/s), plateaus used "
        f"{len(sf['plateaus'])}, settle {sf['settle_s']} s"
    )


def main() -> None:
    measure_logs(
        __doc__ or "", child, write_log, 24, 1e7, _show, __file__, repeat=2, timeout=7200.0
    )


if __name__ == "__main__":
    main()
