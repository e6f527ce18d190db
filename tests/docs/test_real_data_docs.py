"""docs/real-data.md runs as written: every ``$ rotacal …`` line, and every ``expect`` holds.

Each command is expanded by bash (its globs and ``$(…)`` as a reader's shell expands them, with
``ROTACAL_SHARED_DATA`` pointing at the real recordings), and the ``rotacal`` it calls runs in this
process through the CLI's own entry (click's CliRunner) in a fresh folder: a Python start per
command would cost more than most of the analyses (the installed command's own start is tested in
tests/cli/test_cli.py).
Each ``<!-- expect FILE: KEY = VALUE ± TOL; … -->`` line names a JSON file a command wrote and
the reference values the document states next to it (from the data's README or the program that
made the data). A section whose recordings are absent is skipped by the ``shared_data`` fixture.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
from pathlib import Path

import pytest
from click.testing import CliRunner

from rotacal.cli import cli

from ..conftest import SHARED_DATA

DOC = Path(__file__).resolve().parents[2] / "docs" / "real-data.md"
_BLOCK = re.compile(r"```console\n(.*?)```", re.S)
_EXPECT = re.compile(r"<!-- expect (\S+): (.*?) -->")
_CHECK = re.compile(
    r"^(?P<key>[a-z][a-z0-9_]*)(?P<path>(?:\[\d+\]|\.\w+)*) = (?P<value>\S+)(?: ± (?P<tol>\S+))?$"
)
_STEP = re.compile(r"\[(\d+)\]|\.(\w+)")


def _sections() -> list[tuple[str, str]]:
    """(title, text) of each '## ' section of the document."""
    parts = re.split(r"^## ", DOC.read_text(encoding="utf-8"), flags=re.M)[1:]
    return [(p.split("\n", 1)[0], p) for p in parts]


def _commands(text: str) -> list[str]:
    """The ``$ `` lines of the console blocks, continuation lines joined."""
    out = []
    for block in _BLOCK.findall(text):
        joined = re.sub(r"\\\n\s*", "", block)
        out += [line[2:] for line in joined.splitlines() if line.startswith("$ ")]
    return out


SECTIONS = _sections()


def test_every_set_of_the_shared_folder_has_a_section():
    titles = " ".join(t for t, _ in SECTIONS)
    for folder in (
        "xinli_turntable",
        "imucal",
        "imu_tk",
        "imudata_smac",
        "imu_utils",
        "allantools",
    ):
        assert folder in titles, folder
    # every set whose data rotacal can read has a command and a checked reference value
    for title, text in SECTIONS:
        if not title.startswith("imu_utils"):
            assert _commands(text) and _EXPECT.search(text), title


@pytest.mark.parametrize(
    ("title", "text"), [s for s in SECTIONS if _commands(s[1])], ids=lambda v: v.split()[0]
)
def test_section_commands_run_and_match_the_references(
    title, text, tmp_path, shared_data, monkeypatch
):
    shared_data(title.split()[0])  # skips, saying why, when the recordings are absent
    env = {**os.environ, "ROTACAL_SHARED_DATA": str(SHARED_DATA)}
    # bash expands the line and hands the words to a `rotacal` that only prints them
    prelude = "rotacal() { printf '%s\\0' \"$@\"; }\n"
    monkeypatch.chdir(tmp_path)
    runner = CliRunner()
    for command in _commands(text):
        expanded = subprocess.run(
            ["bash", "-c", prelude + command], env=env, capture_output=True, check=False
        )
        assert expanded.returncode == 0, f"{command}\n{expanded.stderr.decode()}"
        argv = expanded.stdout.decode().split("\0")[:-1]
        assert argv, f"{command!r} calls no rotacal"
        result = runner.invoke(cli, argv, prog_name="rotacal")
        assert result.exit_code == 0, (
            f"{command}\n(exit {result.exit_code}) {result.stderr[-2000:]}"
        )
    check_expects(text, tmp_path)


def check_expects(text: str, folder: Path) -> None:
    """Every ``<!-- expect FILE: KEY = VALUE ± TOL; … -->`` of ``text`` holds for the JSON
    files the commands wrote in ``folder`` (``KEY[i]`` picks an element of a list, ``KEY.NAME``
    an entry of an object; they chain: ``scale_misalignment[0][1]``, ``drift_coefficients.DF``)."""
    expects = _EXPECT.findall(text)
    assert expects, text.split("\n", 1)[0]
    for file, checks in expects:
        result = json.loads((folder / file).read_text())
        for check in checks.split("; "):
            m = _CHECK.match(check.strip())
            assert m, check
            value = result[m["key"]]
            for index, name in _STEP.findall(m["path"]):
                value = value[int(index)] if index else value[name]
            tol = float(m["tol"] or 0)
            assert abs(value - float(m["value"])) <= tol, (file, check, value)
