"""`rotacal gyro scale-factor` on long logs: seconds and peak memory of the whole command.

For each N (default 1e7, 1e8, 1e9 rows) an uncompressed NPZ log is written to ``--dir`` piece by
piece (columns rate_deg_s and output as float64: 16·N bytes; 16 GB at 10⁹ — the analysis reads
no time column, so none is written), 11 set rates from −100 to +100 °/s held in turn, output
2.5 V + 0.0125 V/(°/s)·Ω + a cubic nonlinearity + 0.6 mV noise. Then, each in a fresh process
whose peak RSS (``os.wait4``'s ``ru_maxrss``) belongs to that case alone:

- **baseline**: read the two columns in chunks of 2·10⁶ rows (``rotacal.io.iter_capture_chunks``,
  the pages handed back as the command does) and sum them — the time it takes to read the file;
- **command**: ``python -m rotacal gyro scale-factor LOG --json OUT`` as a user runs it (it
  streams by itself above 10⁶ rows); up to 3·10⁷ rows ``--in-memory`` is run too, for comparison.

It prints seconds, M rows/s, peak RSS (MB) and the ratio command/baseline of the same N, measured
back to back, the best of ``--repeat`` interleaved runs (one at 10⁹). The log is deleted after its
cases (also on failure).

    python benchmarks/bench_gyro_stream.py                       # 1e7, 1e8, 1e9 (16 GB on disk)
    python benchmarks/bench_gyro_stream.py --rows 1e7 1e8        # quicker
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
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

PIECE = 4_000_000
RATES = np.arange(-100.0, 101.0, 20.0)


def write_log(path: Path, n: int) -> None:
    """The log: each set rate held for n/11 rows in turn, written in pieces of PIECE rows."""
    per = -(-n // RATES.size)
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name in ("rate_deg_s", "output"):
            with zf.open(name + ".npy", "w", force_zip64=True) as fp:
                np.lib.format.write_array_header_1_0(
                    fp, {"descr": "<f8", "fortran_order": False, "shape": (n,)}
                )
                for lo in range(0, n, PIECE):
                    rate = RATES[np.arange(lo, min(n, lo + PIECE)) // per]
                    if name == "rate_deg_s":
                        fp.write(rate.tobytes())
                        continue
                    noise = np.random.default_rng([11, lo]).normal(0.0, 6e-4, rate.size)
                    fp.write((2.5 + 0.0125 * rate + 4e-8 * rate**3 + noise).tobytes())


def child(mode: str, path: str) -> None:
    """One case; prints its wall time as JSON (the parent reads the peak RSS)."""
    t0 = time.perf_counter()
    if mode == "baseline":
        from rotacal.io import iter_capture_chunks

        total = 0.0
        for chunk in iter_capture_chunks(path, ["rate_deg_s", "output"], chunk_rows=2_000_000):
            total += float(chunk["rate_deg_s"].sum()) + float(chunk["output"].sum())
        extra = {"sum": total}
    else:
        out = path + f".{mode}.json"
        args = [sys.executable, "-m", "rotacal", "gyro", "scale-factor", path, "--json", out]
        args += ["--overwrite"] + (["--in-memory"] if mode == "in-memory" else [])
        subprocess.run(args, check=True, capture_output=True, text=True)
        d = json.loads(Path(out).read_text())
        os.unlink(out)
        extra = {"scale_factor": d["scale_factor"], "nl": d["nonlinearity_percent_fs"]}
    print(json.dumps({"wall_s": time.perf_counter() - t0, **extra}))


def run_child(mode: str, path: Path, timeout: float, script: str = __file__) -> dict:
    """The case in a fresh process (``script --child MODE PATH``), reaped with ``os.wait4``: its
    peak RSS is that process's and its waited-for descendants' largest (Linux), i.e. for the
    command the CLI process's."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(
            [sys.executable, script, "--child", mode, str(path)], stdout=out, stderr=err
        )
        end = time.monotonic() + timeout
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.monotonic() > end:
                proc.kill()
                os.wait4(proc.pid, 0)
                raise TimeoutError(f"{mode} ran over {timeout:g} s")
            time.sleep(0.05)
        proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
        out.seek(0)
        err.seek(0)
        if proc.returncode:
            raise RuntimeError(f"{mode} failed: {err.read().strip()[-2000:]}")
        result = json.loads(out.read().strip().splitlines()[-1])
    result["peak_rss_mb"] = usage.ru_maxrss / 1024
    return result


def measure_logs(
    doc: str,
    child_case: Callable[[str, str], None],
    write: Callable[[Path, int], None],
    bytes_per_row: int,
    in_memory_max: float,
    show: Callable[[int, dict], None],
    script: str,
    repeat: int = 3,
    timeout: float = 3600.0,
) -> None:
    """The command line of a log benchmark: for each ``--rows`` N, the log written by ``write``
    (skipped when the disk has no room for ``bytes_per_row``·N), the cases baseline, command and
    (N ≤ ``in_memory_max``) in-memory run interleaved in fresh processes of ``script``, the best
    of ``--repeat`` (one at 10⁹) handed to ``show``; the log deleted after its cases."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--rows", type=float, nargs="+", default=[1e7, 1e8, 1e9])
    ap.add_argument("--dir", default="/tmp", help="where the logs are written")
    ap.add_argument("--timeout", type=float, default=timeout, help="per case (s)")
    ap.add_argument(
        "--repeat", type=int, default=repeat, help="runs per case below 1e9 rows (best)"
    )
    ap.add_argument("--child", nargs=2, metavar=("MODE", "PATH"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child_case(*args.child)
        return
    work = Path(tempfile.mkdtemp(prefix="bench-gyrolog-", dir=args.dir))
    try:
        for n in (int(x) for x in args.rows):
            need = bytes_per_row * n * 1.02
            free = shutil.disk_usage(args.dir).free
            if free < need:
                print(f"N = {n:.0e}: skipped, {free / 1e9:.1f} GB free, {need / 1e9:.1f} GB needed")
                continue
            path = work / f"log_{n}.npz"
            try:
                t0 = time.perf_counter()
                write(path, n)
                print(
                    f"N = {n:.0e}: wrote {path.stat().st_size / 1e9:.2f} GB in "
                    f"{time.perf_counter() - t0:.0f} s",
                    flush=True,
                )
                modes = ["baseline", "command"] + (["in-memory"] if n <= in_memory_max else [])
                rows: dict = {}
                for _ in range(args.repeat if n < 1e9 else 1):
                    for m in modes:  # interleaved, so that a busy spell hits every case
                        r = run_child(m, path, args.timeout, script=script)
                        if m not in rows or r["wall_s"] < rows[m]["wall_s"]:
                            rows[m] = r
                show(n, rows)
            finally:
                path.unlink(missing_ok=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _show(n: int, rows: dict) -> None:
    base = rows["baseline"]["wall_s"]
    for m, r in rows.items():
        label = {"command": "command (auto)", "in-memory": "command --in-memory"}.get(m, m)
        print(
            f"  {label:<18} {r['wall_s']:8.1f} s  {n / r['wall_s'] / 1e6:7.1f} M rows/s"
            f"  peak RSS {r['peak_rss_mb']:7.0f} MB  ratio to baseline "
            f"{r['wall_s'] / base:5.2f}",
            flush=True,
        )
        if "scale_factor" in r:
            print(f"  {'':<18} S = {r['scale_factor']:.9g} V/(°/s), NL = {r['nl']:.4g} %FS")


def main() -> None:
    measure_logs(__doc__ or "", child, write_log, 16, 3e7, _show, __file__)


if __name__ == "__main__":
    main()
