"""Concurrent writers of one records store, for test_concurrency.py (run as a program, not
collected): ``python writers.py`` reads batches of jobs from its standard input, a JSON list on
each line; it runs every job of a batch in a process of its own, all released together
(:func:`rotacal.records.testing.at_once`), and answers with their outcomes as a JSON list on one
line, in the jobs' order.

A job is one of
- ``{"certify": [ARG, …]}``: the command ``rotacal certify ARG …``;
- ``{"keep": URL, "certificates": [{"serial": S, "date": "YYYY-MM-DD", "values": {KEY: [VALUE,
  U]}}, …]}``: those certificates, made to order (conftest.py ``make_content``), kept one after
  the other through the Store API, each with a number drawn as certify draws it; the task
  returns, for each, the number, the plan's text and the plan_sha256 it gave the store.

rotacal is imported, and warmed up (:func:`warm_up`), once, here before the processes are
forked: each process then starts its work at once instead of spending seconds importing NumPy,
SciPy and Matplotlib, and one program serves all the tests of a module.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import json
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rotacal.cli import main
from rotacal.records import open_store
from rotacal.records.testing import at_once

sys.path.insert(0, str(Path(__file__).parent))
from conftest import files_of, make_content


def _keeper(url: str, certificates: list[dict[str, Any]]) -> Callable[[], list[dict[str, str]]]:
    def run() -> list[dict[str, str]]:
        store = open_store(url)
        kept = []
        for c in certificates:
            content = make_content(
                {key: (value, U) for key, (value, U) in c["values"].items()},
                number="auto",
                serial=c["serial"],
                date=dt.date.fromisoformat(c["date"]),
            )
            number = store.draw_number(content.plan.issue_date)
            content = dataclasses.replace(content, number=number)
            with store.keep(content, files_of(content)):
                pass
            kept.append(
                {
                    "number": number,
                    "plan": content.plan.text.decode(),
                    "plan_sha256": content.plan_sha256,
                }
            )
        return kept

    return run


def _certifier(args: list[str]) -> Callable[[], None]:
    return lambda: main(["certify", *args])


def task(job: dict[str, Any]) -> Callable[[], Any]:
    if "certify" in job:
        return _certifier(job["certify"])
    return _keeper(job["keep"], job["certificates"])


def warm_up() -> None:
    """Do here, once, what every process would do first: import what certify imports lazily
    (rotacal.gyro's modules for the tests' rotation test: the package is lazy, and its names
    pull in SciPy's stats, ~2 s of CPU that each of eight forked writers paid again; the
    PostgreSQL driver), parse the DCC schema, load the store's migrations. Not a whole
    certification: the PDF renderer starts threads, and a process forked from one with threads
    may hang."""
    import psycopg  # noqa: F401
    import rich.progress  # noqa: F401
    import typst  # noqa: F401

    import rotacal.certificate.figures
    import rotacal.certificate.issue
    import rotacal.certificate.pdf
    import rotacal.cli._provenance
    import rotacal.gyro
    from rotacal.certificate.dcc import _schema

    for name in rotacal.gyro.__all__:  # each lazy name imports its module (none starts a thread)
        getattr(rotacal.gyro, name)

    _schema()
    with tempfile.TemporaryDirectory() as folder:
        open_store(f"sqlite:///{folder}/warm.sqlite")


if __name__ == "__main__":
    warm_up()
    for line in sys.stdin:
        outcomes = at_once([task(job) for job in json.loads(line)])
        print(json.dumps([dataclasses.asdict(o) for o in outcomes]), flush=True)
