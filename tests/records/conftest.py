"""Fixtures of the records tests: a store on each engine (SQLite in a temporary folder, and a real
PostgreSQL server started on loopback for the session) and certificates made to order."""

from __future__ import annotations

import dataclasses
import datetime as dt
import itertools
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import pytest

from rotacal.certificate.content import (
    CaptureRef,
    CertificateContent,
    Conformity,
    MeasurementResult,
    ReportedQuantity,
)
from rotacal.plan.model import Conditions, Contact, Item, Person, Plan, Standard

ENGINES = ("sqlite", "postgresql")
_PLANS = itertools.count(1)


@pytest.fixture(params=ENGINES)
def store_url(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """An empty store's URL, once per engine."""
    if request.param == "sqlite":
        return f"sqlite:///{tmp_path / 'records.sqlite'}"
    return request.getfixturevalue("postgres").new_database()


def make_plan(
    *,
    number: str = "auto",
    date: dt.date = dt.date(2026, 11, 25),
    serial: str = "SN-0001",
    supersedes: str | None = None,
    path: Path = Path("/lab/plans/plan.toml"),
    text: bytes | None = None,
) -> Plan:
    """A plan as read, for one gyro; ``text`` (the plan's bytes) differs per date and serial."""
    # each plan made here is another calibration (the store certifies a plan once) unless the
    # test gives the plan's bytes
    body = text if text is not None else f"plan {next(_PLANS)} of {serial} on {date}".encode()
    return Plan(
        path=path,
        text=body,
        data={},
        number=number,
        start_date=date,
        end_date=date,
        issue_date=date,
        laboratory=Contact("Rate Lab", "1 Test Road", "lab@example.org"),
        customer=Contact("Gyro Maker Ltd", "2 Sensor Street", "q@example.com"),
        persons=(Person("A. Operator", "performed"), Person("B. Manager", "approved", "Head")),
        item=Item("gyroscope", "Gyro Maker Ltd", "GM-300", serial),
        standards=(Standard("Rate table encoder", "STD-17", "CAL-2026-123", dt.date(2030, 6, 30)),),
        conditions=Conditions(temperature_c=23.0),
        measurements=(),
        supersedes=supersedes,
    )


def quantity(key: str, value: str, U: str, unit: str = "ppm") -> ReportedQuantity:
    return ReportedQuantity(key, key.replace("_", " "), unit, "\\ppm", value, U, "2.00", "0.95")


def make_content(
    values: Mapping[str, tuple[str, str]],
    *,
    limits: Mapping[str, tuple[str, str]] | None = None,
    number: str = "RC-2026-0001",
    plan_sha256: str | None = None,
    **plan_args: object,
) -> CertificateContent:
    """A certificate of one measurement reporting ``values`` (key → (value, U) as printed), with
    conformity statements for ``limits`` (key → (min, max), "" where open)."""
    plan = make_plan(**plan_args)  # type: ignore[arg-type]
    quantities = tuple(quantity(k, v, u) for k, (v, u) in values.items())
    conformity = tuple(
        Conformity(k, k, "ppm", values[k][0], values[k][1], lo, hi, "simple", "pass", "ok")
        for k, (lo, hi) in (limits or {}).items()
    )
    measurement = MeasurementResult(
        index=1,
        name="Scale factor",
        command="gyro scale-factor",
        method="m",
        references=(),
        captures=(CaptureRef("rates.npz", "ab" * 32, 1234),),
        options={},
        results={"scale_factor": 1.0},
        quantities=quantities,
        conformity=conformity,
        decision_rule="simple",
    )
    from rotacal.certificate.issue import plan_sha256 as digest_of

    captures = [c.sha256 for c in measurement.captures]
    return CertificateContent(
        number=number,
        plan=plan,
        plan_sha256=plan_sha256 or digest_of(plan.text, captures),
        software_version="0.1.0",
        measurements=(measurement,),
    )


def files_of(content: CertificateContent) -> dict[str, bytes]:
    """Stand-ins of a certificate folder's files (the store keeps whatever bytes it is given)."""
    return {
        "results.json": f'{{"certificate_number": "{content.number}"}}\n'.encode(),
        "certificate.pdf": b"%PDF-1.7 " + content.number.encode(),
        "certificate.xml": b"<dcc/>",
    }


@pytest.fixture
def issue() -> Callable[..., CertificateContent]:
    """``issue(store, values, number=…, date=…, …)``: keep a certificate made to order in
    ``store`` the way certify does (draw the number when it is "auto"); returns its content."""

    def run(
        store: object, values: Mapping[str, tuple[str, str]], **args: object
    ) -> CertificateContent:
        content = make_content(values, **args)  # type: ignore[arg-type]
        number = str(args.get("number", content.number))
        if number == "auto":
            number = store.draw_number(content.plan.issue_date)  # type: ignore[attr-defined]
        content = dataclasses.replace(content, number=number)
        with store.keep(content, files_of(content)):  # type: ignore[attr-defined]
            pass
        return content

    return run


__all__: Sequence[str] = ["ENGINES", "files_of", "make_content", "make_plan"]
