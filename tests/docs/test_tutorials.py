"""The getting-started page and the tutorials run as written, and state the numbers rotacal gives.

Each page (docs/getting-started.md, docs/tutorials/*.md) runs in a fresh folder, section by
section: every ``$ rotacal …`` line of its ``console`` blocks, in order, through the CLI's own entry
(click's CliRunner, in this process: the tutorials are many short commands, and starting Python
for each would cost more than the analyses). ``$ROTACAL_SHARED_DATA`` and globs in a command are
expanded as a reader's shell would. Then every ``<!-- expect FILE: KEY = VALUE ± TOL -->`` of the
section holds: the values are the twin's truth (``FILE.truth.json``) or the reference that came
with a real recording, with the tolerance the text states (the result's U, or the reference's
printed digits). A section on a real recording is skipped, by the ``shared_data`` fixture, when
the recordings are absent (they come last on every page, after the twin's). Blocks marked
``bash`` (installing, ``rotacal demo``) are shown, not run here: the demo has tests of its own.
"""

from __future__ import annotations

import glob
import os
import re
import shlex
from pathlib import Path

import pytest
from click.testing import CliRunner

from rotacal.cli import cli

from ..conftest import SHARED_DATA
from .test_real_data_docs import _EXPECT, _commands, check_expects

DOCS = Path(__file__).resolve().parents[2] / "docs"
PAGES = [DOCS / "getting-started.md", *sorted((DOCS / "tutorials").glob("*.md"))]
_SHARED = re.compile(r"\$ROTACAL_SHARED_DATA/([^/\s]+)")


def sections(page: Path) -> list[tuple[str, str]]:
    """(title, text) of each '## ' section of a page that has commands to run."""
    parts = re.split(r"^## ", page.read_text(encoding="utf-8"), flags=re.M)[1:]
    return [(p.split("\n", 1)[0], p) for p in parts if _commands(p)]


def run_section(text: str, folder: Path) -> None:
    """Run the section's ``$ rotacal`` lines in ``folder``; a failure names the command."""
    runner = CliRunner()
    shared = os.environ.get("ROTACAL_SHARED_DATA", str(SHARED_DATA))
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        for command in _commands(text):
            argv = []
            for word in shlex.split(command.replace("$ROTACAL_SHARED_DATA", shared)):
                matches = sorted(glob.glob(word)) if "/" in word and "*" in word else []
                argv += matches or [word]
            assert argv[0] == "rotacal", f"{command!r} is not a rotacal command"
            result = runner.invoke(cli, argv[1:], prog_name="rotacal")
            assert result.exit_code == 0, (
                f"{command}\n(exit {result.exit_code}) {result.stderr[-2000:]}"
            )
    finally:
        os.chdir(cwd)


def test_every_calibration_has_a_tutorial_with_checked_numbers() -> None:
    names = {page.stem for page in PAGES}
    for needed in (
        "getting-started",
        "sinusoidal-motion",
        "angular-velocity-standard",
        "gyro-scale-factor",
        "gyro-triad",
        "multiposition",
        "noise",
        "turntable-budget",
    ):
        assert needed in names, f"docs has no page {needed}.md"
    for page in PAGES[1:]:
        text = page.read_text(encoding="utf-8")
        assert _EXPECT.search(text), f"{page.name} checks no number against the truth"
        for image in re.findall(r"\]\((figures/[^)]+)\)", text):
            path = page.parent / image
            assert path.is_file(), f"{page.name} shows {image}, which is missing"
            assert path.stat().st_size < 120_000, f"{image} is over 120 kB"


@pytest.mark.parametrize(
    "page",
    [
        # the turntable page with the other budgets of the example table (tests/conftest.py)
        pytest.param(page, marks=pytest.mark.xdist_group("demo"))
        if page.stem == "turntable-budget"
        else page
        for page in PAGES
    ],
    ids=lambda page: page.stem,
)
def test_page_runs_and_states_what_rotacal_gives(
    page: Path, tmp_path: Path, shared_data, unrendered_figures
) -> None:
    """The page's sections in order, in one folder (a later section reads what an earlier one
    wrote); the sections on real recordings come last, and skip when the recordings are absent.
    The reports' figures are one pixel here (tests/conftest.py): every command's figures are
    drawn and looked at in tests/report; this test checks that the commands run and the numbers."""
    for _title, text in sections(page):
        for folder in sorted(set(_SHARED.findall(text))):
            shared_data(folder)  # skips, saying why, when the recordings are absent
        run_section(text, tmp_path)
        if _EXPECT.search(text):
            check_expects(text, tmp_path)
