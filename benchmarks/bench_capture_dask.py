"""One huge capture's analysis split over Dask workers, against one process.

``--analysis`` chooses the record, written once (NPZ without compression unless said):

- ``allan`` (the default): ``rotacal allan --taus octave`` of a rate record (time_s, rate_deg_s:
  white noise and a random walk at 100 Hz);
- ``rate``: ``rotacal rate --pulses-per-rev 18000`` of one head of pulse times (HDF5:
  bench_rate.py's twin, 18,000 pulses per revolution at 300 °/s);
- ``encoder``: ``rotacal motion encoder --lines 36000`` of the twin encoder capture of
  ``bench_motion_stream.py`` (time_s, a, b at 1 MHz, a 2 Hz motion);
- ``lts``: ``rotacal motion lts --radius-mm 100`` of the twin LTS capture of
  ``bench_motion_stream.py`` (time_s, displacement_mm at 10 kHz, a 0.5 Hz motion);
- ``scale-factor``: ``rotacal gyro scale-factor`` of a rate-table log (rate_deg_s, output)
  stepping through 11 set rates up and down;
- ``selfcal``: ``rotacal selfcal --pulses-per-rev 18000`` of ``bench_selfcal_stream.py``'s twin
  (12 ragged heads; ``--samples`` pulse times in all, rounded to whole revolutions).
- ``fog``: ``rotacal motion fog`` of the twin FOG capture of ``bench_motion_stream.py``
  (time_s, rate_deg_s at 10 kHz).

On the file it times:

- **one process**: the command with ``--chunked`` in a fresh process (the baseline);
- **N workers**: the command with ``--workers N`` for each N of ``--workers`` (a fresh process
  that starts its local cluster: the start is included);

and checks that every number of the JSON agrees with the baseline's. Prints the best wall
seconds of ``--repeat`` runs, the ratio to the baseline, the CPU seconds of the command and the workers it waited for (on a shared
machine the steadier figure) and the peak RSS of the largest process (the command's, or a Dask
worker's: the kernel counts waited-for descendants too). No asserts.

Run: ``python benchmarks/bench_capture_dask.py [--analysis NAME] [--samples 1e8] [--workers 1,2]
[--repeat 1]`` (NAME: allan, rate, encoder, lts, fog, scale-factor, selfcal)
"""

from __future__ import annotations

import argparse
import inspect
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

#: The set rates of the scale-factor log (°/s), visited up then down.
RATES = np.array([-300.0, -100.0, -30.0, -10.0, -1.0, 0.0, 1.0, 10.0, 30.0, 100.0, 300.0])


def _write_columns(path: Path, n: int, fill: Any) -> None:
    """An NPZ (without compression) of float64 columns of ``n`` rows, named by the parameters of
    ``fill(lo, hi, *columns)`` after lo and hi, which fills rows lo … hi − 1 of each column, a
    10⁷-row piece at a time (memory maps: the file may exceed memory)."""
    names = list(inspect.signature(fill).parameters)[2:]
    parts = {c: path.with_suffix(f".{c}.npy") for c in names}
    maps = {c: np.lib.format.open_memmap(p, "w+", np.float64, (n,)) for c, p in parts.items()}
    for lo in range(0, n, 10_000_000):
        fill(lo, min(n, lo + 10_000_000), *maps.values())
    for m in maps.values():
        m.flush()
    np.savez(path, **maps)
    del maps
    for p in parts.values():
        p.unlink()


