"""Time and peak memory of ``rotacal selfcal`` on captures of 10⁷, 10⁸ and 6.5·10⁸ pulse times.

The captures are NPZ files (stored, so memory-mapped on reading) of 12 heads × 18,000 pulses per
revolution, written head by head in chunks so that no capture is ever held: a table turning at
a constant 300 °/s with 1 ns timing jitter, a scale deviation of a few harmonics plus random
graduation errors, heads placed within 20 arcsec of i·30°; ragged (head 1 starts 1,000 pulses
late, the heads stop at different pulses). Each case runs in its own subprocess; it prints wall
seconds, CPU seconds, M pulse times/s and the peak RSS (``ru_maxrss``):

1. baseline: read every head in chunks (the reader the command uses) and find, for every head-0
   pulse, the nearest pulse of every other head (``np.searchsorted``) — the least any pairing
   of heads in time must do;
2. ``rotacal selfcal FILE --pulses-per-rev 18000 --chunked --json OUT`` (the command chooses
   it by itself above 10⁷ pulse times);
3. at 10⁷ also ``--in-memory``, and the largest difference of every JSON number between the two
   (relative; the curve's points against the curve's size).

Ratios: the command's wall and CPU time against the baseline's in the same run, at each size (on
a shared machine the CPU ratio is the steadier one).
No asserts. Run: ``python benchmarks/bench_selfcal_stream.py [--big] [--dir DIR] [--keep]``
(``--big`` adds 6.5·10⁸: a 5.2 GB file in DIR, default a temporary directory).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np

HEADS, M, RATE_DEG_S = 12, 18000, 300.0
CHUNK = 1 << 22
SIZES = {"1e7": 46, "1e8": 463, "6.5e8": 3000}  # revolutions: 12 × 18,000 × R pulse times

_CHILD = r"""
import json, resource, sys, time
import numpy as np
path, mode, out = sys.argv[1], sys.argv[2], sys.argv[3]
t0 = time.perf_counter()
if mode == "baseline":
    from rotacal.io import capture_columns, iter_capture_chunks
    names = sorted((c for c in capture_columns(path) if c.startswith("head_")),
                   key=lambda c: int(c[5:]))
    def head(name):
        for c in iter_capture_chunks(path, [name], chunk_rows=1 << 19):
            yield np.array(c[name])
    found = 0
    others = [head(n) for n in names[1:]]
    windows = [next(h) for h in others]
    for t0c in head(names[0]):
        for i, h in enumerate(others):
            while windows[i][-1] < t0c[-1]:
                nxt = next(h, None)
                if nxt is None:
                    break
                windows[i] = np.concatenate((windows[i][-1:], nxt))
            found += int(np.searchsorted(windows[i], t0c).sum() & 1)
else:
    from rotacal.cli import cli
    args = ["selfcal", path, "--pulses-per-rev", "18000", "--json", out, "--overwrite"]
    args.append("--in-memory" if mode == "in-memory" else "--chunked")
    cli.main(args, standalone_mode=False, prog_name="rotacal")
seconds = time.perf_counter() - t0
ru = resource.getrusage(resource.RUSAGE_SELF)
print(json.dumps({"seconds": seconds, "cpu": ru.ru_utime + ru.ru_stime, "peak": ru.ru_maxrss * 1024}))
"""


def deviation(m: int, rng: np.random.Generator) -> np.ndarray:
    """A scale's deviation (arcsec): eccentricity, a few harmonics, graduation errors."""
    j = np.arange(m) * 2 * np.pi / m
    d = 1.5 * np.cos(j + 0.3) + 0.4 * np.cos(2 * j + 1.0) + 0.2 * np.sin(7 * j)
    d += 0.05 * rng.standard_normal(m)
    return d - d.mean()


def write_capture(path: Path, revolutions: int) -> int:
    """The twin described above, written member by member in chunks; returns its pulse times."""
    rng = np.random.default_rng(17)
    dev = deviation(M, rng)
    pitch = 360.0 / M
    omega = RATE_DEG_S
    total = 0
    with zipfile.ZipFile(path, "w", zipfile.ZIP_STORED, allowZip64=True) as zf:
        for i in range(HEADS):
            place = i * 360.0 / HEADS + rng.uniform(-20, 20) / 3600.0
            first_line = int(np.ceil(place / pitch)) + (1000 if i == 1 else 0)
            count = revolutions * M + 500 - 37 * i - (1000 if i == 1 else 0)
            total += count
            with zf.open(f"head_{i}.npy", "w", force_zip64=True) as fh:
                np.lib.format.write_array_header_1_0(
                    fh, {"descr": "<f8", "fortran_order": False, "shape": (count,)}
                )
                for k0 in range(0, count, CHUNK):
                    line = np.arange(first_line + k0, first_line + min(k0 + CHUNK, count))
                    angle = line * pitch + dev[line % M] / 3600.0 - place
                    t = angle / omega + 1e-9 * rng.standard_normal(line.size)
                    fh.write(t.tobytes())
    return total


