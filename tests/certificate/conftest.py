"""Fixtures of the certificate tests: twin captures of every measurement command (made once per
test session and shared by the xdist workers), plans around them, and the content of real plan
runs on them."""

from __future__ import annotations

import contextlib
import fcntl
import os
import pickle
import tempfile
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

import pytest
import tomli_w
from click.testing import CliRunner

from rotacal.certificate.content import CertificateContent
from rotacal.certificate.issue import build_content
from rotacal.cli import cli
from rotacal.plan.read import read_plan
from rotacal.plan.run import run_plan

#: command → (the `rotacal simulate` line that makes its capture, capture file, options)
KINDS: dict[str, tuple[str, str, dict[str, Any]]] = {
    "motion encoder": (
        "encoder --harmonic 2:0.01 --harmonic 3:0.003 --noise 0.002 --adc-bits 16",
        "encoder.npz",
        {"lines": 36000},
    ),
    "motion lts": ("lts --harmonic 2:0.01", "lts.npz", {"radius-mm": 100}),
    "motion fog": ("fog --harmonic 2:0.01 --noise 0.05", "fog.npz", {}),
    "selfcal": ("pulses", "pulses.npz", {"pulses-per-rev": 18000}),
    "rate": ("pulses", "pulses.npz", {"pulses-per-rev": 18000}),
    "gyro scale-factor": ("gyro-rates", "rates.npz", {"full-scale-deg-s": 100, "output-unit": "V"}),
    "gyro triad": ("gyro-triad", "triad.npz", {"output-unit": "deg/s"}),
    "gyro rotations": (
        "gyro-rotations",
        "rotations.npz",
        {"sections": "rotations.npz.truth.json", "output-unit": "deg/s"},
    ),
    "gyro multiposition": ("multiposition", "mp.npz", {"axis": "x", "latitude-deg": 45.75}),
    "allan": ("gyro-noise", "noise.npz", {"column": "rate_deg_s"}),
}

#: The five measurements of the certificate tests, with limits that give every verdict: pass,
#: fail (triad K_xy, THD) and indeterminate (bias instability straddles its limit).
FIVE: list[dict[str, Any]] = [
    {
        "name": "Scale factor and nonlinearity, x axis",
        "command": "gyro scale-factor",
        "limits": {
            "nonlinearity_percent_fs": {"max": 0.5},
            "scale_factor": {"min": 0.0124, "max": 0.0126},
        },
    },
    {
        "name": "Scale factors and misalignment, three axes",
        "command": "gyro triad",
        "limits": {"scale_misalignment[0][1]": {"min": -0.003, "max": 0.003}},
    },
    {
        "name": "Noise, x axis (Allan deviation)",
        "command": "allan",
        "limits": {"arw_deg_rt_h": {"max": 0.5}, "bias_instability_deg_h": {"max": 3.5}},
    },
    {
        "name": "Self-calibration of the table's encoder",
        "command": "selfcal",
        "limits": {"deviation_pp_arcsec": {"max": 10.0}},
    },
    {
        "name": "Sinusoidal motion of the table",
        "command": "motion encoder",
        "limits": {"thd_percent": {"max": 1.0}},
        "decision_rule": "simple",
    },
]


def plan_dict(measurements: Sequence[Mapping[str, Any]], number: str = "RC-2026-0042") -> dict:
    """A whole plan (as TOML data) around ``measurements`` (each: name, command and optionally
    limits, decision_rule; capture and options come from :data:`KINDS`)."""
    entries = []
    for m in measurements:
        _, capture, options = KINDS[m["command"]]
        entries.append({"capture": capture, "options": dict(options), **m})
    return {
        "certificate": {"number": number, "start_date": "2026-11-24", "end_date": "2026-11-25"},
        "laboratory": {
            "name": "Rate Lab <Testville> & Co.",
            "address": "1 Test Road, 12345 Testville",
            "email": "lab@example.org",
            "country": "DE",
        },
        "customer": {
            "name": "Gyro Maker Ltd",
            "address": "2 Sensor Street",
            "email": "q@example.com",
        },
        "person": [
            {"name": "A. Operator", "role": "performed"},
            {"name": "B. Manager", "role": "approved", "title": "Head of laboratory"},
        ],
        "item": {
            "kind": "gyroscope",
            "manufacturer": "Gyro Maker Ltd",
            "model": "GM-300",
            "serial": "SN-0001",
            "description": "three-axis MEMS gyroscope",
        },
        "standard": [
            {
                "name": "Rate table encoder",
                "id": "STD-17",
                "certificate": "CAL-2026-123",
                "due": "2027-06-30",
                "traceability": "PTB, Braunschweig",
            }
        ],
        "conditions": {"temperature_c": 23.0, "temperature_u_c": 0.5, "humidity_percent": 45.0},
        "measurement": entries,
    }


