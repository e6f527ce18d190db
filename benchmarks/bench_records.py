"""What keeping a certificate's record costs, and many writers at once, on SQLite and PostgreSQL.

First makes a real certificate: the example plan (``rotacal certify --example``), its captures
simulated as its comments say, certified in this process without a store — its folder's files
(PDF, DCC XML, results.json, figures) and its content are what every record below keeps. Then,
all from this one run:

(a) keeping one certificate's record (``Store.keep``: every row and every file of the folder in
    one transaction, committed), ``--repeat`` times on SQLite (the default store: WAL,
    synchronous=FULL) and on PostgreSQL (a throwaway server on loopback, with PostgreSQL's default
    of flushing every commit to disk), alternating with the baseline: writing the same bytes to
    files, each fsync'ed, and the folder fsync'ed. Also the whole records part of one
    ``certify`` (check_plan, check_unissued, draw_number, keep). The issue's bar: under 50 ms on
    SQLite.
(b) ``--writers`` processes × ``--each`` certificates, released together
    (:func:`rotacal.records.testing.at_once`), drawing numbers and keeping records in a fresh
    store of each engine: the distinct numbers, whether the series has no gap, the complete
    records (every table's rows per certificate; every file's SHA-256 recomputed from the bytes
    in the store), the wall time and the throughput.

Prints medians and ratios, the peak RSS of this process and of the writers. No asserts.

Run: ``python benchmarks/bench_records.py [--repeat 50] [--writers 8] [--each 50]``
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import hashlib
import io
import os
import resource
import shlex
import shutil
import statistics
import tempfile
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import sqlalchemy as sa

from rotacal.certificate.content import CertificateContent
from rotacal.certificate.issue import certify
from rotacal.cli import main as rotacal
from rotacal.cli.certify import example_plan
from rotacal.records import Store, open_store
from rotacal.records import models as m
from rotacal.records.testing import ThrowawayPostgres, at_once


def run_rotacal(*args: str) -> None:
    """``rotacal ARGS`` in this process (its output discarded)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
        try:
            rotacal(list(args))
        except SystemExit as e:
            if e.code:
                raise RuntimeError(f"rotacal {' '.join(args)}: {out.getvalue()}") from None


def example_certificate(folder: Path) -> tuple[CertificateContent, dict[str, bytes]]:
    """The example plan certified in ``folder``, its captures simulated by the commands its
    comments give; returns the content and the certificate folder's files."""
    text = example_plan()
    (folder / "plan.toml").write_text(text, encoding="utf-8")
    for line in text.splitlines():
        command = line.lstrip("# ")
        if command.startswith("rotacal simulate "):
            words = shlex.split(command)
            at = words.index("--out") + 1
            words[at] = str(folder / words[at])
            run_rotacal(*words[1:])
    with contextlib.redirect_stdout(io.StringIO()):
        issued = certify(folder / "plan.toml")
    files = {p.name: p.read_bytes() for p in sorted(issued.folder.iterdir())}
    return issued.content, files


def variant(content: CertificateContent, tag: str, number: str) -> CertificateContent:
    """The certificate under another number, as another calibration (its own plan_sha256)."""
    digest = hashlib.sha256(f"{content.plan_sha256}:{tag}".encode()).hexdigest()
    return dataclasses.replace(content, number=number, plan_sha256=digest)


def timed(action: Callable[[], Any]) -> float:
    start = time.perf_counter()
    action()
    return (time.perf_counter() - start) * 1000.0


def keep(store: Store, content: CertificateContent, files: Mapping[str, bytes]) -> None:
    with store.keep(content, files):
        pass  # certify publishes the folder here


def records_part_of_certify(
    store: Store, content: CertificateContent, files: Mapping[str, bytes], tag: str
) -> None:
    """What certify asks of the store for a plan with ``number = "auto"``."""
    plan = dataclasses.replace(content.plan, number="auto")
    drafted = dataclasses.replace(variant(content, tag, "auto"), plan=plan)
    store.check_plan(plan)
    store.check_unissued(plan, drafted.plan_sha256)
    number = store.draw_number(plan.issue_date)
    keep(store, dataclasses.replace(drafted, number=number), files)


