"""What reading a capture costs: read_capture against the bare library read, per format.

Writes a capture of N rows (time_s, a, b as float64) as uncompressed NPZ, contiguous HDF5 and
CSV, then times in child processes (warm page cache, best of ``--repeat``):

- ``read_capture`` (validation included: declared sizes, finiteness, and for NPZ the zip CRC-32
  of each memory-mapped member),
- the bare library read of the same columns: ``np.load`` (which also checks the CRC while it
  copies), h5py ``ds[...]``, ``np.loadtxt``,
- for NPZ, ``zlib.crc32`` alone over the member bytes, and ``read_capture`` with the CRC check
  switched off in the same process, alternating with it on (the cost of the integrity check).

The same numbers are also written as the text layouts labs' DAQs produce — tab separated without
a header (``tab``), blank separated (``blanks``), semicolon separated with a decimal comma
(``comma``) and gzip-compressed CSV (``gz``) — and ``read_capture`` (which sniffs each layout) is
timed on them beside the CSV: the ratio to the CSV's ``read_capture`` in the same run, and whether
the columns are bit-identical to the CSV's.

With ``--against SRC`` (another checkout's ``src`` folder, e.g. main's) every read_capture is
timed for both source trees in the same run, alternating, and the columns' SHA-256 are compared
(the results of valid files must stay bit-identical).

    python benchmarks/bench_io_read.py --rows 1e7
    python benchmarks/bench_io_read.py --rows 1e7 --against ../main/src
    python benchmarks/bench_io_read.py --rows 1e6 --formats csv,tab,blanks,comma,gz
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

import numpy as np

SRC = Path(__file__).resolve().parents[1] / "src"
FILES = {"npz": "cap.npz", "hdf5": "cap.h5", "csv": "cap.csv"}
#: text layouts derived from the CSV: file name, and how a CSV line becomes one of theirs
TEXT_LAYOUTS = {
    "tab": "cap_tab.dat",
    "blanks": "cap_blanks.txt",
    "comma": "cap_comma.csv",
    "gz": "cap.csv.gz",
}
#: np.loadtxt's own read of each layout (the decimal comma has none: the CSV's stands in)
_LOADTXT = {".dat": "\t", ".txt": None, ".gz": ","}


def _child(kind: str, path: str) -> None:
    """Time one read in this fresh process; print seconds and the columns' SHA-256 as JSON."""
    import zipfile

    import h5py

    from rotacal.io import read_capture

    t0 = time.perf_counter()  # imports done: only the read is timed
    if kind == "read_capture":
        cols = read_capture(path).columns
    elif kind == "crc-share":
        print(json.dumps(_crc_share(path)))
        return
    elif kind == "crc32":
        with zipfile.ZipFile(path) as zf:
            infos = zf.infolist()
        with open(path, "rb") as fh:
            for info in infos:
                fh.seek(info.header_offset + 30 + len(info.filename))
                crc, left = 0, info.compress_size
                while left > 0:
                    block = fh.read(min(left, 1 << 24))
                    crc = zlib.crc32(block, crc)
                    left -= len(block)
        cols = {}
    elif path.endswith(".npz"):
        with np.load(path) as f:
            cols = {k: f[k] for k in f.files}
    elif path.endswith(".h5"):
        with h5py.File(path, "r") as f:
            cols = {k: f[k][...] for k in f}
    else:
        plain = path.replace("cap_comma.csv", "cap.csv")
        skip = 0 if path.endswith(".dat") else 1
        delimiter = _LOADTXT.get(Path(plain).suffix, ",")
        data = np.loadtxt(plain, delimiter=delimiter, skiprows=skip, ndmin=2)
        cols = {str(k): np.ascontiguousarray(data[:, k]) for k in range(data.shape[1])}
    if kind == "read_capture":  # by position: the layouts name their columns differently
        cols = {str(k): v for k, v in enumerate(cols.values())}
    seconds = time.perf_counter() - t0
    digest = {
        k: hashlib.sha256(np.ascontiguousarray(v).tobytes()).hexdigest() for k, v in cols.items()
    }
    print(json.dumps({"seconds": seconds, "sha256": digest}))


def _crc_share(path: str, rounds: int = 7) -> dict:
    """Best read_capture time with and without the NPZ CRC check, alternating in one process."""
    import rotacal.io._npz as npz
    from rotacal.io import read_capture

    feed, check = npz._StoredCrc.feed, npz._StoredCrc.check
    best = {"with": np.inf, "without": np.inf}
    for _ in range(rounds):
        for mode in ("with", "without"):
            on = mode == "with"
            npz._StoredCrc.feed = feed if on else (lambda self, lo, hi: None)  # type: ignore[method-assign]
            npz._StoredCrc.check = check if on else (lambda self: None)  # type: ignore[method-assign]
            t0 = time.perf_counter()
            read_capture(path)
            best[mode] = min(best[mode], time.perf_counter() - t0)
    return {"seconds": best["with"], "without": best["without"], "sha256": {}}


