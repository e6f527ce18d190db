"""Every ``--help`` of the CLI: an example, summaries that are not cut, help for every option.

A newcomer reads ``rotacal --help`` and then the help of one command; each must show how the
command is typed, say what every option means, and spell out the abbreviations of the papers
(OSE, LTS, FOG) where they appear.
"""

from __future__ import annotations

import re
import shlex
from collections.abc import Iterator
from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from rotacal.cli import cli

#: Help is rendered as on an 80-column terminal, the narrowest a newcomer is likely to have.
_WIDTH = 80

#: The abbreviations of the papers and what each must be spelled out as where it is used.
_SPELLED_OUT = {
    "OSE": "optical shaft encoder",
    "LTS": "laser triangulation sensor",
    "FOG": "fibre-optic gyro",
}


def _walk(command: click.Command, path: tuple[str, ...]) -> Iterator[tuple[str, click.Command]]:
    yield " ".join(path), command
    if isinstance(command, click.Group):
        # through the group's own look-up: the top-level commands load on demand
        ctx = click.Context(command)
        for name in command.list_commands(ctx):
            sub = command.get_command(ctx, name)
            assert sub is not None, name
            yield from _walk(sub, (*path, name))


COMMANDS = dict(_walk(cli, ("rotacal",)))


def _help(path: str) -> str:
    result = CliRunner().invoke(cli, [*path.split()[1:], "--help"], terminal_width=_WIDTH)
    assert result.exit_code == 0, f"{path} --help failed: {result.output}"
    return result.output


def test_the_walk_finds_the_commands_of_the_interface() -> None:
    """The checks below see every command (not an empty or partial list)."""
    for path in (
        "rotacal demo",
        "rotacal simulate encoder",
        "rotacal motion encoder",
        "rotacal motion lts",
        "rotacal motion fog",
        "rotacal selfcal",
        "rotacal rate",
        "rotacal gyro scale-factor",
        "rotacal gyro triad",
        "rotacal gyro multiposition",
        "rotacal allan",
        "rotacal turntable budget",
    ):
        assert path in COMMANDS


@pytest.mark.parametrize("path", sorted(COMMANDS))
def test_help_ends_with_an_example_of_this_command(path: str) -> None:
    text = _help(path)
    match = re.search(r"^  Examples?:\n((?:    .*\n?)+)", text, flags=re.MULTILINE)
    assert match, f"'{path} --help' shows no 'Example:' block"
    first = match.group(1).splitlines()[0].strip()
    assert first.startswith(path), f"'{path} --help': its example {first!r} is not '{path} …'"
    assert all(len(line) <= _WIDTH for line in match.group(1).splitlines()), (
        f"'{path} --help': an example line is wider than {_WIDTH} columns"
    )


@pytest.mark.parametrize(
    "path", sorted(p for p, c in COMMANDS.items() if isinstance(c, click.Group))
)
def test_command_summaries_are_not_cut_off(path: str) -> None:
    text = _help(path)
    listing = text.split("\nCommands:\n", 1)[1].split("\n\n", 1)[0]
    for line in listing.splitlines():
        assert not line.rstrip().endswith(("...", "…")), (
            f"'{path} --help' cuts a summary off: {line.strip()!r}"
        )


@pytest.mark.parametrize("path", sorted(COMMANDS))
def test_every_option_has_help(path: str) -> None:
    command = COMMANDS[path]
    bare = [
        "/".join(param.opts)
        for param in command.params
        if isinstance(param, click.Option) and not (param.help or "").strip()
    ]
    assert not bare, f"'{path} --help': no help text for {', '.join(bare)}"


@pytest.mark.parametrize("path", sorted(COMMANDS))
def test_abbreviations_are_spelled_out_where_used(path: str) -> None:
    text = _help(path)
    flat = " ".join(text.split()).lower()
    for short, long in _SPELLED_OUT.items():
        if re.search(rf"\b{short}\b", text):
            assert long in flat, f"'{path} --help' uses {short} without spelling out '{long}'"


def _example_commands(text: str) -> list[list[str]]:
    """The example block's commands as argument lists (continuations joined, comments dropped)."""
    block = re.search(r"^  Examples?:\n((?:    .*\n?)+)", text, flags=re.MULTILINE)
    assert block
    joined = block.group(1).replace("\\\n", " ")
    return [shlex.split(line, comments=True) for line in joined.splitlines() if line.strip()]


@pytest.mark.parametrize("path", sorted(COMMANDS))
def test_the_examples_parse_as_commands_with_their_options(
    path: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each example names an existing command and only options it has, with valid values (it is
    parsed as the CLI parses it, not run)."""
    monkeypatch.chdir(tmp_path)
    Path("lab.toml").write_text("", encoding="utf-8")  # the --specs file an example names
    for argv in _example_commands(_help(path)):
        if argv[1:] == ["COMMAND", "--help"]:
            continue
        command: click.Command = cli
        words = argv[1:]
        while isinstance(command, click.Group):
            sub = command.get_command(None, words[0]) if words else None  # type: ignore[arg-type]
            assert sub is not None, f"'{path}': no command {argv}"
            command, words = sub, words[1:]
        try:
            command.make_context(" ".join(argv[:1]), words)
        except click.UsageError as e:
            pytest.fail(f"'{path} --help': the example {shlex.join(argv)!r} does not parse: {e}")