def write_files(folder: Path, files: Mapping[str, bytes]) -> None:
    """The baseline: the same bytes as files, each flushed to disk, then the folder."""
    folder.mkdir()
    for name, data in files.items():
        with open(folder / name, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def single(
    url: str, content: CertificateContent, files: Mapping[str, bytes], repeat: int, scratch: Path
) -> dict[str, list[float]]:
    """(a): per repetition, keep / the baseline / the records part of certify [ms]."""
    store = open_store(url)
    times: dict[str, list[float]] = {"keep": [], "files": [], "certify": []}
    for i in range(repeat + 3):  # the first three warm up
        kept = variant(content, f"single-{i}", f"RC-BENCH-{i:06d}")
        t_keep = timed(lambda kept=kept: keep(store, kept, files))
        target = scratch / f"files-{i}"
        t_files = timed(lambda target=target: write_files(target, files))
        shutil.rmtree(target)
        t_certify = timed(lambda i=i: records_part_of_certify(store, content, files, f"c-{i}"))
        if i >= 3:
            times["keep"].append(t_keep)
            times["files"].append(t_files)
            times["certify"].append(t_certify)
    store.engine.dispose()
    return times


def writer(
    url: str, w: int, each: int, content: CertificateContent, files: Mapping[str, bytes]
) -> Callable[[], tuple[list[str], float]]:
    def run() -> tuple[list[str], float]:
        """The numbers kept, and this writer's peak RSS [MB]."""
        store = open_store(url)
        numbers = []
        for i in range(each):
            number = store.draw_number(content.plan.issue_date)
            keep(store, variant(content, f"writer-{w}-{i}", number), files)
            numbers.append(number)
        return numbers, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

    return run


def complete(url: str, content: CertificateContent, files: Mapping[str, bytes]) -> int:
    """How many records hold every row and every file of their certificate (each file's
    SHA-256 recomputed from the bytes the store gives back)."""
    expected = {
        m.CertificateFile: len(files),
        m.CertificateInput: sum(len(mr.captures) for mr in content.measurements),
        m.ReportedValue: sum(len(mr.quantities) for mr in content.measurements),
        m.CertificatePerson: len(content.plan.persons),
        m.CertificateStandard: len(content.plan.standards),
    }
    digests = {name: hashlib.sha256(data).hexdigest() for name, data in files.items()}
    store = open_store(url)
    with store.read() as session:
        whole = set(session.execute(sa.select(m.Certificate.id)).scalars())
        for model, count in expected.items():
            rows = session.execute(
                sa.select(model.certificate_id, sa.func.count()).group_by(model.certificate_id)  # type: ignore[attr-defined]  # type: ignore[attr-defined]
            ).all()
            counted = {cid: n for cid, n in rows}
            whole = {cid for cid in whole if counted.get(cid, 0) == count}
        f = m.CertificateFile
        kept = session.execute(
            sa.select(f.certificate_id, f.name, f.sha256, f.content).execution_options(
                yield_per=64  # a few files at a time in memory
            )
        )
        for cid, name, sha256, data in kept:
            if not sha256 == digests.get(name) == hashlib.sha256(data).hexdigest():
                whole.discard(cid)
    store.engine.dispose()
    return len(whole)


def many(
    url: str, content: CertificateContent, files: Mapping[str, bytes], writers: int, each: int
) -> None:
    """(b): the writers at once; prints what they kept."""
    open_store(url).engine.dispose()  # the schema, before the writers start
    start = time.perf_counter()
    outcomes = at_once([writer(url, w, each, content, files) for w in range(writers)])
    wall = time.perf_counter() - start
    failed = [o for o in outcomes if o.exit_code]
    numbers = [n for o in outcomes if o.value for n in o.value[0]]
    rss = max((o.value[1] for o in outcomes if o.value), default=0.0)
    year = content.plan.issue_date.year
    series = [f"RC-{year}-{n:04d}" for n in range(1, writers * each + 1)]
    print(
        f"  writers that failed:          {len(failed)}"
        + (f"  ({failed[0].error})" if failed else "")
    )
    print(f"  numbers drawn and kept:       {len(numbers)}  ({len(set(numbers))} distinct)")
    print(f"  the series without a gap:     {sorted(numbers) == series}")
    print(f"  complete records:             {complete(url, content, files)}")
    print(f"  wall time:                    {wall:6.2f} s")
    print(f"  throughput:                   {len(numbers) / wall:6.1f} certificates/s "
          f"({wall / max(1, len(numbers)) * 1000:.1f} ms each, all writers together)")  # fmt: skip
    print(f"  peak RSS of a writer:         {rss:6.0f} MB")


def summary(name: str, ms: list[float]) -> str:
    q = statistics.quantiles(ms, n=10, method="inclusive")
    return f"{name:44s} {statistics.median(ms):7.1f} ms  (p90 {q[-1]:6.1f}, max {max(ms):6.1f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=50, help="repetitions of (a)")
    parser.add_argument("--writers", type=int, default=8, help="concurrent writers of (b)")
    parser.add_argument("--each", type=int, default=50, help="certificates per writer of (b)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-records-") as tmp:
        folder = Path(tmp)
        (folder / "example").mkdir()
        content, files = example_certificate(folder / "example")
        size = sum(len(d) for d in files.values())
        print(f"the certificate: the example plan, {len(content.measurements)} measurements; "
              f"{len(files)} files, {size / 1e3:.0f} kB")  # fmt: skip
        server = ThrowawayPostgres(durable=True)
        try:
            engines = {
                "SQLite": (f"sqlite:///{folder / 'a.sqlite'}", f"sqlite:///{folder / 'b.sqlite'}"),
                "PostgreSQL": (server.new_database(), server.new_database()),
            }
            print(f"(a) one certificate's record, median of {args.repeat}:")
            for name, (url, _) in engines.items():
                times = single(url, content, files, args.repeat, folder)
                keep_ms, files_ms = times["keep"], times["files"]
                print(summary(f"  {name}: keep() (bar on SQLite: < 50 ms)", keep_ms))
                print(summary("    baseline: the same bytes to files, fsync", files_ms))
                ratio = statistics.median(keep_ms) / statistics.median(files_ms)
                print(f"    ratio keep / baseline                    {ratio:7.2f}")
                print(summary("    records part of certify (+checks, draw)", times["certify"]))
            for name, (_, url) in engines.items():
                print(f"(b) {args.writers} writers × {args.each} certificates at once, {name}:")
                many(url, content, files, args.writers, args.each)
        finally:
            server.stop()
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS of this process: {own:.0f} MB")


if __name__ == "__main__":
    main()
