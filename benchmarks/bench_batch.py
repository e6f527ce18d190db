"""What ``rotacal batch`` gains on Dask distributed, and what Dask costs a plan.

Writes ``--plans`` twin plans of a gyro end-of-line test (``rotacal.batch.testing``: each unit its
own three captures and a plan of three measurements — scale factor, triad, rotation test), then, in
this order and each into a store and folder of its own (SQLite, written by the client):

- **serial**: ``certify()`` of every plan, one after the other, in this process (the baseline);
- **1 worker** and **2 workers**: ``run_batch`` on a ``LocalCluster`` of that many worker processes;
- **resumed**: the 2-worker batch run again, every plan certified already (all skipped);
- with ``--postgres``: the 2-worker batch against a throwaway PostgreSQL server, written by the
  workers directly.

Each process imports rotacal before its clock starts (the cluster's start and the workers' imports
are printed apart). Prints plans per second, the speedup of 2 workers over 1 (the issue's bar:
≥ 1.7), Dask's overhead a plan — (1-worker batch − serial) / plans (bar: ≤ 50 ms) — and the resumed
batch's seconds (bar: < 5 s), with the client's peak RSS. No asserts.

Run: ``python benchmarks/bench_batch.py [--plans 200] [--postgres]``
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from distributed import Client

from rotacal.batch import run_batch
from rotacal.batch.cluster import dask_client
from rotacal.batch.testing import write_twin_plans


def _warm() -> None:
    """Import what a plan's certification uses (in the process that calls it)."""
    import rotacal.certificate.issue  # noqa: F401
    from rotacal.cli import cli

    cli.load_all()


@contextmanager
def cluster(workers: int) -> Iterator[tuple[Client, float]]:
    """A client of a warmed local cluster as ``rotacal batch --workers`` makes it, and the
    seconds its start and warm-up took."""
    start = time.perf_counter()
    with dask_client(workers, None, None) as client:
        client.run(_warm)
        yield client, time.perf_counter() - start


def serial(plans: list[Path], folder: Path) -> float:
    """Every plan certified in this process, one after the other (s)."""
    from rotacal.certificate.issue import certify
    from rotacal.records import open_store

    out = folder / "serial"
    out.mkdir()
    store = open_store(f"sqlite:///{folder / 'serial.sqlite'}")
    start = time.perf_counter()
    for plan in plans:
        certify(plan, registry=store, into=out)
    seconds = time.perf_counter() - start
    store.close()
    return seconds


def batch(
    plans: list[Path], folder: Path, name: str, workers: int, url: str | None = None
) -> float:
    """A batch of ``plans`` on a new local cluster of ``workers``, into the store at ``url``
    [default: a new SQLite file]; prints and returns its seconds (without the cluster's start)."""
    with cluster(workers) as (client, started):
        url = url or f"sqlite:///{folder / f'{name}.sqlite'}"
        t = time.perf_counter()
        result = run_batch(plans, out=folder / name, db=url, client=client)
        seconds = time.perf_counter() - t
    counts = {s: result.count(s) for s in ("issued", "skipped", "failed")}
    print(
        f"{name:<24}{seconds:8.2f} s  {len(plans) / seconds:6.2f} plans/s  "
        f"(cluster start and warm-up {started:.1f} s; {counts})"
    )
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plans", type=int, default=200)
    parser.add_argument(
        "--postgres", action="store_true", help="also a 2-worker batch on PostgreSQL"
    )
    args = parser.parse_args()
    _warm()
    with tempfile.TemporaryDirectory(prefix="rotacal-bench-batch-") as tmp:
        folder = Path(tmp)
        t = time.perf_counter()
        plans = write_twin_plans(folder / "plans", args.plans)
        print(
            f"{args.plans} twin plans of 3 measurements written in {time.perf_counter() - t:.1f} s"
        )
        base = serial(plans, folder)
        print(f"{'serial (this process)':<24}{base:8.2f} s  {len(plans) / base:6.2f} plans/s")
        one = batch(plans, folder, "1 worker", 1)
        two = batch(plans, folder, "2 workers", 2)
        with cluster(2) as (client, _):
            t = time.perf_counter()
            resumed = run_batch(
                plans,
                out=folder / "2 workers",
                db=f"sqlite:///{folder / '2 workers.sqlite'}",
                client=client,
            )
            again = time.perf_counter() - t
        print(f"{'resumed (all done)':<24}{again:8.2f} s  ({resumed.count('skipped')} skipped)")
        if args.postgres:
            from rotacal.records.testing import ThrowawayPostgres

            server = ThrowawayPostgres(durable=True)
            try:
                batch(plans, folder, "2 workers, PostgreSQL", 2, server.new_database())
            finally:
                server.stop()
        print(f"speedup 2 workers / 1 worker:   {one / two:.2f}x  (bar: >= 1.7)")
        print(
            f"Dask overhead a plan:           {(one - base) / len(plans) * 1e3:.1f} ms  (bar: <= 50 ms)"
        )
        print(f"resumed batch, all skipped:     {again:.2f} s  (bar: < 5 s)")
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        print(f"peak RSS of this (client) process: {rss:.0f} MB")


if __name__ == "__main__":
    main()
