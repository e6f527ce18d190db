"""Long fuzz run of the capture readers: untyped exceptions per 10⁵ damaged inputs, per reader.

Uses the seeds and the mutation engine of ``tests/io/test_fuzz_readers.py`` (one definition of
both), driven here by a plain seeded ``random.Random`` per input, so that input ``i`` of a reader
is the same file on every run and can be written out again with ``--write READER I``. Each input
goes through ``read_capture``, ``iter_capture_chunks`` and ``capture_length``; anything but
CaptureError/ConfigError counts as untyped, and a Python warning or log record (which a user
would see on stderr) is counted beside it. Inputs run in worker processes (``--jobs``, at most
the 2 cores of this machine); an input that hangs for ``--hang-s`` or kills its process (a crash
in a C library) is counted as such and the worker goes on after it.

    python benchmarks/fuzz_readers.py                       # 10⁵ inputs per reader, 2 processes
    python benchmarks/fuzz_readers.py --inputs 2000 --jobs 1
    python benchmarks/fuzz_readers.py --write npz-compressed 4711   # -> ./fuzz-npz-compressed-4711.npz

Prints per reader: inputs, untyped exceptions (count, per 10⁵, by entry point and type, with one
example: input number, seed and message), warnings/log lines, the slowest input and the wall time.
"""

from __future__ import annotations

import argparse
import faulthandler
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path
from random import Random
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
ENGINE_PATH = ROOT / "tests" / "io" / "test_fuzz_readers.py"
PIECE = 5000  # inputs per worker process


def _engine() -> Any:
    spec = importlib.util.spec_from_file_location("fuzz_engine", ENGINE_PATH)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["fuzz_engine"] = module
    spec.loader.exec_module(module)
    return module


def _input(engine: Any, seeds: dict[str, list[Any]], reader: str, index: int) -> tuple[Any, bytes]:
    """Seed and damaged bytes of input ``index`` of ``reader`` (the same on every run)."""
    rng = Random(f"rotacal-fuzz/{reader}/{index}")
    pool = seeds[reader]
    seed = pool[rng.randrange(len(pool))]
    return seed, engine.mutate(seed, rng)


