"""Angle and counter readings: the unwrap's speed, and `motion angle` / `rate` streamed: s, peak RSS.

Three measurements, each against a baseline measured in the same run, and an accuracy check:

1. ``unwrap``: :func:`rotacal.signal.counter.unwrap_counts` of N readings of a wrapping 16-bit
   register, whole and streamed in 2²⁰-row chunks (:class:`CounterUnwrapper`), against the least
   any unwrap must do, ``np.cumsum(np.diff(c))``; CPU seconds, best of 5, and the ratio.
2. ``motion``: ``python -m rotacal motion angle FILE --counts-per-rev N --chunked`` on an
   uncompressed NPZ of N rows (time_s, count; a 0.5°, 0.5 Hz sine read by a 16-bit counter at
   10 kHz), in a fresh process, against reading the file in chunks doing nothing
   (``bench_motion_stream``'s baseline); wall and CPU ratio, peak RSS (flat ⇒ the same at every N).
3. ``rate``: ``python -m rotacal rate FILE --pulses-per-rev 360 --counts-per-rev N`` on a
   one-hour record at 300 °/s (10 kHz, 3.6·10⁷ rows, a 16-bit counter that wraps 4·10⁴ times),
   against the same baseline.

4. ``accuracy``: `motion angle` against the twin's truth over 20 draws (:func:`bench_accuracy`).

    python benchmarks/bench_angle.py                     # unwrap 1e7, accuracy, motion 1e7, rate 1 h
    python benchmarks/bench_angle.py --motion-sizes 1e7,1e8 --rate-hours 1
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from bench_motion_stream import measured

PIECE = 2_000_000
CPR = 144_000
FS = 10_000.0


def _cpu_best(fn: Callable[[], object], repeat: int = 5) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.process_time()
        fn()
        best = min(best, time.process_time() - t0)
    return best


def bench_unwrap(n: int) -> str:
    from rotacal.signal.counter import CounterUnwrapper, unwrap_counts

    rng = np.random.default_rng(0)
    true = np.cumsum(rng.integers(-3000, 9000, n)).astype(np.int64)
    reg = true % 65536

    def streamed() -> None:
        u = CounterUnwrapper(16, False)
        for s in range(0, n, 1 << 20):
            u.feed(reg[s : s + (1 << 20)])

    base = _cpu_best(lambda: np.cumsum(np.diff(reg)))
    whole = _cpu_best(lambda: unwrap_counts(reg, 16, False))
    chunks = _cpu_best(streamed)
    out, _, _ = unwrap_counts(reg, 16, False)
    assert np.array_equal(out - out[0], true - true[0])
    return (
        f"unwrap N={n:.0e}: baseline {base:.3f} s, whole {whole:.3f} s ({whole / base:.2f}×, "
        f"{n / whole / 1e6:.0f} M/s), chunked {chunks:.3f} s ({chunks / base:.2f}×)"
    )


def bench_accuracy(draws: int) -> list[str]:
    """`motion angle` against the twin's truth over ``draws`` noise draws: the spread of
    (value − truth)/u of the amplitude (≈ 1 when u is right) and how many 95 % THD intervals
    hold the true THD — a dithered 16-bit counter, and an undithered 0.002° readout sampled
    commensurately (its quantisation error repeats every period)."""
    from rotacal.sim import SineMotion, simulate_angle
    from rotacal.table.motion_angle import calibrate_angle_motion, calibrate_count_motion

    motion = SineMotion(
        amplitude_deg=0.5, frequency_hz=2.0, harmonics={2: (0.005, 1.0), 3: (0.01, 0.3)}
    )
    lines = []
    for label, make, calibrate in (
        (
            "counter, 16-bit, noise 0.002°",
            lambda s: simulate_angle(motion, counter_bits=16, signed=True, noise_deg=0.002, seed=s),
            lambda c: calibrate_count_motion(
                c.columns["time_s"], c.columns["count"], counts_per_rev=CPR
            ),
        ),
        (
            "readout q = 0.002°, no noise",
            lambda s: simulate_angle(
                motion, reading="angle", resolution_deg=0.002, fs_hz=1000 + 37 * s, seed=s
            ),
            lambda c: calibrate_angle_motion(c.columns["time_s"], c.columns["angle_deg"]),
        ),
    ):
        z, held = [], 0
        for seed in range(draws):
            cap = make(seed)
            d = calibrate(cap).to_dict()
            z.append((d["amplitude_deg"] - cap.truth["amplitude_deg"]) / d["amplitude_deg_u"])
            lo, hi = d["thd_percent_interval"]
            held += lo <= cap.truth["thd_percent"] <= hi
        lines.append(
            f"accuracy {label}: sd of (A − truth)/u over {draws} draws {np.std(z):.2f}; "
            f"THD interval holds the truth {held}/{draws}"
        )
    return lines


def _angle(kind: str, t: np.ndarray) -> np.ndarray:
    if kind == "rate":
        return 300.0 * t
    return 0.5 * np.sin(2 * np.pi * 0.5 * t) + 0.005 * np.sin(2 * np.pi * 1.5 * t + 0.3)


def write_npz(path: Path, kind: str, n: int) -> None:
    """time_s and count of a 16-bit register, written in pieces (memory flat)."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED, allowZip64=True) as zf:
        for name in ("time_s", "count"):
            with zf.open(name + ".npy", "w", force_zip64=True) as fp:
                header = {"descr": "<f8", "fortran_order": False, "shape": (n,)}
                np.lib.format.write_array_header_1_0(fp, header)
                for lo in range(0, n, PIECE):
                    t = np.arange(lo, min(n, lo + PIECE), dtype=np.float64) / FS
                    if name == "time_s":
                        fp.write(t.tobytes())
                        continue
                    noise = np.random.default_rng([3, lo]).normal(0.0, 0.002, t.size)
                    c = np.floor((_angle(kind, t) + noise) * CPR / 360.0).astype(np.int64) % 65536
                    fp.write(c.astype(np.float64).tobytes())


