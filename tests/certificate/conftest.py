"""TEMPORARY fixtures of tests/certificate until the plan runner's own conftest replaces this file.

``content``: the sample CertificateContent of issue 15 (/work/helpers/15/sample_content.py, five
measurements on real command JSONs in /tmp/c15). ``kind_content``: one measurement per command:
the sample's five, and motion lts, motion fog, rate and gyro rotations run in-process on the
sample's captures. ``gyro multiposition`` is missing: its results are in deg/h/g, which
certificate/units.py cannot state in D-SI yet.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from rotacal.certificate.content import CaptureRef, CertificateContent, MeasurementResult
from rotacal.certificate.quantities import reported_quantities
from rotacal.cli import cli
from rotacal.plan.model import Measurement

SAMPLE = Path("/work/helpers/15")
CAPTURES = Path("/tmp/c15")
#: command → (capture, options as on the CLI, the gyro's output unit) of the commands the sample
#: does not hold.
EXTRA_RUNS = {
    "motion lts": ("lts.npz", {"radius-mm": 100}, ""),
    "motion fog": ("fog.npz", {}, ""),
    "rate": ("pulses.npz", {"pulses-per-rev": 18000}, ""),
    "gyro rotations": (
        "gyro-rotations.npz",
        {"sections": str(CAPTURES / "gyro-rotations.npz.truth.json")},
        "V",
    ),
}


@pytest.fixture(scope="session")
def content() -> CertificateContent:
    sys.path.insert(0, str(SAMPLE))
    from sample_content import sample_content  # type: ignore[import-not-found]

    return sample_content()


def _one(content: CertificateContent, m: MeasurementResult, pm: Measurement) -> CertificateContent:
    m = dataclasses.replace(m, index=1)
    plan = dataclasses.replace(content.plan, measurements=(dataclasses.replace(pm, index=1),))
    return dataclasses.replace(content, plan=plan, measurements=(m,))


@pytest.fixture(scope="session")
def kind_content(content, tmp_path_factory) -> dict[str, CertificateContent]:
    kinds = {
        m.command: _one(content, m, pm)
        for m, pm in zip(content.measurements, content.plan.measurements, strict=True)
    }
    folder = tmp_path_factory.mktemp("kinds")
    template, plan_template = content.measurements[0], content.plan.measurements[0]
    for command, (capture, options, output_unit) in EXTRA_RUNS.items():
        out = folder / (command.replace(" ", "-") + ".json")
        args = [*command.split(), str(CAPTURES / capture), "--json", str(out)]
        for name, value in options.items():
            args += [f"--{name}", str(value)]
        run = CliRunner().invoke(cli, args, prog_name="rotacal")
        assert run.exit_code == 0, run.output
        results = json.loads(out.read_text())
        data = (CAPTURES / capture).read_bytes()
        m = dataclasses.replace(
            template,
            name=command,
            command=command,
            method=f"{command}: the method of the command",
            captures=(CaptureRef(capture, hashlib.sha256(data).hexdigest(), len(data)),),
            options=options,
            results=results,
            quantities=reported_quantities(command, results, output_unit=output_unit),
            conformity=(),
        )
        pm = dataclasses.replace(
            plan_template, name=command, command=command, options=tuple(options.items()), limits=()
        )
        kinds[command] = _one(content, m, pm)
    return kinds