def _worker(reader: str, lo: int, hi: int, hang_s: float) -> None:
    """Run inputs lo..hi-1; one JSON line per finding on stdout, 'at I' on stderr before each."""
    engine = _engine()
    work = engine.fuzz_dir()
    seeds = engine.build_seeds(work)
    slowest = (0.0, -1)
    try:
        for index in range(lo, hi):
            seed, data = _input(engine, seeds, reader, index)
            path = work / f"in{seed.ext}"
            path.write_bytes(data)
            print(f"at {index}", file=sys.stderr, flush=True)
            faulthandler.dump_traceback_later(hang_s, exit=True)
            t0 = time.perf_counter()
            escaped = engine.run_readers(path, seed)
            faulthandler.cancel_dump_traceback_later()
            slowest = max(slowest, (time.perf_counter() - t0, index))
            for what, exc in escaped:
                if isinstance(exc, str):
                    kind, text = "printed", exc
                    key = f"{what}: {exc.split(':', 2)[0]}: {exc.split(':', 2)[1].strip()}"
                else:
                    kind, text = "untyped", repr(str(exc))
                    key = f"{what}: {type(exc).__module__}.{type(exc).__qualname__}"
                line = {"kind": kind, "key": key, "index": index, "seed": seed.name, "text": text}
                print(json.dumps(line), flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(json.dumps({"kind": "done", "slowest_s": slowest[0], "slowest": slowest[1]}), flush=True)


class _Tally:
    def __init__(self) -> None:
        self.n = 0
        self.counts: dict[str, Counter[str]] = {"untyped": Counter(), "printed": Counter()}
        self.examples: dict[str, str] = {}
        self.slowest = (0.0, -1)
        self.bad_inputs: set[int] = set()  # inputs with at least one untyped exception

    def add(self, item: dict[str, Any]) -> None:
        key = item["key"]
        self.counts[item["kind"]][key] += 1
        if item["kind"] == "untyped":
            self.bad_inputs.add(item["index"])
        self.examples.setdefault(
            key, f"input {item['index']} ({item['seed']}): {item['text'][:200]}"
        )


def _run(reader: str, lo: int, hi: int, hang_s: float, tally: _Tally) -> subprocess.Popen[str]:
    cmd = [sys.executable, __file__, "--worker", reader, str(lo), str(hi), "--hang-s", str(hang_s)]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _collect(
    proc: subprocess.Popen[str], reader: str, lo: int, hi: int, tally: _Tally
) -> int | None:
    """Fold a finished worker's output into ``tally``; return where to resume after a crash."""
    out, err = proc.communicate()
    done = False
    for line in out.splitlines():
        item = json.loads(line)
        if item["kind"] == "done":
            done = True
            tally.slowest = max(tally.slowest, (item["slowest_s"], item["slowest"]))
        else:
            tally.add(item)
    if done:
        return None
    marks = [ln for ln in err.splitlines() if ln.startswith("at ")]
    detail = " | ".join(ln.strip() for ln in err.splitlines()[-12:] if ln.strip())
    if not marks:  # the worker failed before its first input: not an input's doing
        raise SystemExit(f"worker for {reader} {lo}..{hi} failed to start: {detail}")
    index = int(marks[-1].split()[1])
    why = f"hang or crash (process ended with {proc.returncode})"
    tally.add(
        {"kind": "untyped", "key": f"all: {why}", "index": index, "seed": "?", "text": detail}
    )
    return index + 1 if index + 1 < hi else None


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n\n")[0])
    ap.add_argument("--inputs", type=int, default=100_000, help="damaged inputs per reader")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (at most 2 here)")
    ap.add_argument("--readers", default=None, help="comma-separated subset of the readers")
    ap.add_argument("--hang-s", type=float, default=60.0, help="an input this slow is a hang")
    ap.add_argument("--write", nargs=2, metavar=("READER", "INDEX"), help="write one input")
    ap.add_argument("--worker", nargs=3, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        _worker(args.worker[0], int(args.worker[1]), int(args.worker[2]), args.hang_s)
        return
    engine = _engine()
    if args.write:
        work = engine.fuzz_dir()
        seed, data = _input(engine, engine.build_seeds(work), args.write[0], int(args.write[1]))
        shutil.rmtree(work, ignore_errors=True)
        out = Path(f"fuzz-{args.write[0]}-{args.write[1]}{seed.ext}")
        out.write_bytes(data)
        print(f"{out}  (seed {seed.name}, group {seed.group!r}, ragged {seed.ragged})")
        return
    readers = args.readers.split(",") if args.readers else list(engine.READERS)
    pending = [
        (r, lo, min(args.inputs, lo + PIECE))
        for r in readers
        for lo in range(0, args.inputs, PIECE)
    ]
    tallies = {r: _Tally() for r in readers}
    running: list[tuple[subprocess.Popen[str], str, int, int]] = []
    t0 = time.perf_counter()
    env_jobs = max(1, min(args.jobs, os.cpu_count() or 1))
    while pending or running:
        while pending and len(running) < env_jobs:
            reader, lo, hi = pending.pop(0)
            running.append((_run(reader, lo, hi, args.hang_s, tallies[reader]), reader, lo, hi))
        proc, reader, lo, hi = running.pop(0)
        resume = _collect(proc, reader, lo, hi, tallies[reader])
        tallies[reader].n += (resume if resume is not None else hi) - lo
        if resume is not None:
            pending.insert(0, (reader, resume, hi))
        bad = len(tallies[reader].bad_inputs)
        elapsed = time.perf_counter() - t0
        print(f"  {reader} {lo}..{hi}: {bad} bad inputs so far ({elapsed:.0f} s)", file=sys.stderr)
    wall = time.perf_counter() - t0
    print(f"fuzz_readers: {args.inputs} damaged inputs per reader, {env_jobs} processes")
    for reader in readers:
        tally = tallies[reader]
        bad = len(tally.bad_inputs)
        printed = sum(tally.counts["printed"].values())
        secs, idx = tally.slowest
        print(
            f"\n{reader}: {tally.n} inputs, {bad} with an untyped exception "
            f"({1e5 * bad / max(tally.n, 1):.0f} per 10^5 inputs), {printed} warnings/log "
            f"lines; slowest input {idx} ({secs * 1e3:.0f} ms)"
        )
        for kind in ("untyped", "printed"):
            for key, count in tally.counts[kind].most_common():
                print(f"  {count:6d}  {key}{' (printed)' if kind == 'printed' else ''}")
                print(f"          e.g. {tally.examples[key]}")
    print(f"\nwall time {wall:.0f} s")


if __name__ == "__main__":
    main()
