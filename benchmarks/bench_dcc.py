"""What writing and validating certificate.xml costs `rotacal certify`.

    python benchmarks/bench_dcc.py [--measurements 5] [--quantities 12]

Builds a certificate content of that many measurements, each with that many reported quantities
(one limited), then times: the DCC's XML (dcc_xml), validate_dcc (lxml/libxml2 with the schema the
package carries: the first call loads the schema), and, for comparison, the xmlschema package
(import, load, validate) that the tests use. Times are single runs in seconds (the best of
--repeat for the warm calls).
"""

from __future__ import annotations

import argparse
import datetime as dt
import io
import time
from pathlib import Path

from rotacal.certificate.conformity import judge
from rotacal.certificate.content import (
    CaptureRef,
    CertificateContent,
    MeasurementResult,
    ReportedQuantity,
)
from rotacal.certificate.dcc import dcc_xml, validate_dcc
from rotacal.plan.model import Conditions, Contact, Item, Limit, Measurement, Person, Plan, Standard

SCHEMA = Path(__file__).resolve().parents[1] / "src" / "rotacal" / "certificate" / "schema"


def content(measurements: int, quantities: int) -> CertificateContent:
    results, plan_measurements = [], []
    for i in range(1, measurements + 1):
        qs = tuple(
            ReportedQuantity(
                f"q[{j}]",
                f"quantity {j}",
                "°/s",
                r"\degree\per\second",
                "1.00012",
                "0.00020",
                "1.96",
                "0.95",
            )
            for j in range(quantities)
        )
        limit = Limit("q[0]", min=0.999, max=1.001)
        results.append(
            MeasurementResult(
                index=i,
                name=f"measurement {i}",
                command="gyro triad",
                method="a method (Feng et al. 2023, eq. (1))",
                references=("Feng R. et al. (2023). Sensors 23(10), 4876.",),
                captures=(CaptureRef("c.npz", "0" * 64, 1000),),
                options={"output-unit": "V"},
                results={},
                quantities=qs,
                conformity=(judge(qs[0], limit, "guarded"),),
                decision_rule="guarded",
            )
        )
        plan_measurements.append(Measurement(i, f"measurement {i}", "gyro triad", (Path("c.npz"),)))
    plan = Plan(
        path=Path("plan.toml"),
        text=b"",
        data={},
        number="RC-1",
        start_date=dt.date(2026, 11, 25),
        end_date=dt.date(2026, 11, 25),
        issue_date=dt.date(2026, 11, 25),
        laboratory=Contact("Rate Lab", "1 Test Road", "lab@example.org"),
        customer=Contact("Gyro Maker Ltd", "2 Sensor Street", "quality@example.com"),
        persons=(Person("A. Operator", "performed"), Person("B. Manager", "approved")),
        item=Item("gyroscope", "Gyro Maker Ltd", "GM-300", "SN-0001"),
        standards=(Standard("Rate table encoder", "STD-17", "CAL-1", dt.date(2027, 6, 30)),),
        conditions=Conditions(23.0, 0.5),
        measurements=tuple(plan_measurements),
    )
    return CertificateContent("RC-1", plan, "0" * 64, "0.1.0", tuple(results))


def best(f, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--measurements", type=int, default=5)
    parser.add_argument("--quantities", type=int, default=12)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    c = content(args.measurements, args.quantities)
    t = time.perf_counter()
    xml = dcc_xml(c)
    build = time.perf_counter() - t
    t = time.perf_counter()
    validate_dcc(xml)
    cold = time.perf_counter() - t
    warm = best(lambda: validate_dcc(xml), args.repeat)
    t = time.perf_counter()
    import xmlschema

    imported = time.perf_counter() - t
    t = time.perf_counter()
    schema = xmlschema.XMLSchema(str(SCHEMA / "dcc.xsd"))
    loaded = time.perf_counter() - t
    checked = best(lambda: schema.validate(io.BytesIO(xml)), args.repeat)
    print(
        f"certificate.xml: {args.measurements} measurements × {args.quantities} quantities, "
        f"{len(xml)} bytes"
    )
    print(f"dcc_xml (build and serialise)          {build:8.4f} s")
    print(f"validate_dcc, first (loads the schema) {cold:8.4f} s")
    print(f"validate_dcc, schema loaded            {warm:8.4f} s")
    print(
        f"xmlschema: import {imported:.3f} s + load {loaded:.3f} s + validate {checked:.3f} s "
        f"= {imported + loaded + checked:.3f} s"
    )


if __name__ == "__main__":
    main()
