"""What ``rotacal records history`` costs over 1,000 certificates of one item, on both engines.

Makes a records store on each engine — SQLite in a temporary folder, PostgreSQL on a throwaway
server (:class:`rotacal.records.testing.ThrowawayPostgres`) — and keeps ``--certificates``
certificates of one item in it the way ``rotacal certify`` does (``Store.keep``, one transaction
each), every one reporting ``--quantities`` quantities with limits, plus a few certificates of
other items. Then, in a fresh process per engine (so that its peak RSS is the reading alone),
times best of ``--repeat``:

- ``item_history(store, serial)``: the whole history (the query, the parsing of the printed
  decimals, the drift fits and next_due);
- the baseline: the bare SELECT of the same rows (items ⋈ certificates ⋈ reported_values of that
  serial) through SQLAlchemy's core, every row fetched;

and prints both, their ratio, the rows read, the process's RSS once the store is open and its
peak, and (once) the time to make and render the ``--report`` page (a figure per quantity). The issue's bar is
history under 1 s on both engines. No asserts.

Run: ``python benchmarks/bench_records_history.py [--certificates 1000] [--quantities 4]
[--repeat 7]``
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: The bare SELECT of the rows a history reads (the baseline).
BARE_SELECT = """
SELECT c.number, c.end_date, c.issue_date, c.supersedes, v.measurement, v.measurement_name,
       v.quantity, v.name, v.unit, v.value, v.expanded, v.coverage_factor, v.limit_min,
       v.limit_max, v.verdict
FROM items i JOIN certificates c ON c.item_id = i.id
JOIN reported_values v ON v.certificate_id = c.id
WHERE i.serial = :serial
ORDER BY c.end_date, c.id, v.measurement, v.position
"""


def fill(url: str, certificates: int, quantities: int) -> float:
    """Keep ``certificates`` certificates of SN-0001 (and 20 of other items) in the store at
    ``url``; returns the mean time to keep one [s]."""
    sys.path.insert(0, str(ROOT))
    import numpy as np
    from tests.records.conftest import files_of, make_content

    from rotacal.records import open_store

    store = open_store(url)
    rng = np.random.default_rng(16)
    start = dt.date(2000, 1, 1)
    keys = [f"quantity_{i}" for i in range(quantities)]
    spent = 0.0
    for n in range(certificates + 20):
        serial = "SN-0001" if n < certificates else f"SN-{n:04d}"
        day = start + dt.timedelta(days=7 * n)
        years = (day - start).days / 365.25
        values = {
            key: (f"{100 + (i + 1) * 0.3 * years + rng.normal(0, 0.2):.2f}", "0.50")
            for i, key in enumerate(keys)
        }
        limits = {key: ("90", "130") for key in keys}
        content = make_content(values, limits=limits, date=day, serial=serial)
        begin = time.perf_counter()
        content = dataclasses.replace(content, number=store.draw_number(day))
        with store.keep(content, files_of(content)):
            pass
        spent += time.perf_counter() - begin
    return spent / (certificates + 20)


def measure(url: str, repeat: int) -> dict[str, float]:
    """Time the history and the bare SELECT in this process (the child's work)."""
    import sqlalchemy as sa

    from rotacal.records import open_store
    from rotacal.records.history import item_history

    store = open_store(url)
    before_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss

    def best(run) -> float:
        times = []
        for _ in range(repeat):
            begin = time.perf_counter()
            run()
            times.append(time.perf_counter() - begin)
        return min(times)

    def bare() -> int:
        with store.engine.connect() as connection:
            return len(connection.execute(sa.text(BARE_SELECT), {"serial": "SN-0001"}).all())

    history = item_history(store, "SN-0001")
    out = {
        "rows": bare(),
        "history_s": best(lambda: item_history(store, "SN-0001")),
        "select_s": best(bare),
        "calibrations": len(history.calibrations),
        "quantities": len(history.drift_per_year),
        "next_due": history.next_due.date.isoformat(),
        "rss_before_mb": before_kib / 1024,
        "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }
    from rotacal.report.history import history_report  # after the RSS: matplotlib is large
    from rotacal.report.html import render_html

    begin = time.perf_counter()
    render_html(history_report(history, store.shown))
    out["report_s"] = time.perf_counter() - begin
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--certificates", type=int, default=1000)
    parser.add_argument("--quantities", type=int, default=4)
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--measure", metavar="URL", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.measure:
        print(json.dumps(measure(args.measure, args.repeat)))
        return

    from rotacal.records.testing import ThrowawayPostgres

    print(
        f"{args.certificates} certificates of one item × {args.quantities} quantities "
        f"(+20 of other items), best of {args.repeat}"
    )
    print(
        f"{'engine':<11}{'keep/cert':>11}{'history':>10}{'bare SELECT':>13}{'ratio':>7}"
        f"{'rows':>7}{'RSS open':>10}{'peak RSS':>10}{'report':>9}  next_due"
    )
    postgres = ThrowawayPostgres()
    try:
        with tempfile.TemporaryDirectory() as folder:
            urls = {
                "SQLite": f"sqlite:///{Path(folder) / 'records.sqlite'}",
                "PostgreSQL": postgres.new_database(),
            }
            for engine, url in urls.items():
                keep_s = fill(url, args.certificates, args.quantities)
                child = subprocess.run(
                    [sys.executable, __file__, "--measure", url, "--repeat", str(args.repeat)],
                    capture_output=True,
                    text=True,
                    check=True,
                )
                r = json.loads(child.stdout)
                print(
                    f"{engine:<11}{keep_s * 1e3:>8.1f} ms{r['history_s'] * 1e3:>7.1f} ms"
                    f"{r['select_s'] * 1e3:>10.1f} ms{r['history_s'] / r['select_s']:>7.2f}"
                    f"{r['rows']:>7d}{r['rss_before_mb']:>7.0f} MB{r['peak_rss_mb']:>7.0f} MB"
                    f"{r['report_s']:>7.1f} s  {r['next_due']}"
                )
    finally:
        postgres.stop()


if __name__ == "__main__":
    main()
