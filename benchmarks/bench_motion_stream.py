"""The whole `rotacal motion encoder|lts|fog` command on long captures: seconds and peak RSS.

For each scheme and each size N, a twin capture is written to an uncompressed NPZ piece by piece
(memory flat while writing; float64 columns: 24·N bytes for the encoder, 16·N for LTS and FOG),
then, each in a fresh process whose ``RUSAGE_CHILDREN`` peak is its own:

- baseline: the file read in chunks doing nothing (``rotacal.io.iter_capture_chunks`` over the
  same columns, 2·10⁶ rows a chunk — the least any streaming analysis must do);
- ``python -m rotacal motion SCHEME FILE ... --chunked --json OUT`` (the streaming path at every
  N, as the command chooses by itself above 3·10⁷ samples: checks, reversals, fit, budgets, JSON).

Prints wall seconds, M samples/s, peak RSS and the ratios command/baseline — of wall time and of
CPU time (user + system of the child: steadier than wall time on a shared machine) —, and the
peak's ratio to that of the smallest N (flat memory ⇒ ≈ 1). Files go to ``--dir`` (default /tmp/bench-motionstream)
and are deleted after each case, also on failure. Check ``df -h /tmp`` first: 10⁹ encoder
samples are 24 GB.

    python benchmarks/bench_motion_stream.py --sizes 1e7,1e8 --schemes encoder,lts,fog
    timeout 3600 python benchmarks/bench_motion_stream.py --sizes 1e9 --schemes lts
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import time
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

PIECE = 2_000_000
LINES = 36000
RADIUS_MM = 100.0
HARMONICS = {2: (0.010, 0.4), 3: (0.008, 1.1), 5: (0.002, 2.0)}
# (sampling rate Hz, motion frequency Hz, amplitude deg): the encoder as bench_memory.py; LTS and
# FOG a 10 kHz DAQ on a slow motion (a 10⁹-sample capture is 28 h of it)
SETTINGS = {
    "encoder": (1_000_000.0, 2.0, 0.5),
    "lts": (10_000.0, 0.5, 0.5),
    "fog": (10_000.0, 0.5, 0.5),
}
COLUMNS = {
    "encoder": ("time_s", "a", "b"),
    "lts": ("time_s", "displacement_mm"),
    "fog": ("time_s", "rate_deg_s"),
}


def _motion(scheme: str):
    from rotacal import sim

    _, f, amp = SETTINGS[scheme]
    return sim.SineMotion(amplitude_deg=amp, frequency_hz=f, harmonics=HARMONICS)


def _column(scheme: str, name: str, lo: int, hi: int, motion) -> np.ndarray:
    """Rows lo..hi-1 of one column of the twin capture (noise seeded by the rows)."""
    fs = SETTINGS[scheme][0]
    t = np.arange(lo, hi, dtype=np.float64) / fs
    if name == "time_s":
        return t
    rng = np.random.default_rng([7, lo, COLUMNS[scheme].index(name)])
    if scheme == "lts":
        d = RADIUS_MM * np.tan(np.radians(motion.angle_deg(t)))
        return d + rng.normal(0.0, 3e-5, d.size)
    if scheme == "fog":
        w = motion.rate_deg_s(t) + 0.02
        return w + rng.normal(0.0, 0.01, w.size)
    phi = (2.0 * math.pi * LINES / 360.0) * motion.angle_deg(t)
    if name == "a":
        x = 0.03 + np.cos(phi)
    else:
        x = -0.02 + 0.97 * np.sin(phi + math.radians(1.5))
    x += rng.normal(0.0, 0.004, x.size)
    lsb = 2.5 / 2**16  # 16-bit ADC over ±1.25
    return -1.25 + (np.clip(np.floor((x + 1.25) / lsb), 0, 2**16 - 1) + 0.5) * lsb


def write_npz(path: Path, scheme: str, n: int) -> None:
    """An uncompressed NPZ (memory-mappable), each member written in pieces of PIECE rows."""
    motion = _motion(scheme)
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name in COLUMNS[scheme]:
            with zf.open(name + ".npy", "w", force_zip64=True) as fp:
                header = {"descr": "<f8", "fortran_order": False, "shape": (n,)}
                np.lib.format.write_array_header_1_0(fp, header)
                for lo in range(0, n, PIECE):
                    fp.write(_column(scheme, name, lo, min(n, lo + PIECE), motion).tobytes())


def baseline(path: str, scheme: str) -> None:
    """Read the capture in chunks and do nothing (the child of the baseline case)."""
    from rotacal.io import iter_capture_chunks

    total = 0.0
    # the reader hands each chunk's pages back itself once the next is asked for
    for chunk in iter_capture_chunks(path, COLUMNS[scheme], chunk_rows=PIECE):
        total += float(chunk[COLUMNS[scheme][1]][-1])  # touch every chunk
    print(total)


def measured(cmd: list[str], env: dict[str, str]) -> tuple[float, float, float]:
    """Wall time (s), CPU time (s) and peak RSS (MB) of ``cmd`` run in a fresh wrapper process."""
    wrapper = [
        sys.executable,
        "-c",
        "import resource, subprocess, sys, time\n"
        "t0 = time.perf_counter()\n"
        "p = subprocess.run(sys.argv[1:], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, "
        "text=True)\n"
        "if p.returncode: sys.exit(p.stderr[-2000:])\n"
        "ru = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
        "print(time.perf_counter() - t0, ru.ru_utime + ru.ru_stime, ru.ru_maxrss / 1024)",
        *cmd,
    ]
    out = subprocess.run(wrapper, capture_output=True, text=True, env=env)
    if out.returncode:
        raise RuntimeError(out.stderr)
    wall, cpu, rss = out.stdout.split()
    return float(wall), float(cpu), float(rss)


def command(scheme: str, path: Path, out: Path) -> list[str]:
    extra = {"encoder": ["--lines", str(LINES)], "lts": ["--radius-mm", str(RADIUS_MM)], "fog": []}
    return [
        sys.executable,
        "-m",
        "rotacal",
        "motion",
        scheme,
        str(path),
        *extra[scheme],
        "--chunked",
        "--json",
        str(out),
        "--overwrite",
    ]


def run_case(scheme: str, n: int, work: Path, env: dict[str, str]) -> dict:
    path = work / f"{scheme}_{n}.npz"
    out = work / f"{scheme}_{n}.json"
    try:
        t0 = time.perf_counter()
        write_npz(path, scheme, n)
        wrote = time.perf_counter() - t0
        base = measured([sys.executable, __file__, "--baseline", scheme, str(path)], env)
        cmd = measured(command(scheme, path, out), env)
        result = json.loads(out.read_text())
    finally:
        path.unlink(missing_ok=True)
        out.unlink(missing_ok=True)
    return {
        "n": n,
        "write_s": wrote,
        "base": base,
        "cmd": cmd,
        "thd": result["thd_percent"],
        "amp": result["amplitude_deg"],
        "periods": result["periods_used"],
    }


def main(argv: list[str] | None = None, report: Callable[[str], None] = print) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1e7,1e8", help="N, comma-separated (default 1e7,1e8)")
    ap.add_argument("--schemes", default="encoder,lts,fog")
    ap.add_argument("--dir", default="/tmp/bench-motionstream")
    ap.add_argument("--baseline", nargs=2, metavar=("SCHEME", "PATH"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.baseline:
        baseline(args.baseline[1], args.baseline[0])
        return
    work = Path(args.dir)
    work.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    sizes = [int(float(s)) for s in args.sizes.split(",")]
    report(
        f"{'scheme':8s} {'N':>8s} {'base s':>8s} {'cmd s':>8s} {'ratio':>6s} {'Msa/s':>6s} "
        f"{'CPU rat':>7s} {'base MB':>8s} {'cmd MB':>7s} {'MB/first':>8s} {'periods':>8s} "
        f"{'THD %':>9s}"
    )
    try:
        for scheme in args.schemes.split(","):
            first_rss = None
            for n in sizes:
                need = 8 * len(COLUMNS[scheme]) * n * 1.02
                free = shutil.disk_usage(work).free
                if free < need:
                    report(
                        f"{scheme:8s} {n:8.0e} skipped: {free / 1e9:.1f} GB free, {need / 1e9:.1f} needed"
                    )
                    continue
                r = run_case(scheme, n, work, env)
                (b_s, b_cpu, b_mb), (c_s, c_cpu, c_mb) = r["base"], r["cmd"]
                first_rss = first_rss or c_mb
                report(
                    f"{scheme:8s} {n:8.0e} {b_s:8.2f} {c_s:8.2f} {c_s / b_s:6.2f} {n / c_s / 1e6:6.2f} "
                    f"{c_cpu / b_cpu:7.2f} {b_mb:8.0f} {c_mb:7.0f} {c_mb / first_rss:8.2f} "
                    f"{r['periods']:8d} {r['thd']:9.5f}"
                )
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
