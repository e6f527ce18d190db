"""Speed and memory of MDEV, overlapping HDEV, TDEV and TOTDEV (rotacal.signal.deviations)
against allantools 2019.9, one core, in the same run.

A gyro-like rate record (white rate noise + a small rate random walk, 100 Hz) of ``--samples``
points (default 10⁷), octave τ. Each (deviation, implementation) runs in its own child process
(``--child``), which builds the record, times the call (best of ``--repeat``; CPU time of the
process, user + system, and wall time) and reports its peak RSS (``ru_maxrss``; building the
record alone, printed first, is in both). The parent prints the times, the CPU-time ratio allantools/rotacal,
the peak RSS of each and the largest relative difference of the two results on the same τ.
No asserts.

Run: ``python benchmarks/bench_allan_family.py [--samples N] [--repeat R] [--kinds mdev,hdev]``
"""

from __future__ import annotations

import argparse
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import json  # noqa: E402
import math  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

FS_HZ = 100.0
KINDS = ("mdev", "hdev", "tdev", "totdev")


def gyro_rate(n: int, seed: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return 0.1 + 0.3 * rng.standard_normal(n) + np.cumsum(2e-5 * rng.standard_normal(n))


def child(kind: str, impl: str, n: int, repeat: int, out: str) -> None:
    """Time one deviation of one implementation; write τ and σ to ``out`` (NPZ) and print JSON."""
    y = gyro_rate(n)
    if impl == "none":  # the floor: the interpreter, NumPy and building the record
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
        print(json.dumps({"rss_mb": rss}))
        return
    if impl == "rotacal":
        from rotacal.signal.deviations import stability_deviation

        def call() -> tuple[np.ndarray, np.ndarray]:
            r = stability_deviation(y, fs=FS_HZ, kind=kind, taus="octave")
            return r.tau_s, r.deviation
    else:
        import allantools

        fn = {"mdev": allantools.mdev, "hdev": allantools.ohdev, "tdev": allantools.tdev,
              "totdev": allantools.totdev}[kind]  # fmt: skip

        def call() -> tuple[np.ndarray, np.ndarray]:
            t, d, _, _ = fn(y, rate=FS_HZ, data_type="freq", taus="octave")
            return t, d

    cpu = wall = math.inf
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        tau, dev = call()
        cpu = min(cpu, time.process_time() - c0)
        wall = min(wall, time.perf_counter() - t0)
    np.savez(out, tau=tau, dev=dev)
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(json.dumps({"cpu": cpu, "wall": wall, "rss_mb": rss, "taus": int(np.size(tau))}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=10_000_000)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--kinds", default=",".join(KINDS))
    ap.add_argument("--child", nargs=2, metavar=("KIND", "IMPL"))
    ap.add_argument("--out")
    args = ap.parse_args()
    if args.child:
        child(args.child[0], args.child[1], args.samples, args.repeat, args.out)
        return
    print(f"{args.samples:.3g} samples at {FS_HZ:g} Hz, octave τ, best of {args.repeat}")
    floor = subprocess.run(
        [sys.executable, __file__, "--child", "-", "none", "--samples", str(args.samples)],
        capture_output=True, text=True, check=True,
    )  # fmt: skip
    print(f"peak RSS of building the record alone: {json.loads(floor.stdout)['rss_mb']:.0f} MB")
    print(f"{'':7} {'rotacal cpu':>12} {'allantools cpu':>15} {'ratio':>7} "
          f"{'RSS rotacal':>12} {'RSS allantools':>15} {'max rel diff':>13}")  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="bench-allan-family-") as tmp:
        for kind in args.kinds.split(","):
            res, arrays = {}, {}
            for impl in ("rotacal", "allantools"):
                out = str(Path(tmp) / f"{kind}-{impl}.npz")
                cmd = [sys.executable, __file__, "--child", kind, impl, "--out", out,
                       "--samples", str(args.samples), "--repeat", str(args.repeat)]  # fmt: skip
                proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
                res[impl] = json.loads(proc.stdout.strip().splitlines()[-1])
                arrays[impl] = np.load(out)
            a, b = arrays["rotacal"], arrays["allantools"]
            common, ia, ib = np.intersect1d(a["tau"], b["tau"], return_indices=True)
            diff = float(np.max(np.abs(a["dev"][ia] / b["dev"][ib] - 1.0)))
            r, t = res["rotacal"], res["allantools"]
            print(
                f"{kind:7} {r['cpu']:10.2f} s {t['cpu']:13.2f} s {t['cpu'] / r['cpu']:6.2f}× "
                f"{r['rss_mb']:9.0f} MB {t['rss_mb']:12.0f} MB {diff:13.1e}  ({common.size} τ)"
            )


if __name__ == "__main__":
    main()
