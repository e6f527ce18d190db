"""TEMPORARY fixtures of the certificate tests, until the plan runner's conftest replaces this file.

The lead's conftest builds ``content`` (five measurements: gyro scale-factor, gyro triad, allan,
selfcal, motion encoder, with limits giving pass, fail and indeterminate) and ``kind_content``
(command → the content of one measurement of that command) with the real plan runner on
simulated captures. Until it exists these fixtures build the same shapes from command JSONs
made earlier on this machine (/tmp/c15 and the baseline demo), so they only run here.
"""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path

import pytest

from rotacal.certificate.conformity import judge
from rotacal.certificate.content import CertificateContent, MeasurementResult
from rotacal.certificate.quantities import reported_quantities
from rotacal.errors import ConfigError
from rotacal.plan.model import Limit

_HELPERS = Path("/work/helpers/15")
_C15 = Path("/tmp/c15")
_DEMO = Path("/work/helpers/baseline/demo")
#: command → the JSON of one run of it.
_KIND_JSON = {
    "gyro scale-factor": _C15 / "sf.json",
    "gyro triad": _C15 / "tr.json",
    "allan": _C15 / "al.json",
    "selfcal": _C15 / "sc.json",
    "motion encoder": _C15 / "mo.json",
    "motion lts": _DEMO / "motion_0.025deg_10hz_lts.json",
    "motion fog": _DEMO / "motion_0.025deg_10hz_fog.json",
    "rate": _DEMO / "rate.json",
    "gyro rotations": _DEMO / "gyro_rotations.json",
    "gyro multiposition": _DEMO / "gyro_multiposition.json",
}


@pytest.fixture(scope="session")
def content() -> CertificateContent:
    sys.path.insert(0, str(_HELPERS))
    from sample_content import sample_content  # type: ignore[import-not-found]

    return sample_content()


def _one(base: CertificateContent, command: str, results: dict) -> CertificateContent:
    output_unit = results.get("output_unit") or ("V" if command.startswith("gyro") else "")
    try:
        quantities = reported_quantities(command, results, output_unit=output_unit)
    except ConfigError:  # units.py does not know the multiposition drift units yet
        quantities = ()
    conformity = ()
    if quantities:
        first = quantities[0]
        value = float(first.value)
        limit = Limit(first.key, max=2 * value) if value > 0 else Limit(first.key, min=2 * value)
        conformity = (judge(first, limit, "guarded"),)
    template = base.measurements[0]
    measurement = MeasurementResult(
        index=1,
        name=f"One {command} measurement",
        command=command,
        method=f"{command}: the method sentence.",
        references=template.references,
        captures=template.captures,
        options={},
        results=results,
        quantities=quantities,
        conformity=conformity,
        decision_rule="guarded",
        warnings=tuple(results.get("warnings", ())),
    )
    return dataclasses.replace(base, measurements=(measurement,))


@pytest.fixture(scope="session")
def kind_content(content: CertificateContent) -> dict[str, CertificateContent]:
    return {
        command: _one(content, command, json.loads(path.read_text()))
        for command, path in _KIND_JSON.items()
    }