def _time(kind: str, path: Path, src: Path) -> dict:
    env = dict(os.environ, PYTHONPATH=str(src))
    out = subprocess.run(
        [sys.executable, __file__, "--child", kind, str(path)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def _write(folder: Path, rows: int) -> dict[str, Path]:
    sys.path.insert(0, str(SRC))
    from rotacal.io import write_capture

    rng = np.random.default_rng(7)
    t = np.arange(rows) / 1e5
    cols = {"time_s": t, "a": np.cos(2 * np.pi * 3 * t), "b": rng.normal(size=rows)}
    paths = {kind: write_capture(folder / name, cols) for kind, name in FILES.items()}
    return paths | _text_layouts(paths["csv"], folder)


def _text_layouts(csv: Path, folder: Path) -> dict[str, Path]:
    """The CSV rewritten as each of TEXT_LAYOUTS, block by block (C string methods)."""
    import gzip

    out = {kind: folder / name for kind, name in TEXT_LAYOUTS.items()}
    with (
        open(csv, encoding="utf-8") as src,
        open(out["tab"], "w", encoding="utf-8") as tab,
        open(out["blanks"], "w", encoding="utf-8") as blanks,
        open(out["comma"], "w", encoding="utf-8") as comma,
        gzip.open(out["gz"], "wt", encoding="utf-8", compresslevel=1) as gz,
    ):
        header = src.readline()
        blanks.write(header.replace(",", " "))
        comma.write(header.replace(",", ";"))
        gz.write(header)
        while block := "".join(src.readlines(1 << 24)):
            tab.write(block.replace(",", "\t"))
            blanks.write(block.replace(",", "  "))
            comma.write(block.replace(",", ";").replace(".", ","))
            gz.write(block)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--rows", type=float, default=1e7)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--formats", default="npz,hdf5,csv")
    ap.add_argument("--against", type=Path, default=None, help="another src folder to compare")
    ap.add_argument("--dir", type=Path, default=None, help="where to write the captures")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        _child(*args.child)
        return
    rows = int(args.rows)
    folder = Path(tempfile.mkdtemp(prefix="rotacal-bench-io-", dir=args.dir))
    try:
        t0 = time.perf_counter()
        paths = _write(folder, rows)
        print(f"{rows} rows x 3 float64 columns, written in {time.perf_counter() - t0:.0f} s")
        csv_digest: dict = {}
        for kind in args.formats.split(","):
            path = paths[kind]
            trees = {"this tree": SRC} | ({"against": args.against} if args.against else {})
            best: dict[str, float] = {}
            digests: dict[str, dict] = {}
            for _ in range(args.repeat):  # alternate, so that load on the machine hits both
                for name, src in trees.items():
                    r = _time("read_capture", path, src)
                    best[name] = min(best.get(name, np.inf), r["seconds"])
                    digests[name] = r["sha256"]
                r = _time("library", path, SRC)
                best["library"] = min(best.get("library", np.inf), r["seconds"])
                if kind in TEXT_LAYOUTS:  # the CSV again, alternating: the same machine load
                    r = _time("read_capture", paths["csv"], SRC)
                    best["csv"] = min(best.get("csv", np.inf), r["seconds"])
                    csv_digest = r["sha256"]
                if kind == "npz":
                    r = _time("crc32", path, SRC)
                    best["crc32"] = min(best.get("crc32", np.inf), r["seconds"])
            if kind == "npz":
                r = _time("crc-share", path, SRC)
                best["crc on"], best["crc off"] = r["seconds"], r["without"]
            size = path.stat().st_size / 1e6
            line = f"{kind:5s} ({size:.0f} MB): read_capture {best['this tree']:.3f} s"
            line += f", library read {best['library']:.3f} s"
            line += f" (ratio {best['this tree'] / best['library']:.2f})"
            if "crc32" in best:
                line += (
                    f", zlib.crc32 alone {best['crc32']:.3f} s; in one process read_capture "
                    f"{best['crc on']:.3f} s with the CRC check, {best['crc off']:.3f} s without "
                    f"(ratio {best['crc on'] / best['crc off']:.2f})"
                )
            if kind in TEXT_LAYOUTS:
                same = digests["this tree"] == csv_digest
                line += (
                    f"; the CSV's read_capture, alternating with it: {best['csv']:.3f} s, ratio "
                    f"{best['this tree'] / best['csv']:.2f}, columns "
                    f"{'bit-identical to the CSV' if same else 'DIFFER from the CSV'}"
                )
            if args.against:
                same = digests["this tree"] == digests["against"]
                line += (
                    f"; against: {best['against']:.3f} s "
                    f"(ratio this/against {best['this tree'] / best['against']:.2f}, "
                    f"columns {'bit-identical' if same else 'DIFFER'})"
                )
            print(line, flush=True)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
