"""Time of the PDF certificate's parts: drawing each figure, and compiling the PDF with Typst.

    python benchmarks/bench_certificate_pdf.py [DEMO_DIR] [--repeat 5]

DEMO_DIR is a folder written by ``rotacal demo`` (made in a temporary folder when not given,
which takes about a minute). A certificate of its five measurements of the issue (gyro
scale-factor, gyro triad, allan, selfcal, motion encoder) is drawn and rendered; the figures are
timed once each, the compile ``--repeat`` times (median and fastest, in process CPU time too,
since the machine may be shared).
"""

from __future__ import annotations

import argparse
import dataclasses
import datetime as dt
import io
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rotacal.certificate.conformity import judge
from rotacal.certificate.content import (
    CaptureRef,
    CertificateContent,
    Figure,
    MeasurementResult,
)
from rotacal.certificate.figures import draw_figures
from rotacal.certificate.pdf import render_pdf
from rotacal.certificate.quantities import reported_quantities
from rotacal.plan.model import Conditions, Contact, Item, Limit, Person, Plan, Standard

#: The five measurements of the issue's plan: command → the demo's JSON of it.
FIVE = {
    "gyro scale-factor": "gyro_scale_factor.json",
    "gyro triad": "gyro_triad.json",
    "allan": "allan.json",
    "selfcal": "selfcal.json",
    "motion encoder": "motion_0.5deg_2hz_encoder.json",
}


def content_from(demo: Path) -> CertificateContent:
    """A certificate of the five demo analyses; each one's first result gets a limit at twice
    its value, so that every measurement has a conformity row."""
    measurements = []
    for index, (command, name) in enumerate(FIVE.items(), start=1):
        results = json.loads((demo / name).read_text())
        unit = results.get("output_unit") or ("V" if command.startswith("gyro") else "")
        quantities = reported_quantities(command, results, output_unit=unit)
        first = quantities[0]
        limit = Limit(first.key, max=2 * abs(float(first.value)))
        measurements.append(
            MeasurementResult(
                index=index,
                name=f"Demo {command}",
                command=command,
                method=f"rotacal {command} on the demo's capture.",
                references=(),
                captures=(CaptureRef(name, "0" * 64, 0),),
                options={},
                results=results,
                quantities=quantities,
                conformity=(judge(first, limit, "guarded"),),
                decision_rule="guarded",
            )
        )
    day = dt.date(2026, 11, 25)
    plan = Plan(
        path=demo / "plan.toml",
        text=b"",
        data={},
        number="BENCH-1",
        start_date=day,
        end_date=day,
        issue_date=day,
        laboratory=Contact("Rate Lab", "1 Test Road, Testville", "lab@example.org"),
        customer=Contact("Gyro Maker Ltd", "2 Sensor Street, Sensortown"),
        persons=(Person("A. Operator", "performed"), Person("B. Manager", "approved")),
        item=Item("gyroscope", "Gyro Maker Ltd", "GM-300", "SN-0001"),
        standards=(Standard("Rate table encoder", "STD-17", "CAL-2026-123", dt.date(2027, 6, 30)),),
        conditions=Conditions(23.0, 0.5),
        measurements=(),
    )
    return CertificateContent("BENCH-1", plan, "0" * 64, "bench", tuple(measurements))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("demo", nargs="?", type=Path)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        demo = args.demo
        if demo is None:
            demo = Path(tmp) / "demo"
            subprocess.run(
                [sys.executable, "-m", "rotacal", "demo", "--out", str(demo)],
                check=True,
                capture_output=True,
            )
        folder = Path(tmp) / "figures"
        folder.mkdir()
        content = content_from(demo)
        draw_figures(content.measurements[0])  # matplotlib's first-use cost out of the figures
        drawn = []
        print("figure                                   wall s   cpu s")
        for m in content.measurements:
            wall, cpu = time.perf_counter(), time.process_time()
            figures = draw_figures(m)
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            for name, _caption, svg in figures:
                (folder / name).write_bytes(svg)
                print(f"{name:40s} {wall / len(figures):6.2f}  {cpu / len(figures):6.2f}")
            drawn.append(dataclasses.replace(m, figures=tuple(Figure(n, c) for n, c, _ in figures)))
        content = dataclasses.replace(content, measurements=tuple(drawn))
        render_pdf(content, folder)  # the first compile loads the fonts
        walls, cpus = [], []
        for _ in range(args.repeat):
            wall, cpu = time.perf_counter(), time.process_time()
            pdf = render_pdf(content, folder)
            walls.append(time.perf_counter() - wall)
            cpus.append(time.process_time() - cpu)
        import pypdf

        pages = len(pypdf.PdfReader(io.BytesIO(pdf)).pages)
        print(
            f"PDF compile ({pages} pages, {len(pdf) / 1e3:.0f} kB): median {statistics.median(walls):.3f} s"
            f", fastest {min(walls):.3f} s wall; median {statistics.median(cpus):.3f} s CPU"
        )


if __name__ == "__main__":
    main()
