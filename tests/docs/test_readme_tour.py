"""The README's tour runs as written: every command, in order, in a fresh empty folder.

The tour is the section "## A tour" of README.md: its fenced ``bash`` blocks (a line ending in a
backslash continues on the next; ``#`` starts a comment) and its ``python`` block. Each command
runs in this process through the CLI's own entry (click's CliRunner), so a failure names the
README line, the command and what rotacal said. The set-up commands of the README are checked
against what ``.ci/run`` runs.
"""

from __future__ import annotations

import itertools
import re
import shlex
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from rotacal.cli import cli

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"


def _section(text: str, heading: str) -> tuple[int, str]:
    """The text under ``## heading`` up to the next ``## `` heading, and its first line number."""
    match = re.search(rf"^## {re.escape(heading)}\n(.*?)(?=^## |\Z)", text, re.S | re.M)
    assert match, f"README.md has no section '## {heading}'"
    return text.count("\n", 0, match.start(1)) + 1, match.group(1)


def _blocks(section: str, first_line: int, language: str) -> list[tuple[int, list[str]]]:
    """Fenced blocks of ``language``: (README line number of the block's first line, its lines)."""
    blocks = []
    for match in re.finditer(rf"^```{language}\n(.*?)^```$", section, re.S | re.M):
        line = first_line + section.count("\n", 0, match.start(1))
        blocks.append((line, match.group(1).splitlines()))
    return blocks


def shell_commands(section: str, first_line: int) -> list[tuple[int, str]]:
    """Each shell command of the section's bash blocks, continuation lines joined, with the README
    line it starts on; comment-only and blank lines are left out."""
    commands: list[tuple[int, str]] = []
    for start, lines in _blocks(section, first_line, "bash"):
        pending: tuple[int, str] | None = None
        for offset, line in enumerate(lines):
            if pending is None:
                if not line.strip() or line.lstrip().startswith("#"):
                    continue
                pending = (start + offset, "")
            text = pending[1] + (line.strip() if pending[1] else line.rstrip())
            if text.endswith("\\"):
                pending = (pending[0], text[:-1].rstrip() + " ")
                continue
            commands.append((pending[0], text))
            pending = None
        assert pending is None, f"README.md line {pending[0]}: a continuation ends its block"
    return commands


#: The tour's part that reads no file of the others and takes most of its time (the turntable's
#: allocation and Monte Carlo check): it runs in a folder of its own, beside the rest.
_SEPARATE_PART = "### A turntable's geometric error budget"


def tour(part: str = "all") -> tuple[list[tuple[int, str]], list[tuple[int, str]]]:
    """The tour's shell commands and its Python snippets, each with its README line.

    ``part``: "all", "turntable" (the subsection _SEPARATE_PART) or "rest" (all but it).
    """
    first, section = _section(README.read_text(encoding="utf-8"), "A tour")
    start = section.index(_SEPARATE_PART)
    end = section.find("\n### ", start + 1)
    end = len(section) if end < 0 else end + 1
    if part == "turntable":
        first, section = first + section.count("\n", 0, start), section[start:end]
    elif part == "rest":  # blank the part out, keeping the line numbers of what follows it
        section = section[:start] + "\n" * section.count("\n", start, end) + section[end:]
    snippets = [(line, "\n".join(body)) for line, body in _blocks(section, first, "python")]
    return shell_commands(section, first), snippets


def _outputs(argv: list[str]) -> list[str]:
    """The files a command line names for writing (``--out``, ``--json``, ``--report``)."""
    return [
        value
        for option, value in itertools.pairwise(argv)
        if option in ("--out", "--json", "--report") and value != "-"
    ]


def test_the_parser_joins_continuations_and_drops_comments() -> None:
    """Against a hand-written block whose commands are known."""
    section = "text\n```bash\n# a comment\nrotacal a \\\n    --b 1   # why\n\nrotacal c\n```\n"
    assert shell_commands(section, 10) == [(13, "rotacal a --b 1   # why"), (16, "rotacal c")]