def baseline(path: str) -> None:
    from rotacal.io import iter_capture_chunks

    total = 0.0
    for chunk in iter_capture_chunks(path, ("time_s", "count"), chunk_rows=PIECE):
        total += float(chunk["count"][-1])
    print(total)


def case(kind: str, n: int, work: Path, env: dict[str, str]) -> str:
    path = work / f"{kind}_{n}.npz"
    out = work / f"{kind}_{n}.json"
    head, tail = {
        "motion": (["motion", "angle"], ["--counts-per-rev", str(CPR), "--chunked"]),
        "rate": (["rate"], ["--pulses-per-rev", "360", "--counts-per-rev", str(CPR)]),
    }[kind]
    try:
        write_npz(path, kind, n)
        base = measured([sys.executable, __file__, "--baseline", str(path)], env)
        cmd = [sys.executable, "-m", "rotacal", *head, str(path), *tail]
        got = measured([*cmd, "--json", str(out), "--overwrite"], env)
        d = json.loads(out.read_text())
    finally:
        path.unlink(missing_ok=True)
        out.unlink(missing_ok=True)
    what = (
        f"amplitude {d['amplitude_deg']:.6f}° THD {d['thd_percent']:.4f} %"
        if kind == "motion"
        else f"mean rate {d['mean_rate_deg_s']:.9f} °/s"
    )
    return (
        f"{kind:6s} N={n:.2e}: base {base[0]:.1f} s / {base[2]:.0f} MB; command {got[0]:.1f} s "
        f"(wall {got[0] / base[0]:.1f}×, CPU {got[1] / base[1]:.1f}×), peak RSS {got[2]:.0f} MB; "
        f"{what}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--unwrap-size", default="1e7")
    ap.add_argument("--motion-sizes", default="1e7")
    ap.add_argument("--rate-hours", type=float, default=1.0)
    ap.add_argument("--draws", type=int, default=20, help="twin draws of the accuracy check")
    ap.add_argument("--dir", default="/tmp/bench-angle")
    ap.add_argument("--baseline", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.baseline:
        baseline(args.baseline)
        return
    work = Path(args.dir)
    work.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    print(bench_unwrap(int(float(args.unwrap_size))), flush=True)
    if args.draws:
        print("\n".join(bench_accuracy(args.draws)), flush=True)
    for n in [int(float(s)) for s in args.motion_sizes.split(",") if s]:
        print(case("motion", n, work, env), flush=True)
    if args.rate_hours > 0:
        print(case("rate", int(args.rate_hours * 3600 * FS), work, env), flush=True)


if __name__ == "__main__":
    main()
