"""Running a plan's measurements: each one is its analysis command, run in this process.

A measurement's ``options`` are the command's options as on the CLI without ``--`` (INTERFACE.md),
so the runner hands them to the command itself: the CLI's own parser checks and converts them,
fills in its defaults and writes the command's own JSON, ``provenance`` included. There is one
definition of every option and one JSON per command, whether a user types the command or a plan
names it. Files the options name are taken relative to the plan's folder, like the captures.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import click

from rotacal.errors import ConfigError, RotacalError

from .model import Measurement, Plan

__all__ = ["command_of", "measurement_inputs", "run_measurement", "run_plan"]


def command_of(name: str) -> click.Command:
    """The click command of an analysis (``"gyro scale-factor"``)."""
    from rotacal.cli import cli

    command: click.Command = cli
    for word in name.split():
        assert isinstance(command, click.Group)
        found = command.get_command(click.Context(command), word)  # loads the command's module
        if found is None:  # read_plan admits only MEASUREMENT_COMMANDS
            raise ConfigError(f"no such command: rotacal {name}")
        command = found
    return command


def _arguments(plan: Plan, m: Measurement, json_path: Path) -> list[str]:
    """The command line (after ``rotacal``) that runs measurement ``m``, its JSON to ``json_path``."""
    from rotacal.cli._provenance import option_name

    command = command_of(m.command)
    params = {option_name(p): p for p in command.params if isinstance(p, click.Option)}
    variadic = [p for p in command.params if isinstance(p, click.Argument) and p.nargs == -1]
    if len(m.captures) > 1 and not variadic:
        raise ConfigError(
            f"{plan.path}: {m.key}.capture: '{m.command}' reads one capture, not {len(m.captures)}"
        )
    args = [*m.command.split(), *(os.fspath(c) for c in m.captures)]
    for name, value in m.options:
        param = params.get(name)
        if param is None or name in ("help", "json", "report", "overwrite"):
            known = ", ".join(
                sorted(n for n in params if n not in ("help", "json", "report", "overwrite"))
            )
            raise ConfigError(
                f"{plan.path}: {m.key}.options.{name}: '{m.command}' has no option --{name} "
                f"(its options: {known})"
            )
        flag = f"--{name}"
        values = value if isinstance(value, list) else [value]
        if isinstance(value, list) and not param.multiple and not (param.nargs and param.nargs > 1):
            raise ConfigError(
                f"{plan.path}: {m.key}.options.{name}: --{name} takes one value, not a list"
            )
        if param.is_flag:
            if not isinstance(value, bool):
                raise ConfigError(
                    f"{plan.path}: {m.key}.options.{name}: --{name} is a switch: true or false"
                )
            if value:
                args.append(flag)
            elif param.secondary_opts:
                args.append(param.secondary_opts[0])
            continue
        for v in values:
            if isinstance(v, bool):
                raise ConfigError(
                    f"{plan.path}: {m.key}.options.{name}: --{name} takes a value, not {v}"
                )
            text = str(v)
            if isinstance(param.type, click.Path):  # a file named in the plan: relative to it
                text = os.fspath(plan.path.parent / text)
            args += [flag, text]
    args += ["--json", os.fspath(json_path)]
    return args


def measurement_inputs(plan: Plan, m: Measurement) -> list[str]:
    """The files measurement ``m`` reads, as its JSON's ``provenance.inputs`` will list them:
    in the order its command declares them (the capture first), each once, a file the options
    name taken relative to the plan's folder. Known before anything runs, so that a batch can
    tell a plan certified already from its ``plan_sha256`` without measuring it."""
    from rotacal.cli._common import INPUT_FILE
    from rotacal.cli._provenance import option_name

    options = dict(m.options)
    paths: list[str] = []
    for param in command_of(m.command).params:
        if type(param.type) is not type(INPUT_FILE):
            continue
        if isinstance(param, click.Argument):
            paths += [os.fspath(c) for c in m.captures]
            continue
        value = options.get(option_name(param))
        if value is None:
            continue
        for v in value if isinstance(value, list) else [value]:
            paths.append(os.fspath(plan.path.parent / str(v)))
    return list(dict.fromkeys(paths))


def _relative_paths(data: Any, plan_dir: Path) -> Any:
    """``provenance`` with every path the plan named written relative to the plan's folder, so
    that the JSON does not depend on where the plan lies."""
    prefix = os.fspath(plan_dir) + os.sep
    if isinstance(data, str) and data.startswith(prefix):
        return Path(os.path.relpath(data, plan_dir)).as_posix()
    if isinstance(data, list):
        return [_relative_paths(v, plan_dir) for v in data]
    if isinstance(data, Mapping):
        return {k: _relative_paths(v, plan_dir) for k, v in data.items()}
    return data


def run_measurement(plan: Plan, m: Measurement, scratch: Path) -> dict[str, Any]:
    """Run measurement ``m`` of ``plan`` and return the command's JSON (a dict).

    ``scratch`` is a folder for the command's JSON file. The command's summary (stdout) and its
    ``wrote`` line are not shown; its warnings are (on stderr, naming the measurement).

    Raises
    ------
    ConfigError
        One line naming the plan file, the measurement (``measurement[2]``) and the capture or
        option at fault: a bad option value, or a capture the command refuses.
    """
    from rotacal.cli import cli

    json_path = scratch / f"measurement-{m.index}.json"
    args = _arguments(plan, m, json_path)
    names = ", ".join(os.path.relpath(c, plan.path.parent) for c in m.captures)
    out, err = io.StringIO(), io.StringIO()
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            with cli.make_context("rotacal", args) as ctx:
                cli.invoke(ctx)
    except click.UsageError as e:
        raise ConfigError(f"{plan.path}: {m.key}.options: {e.format_message()}") from None
    except click.ClickException as e:
        raise ConfigError(f"{plan.path}: {m.key} ({names}): {e.format_message()}") from None
    except RotacalError as e:
        raise type(e)(f"{plan.path}: {m.key} ({names}): {' '.join(str(e).split())}") from None
    except (OSError, MemoryError) as e:
        raise ConfigError(f"{plan.path}: {m.key} ({names}): {e}") from None
    finally:
        for line in err.getvalue().splitlines():
            if line.startswith("rotacal: warning: "):
                click.echo(f"rotacal: warning: {m.key}: {line[18:]}", err=True)
    data = json.loads(json_path.read_text(encoding="utf-8"))
    data["provenance"] = _relative_paths(data.get("provenance", {}), plan.path.parent)
    return data


def run_plan(
    plan: Plan, scratch: Path, advance: Callable[[str], None] | None = None
) -> list[dict[str, Any]]:
    """Run every measurement of ``plan`` in order; the commands' JSON, one per measurement.

    ``advance(name)`` is called after each measurement (a progress bar). Every measurement's
    option names and captures are checked before the first one runs, so a misspelt option of the
    last measurement does not wait for the others."""
    for m in plan.measurements:
        _arguments(plan, m, scratch / "check.json")
    results = []
    for m in plan.measurements:
        results.append(run_measurement(plan, m, scratch))
        if advance is not None:
            advance(m.name)
    return results