def _analysis_commands(command: click.Command, path: tuple[str, ...]) -> list[str]:
    """The commands that read a file: those with a CAPTURE or CONFIG argument."""
    if isinstance(command, click.Group):
        ctx = click.Context(command)  # the group's own look-up: top-level commands load on demand
        return [
            found
            for name in command.list_commands(ctx)
            for found in _analysis_commands(command.get_command(ctx, name), (*path, name))
        ]
    names = {p.name for p in command.params if isinstance(p, click.Argument)}
    return [" ".join(path)] if names & {"capture", "config"} else []


def test_the_tour_covers_every_analysis_and_writes_nothing_twice() -> None:
    commands, snippets = tour()
    words = [shlex.split(command, comments=True) for _, command in commands]
    ran = {" ".join(w[1:3]) for w in words} | {w[1] for w in words}
    analyses = _analysis_commands(cli, ())
    assert "motion encoder" in analyses and "turntable budget" in analyses  # the walk works
    for needed in analyses:
        assert needed in ran, f"the README tour does not show 'rotacal {needed}'"
    assert snippets, "the README tour has no Python example"
    assert not any("--overwrite" in w for w in words), "the tour must not need --overwrite"
    written = [name for w in words for name in _outputs(w)]
    twice = sorted({name for name in written if written.count(name) > 1})
    assert not twice, f"the README tour writes {', '.join(twice)} more than once"
    separate = {name for _, c in tour("turntable")[0] for name in _outputs(shlex.split(c, True))}
    assert separate and separate.isdisjoint(
        name for _, c in tour("rest")[0] for name in _outputs(shlex.split(c, True))
    )


@pytest.mark.parametrize(
    "part",
    # the turntable part with the other budgets of the example table (tests/conftest.py)
    ["rest", pytest.param("turntable", marks=pytest.mark.xdist_group("demo"))],
)
def test_the_readme_tour_runs_line_by_line(
    part: str,
    tmp_path: Path,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    unrendered_figures: None,
) -> None:
    """Each part in an empty folder of its own: the turntable's part reads only what it makes,
    and the rest runs in order without it. (The reports' figures are one pixel here, as in the
    tutorials' test: tests/report draws and looks at every command's figures.)"""
    commands, snippets = tour(part)
    assert commands
    monkeypatch.chdir(tmp_path)
    runner = CliRunner()
    for line, command in commands:
        argv = shlex.split(command, comments=True)
        assert argv[0] == "rotacal", f"README.md line {line}: {command!r} is not a rotacal command"
        result = runner.invoke(cli, argv[1:], prog_name="rotacal")
        assert result.exit_code == 0, (
            f"README.md line {line} fails (exit {result.exit_code}): {command}\n"
            f"{result.stderr[-2000:]}{result.stdout[-500:]}"
        )
    for line, code in snippets:
        try:
            exec(compile(code, f"README.md line {line}", "exec"), {})
        except Exception as e:
            pytest.fail(f"README.md line {line}: the Python example fails: {type(e).__name__}: {e}")
    if snippets:
        assert "thd_percent" in capsys.readouterr().out  # the snippet printed the result's JSON


def test_ci_runs_exactly_the_readme_developer_set_up() -> None:
    """``.ci/run`` installs and tests with the README's two developer commands, in that order."""
    _, section = _section(README.read_text(encoding="utf-8"), "Set up")
    developer = section.split("### For developers", 1)[1]
    blocks = _blocks(developer, 0, "bash")
    commands = [c for c in blocks[0][1] if c.strip()]
    assert commands == ['pip install -e ".[dev]"', "pytest"]
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    positions = [ci.index(command) for command in commands]
    assert positions == sorted(positions)
    assert "python3 -m venv" in "\n".join(ci)
