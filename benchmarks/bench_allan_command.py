"""The whole `rotacal allan` command (file in → JSON out) at 10⁷, 10⁸ and 10⁹ samples: seconds and
peak RSS, against reading the same file, in one run.

    python benchmarks/bench_allan_command.py [--sizes 1e7,1e8,1e9] [--repeat 1] [--folder /tmp/…]

For each size a gyro-like rate record (100 Hz: white rate noise, a rate random walk, a small rate
ramp) is written as an NPZ piece by piece (a stored zip member written in chunks of 2²² samples,
never held whole), then timed as separate processes, from start to exit:

- baseline: reading the file — ``python -c`` that streams the rate column with
  ``rotacal.io.iter_capture_chunks`` (the reader and its NaN/range checks) and sums it;
- ``rotacal allan FILE --fs-hz 100 --json OUT``: chunked by itself above 3·10⁷ samples (octave τ,
  noise terms, budgets, JSON), in memory below (log τ);
- at 10⁷ also ``--taus all`` (5·10⁶ τ in the JSON) and ``--chunked`` (octave τ).

Prints seconds, seconds per 10⁷ samples (linear time: the same figure at every size), the ratio
to reading the file and the peak RSS of each process (``resource.getrusage`` of the children).
The file (8 bytes a sample) and the command's temporary phase file (8 bytes a sample, on the
chunked path) are on the disk together: 16 GB at 10⁹; each file is deleted once its size has run.
No asserts.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from bench_encoder_command import best  # wall time and peak RSS of one command

FS = 100.0
PIECE = 1 << 22

_READ = (
    "import sys\n"
    "from rotacal.io import iter_capture_chunks\n"
    "total = 0.0\n"
    "for c in iter_capture_chunks(sys.argv[1], ['rate_deg_s'], chunk_rows=1 << 22):\n"
    "    total += float(c['rate_deg_s'].sum())\n"
    "print(total)\n"
)


def write_npz(path: Path, n: int, seed: int = 1) -> None:
    """``rate_deg_s`` of ``n`` samples as a stored NPZ member, written piece by piece."""
    rng = np.random.default_rng(seed)
    walk = 0.0
    header = {"descr": "<f8", "fortran_order": False, "shape": (n,)}
    with (
        zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED) as zf,
        zf.open("rate_deg_s.npy", "w", force_zip64=True) as member,
    ):
        np.lib.format.write_array_header_2_0(member, header)
        for start in range(0, n, PIECE):
            c = min(PIECE, n - start)
            w = np.cumsum(2e-5 * rng.standard_normal(c))
            w += walk
            walk = float(w[-1])
            w += 0.3 * rng.standard_normal(c)
            w += 0.1 + 1e-9 * np.arange(start, start + c)
            member.write(w.tobytes())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="1e7,1e8,1e9", help="comma-separated sample counts")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--folder", default=None, help="where the files go (default: a temp folder)")
    args = ap.parse_args()
    sizes = [int(float(s)) for s in args.sizes.split(",")]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    folder = Path(tempfile.mkdtemp(prefix="bench-allan-", dir=args.folder))
    env["TMPDIR"] = str(folder)  # the command's phase file goes there too
    print(f"rotacal allan, gyro rate at {FS:g} Hz; best of {args.repeat}; separate processes")
    print(f"{'samples':>13s}  {'what':44s} {'s':>8s} {'s/1e7':>7s} {'/read':>6s} {'peak MB':>8s}")
    try:
        for n in sizes:
            path = folder / f"gyro-{n}.npz"
            try:
                write_npz(path, n)
                out = folder / "out.json"
                read_s, read_mb = best([sys.executable, "-c", _READ, str(path)], env, 1)
                rows = [("read the file (iter_capture_chunks)  [baseline]", read_s, read_mb)]
                base = [sys.executable, "-m", "rotacal", "allan", str(path), "--fs-hz", str(FS)]
                base += ["--json", str(out), "--overwrite"]
                cases: list[tuple[str, list[str]]] = [("rotacal allan (chunked above 3e7)", [])]
                if n <= 10_000_000:
                    cases += [("rotacal allan --taus all", ["--taus", "all"])]
                    cases += [("rotacal allan --chunked", ["--chunked", "--taus", "octave"])]
                for label, extra in cases:
                    s, mb = best(base + extra, env, args.repeat)
                    rows.append((label, s, mb))
                for label, s, mb in rows:
                    print(
                        f"{n:13,d}  {label:44s} {s:8.2f} {s / n * 1e7:7.2f} "
                        f"{s / read_s:6.2f} {mb:8.0f}",
                        flush=True,
                    )
            finally:
                path.unlink(missing_ok=True)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    print("s/1e7: seconds per 10⁷ samples; /read: the ratio to reading the file in the same run")


if __name__ == "__main__":
    main()
