"""Plans for ``rotacal certify`` in the records tests: one cheap measurement (a gyro's rotation
test, a fraction of a second) on its twin capture, ``number = "auto"``."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from click.testing import CliRunner

from rotacal.cli import cli

from ..certificate.conftest import KINDS, plan_dict, write_plan

COMMAND = "gyro rotations"
#: the capture file the plans name
CAPTURE = KINDS[COMMAND][1]


@pytest.fixture(scope="module", name="capture_folder")
def capture_folder_fixture(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The twin capture of :data:`COMMAND` (and its sections file)."""
    folder = tmp_path_factory.mktemp("captures")
    line = KINDS[COMMAND][0]
    result = CliRunner().invoke(cli, ["simulate", *line.split(), "--out", str(folder / CAPTURE)])
    assert result.exit_code == 0, result.output
    return folder


def write_plans(folder: Path, captures: Path, count: int, **changes: Any) -> list[Path]:
    """``count`` different plans with ``number = "auto"`` in ``folder`` (the captures copied in):
    one measurement each, items SN-0 … SN-2 (so that writers share items), each on a day of its
    own; ``changes`` replace whole tables of every plan."""
    folder.mkdir(parents=True, exist_ok=True)
    for file in captures.iterdir():
        (folder / file.name).write_bytes(file.read_bytes())
    plans = []
    for i in range(count):
        data = plan_dict([{"name": f"Rotation test {i}", "command": COMMAND}])
        data["certificate"] = {"number": "auto", "date": f"2026-11-{i + 1:02d}"}
        data["item"]["serial"] = f"SN-{i % 3}"
        data.update(changes)
        plans.append(write_plan(folder, data, f"plan-{i}.toml"))
    return plans