def write_plan(folder: Path, data: Mapping[str, Any], name: str = "plan.toml") -> Path:
    path = folder / name
    path.write_text(tomli_w.dumps(data), encoding="utf-8")
    return path


@contextlib.contextmanager
def _lock(path: Path) -> Iterator[None]:
    with open(path, "a") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def make_captures(folder: Path) -> Path:
    """Simulate every capture of :data:`KINDS` into ``folder`` (once: other workers wait)."""
    folder.mkdir(parents=True, exist_ok=True)
    with _lock(folder / ".lock"):
        for line, capture, _ in KINDS.values():
            if (folder / capture).exists():
                continue
            result = CliRunner().invoke(
                cli, ["simulate", *line.split(), "--out", str(folder / capture)]
            )
            assert result.exit_code == 0, result.output
    return folder


def cached(folder: Path, name: str, make: Any) -> Any:
    """``make()`` pickled in ``folder/name``: computed by the first worker, read by the others."""
    path = folder / f"{name}.pickle"
    with _lock(folder / ".lock"):
        if not path.exists():
            path.write_bytes(pickle.dumps(make()))
        return pickle.loads(path.read_bytes())


@pytest.fixture(scope="session")
def twin_folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The twin captures of every measurement command, shared by the xdist workers."""
    base = tmp_path_factory.getbasetemp()
    # an xdist worker's base is a folder of this session's (pytest-N/popen-gwK): its parent is
    # shared by the workers of this session only; without xdist the base itself is this session's
    session = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    shared = session / "certificate-twins"
    return make_captures(shared)


def _content(folder: Path, measurements: list[dict], name: str) -> CertificateContent:
    plan = read_plan(write_plan(folder, plan_dict(measurements), f"{name}.toml"))
    with tempfile.TemporaryDirectory() as scratch:
        runs = run_plan(plan, Path(scratch))
    return build_content(plan, runs, plan.number, "0.1.0")


@pytest.fixture(scope="session")
def content(twin_folder: Path) -> CertificateContent:
    """The content of the five-measurement plan (scale factor, triad, Allan, selfcal, motion)."""
    return cached(twin_folder, "content-five", lambda: _content(twin_folder, FIVE, "five"))


@pytest.fixture(scope="session")
def kind_content(twin_folder: Path) -> dict[str, CertificateContent]:
    """command → the content of a plan of one measurement of that command, for every command."""

    def make() -> dict[str, CertificateContent]:
        out = {}
        for i, command in enumerate(KINDS):
            m = {"name": f"{command} on its twin", "command": command}
            out[command] = _content(twin_folder, [m], f"kind-{i}")
        return out

    return cached(twin_folder, "content-kinds", make)


@pytest.fixture(scope="session")
def make_plan(twin_folder: Path) -> Callable[..., Path]:
    """``make_plan(folder, measurements, number=…, **changes)``: a plan file in ``folder`` whose
    captures are the twins (copied in) — ``changes`` replace whole tables of the plan."""
    import shutil

    def make(
        folder: Path,
        measurements: Sequence[Mapping[str, Any]] = FIVE,
        name: str = "plan.toml",
        **changes: Any,
    ) -> Path:
        data = plan_dict(measurements)
        data.update(changes)
        for m in data["measurement"]:
            for file in [
                m["capture"],
                *(v for k, v in m.get("options", {}).items() if k == "sections"),
            ]:
                for copied in (file, f"{file}.truth.json"):
                    if not (folder / copied).exists() and (twin_folder / copied).exists():
                        shutil.copy(twin_folder / copied, folder / copied)
        return write_plan(folder, data, name)

    return make


@pytest.fixture(scope="session")
def dcc_schema() -> Any:
    """PTB's DCC schema v3.1.2 from the shared standards folder beside the project (offline)."""
    import xmlschema

    path = Path(__file__).resolve().parents[3] / "shared" / "standards" / "dcc" / "dcc.xsd"
    return xmlschema.XMLSchema(str(path))
