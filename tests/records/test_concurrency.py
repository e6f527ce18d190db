"""Several writers of one store at the same moment, on each engine (ISSUE 16, "Numbers"): every
number drawn once, the series without gaps, every record whole, nothing lost.

The writers are real processes released together (writers.py, run as a program): eight
``rotacal certify`` commands on eight plans with ``number = "auto"``, and eight writers keeping
certificates through the Store API, one of them a certification whose rendering fails after its
number was drawn; and, on PostgreSQL, two writers forced to reach the same new rows in opposite
orders. What each record must hold comes from the files on disk and the plans the test wrote,
never from the store.
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import hashlib
import json
import os
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

import pytest
import sqlalchemy as sa
import tomllib

from rotacal.plan.model import Person
from rotacal.records import models as m
from rotacal.records import open_store
from rotacal.records.testing import ThrowawayPostgres

from .certify_plans import CAPTURE, capture_folder_fixture, write_plans  # noqa: F401  (a fixture)
from .conftest import files_of, make_content

WRITERS = Path(__file__).with_name("writers.py")


@pytest.fixture(scope="module")
def run_at_once() -> Iterator[Callable[[Sequence[Mapping[str, Any]]], list[dict[str, Any]]]]:
    """``run_at_once(jobs)``: the jobs of writers.py at once; their outcomes (exit_code, stdout,
    stderr, value …). One writers.py program serves the module."""
    program = subprocess.Popen(
        [sys.executable, str(WRITERS)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
    )
    assert program.stdin is not None and program.stdout is not None

    def run(jobs: Sequence[Mapping[str, Any]]) -> list[dict[str, Any]]:
        assert program.stdin is not None and program.stdout is not None
        program.stdin.write(json.dumps(list(jobs)) + "\n")
        program.stdin.flush()
        answer = program.stdout.readline()
        assert answer, f"writers.py ended (exit code {program.poll()})"
        return list(json.loads(answer))

    yield run
    program.stdin.close()
    program.wait(timeout=60)


def series(count: int) -> list[str]:
    return [f"RC-2026-{n:04d}" for n in range(1, count + 1)]


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def record(session: Any, number: str) -> m.Certificate:
    return session.execute(
        sa.select(m.Certificate).where(m.Certificate.number == number)
    ).scalar_one()


def voided(url: str) -> dict[str, str]:
    with open_store(url).read() as session:
        return dict(session.execute(sa.select(m.VoidedNumber.number, m.VoidedNumber.reason)).all())


def issued(url: str) -> list[str]:
    with open_store(url).read() as session:
        return sorted(session.execute(sa.select(m.Certificate.number)).scalars())


def check_certified(session: Any, number: str, plan: Path) -> None:
    """The record of ``number`` is the whole certificate of ``plan``: the plan's bytes, every
    file of its folder (bytes and SHA-256), every input (the SHA-256 of the file on disk), every
    reported value of the issued results.json, the item, persons and standards of the plan."""
    folder = plan.parent / number
    results = json.loads((folder / "results.json").read_text())
    assert results["certificate_number"] == number
    kept = record(session, number)
    assert kept.plan == plan.read_bytes()
    assert kept.plan_sha256 == results["plan_sha256"]
    assert kept.results == (folder / "results.json").read_text()
    on_disk = {p.name: p.read_bytes() for p in folder.iterdir()}
    assert {f.name: (f.sha256, f.content) for f in kept.files} == {
        name: (sha256(data), data) for name, data in on_disk.items()
    }
    assert kept.inputs, "no inputs kept"
    for i in kept.inputs:
        data = (plan.parent / i.path).read_bytes()
        assert (i.sha256, i.size_bytes) == (sha256(data), len(data)), i.path
    assert {i.path for i in kept.inputs} >= {CAPTURE}
    reported = [q for mr in results["measurements"] for q in mr["reported"]]
    assert reported, "the certificate reports nothing"
    assert [(v.quantity, float(v.value), float(v.expanded)) for v in kept.values] == [
        (q["quantity"], q["value"], q["U"]) for q in reported
    ]
    given = tomllib.loads(plan.read_text(encoding="utf-8"))
    assert [(p.person.name, p.role) for p in kept.persons] == [
        (p["name"], p["role"]) for p in given["person"]
    ]
    assert [s.standard.identifier for s in kept.standards] == [s["id"] for s in given["standard"]]
    assert kept.item.serial == given["item"]["serial"]


def test_eight_certify_commands_at_once_draw_eight_numbers_and_keep_eight_records(
    store_url: str, capture_folder: Path, tmp_path: Path, run_at_once: Any
) -> None:
    plans = write_plans(tmp_path / "plans", capture_folder, 8)
    outcomes = run_at_once([{"certify": [str(p), "--db", store_url]} for p in plans])

    for o in outcomes:
        assert o["exit_code"] == 0, o["stderr"] + o["error"]
    numbers = [o["stdout"].splitlines()[-1].split()[1].rstrip(":") for o in outcomes]
    assert sorted(numbers) == series(8)
    assert issued(store_url) == series(8)
    assert voided(store_url) == {}
    assert sorted(p.name for p in (tmp_path / "plans").glob("RC-*")) == series(8)
    with open_store(store_url).read() as session:
        for plan, number in zip(plans, numbers, strict=True):
            check_certified(session, number, plan)


def test_writers_through_the_store_api_draw_a_series_without_gaps_and_keep_every_record(
    store_url: str, capture_folder: Path, tmp_path: Path, run_at_once: Any
) -> None:
    writers, each = 8, 10
    jobs: list[dict[str, Any]] = [
        {
            "keep": store_url,
            "certificates": [
                {
                    "serial": f"SN-{w % 3}",
                    "date": str(dt.date(2026, 1, 1) + dt.timedelta(days=w * each + i)),
                    "values": {"scale_factor": [f"{w}.{i:03d}", "0.002"], "bias": ["-0.5", "0.1"]},
                }
                for i in range(each)
            ],
        }
        for w in range(writers)
    ]
    # and a certification whose DCC cannot be rendered (a control character in the customer's
    # name), which it finds out only after its number was drawn
    (bad,) = write_plans(
        tmp_path / "bad",
        capture_folder,
        1,
        customer={"name": "Gyro\x01Maker", "address": "2 Sensor Street", "email": "q@example.com"},
    )
    jobs.append({"certify": [str(bad), "--db", store_url]})
    outcomes = run_at_once(jobs)

    *kept, failed = outcomes
    for o in kept:
        assert o["exit_code"] == 0, o["stderr"] + o["error"]
    assert failed["exit_code"] == 2
    assert "control character U+0001" in failed["stderr"]
    assert len(failed["stderr"].strip().splitlines()) == 1
    numbers = [c["number"] for o in kept for c in o["value"]]
    assert len(numbers) == len(set(numbers)) == writers * each
    gaps = voided(store_url)
    assert len(gaps) == 1
    ((lost, reason),) = gaps.items()
    assert "control character U+0001" in reason
    assert sorted([*numbers, lost]) == series(writers * each + 1)
    assert issued(store_url) == sorted(numbers)
    assert not [p for p in (tmp_path / "bad").iterdir() if p.name.startswith(("RC-", ".rotacal"))]

    with open_store(store_url).read() as session:
        for job, o in zip(jobs[:-1], kept, strict=True):
            for given, written in zip(job["certificates"], o["value"], strict=True):
                number = written["number"]
                c = record(session, number)
                values = {k: (value, U) for k, (value, U) in given["values"].items()}
                date = dt.date.fromisoformat(given["date"])
                assert (c.item.serial, c.issue_date, c.plan, c.plan_sha256) == (
                    given["serial"],
                    date,
                    written["plan"].encode(),
                    written["plan_sha256"],
                )
                assert [(v.quantity, v.value, v.expanded) for v in c.values] == [
                    (k, value, U) for k, (value, U) in values.items()
                ]
                content = make_content(values, number=number)  # files_of reads its number
                assert {f.name: (f.sha256, f.content) for f in c.files} == {
                    name: (sha256(data), data) for name, data in files_of(content).items()
                }
                assert [(i.path, i.sha256, i.size_bytes) for i in c.inputs] == [
                    ("rates.npz", "ab" * 32, 1234)
                ]
                assert [(p.person.name, p.role) for p in c.persons] == [
                    ("A. Operator", "performed"),
                    ("B. Manager", "approved"),
                ]
                assert [s.standard.identifier for s in c.standards] == ["STD-17"]


def test_two_writers_naming_the_same_new_persons_in_another_order_both_keep_their_record(
    postgres: ThrowawayPostgres,
) -> None:
    """Two stations certify at the same time, each the first certificate of two new persons,
    one naming them as (performed A, approved B), the other as (performed B, approved A): both
    certificates are kept. The order in which the store's transactions reach the rows is forced
    with a third transaction that holds a person row of each plan until both writers wait on it;
    then each holds the row the other needs next."""
    url = postgres.new_database()
    open_store(url).engine.dispose()  # the schema
    a, b = Person("A. New", "performed"), Person("B. New", "approved")

    def content(first: Person, gate: str, second: Person, day: int) -> Any:
        c = make_content({"bias": ("0.1", "0.01")}, number=f"RC-2026-{day:04d}", serial=gate)
        persons = (first, Person(gate, "performed"), second)
        plan = dataclasses.replace(c.plan, persons=persons, issue_date=dt.date(2026, 1, day))
        return dataclasses.replace(c, plan=plan, plan_sha256=f"{day:064d}")

    errors: list[BaseException] = []

    def write(c: Any) -> None:
        station = open_store(url)  # a store of its own, as on another test station
        try:
            with station.keep(c, files_of(c)):
                pass
        except BaseException as e:
            errors.append(e)
        finally:
            station.engine.dispose()

    writers = [
        threading.Thread(target=write, args=(content(a, "Gate 1", b, 1),), daemon=True),
        threading.Thread(target=write, args=(content(b, "Gate 2", a, 2),), daemon=True),
    ]
    engine = sa.create_engine(url)
    try:
        with engine.connect() as gate, engine.connect() as watch:
            gate.begin()
            for name in ("Gate 1", "Gate 2"):  # held, uncommitted: the writers wait here
                gate.execute(sa.insert(m.Person).values(name=name, title=""))
            for w in writers:
                w.start()
            for _ in range(600):  # until both writers wait on the gate
                waiting = watch.execute(
                    sa.text(
                        "SELECT count(*) FROM pg_stat_activity WHERE wait_event_type = 'Lock' "
                        "AND datname = current_database()"
                    )
                ).scalar_one()
                watch.rollback()  # the activity view is read once per transaction
                if waiting == 2:
                    break
                time.sleep(0.05)
            assert waiting == 2, ("the writers did not reach the gate", errors)
            gate.rollback()
        for w in writers:
            w.join(timeout=120)
    finally:
        engine.dispose()
    assert not errors, [str(e) for e in errors]
    assert issued(url) == ["RC-2026-0001", "RC-2026-0002"]
