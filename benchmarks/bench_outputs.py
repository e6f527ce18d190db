"""Cost of writing outputs safely (rotacal.io.outputs) against a plain write, and a race's outcome.

For a 10 kB JSON, a 2 MB HTML report and an NPZ capture of two 2·10⁶-sample columns (32 MB), times
``write_output`` (hidden temporary file, fsync, hard link) and ``write_output(overwrite=True)``
(atomic rename over the old file) against ``Path.write_bytes`` / ``numpy.savez`` of the same bytes
into the same folder, median of several runs with ``time.perf_counter``. The difference is mostly
the fsync, which puts the data on disk before the file gets its name. Then runs 10 processes that
write one name at once, N times, and prints how many rounds had exactly one winner. No asserts.

Run: ``python benchmarks/bench_outputs.py [--folder DIR] [--rounds N]``
"""

from __future__ import annotations

import argparse
import multiprocessing
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rotacal.errors import ConfigError
from rotacal.io import write_capture
from rotacal.io.outputs import write_output


def median_time(fn: Callable[[int], object], repeat: int) -> float:
    times = []
    for i in range(repeat):
        t0 = time.perf_counter()
        fn(i)
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def text_times(stem: Path, data: bytes, repeat: int) -> tuple[float, float, float]:
    """Median seconds of a plain, an exclusive and an overwriting write of ``data``."""
    plain = median_time(lambda i: Path(f"{stem}p{i}").write_bytes(data), repeat)
    excl = median_time(lambda i: write_output(f"{stem}e{i}", data), repeat)
    over = median_time(lambda i: write_output(f"{stem}o", data, overwrite=True), repeat)
    return plain, excl, over


def print_row(label: str, plain: float, excl: float, over: float) -> None:
    print(f"{label:<22} {1e3 * plain:>10.2f} {1e3 * excl:>10.2f} {1e3 * over:>10.2f}")


def _writer(path: str, barrier: object, results: object) -> None:
    barrier.wait()  # type: ignore[attr-defined]
    try:
        write_output(path, b"x" * 10_000)
        results.put(True)  # type: ignore[attr-defined]
    except ConfigError:
        results.put(False)  # type: ignore[attr-defined]


def race(folder: Path, rounds: int) -> int:
    """Rounds (of ``rounds``) in which exactly one of 10 simultaneous writers succeeded."""
    ctx = multiprocessing.get_context("fork")
    one_winner = 0
    for r in range(rounds):
        barrier, results = ctx.Barrier(10), ctx.Queue()
        path = str(folder / f"race{r}.json")
        procs = [ctx.Process(target=_writer, args=(path, barrier, results)) for _ in range(10)]
        for p in procs:
            p.start()
        wins = sum(results.get() for _ in procs)
        for p in procs:
            p.join()
        one_winner += wins == 1
    return one_winner


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--folder", default=None, help="where to write [a temporary folder]")
    ap.add_argument("--rounds", type=int, default=20, help="rounds of the 10-writer race")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(dir=args.folder) as tmp:
        folder = Path(tmp)
        print(f"folder {folder}")
        print(f"{'output':<22} {'plain':>10} {'exclusive':>10} {'overwrite':>10}  (median, ms)")
        for n, (label, data, repeat) in enumerate(
            (("JSON, 10 kB", b"{}" * 5_000, 30), ("HTML report, 2 MB", b"<p>" * 700_000, 15))
        ):
            print_row(label, *text_times(folder / str(n), data, repeat))
        cols = {"time_s": np.arange(2_000_000) / 1e4, "rate_deg_s": np.zeros(2_000_000)}
        plain = median_time(lambda i: np.savez(folder / f"p{i}.npz", **cols), 3)
        excl = median_time(lambda i: write_capture(folder / f"e{i}.npz", cols), 3)
        over = median_time(lambda i: write_capture(folder / "o.npz", cols, overwrite=True), 3)
        print_row("NPZ capture, 32 MB", plain, excl, over)
        print(
            f"10 writers on one name: exactly one winner in {race(folder, args.rounds)} of "
            f"{args.rounds} rounds"
        )


if __name__ == "__main__":
    main()
