"""The top-level commands load their modules on first use; the table of them is complete."""

from __future__ import annotations

import importlib
import pkgutil

import click

import rotacal.cli
from rotacal.cli import cli
from rotacal.cli._app import COMMAND_MODULES


def test_each_command_comes_from_the_module_the_table_names():
    for name, module in COMMAND_MODULES.items():
        command = cli.get_command(click.Context(cli), name)
        assert command is not None, name
        assert command.callback is None or command.callback.__module__ == f"rotacal.cli.{module}"


def test_no_command_is_missing_from_the_table():
    # import every module of rotacal.cli: whatever registers on `cli` must be in the table
    for m in pkgutil.iter_modules(rotacal.cli.__path__, "rotacal.cli."):
        importlib.import_module(m.name)
    assert set(cli.commands) == set(COMMAND_MODULES)
    assert cli.list_commands(click.Context(cli)) == sorted(COMMAND_MODULES)


def test_command_modules_are_attributes_of_the_package():
    assert rotacal.cli.motion.__name__ == "rotacal.cli.motion"
