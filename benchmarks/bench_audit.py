"""What the audit trail costs: keeping a certificate with its events, and checking a store's chains,
on SQLite and PostgreSQL.

First makes a real certificate (the example plan, as ``bench_records.py`` does); every record
below keeps its folder's files. Then, all from this one run, on each engine:

(a) ``Store.keep`` of one certificate with its audit events (an explicit number: the ``draft`` and
    ``issued`` events), alternating ``--repeat`` times with the same ``keep`` whose audit events
    are left out (the baseline: the record alone, as before the trail): medians and the ratio.
(b) a store of ``--certificates`` certificates, every fifth superseding the one before (so three
    events for those), checked whole (``rotacal records audit``'s
    :func:`rotacal.records.query.audit_trail`: every hash recomputed, every chain linked, every
    record matched), against the baseline of reading the same events (``events_of``): the time
    of each, the events per second and the ratio.

Prints medians and ratios and the peak RSS of this process. No asserts.

Run: ``python benchmarks/bench_audit.py [--repeat 30] [--certificates 500]``
"""

from __future__ import annotations

import argparse
import dataclasses
import resource
import statistics
import tempfile
from pathlib import Path

import rotacal.records.store as store_module
from bench_records import example_certificate, timed, variant
from rotacal.records import open_store
from rotacal.records.audit import events_of
from rotacal.records.query import audit_trail
from rotacal.records.testing import ThrowawayPostgres


def keep_cost(url: str, content, files, repeat: int) -> tuple[float, float]:
    """Median ms of keep() with and without the audit events, alternating in one store."""
    store = open_store(url)
    real = store_module.record_issue
    with_trail, without = [], []
    try:
        for i in range(repeat):
            for kind, sink in (("with", with_trail), ("without", without)):
                store_module.record_issue = real if kind == "with" else _nothing
                kept = variant(content, f"{kind}-{i}", f"K-{kind}-{i:05d}")

                def keep(kept=kept) -> None:
                    with store.keep(kept, files):
                        pass

                sink.append(timed(keep))
    finally:
        store_module.record_issue = real
        store.close()
    return statistics.median(with_trail), statistics.median(without)


def _nothing(*_args: object, **_kwargs: object) -> None:
    return None


def check_cost(url: str, content, files, count: int) -> tuple[int, float, float, bool]:
    """(events, ms to check the whole trail, ms to read its events, intact) of a store of
    ``count`` certificates, every fifth superseding the one before."""
    store = open_store(url)
    previous = None
    for i in range(count):
        supersedes = previous if i % 5 == 4 else None
        kept = variant(content, f"chain-{i}", f"C-{i:06d}")
        kept = dataclasses.replace(kept, plan=dataclasses.replace(kept.plan, supersedes=supersedes))
        with store.keep(kept, files):
            pass
        previous = kept.number
    checks, reads = [], []
    trail: dict = {}
    for _ in range(3):  # best of three
        checks.append(timed(lambda: trail.update(audit_trail(store))))
        with store.begin(read_only=True) as connection:
            reads.append(timed(lambda connection=connection: events_of(connection)))
    store.close()
    return len(trail["events"]), min(checks), min(reads), bool(trail["intact"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=30)
    parser.add_argument("--certificates", type=int, default=500)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="rotacal-bench-audit-") as name:
        folder = Path(name)
        content, files = example_certificate(folder)
        size = sum(len(b) for b in files.values())
        print(f"the certificate: the example plan, {len(files)} files, {size / 1e3:.0f} kB")
        server = ThrowawayPostgres(durable=True)
        try:
            urls = {
                "SQLite": lambda tag: f"sqlite:///{folder}/{tag}.sqlite",
                "PostgreSQL": lambda _tag: server.new_database(),
            }
            for engine, url in urls.items():
                with_ms, without_ms = keep_cost(url("keep"), content, files, args.repeat)
                print(f"{engine}:")
                print(f"  (a) keep() with its audit events, median of {args.repeat}: "
                      f"{with_ms:7.1f} ms")  # fmt: skip
                print(f"      baseline: keep() without them            {without_ms:7.1f} ms")
                print(f"      ratio                                   {with_ms / without_ms:7.2f}")
                events, check_ms, read_ms, intact = check_cost(
                    url("chain"), content, files, args.certificates
                )
                print(f"  (b) the trail of {args.certificates} certificates: {events} events, "
                      f"intact = {intact}")  # fmt: skip
                print(f"      check (hashes, links, records), best of 3 {check_ms:7.1f} ms "
                      f"({events / check_ms * 1e3:,.0f} events/s)")  # fmt: skip
                print(f"      baseline: reading the events             {read_ms:7.1f} ms")
                print(f"      ratio                                   {check_ms / read_ms:7.2f}")
        finally:
            server.stop()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS of this process: {peak:.0f} MB")


if __name__ == "__main__":
    main()
