"""Twin plans for the tests and benchmarks of batches: a gyro end-of-line test of many units;
and the comparison of two results' JSON (a split capture's against one process's).

Each unit gets three twin captures of its own (``rotacal simulate``, seeded by the unit, so its
noise differs) and a plan of three measurements — scale factor and nonlinearity, the triad's scale
factors and misalignment, and the rotation test — with ``number = "auto"`` and its own serial.
"""

from __future__ import annotations

import contextlib
import io
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import tomli_w

__all__ = [
    "MEASUREMENTS",
    "largest_difference",
    "split_and_one_process",
    "twin_plan",
    "write_twin_plans",
]

#: (command, `rotacal simulate` kind, capture file, options, limits) of each measurement.
MEASUREMENTS: tuple[tuple[str, str, str, dict[str, Any], dict[str, Any]], ...] = (
    (
        "gyro scale-factor",
        "gyro-rates",
        "rates.npz",
        {"full-scale-deg-s": 100, "output-unit": "V"},
        {"nonlinearity_percent_fs": {"max": 0.5}},
    ),
    ("gyro triad", "gyro-triad", "triad.npz", {"output-unit": "deg/s"}, {}),
    (
        "gyro rotations",
        "gyro-rotations",
        "rotations.npz",
        {"sections": "rotations.npz.truth.json", "output-unit": "deg/s"},
        {},
    ),
)


_Measurement = tuple[str, str, str, dict[str, Any], dict[str, Any]]


def _chosen(commands: Sequence[str] | None) -> list[_Measurement]:
    return [m for m in MEASUREMENTS if commands is None or m[0] in commands]


def twin_plan(unit: int, captures: str, commands: Sequence[str] | None = None) -> dict[str, Any]:
    """The plan (TOML data) of unit ``unit`` whose captures are in the folder ``captures``
    (relative to the plan): the measurements of :data:`MEASUREMENTS` (those of ``commands``)."""
    measurements = []
    for command, _, capture, options, limits in _chosen(commands):
        given = {k: f"{captures}/{v}" if k == "sections" else v for k, v in options.items()}
        entry: dict[str, Any] = {
            "name": f"{command} of SN-{unit:04d}",
            "command": command,
            "capture": f"{captures}/{capture}",
            "options": given,
        }
        if limits:
            entry["limits"] = limits
        measurements.append(entry)
    return {
        "certificate": {"number": "auto", "date": "2026-11-25"},
        "laboratory": {"name": "Rate Lab", "address": "1 Test Road, Testville"},
        "customer": {"name": "Gyro Maker Ltd", "address": "2 Sensor Street, Sensortown"},
        "person": [
            {"name": "A. Operator", "role": "performed"},
            {"name": "B. Manager", "role": "approved"},
        ],
        "item": {
            "kind": "gyroscope",
            "manufacturer": "Gyro Maker Ltd",
            "model": "GM-300",
            "serial": f"SN-{unit:04d}",
        },
        "standard": [
            {
                "name": "Rate table",
                "id": "STD-17",
                "certificate": "CAL-2026-123",
                "due": "2027-06-30",
            }
        ],
        "conditions": {"temperature_c": 23.0, "temperature_u_c": 0.5},
        "measurement": measurements,
    }


def write_twin_plans(
    folder: Path, count: int, *, first: int = 0, commands: Sequence[str] | None = None
) -> list[Path]:
    """Write the plans of units ``first`` … ``first + count - 1`` into ``folder``
    (``unit-NNNN.toml``), each with its captures in ``captures-NNNN/``; their paths. ``commands``
    chooses among the measurements (the tests use the rotation test alone: 30 ms)."""
    from rotacal.cli import cli

    folder.mkdir(parents=True, exist_ok=True)
    plans = []
    for unit in range(first, first + count):
        captures = f"captures-{unit:04d}"
        (folder / captures).mkdir(exist_ok=True)
        for _, kind, capture, _, _ in _chosen(commands):
            args = ["simulate", kind, "--out", str(folder / captures / capture)]
            args += ["--seed", str(unit), "--overwrite"]
            with contextlib.redirect_stderr(io.StringIO()):
                cli.main(args, prog_name="rotacal", standalone_mode=False)
        path = folder / f"unit-{unit:04d}.toml"
        plan = twin_plan(unit, captures, commands)
        path.write_text(tomli_w.dumps(plan), encoding="utf-8")
        plans.append(path)
    return plans


def largest_difference(
    a: Any, b: Any, skip: Sequence[str] = ("provenance",), where: str = ""
) -> float:
    """The largest relative difference between the finite numbers of two JSON documents,
    checking that everything else is equal (AssertionError naming the first place that is not);
    keys in ``skip`` are left out."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), where
        parts = (largest_difference(a[k], b[k], skip, f"{where}/{k}") for k in a if k not in skip)
        return max(parts, default=0.0)
    if isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), where
        parts = (largest_difference(u, v, skip, where) for u, v in zip(a, b, strict=True))
        return max(parts, default=0.0)
    if isinstance(a, float) and isinstance(b, float) and math.isfinite(a):
        return 0.0 if a == b else abs(a - b) / max(abs(a), abs(b))
    assert a == b, where
    return 0.0


def split_and_one_process(
    args: Sequence[str], scheduler: str, folder: Path
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The JSON of ``rotacal ARGS`` split over the workers of ``scheduler`` and of the same
    command streamed in one process (``--chunked``), written in ``folder``; AssertionError with
    the output when either fails. The split's last note, which names the workers used, is
    checked and taken out (the rest must be equal)."""
    import json

    from click.testing import CliRunner

    from rotacal.cli import cli

    outputs = []
    for name, extra in (("split", ["--scheduler", scheduler]), ("chunked", ["--chunked"])):
        out = folder / f"{name}.json"
        result = CliRunner().invoke(cli, [*args, *extra, "--json", str(out)])
        assert result.exit_code == 0, result.output
        outputs.append(json.loads(out.read_text()))
    split, one = outputs
    *notes, note = split["notes"]
    assert note.startswith("split over ") and " Dask workers (" in note, note
    return {**split, "notes": notes}, one
