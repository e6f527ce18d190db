"""The ``provenance`` of the running command, taken from its click context."""

from __future__ import annotations

import os
from typing import Any

import click

from rotacal.provenance import provenance_record

from ._common import _INPUT_PATHS_KEY

#: Parameters that say where the results go, not how they were obtained: not in ``options``.
OUTPUT_PARAMETERS = frozenset({"json_path", "report_path", "overwrite"})


def command_name(ctx: click.Context) -> str:
    """The command as a user types it after ``rotacal``, e.g. ``"gyro scale-factor"``."""
    names = []
    while ctx.parent is not None:
        names.append(ctx.info_name or "")
        ctx = ctx.parent
    return " ".join(reversed(names))


def option_name(param: click.Parameter) -> str:
    """A parameter's name on the command line without dashes (``full-scale-deg-s``, ``capture``):
    the spelling a calibration plan's ``options`` use."""
    if isinstance(param, click.Option):
        long = [o for o in param.opts if o.startswith("--")]
        return (long[0] if long else param.opts[0]).lstrip("-")
    return param.name or param.human_readable_name


def _plain(value: Any) -> Any:
    if isinstance(value, (tuple, list)):
        return [_plain(v) for v in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    return str(value)


def command_options(ctx: click.Context) -> dict[str, Any]:
    """Every parameter of the command but its outputs: as given, defaults filled in; a file as the
    path given (also where a callback turned it into its contents, e.g. ``--specs``)."""
    paths = ctx.meta.get(_INPUT_PATHS_KEY, {})
    out: dict[str, Any] = {}
    for param in ctx.command.params:
        if param.name is None or param.name in OUTPUT_PARAMETERS:
            continue
        value = ctx.params.get(param.name)
        if param.name in paths:  # a file: the path(s) as given
            given = paths[param.name]
            value = given if param.multiple or param.nargs != 1 else given[-1]
        if param.name == "db" and value:  # a records store's URL: never its password
            from rotacal.records.engine import display_url

            value = display_url(str(value))
        out[option_name(param)] = _plain(value)
    return out


def input_paths(ctx: click.Context) -> list[str]:
    """The files the command read, in the order its parameters are declared (the capture first),
    whatever the order on the command line."""
    paths = ctx.meta.get(_INPUT_PATHS_KEY, {})
    return [path for param in ctx.command.params for path in paths.get(param.name, ())]


def provenance() -> dict[str, Any]:
    """The ``provenance`` of the running command (INTERFACE.md "Every result")."""
    ctx = click.get_current_context()
    return provenance_record(command_name(ctx), command_options(ctx), input_paths(ctx))
