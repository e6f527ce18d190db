"""What the ``provenance`` of a JSON result costs: hashing the input capture.

    python benchmarks/bench_provenance.py [--mib 512]

Writes a file of random bytes, hashes it with rotacal.provenance.sha256_file (1 MiB blocks) and
with hashlib over the whole file read at once, and prints the throughput of both and the peak
memory the block-wise hash added (ru_maxrss, Linux kiB) — flat, whatever the file's size.
"""

from __future__ import annotations

import argparse
import hashlib
import resource
import tempfile
import time
from pathlib import Path

import numpy as np

from rotacal.provenance import sha256_file


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--mib", type=int, default=512, help="size of the file (MiB)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "capture.bin"
        rng = np.random.default_rng(0)
        with open(path, "wb") as fh:
            for _ in range(args.mib):
                fh.write(rng.bytes(1 << 20))
        before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
        start = time.perf_counter()
        streamed = sha256_file(path)
        streamed_s = time.perf_counter() - start
        added_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before
        start = time.perf_counter()
        whole = hashlib.sha256(path.read_bytes()).hexdigest()
        whole_s = time.perf_counter() - start
    assert streamed == whole
    print(f"file                 {args.mib} MiB")
    print(
        f"sha256_file (1 MiB)  {args.mib / streamed_s:8.0f} MiB/s   peak memory added {added_kib} kiB"
    )
    print(f"read whole + hash    {args.mib / whole_s:8.0f} MiB/s   (holds the file in memory)")


if __name__ == "__main__":
    main()
