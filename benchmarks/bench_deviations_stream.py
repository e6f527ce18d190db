"""Time and peak memory of the MDEV, HDEV and TOTDEV read in chunks (rotacal.signal.deviations_stream).

A gyro-like rate record (white rate noise + rate random walk + rate ramp, 100 Hz) is written
chunk by chunk to a raw float64 file under ``/tmp/bench-devstream17`` (never held whole; deleted
at the end). Each case then runs in its own subprocess (CPU seconds from ``time.process_time``,
wall seconds, peak RSS from ``resource.getrusage``) and reads that file in chunks of 2²² rows:

1. ``read``: reading the chunks alone — the baseline of the same run;
2. ``adev``, ``mdev``, ``hdev``, ``totdev``: the same reading fed to
   :class:`~rotacal.signal.deviations_stream.ChunkedDeviation` at octave τ (TDEV is MDEV's sums).

Ratio: the case's CPU seconds over reading's at the same N. With ``--check-up-to 1e7`` each
deviation (at sizes up to that) is compared with the in-memory ``stability_deviation`` of the
whole record (max relative difference printed); with ``--exact-up-to`` too, the ADEV and HDEV of
both paths with the literal sum over the phase integrated in long double. No asserts. Run:
``python benchmarks/bench_deviations_stream.py [--sizes 1e7,1e8,1e9] [--check-up-to 1e8]
[--exact-up-to 1e8]``
"""

from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import numpy as np

from _child import child_json

FS_HZ = 100.0
CHUNK = 1 << 22
SCRATCH = Path("/tmp/bench-devstream17")
KINDS = ("adev", "mdev", "hdev", "totdev")

_CHILD = r"""
import json, resource, sys, time
import numpy as np
path, mode, chunk = sys.argv[1], sys.argv[2], int(sys.argv[3])
check, exact = sys.argv[4] == "1", sys.argv[5] == "1"
# second and third differences of the phase, and their σ² normalisation (NIST SP 1065 (11), (18))
EXACT = {"adev": ((1.0, -2.0, 1.0), 2.0), "hdev": ((-1.0, 3.0, -3.0, 1.0), 6.0)}
wall, cpu = time.perf_counter(), time.process_time()

def chunks():
    with open(path, "rb") as f:  # plain reads: a memory map's pages would count in the RSS
        while True:
            c = np.fromfile(f, dtype=np.float64, count=chunk)
            if not c.size:
                return
            yield c

out = {}
if mode == "read":
    total = 0.0
    for c in chunks():
        total += float(c[0])
else:
    from rotacal.signal.deviations_stream import ChunkedDeviation
    with ChunkedDeviation(mode, taus="octave") as acc:
        for c in chunks():
            acc.add(c)
        res = acc.result(fs=100.0)
    out["taus"] = int(res.tau_s.size)
out["cpu"] = time.process_time() - cpu
out["seconds"] = time.perf_counter() - wall
out["peak"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
if check and mode != "read":
    from rotacal.signal.deviations import stability_deviation
    ref = stability_deviation(np.fromfile(path), fs=100.0, kind=mode, taus="octave")
    out["max_rel"] = float(np.max(np.abs(res.deviation / ref.deviation - 1.0)))
    if exact and mode in EXACT:
        # the literal sum over the phase integrated in long double (64-bit mantissa)
        y = np.fromfile(path).astype(np.longdouble)
        y -= y.mean()
        x = np.concatenate([np.zeros(1, dtype=np.longdouble), np.cumsum(y)])
        del y
        weights, norm = EXACT[mode]
        truth = []
        for m in np.rint(res.tau_s * 100.0).astype(np.int64).tolist():
            n = x.size - (len(weights) - 1) * m
            d = sum(w * x[j * m : j * m + n] for j, w in enumerate(weights))
            truth.append(np.sqrt(float(np.dot(d, d)) / (norm * float(m) ** 2 * n)))
        out["exact_mem"] = float(np.max(np.abs(ref.deviation / truth - 1.0)))
        out["exact_stream"] = float(np.max(np.abs(res.deviation / truth - 1.0)))
print(json.dumps(out))
"""


def write_record(path: Path, n: int) -> None:
    """The rate record (°/s) written chunk by chunk as raw float64 (random walk carried)."""
    rng = np.random.default_rng(1)
    walk = 0.0
    with open(path, "wb") as out:
        for start in range(0, n, CHUNK):
            c = min(CHUNK, n - start)
            w = np.cumsum(2e-5 * rng.standard_normal(c))
            w += walk
            walk = float(w[-1])
            w += 0.3 * rng.standard_normal(c)
            w += 0.1 + 1e-6 * np.arange(start, start + c)
            w.tofile(out)


def run(path: Path, mode: str, check: bool, exact: bool = False) -> dict[str, float]:
    flags = ("1" if check else "0", "1" if exact else "0")
    return child_json(_CHILD, str(path), mode, str(CHUNK), *flags)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1e7,1e8", help="record lengths (comma-separated)")
    ap.add_argument("--kinds", default=",".join(KINDS), help="deviations (comma-separated)")
    ap.add_argument(
        "--check-up-to",
        type=float,
        default=0,
        help="compare with the in-memory deviation at sizes up to this (10⁸: ~3 GB more)",
    )
    ap.add_argument(
        "--exact-up-to",
        type=float,
        default=0,
        help="and both with the exact ADEV/HDEV (long double) at sizes up to this (10⁸: ~6 GB)",
    )
    args = ap.parse_args()
    sizes = [int(float(s)) for s in args.sizes.split(",")]
    kinds = args.kinds.split(",")
    SCRATCH.mkdir(parents=True, exist_ok=True)
    print(f"octave deviations of a gyro rate record at {FS_HZ:g} Hz read in chunks of {CHUNK:,}")
    print(f"{'case':28s} {'cpu':>9s} {'wall':>9s} {'peak RSS':>9s} {'cpu/read':>9s}  check")
    try:
        for n in sizes:
            path = SCRATCH / f"rate_{n}.f64"
            write_record(path, n)
            read = run(path, "read", False)
            print(
                f"{f'read, N={n:,}':28s} {read['cpu']:8.2f}s {read['seconds']:8.2f}s "
                f"{read['peak'] / 2**20:7.0f}MB {1.0:9.2f}"
            )
            for kind in kinds:
                r = run(path, kind, n <= args.check_up_to, n <= args.exact_up_to)
                rel = f"max rel. diff. to in memory {r['max_rel']:.1e}" if "max_rel" in r else ""
                if "exact_mem" in r:
                    rel += f"; to exact: in memory {r['exact_mem']:.1e}, "
                    rel += f"streamed {r['exact_stream']:.1e}"
                case = f"{kind}, N={n:,} ({r['taus']:.0f} τ)"
                print(
                    f"{case:28s} {r['cpu']:8.2f}s "
                    f"{r['seconds']:8.2f}s {r['peak'] / 2**20:7.0f}MB "
                    f"{r['cpu'] / read['cpu']:9.2f}  {rel}"
                )
            path.unlink()
    finally:
        shutil.rmtree(SCRATCH, ignore_errors=True)
    print("cpu, wall: the subprocess's seconds after start-up; peak RSS of the whole subprocess")


if __name__ == "__main__":
    main()