def write_log(path: Path, n: int) -> None:
    """A rate-table log of ``n`` rows: plateaus of equal length through RATES up and down, the
    output 0.01 V/(°/s) with a bias, a slight nonlinearity and white noise."""
    rng = np.random.default_rng(7)
    plan = np.r_[RATES, RATES[::-1]]

    def fill(lo: int, hi: int, rate_deg_s: np.ndarray, output: np.ndarray) -> None:
        r = plan[np.arange(lo, hi) * plan.size // n]
        rate_deg_s[lo:hi] = r
        output[lo:hi] = 0.01 * r + 0.02 + 2e-8 * r**2 + 1e-3 * rng.standard_normal(hi - lo)

    _write_columns(path, n, fill)


def write_record(path: Path, n: int) -> None:
    """White rate noise plus a random walk, at 100 Hz."""
    rng = np.random.default_rng(7)
    walk = 0.0

    def fill(lo: int, hi: int, time_s: np.ndarray, rate_deg_s: np.ndarray) -> None:
        nonlocal walk
        steps = np.cumsum(1e-5 * rng.standard_normal(hi - lo)) + walk
        rate_deg_s[lo:hi] = 3.0 + 0.01 * rng.standard_normal(hi - lo) + steps
        walk = float(steps[-1])
        time_s[lo:hi] = np.arange(lo, hi) / 100.0

    _write_columns(path, n, fill)


def motion_writer(scheme: str) -> Callable[[Path, int], None]:
    """The writer of ``bench_motion_stream.py``'s twin capture of a motion ``scheme`` (encoder:
    time_s, a, b at 1 MHz, a 2 Hz motion; lts: displacement_mm at 10 kHz, 0.5 Hz; fog:
    rate_deg_s at 10 kHz)."""

    def write(path: Path, n: int) -> None:
        from bench_motion_stream import write_npz

        write_npz(path, scheme, n)

    return write


def write_pulses(path: Path, n: int) -> None:
    """One head of ``n`` pulse times: ``bench_rate.py``'s twin (HDF5)."""
    from bench_rate import write_h5

    write_h5(str(path), n)


def write_heads(path: Path, n: int) -> None:
    """12 heads of about ``n`` pulse times in all: ``bench_selfcal_stream.py``'s twin."""
    from bench_selfcal_stream import HEADS, M, write_capture

    write_capture(path, max(2, n // (HEADS * M)))


#: analysis → (writer of its record, the record's file name, the command and its options)
ANALYSES = {
    "allan": (write_record, "rate.npz", ["allan", "--taus", "octave"]),
    "rate": (write_pulses, "pulses.h5", ["rate", "--pulses-per-rev", "18000"]),
    "encoder": (motion_writer("encoder"), "capture.npz", ["motion", "encoder", "--lines", "36000"]),
    "lts": (motion_writer("lts"), "lts.npz", ["motion", "lts", "--radius-mm", "100"]),
    "scale-factor": (write_log, "log.npz", ["gyro", "scale-factor"]),
    "selfcal": (write_heads, "heads.npz", ["selfcal", "--pulses-per-rev", "18000"]),
    "fog": (motion_writer("fog"), "fog.npz", ["motion", "fog"]),
}


def run(args: list[str]) -> tuple[float, float, float]:
    """``rotacal ARGS`` in a fresh process: its wall seconds, peak RSS (MB) and CPU seconds — of
    the process and of the descendants it waited for (the Dask workers), from its wait4 record
    (on a shared machine the CPU seconds are the steadier figure)."""
    start = time.perf_counter()
    with tempfile.TemporaryFile() as errors:
        child = subprocess.Popen(
            [sys.executable, "-m", "rotacal", *args], stdout=subprocess.DEVNULL, stderr=errors
        )
        _, status, usage = os.wait4(child.pid, 0)
        child.returncode = os.waitstatus_to_exitcode(status)
        seconds = time.perf_counter() - start
        if child.returncode:
            errors.seek(0)
            tail = errors.read().decode(errors="replace").strip().splitlines()[-5:]
            raise SystemExit(
                f"rotacal {' '.join(args)} failed ({child.returncode}):\n" + "\n".join(tail)
            )
    return seconds, usage.ru_maxrss / 1024, usage.ru_utime + usage.ru_stime


def best(args: list[str], repeat: int) -> tuple[float, float, float]:
    """The run of least wall time of ``repeat`` (the machine is shared: noise only adds)."""
    return min(run(args) for _ in range(max(1, repeat)))


def worst(a: Any, b: Any) -> float:
    if isinstance(a, dict):
        return max((worst(a[k], b[k]) for k in a if k not in ("provenance", "notes")), default=0)
    if isinstance(a, list):
        return max((worst(u, v) for u, v in zip(a, b, strict=True)), default=0.0)
    if isinstance(a, float) and isinstance(b, float) and math.isfinite(a) and a != b:
        return abs(a - b) / max(abs(a), abs(b))
    return 0.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--analysis", choices=sorted(ANALYSES), default="allan")
    parser.add_argument("--samples", type=float, default=1e8)
    parser.add_argument("--workers", default="1,2")
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--write", metavar="PATH", help=argparse.SUPPRESS)
    args = parser.parse_args()
    n = int(args.samples)
    write, name, command = ANALYSES[args.analysis]
    if args.write:  # in a child: the pages it touches must not count in the measured children
        write(Path(args.write), n)
        return
    with tempfile.TemporaryDirectory(prefix="rotacal-bench-dask-") as tmp:
        path = Path(tmp) / name
        t = time.perf_counter()
        writer = [sys.executable, __file__, "--analysis", args.analysis, "--samples", str(n)]
        subprocess.run([*writer, "--write", str(path)], check=True)
        print(
            f"{args.analysis}: {n:.3g} samples, {os.path.getsize(path) / 1e6:.0f} MB, written in "
            f"{time.perf_counter() - t:.1f} s; best of {max(1, args.repeat)}"
        )
        common = [*command, str(path), "--overwrite"]
        base_json = Path(tmp) / "one.json"
        base, rss, cpu = best([*common, "--chunked", "--json", str(base_json)], args.repeat)
        print(
            f"{'one process (--chunked)':<28}{base:8.2f} s   1.00x   CPU {cpu:6.2f} s   "
            f"peak RSS {rss:.0f} MB"
        )
        reference = json.loads(base_json.read_text())
        for w in [int(x) for x in args.workers.split(",")]:
            out = Path(tmp) / f"w{w}.json"
            seconds, rss, cpu = best(
                [*common, "--workers", str(w), "--json", str(out)], args.repeat
            )
            diff = worst(json.loads(out.read_text()), reference)
            print(
                f"{f'{w} Dask worker(s)':<28}{seconds:8.2f} s   {base / seconds:.2f}x   "
                f"CPU {cpu:6.2f} s   peak RSS {rss:.0f} MB; largest difference {diff:.1e} "
                "relative"
            )


if __name__ == "__main__":
    main()
