"""Plateau detection on a 24-h, 100 Hz continuous log (8.64·10⁶ rows × 3 columns): seconds and
peak memory, against a bare load of the same file.

The log is the ``gyro-log`` twin (``rotacal.sim.simulate_gyro_log``): the eleven default rates run
26 times over, 300 s each, ramps at 50 °/s², a measured table rate (0.02 °/s noise), a lagging,
ringing DUT; it is written once to ``--dir`` as an uncompressed NPZ (0.2 GB). Then, each in a fresh
process whose peak RSS (``os.wait4``'s ``ru_maxrss``) belongs to that case alone, best of
``--repeat`` interleaved runs:

- **baseline**: ``np.load`` the three columns and ``np.diff`` each (the least any detector does);
- **detect**: the same load, then :func:`rotacal.gyro.plateaus.find_plateaus` (time, rate, output;
  the settling read from the output); its own seconds are printed apart (the target: < 2 s).

CPU seconds (``time.process_time``) are printed beside wall seconds: the machine is shared.

    python benchmarks/bench_plateaus.py [--repeat 3] [--dir /tmp]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def write_log(path: Path) -> int:
    from rotacal.sim import simulate_gyro_log
    from rotacal.sim.gyro_log import DEFAULT_LOG_RATES_DEG_S

    cap = simulate_gyro_log(rates_deg_s=DEFAULT_LOG_RATES_DEG_S * 26, plateau_s=300.0)
    np.savez(path, **cap.columns)
    return len(cap.truth["plateaus"])


def child(mode: str, path: str) -> None:
    """One case; prints its seconds as JSON (the parent reads the peak RSS)."""
    w0, c0 = time.perf_counter(), time.process_time()
    with np.load(path) as z:
        t, rate, out = z["time_s"], z["rate_deg_s"], z["output"]
    extra: dict = {"rows": int(t.size)}
    if mode == "baseline":
        extra["sum"] = float(sum(np.diff(x)[-1] for x in (t, rate, out)))
    else:
        from rotacal.gyro.plateaus import find_plateaus

        w1, c1 = time.perf_counter(), time.process_time()
        found = find_plateaus(t, rate, out)
        extra.update(
            detect_wall_s=time.perf_counter() - w1,
            detect_cpu_s=time.process_time() - c1,
            plateaus=len(found.plateaus),
            rejected=len(found.rejected),
            settle_s=found.settle_s,
        )
    extra.update(wall_s=time.perf_counter() - w0, cpu_s=time.process_time() - c0)
    print(json.dumps(extra))


def run_child(mode: str, path: Path) -> dict:
    proc = subprocess.Popen(
        [sys.executable, __file__, "--child", mode, str(path)], stdout=subprocess.PIPE, text=True
    )
    assert proc.stdout is not None
    text = proc.stdout.read()
    _, status, usage = os.wait4(proc.pid, 0)
    if status != 0:
        raise SystemExit(f"{mode} failed: {text}")
    d = json.loads(text)
    d["peak_mb"] = usage.ru_maxrss / 1024.0
    return d


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--dir", default=tempfile.gettempdir())
    ap.add_argument("--child", nargs=2, metavar=("MODE", "PATH"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        child(*a.child)
        return
    path = Path(a.dir) / "bench_plateaus_24h.npz"
    try:
        truth = write_log(path)
        best: dict[str, dict] = {}
        for _ in range(a.repeat):
            for mode in ("baseline", "detect"):
                d = run_child(mode, path)
                if mode not in best or d["cpu_s"] < best[mode]["cpu_s"]:
                    best[mode] = d
        b, d = best["baseline"], best["detect"]
        print(f"log: {d['rows']} rows × 3 columns, {truth} plateaus in the twin's truth")
        print(
            f"baseline (np.load + np.diff)  {b['wall_s']:.2f} s wall  {b['cpu_s']:.2f} s CPU  "
            f"peak {b['peak_mb']:.0f} MB"
        )
        print(
            f"load + find_plateaus          {d['wall_s']:.2f} s wall  {d['cpu_s']:.2f} s CPU  "
            f"peak {d['peak_mb']:.0f} MB"
        )
        print(
            f"find_plateaus alone           {d['detect_wall_s']:.2f} s wall  "
            f"{d['detect_cpu_s']:.2f} s CPU  (target < 2 s): {d['plateaus']} used, "
            f"{d['rejected']} rejected, settle {d['settle_s']:.2f} s"
        )
        print(f"ratio (CPU) detect/baseline   {d['cpu_s'] / b['cpu_s']:.2f}×")
    finally:
        path.unlink(missing_ok=True)


if __name__ == "__main__":
    main()
