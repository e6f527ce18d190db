"""Time and peak memory of the octave Allan deviation read in chunks (rotacal.signal.allan_stream).

Each case runs in its own subprocess (peak RSS from ``resource.getrusage``), on a gyro-like rate
record (white rate noise + rate random walk + rate ramp, 100 Hz) generated chunk by chunk
(2²² samples, the random walk carried), so that the record itself is never held:

1. the generator alone (its time is subtracted from the rows below);
2. ``octave_adev_chunks`` at 10⁷, 10⁸ (and 10⁹ with ``--big``) samples;
3. the baseline, the in-memory ``overlapping_adev(whole, taus="octave")`` at 10⁷ (and 10⁸ with
   ``--in-memory-1e8``: about 3 GB), the record concatenated first.

Ratios: analysis time per sample against the in-memory baseline's at 10⁷, measured in the same
run. No asserts. Run: ``python benchmarks/bench_allan_stream.py [--quick] [--big]``
"""

from __future__ import annotations

import argparse

from _child import child_json

FS_HZ = 100.0
CHUNK = 1 << 22

_CHILD = r"""
import json, resource, sys, time
import numpy as np
n, mode = int(sys.argv[1]), sys.argv[2]
chunk = int(sys.argv[3])

def chunks():
    rng = np.random.default_rng(1)
    walk = 0.0
    for start in range(0, n, chunk):
        c = min(chunk, n - start)
        w = np.cumsum(2e-5 * rng.standard_normal(c))
        w += walk
        walk = float(w[-1])
        w += 0.3 * rng.standard_normal(c)
        w += 0.1 + 1e-6 * np.arange(start, start + c)
        yield w

t0 = time.perf_counter()
if mode == "generate":
    for _ in chunks():
        pass
elif mode == "stream":
    from rotacal.signal.allan_stream import octave_adev_chunks
    res = octave_adev_chunks(chunks(), fs=100.0)
else:
    from rotacal.signal.allan import overlapping_adev
    res = overlapping_adev(np.concatenate(list(chunks())), fs=100.0, taus="octave")
seconds = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"seconds": seconds, "peak": peak}))
"""


def run(n: int, mode: str) -> dict[str, float]:
    return child_json(_CHILD, str(n), mode, str(CHUNK))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="10⁶ and 10⁷ samples only")
    ap.add_argument("--big", action="store_true", help="also 10⁹ samples (minutes; 8 GB temp)")
    ap.add_argument("--in-memory-1e8", action="store_true", help="baseline at 10⁸ too (~3 GB)")
    args = ap.parse_args()
    sizes = [1_000_000, 10_000_000] if args.quick else [10_000_000, 100_000_000]
    if args.big:
        sizes.append(1_000_000_000)
    base_n = sizes[-1] if args.quick else 10_000_000
    print(f"octave overlapping ADEV of a gyro rate record at {FS_HZ:g} Hz, chunks of {CHUNK:,}")
    print(f"{'case':42s} {'analysis':>10s} {'peak RSS':>10s} {'s/sample ratio':>15s}")
    gen = run(base_n, "generate")
    base = run(base_n, "memory")
    base_s = (base["seconds"] - gen["seconds"]) / base_n
    print(
        f"{f'in memory (baseline), N={base_n:,}':42s} {base_s * base_n:9.2f}s "
        f"{base['peak'] / 2**20:8.0f}MB {1.0:15.2f}"
    )
    big_memory = [100_000_000] if args.in_memory_1e8 else []
    for n in big_memory:
        g, r = run(n, "generate"), run(n, "memory")
        s = r["seconds"] - g["seconds"]
        print(
            f"{f'in memory, N={n:,}':42s} {s:9.2f}s {r['peak'] / 2**20:8.0f}MB "
            f"{s / n / base_s:15.2f}"
        )
    for n in sizes:
        g = gen if n == base_n else run(n, "generate")
        r = run(n, "stream")
        s = r["seconds"] - g["seconds"]
        print(
            f"{f'chunked (octave_adev_chunks), N={n:,}':42s} {s:9.2f}s "
            f"{r['peak'] / 2**20:8.0f}MB {s / n / base_s:15.2f}"
        )
    print(
        "analysis: seconds less the generator's; ratio: seconds per sample / the in-memory "
        "baseline's; peak RSS of the whole subprocess (generator included)"
    )


if __name__ == "__main__":
    main()