def run(path: Path, mode: str, out: Path) -> dict[str, float]:
    res = subprocess.run(
        [sys.executable, "-c", _CHILD, str(path), mode, str(out)],
        capture_output=True,
        text=True,
        check=False,
    )
    if res.returncode != 0:
        raise SystemExit(f"{mode} failed:\n{res.stderr[-3000:]}")
    return dict(json.loads(res.stdout.strip().splitlines()[-1]))


def leaves(d: object, key: str = "") -> dict[str, object]:
    out: dict[str, object] = {}
    if isinstance(d, dict):
        for k, v in d.items():
            if k != "provenance":
                out.update(leaves(v, f"{key}/{k}"))
    elif isinstance(d, list):
        for i, v in enumerate(d):
            out.update(leaves(v, f"{key}[{i}]"))
    else:
        out[key] = d
    return out


def largest_difference(a_path: Path, b_path: Path) -> float:
    a, b = leaves(json.loads(a_path.read_text())), leaves(json.loads(b_path.read_text()))
    scale = max(abs(float(v)) for k, v in a.items() if k.startswith("/deviation_arcsec["))  # type: ignore[arg-type]
    worst = 0.0
    for k, x in a.items():
        y = b.get(k)
        if isinstance(x, float) and isinstance(y, float):
            curve = k.startswith(("/deviation_arcsec[", "/harmonic_amplitudes_arcsec["))
            ref = scale if curve else abs(x)
            worst = max(worst, abs(x - y) / ref if ref else abs(x - y))
        elif x != y:
            return float("inf")
    return worst


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--big", action="store_true", help="add 6.5e8 pulse times (a 5.2 GB file)")
    ap.add_argument("--dir", default=None, help="where the captures are written")
    ap.add_argument("--keep", action="store_true", help="keep the captures")
    ap.add_argument("--sizes", default=None, help="comma-separated subset of " + ",".join(SIZES))
    args = ap.parse_args()
    sizes = [s for s in SIZES if args.big or s != "6.5e8"]
    if args.sizes:
        sizes = [s for s in args.sizes.split(",") if s in SIZES]
    work = Path(args.dir or tempfile.mkdtemp(prefix="bench-selfcal-"))
    work.mkdir(parents=True, exist_ok=True)
    print(f"{HEADS} heads x {M} pulses/rev at {RATE_DEG_S} deg/s; files in {work}")
    print(
        f"{'case':24s} {'pulse times':>12s} {'s':>8s} {'CPU s':>8s} {'M/s':>7s} "
        f"{'peak MB':>8s} {'x base':>7s} {'x base CPU':>10s}"
    )
    for size in sizes:
        path = work / f"heads_{size}.npz"
        if not path.exists():
            write_capture(path, SIZES[size])
        n = _count(path)
        base = run(path, "baseline", work / "none.json")
        cases = [("baseline (read + nearest)", base)]
        out = work / f"chunked_{size}.json"
        cases.append(("rotacal selfcal --chunked", run(path, "chunked", out)))
        if size == "1e7":
            mem = work / f"memory_{size}.json"
            cases.append(("rotacal selfcal --in-memory", run(path, "in-memory", mem)))
        for label, c in cases:
            print(
                f"{label:24s} {n:12,d} {c['seconds']:8.2f} {c['cpu']:8.2f} "
                f"{n / c['seconds'] / 1e6:7.1f} {c['peak'] / 2**20:8.0f} "
                f"{c['seconds'] / base['seconds']:7.2f} {c['cpu'] / base['cpu']:10.2f}"
            )
        if size == "1e7":
            print(
                f"  largest difference chunked vs in-memory JSON: {largest_difference(mem, out):.2e}"
            )
        if not args.keep and args.dir is None:
            path.unlink()
    if not args.keep and args.dir is None:
        for f in work.iterdir():
            f.unlink()
        work.rmdir()


def _count(path: Path) -> int:
    with zipfile.ZipFile(path) as zf:
        total = 0
        for name in zf.namelist():
            with zf.open(name) as fh:
                np.lib.format.read_magic(fh)
                shape, _, _ = np.lib.format.read_array_header_1_0(fh)
                total += int(np.prod(shape))
        return total


if __name__ == "__main__":
    main()
