"""The ``rotacal`` command group and its entry point: every error becomes one line.

A user's mistake (bad file, missing column, impossible option) ends with ONE line on stderr and exit
code 2. Unexpected internal errors end with one line and exit code 1; set ROTACAL_DEBUG=1 to see the
traceback.
"""

from __future__ import annotations

import importlib
import os
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import click
import numpy as np

from rotacal.errors import RotacalError

from ._help import example

F = TypeVar("F", bound=Callable[..., Any])


#: The module of ``rotacal.cli`` that defines each top-level command. A command's module is
#: imported when the command is looked up, so ``rotacal motion encoder`` does not import the
#: Allan, gyro, pulse, simulation and records commands (and what they import) at start-up.
COMMAND_MODULES = {
    "allan": "allan",
    "batch": "batch",
    "certify": "certify",
    "demo": "simulate",
    "gyro": "gyro",
    "inspect": "inspect",
    "motion": "motion",
    "position": "position",
    "rate": "pulses",
    "records": "records",
    "selfcal": "pulses",
    "simulate": "simulate",
    "specs": "turntable",
    "turntable": "turntable",
    "verify": "verify",
}


class _Group(click.Group):
    """Turns every error into one line: exit 2 for the user's, 1 for ours; loads each command's
    module when the command is first looked up (:data:`COMMAND_MODULES`)."""

    def list_commands(self, ctx: click.Context | None) -> list[str]:
        return sorted(set(self.commands) | set(COMMAND_MODULES))

    def get_command(self, ctx: click.Context | None, cmd_name: str) -> click.Command | None:
        if cmd_name not in self.commands and cmd_name in COMMAND_MODULES:
            # the module registers its commands on `cli` as it is imported
            importlib.import_module(f"rotacal.cli.{COMMAND_MODULES[cmd_name]}")
        return self.commands.get(cmd_name)

    def load_all(self) -> None:
        """Import every command module (``commands`` then holds every command)."""
        for name in COMMAND_MODULES:
            self.get_command(None, name)

    def main(self, *args: Any, **kwargs: Any) -> Any:
        try:
            # Warnings become one line each; NumPy's floating-point chatter is silenced because
            # the checks name the fault (a NaN, an overflowing value) themselves.
            with warnings.catch_warnings(), np.errstate(all="ignore"):
                warnings.showwarning = _one_line_warning
                return super().main(*args, **{**kwargs, "standalone_mode": False})
        except click.exceptions.Exit as e:
            sys.exit(e.exit_code)
        except click.Abort:
            click.echo("rotacal: aborted", err=True)
            sys.exit(130)
        except click.UsageError as e:
            hint = f" (see '{e.ctx.command_path} --help')" if e.ctx else ""
            click.echo(f"rotacal: error: {e.format_message()}{hint}", err=True)
            sys.exit(2)
        except click.ClickException as e:
            click.echo(f"rotacal: error: {e.format_message()}", err=True)
            sys.exit(2)
        except RotacalError as e:
            click.echo(f"rotacal: error: {_one_line(e)}", err=True)
            sys.exit(2)
        except (FileNotFoundError, IsADirectoryError, PermissionError) as e:
            click.echo(f"rotacal: error: {e.strerror}: {e.filename}", err=True)
            sys.exit(2)
        except MemoryError:
            click.echo(
                "rotacal: error: out of memory — analyse a shorter span (--periods)", err=True
            )
            sys.exit(2)
        except Exception as e:  # pragma: no cover - a bug, not a user error
            if os.environ.get("ROTACAL_DEBUG"):
                raise
            click.echo(
                f"rotacal: internal error: {type(e).__name__}: {_one_line(e)} "
                "(a bug: please report it; ROTACAL_DEBUG=1 shows the traceback)",
                err=True,
            )
            sys.exit(1)


def _one_line_warning(message: Any, *args: Any, **kwargs: Any) -> None:
    click.echo(f"rotacal: warning: {' '.join(str(message).split())}", err=True)


def _one_line(e: BaseException) -> str:
    return " ".join(str(e).split()) or type(e).__name__


@click.group(
    cls=_Group,
    context_settings={"help_option_names": ["-h", "--help"]},
    epilog=example(
        "rotacal demo                                  # a campaign on the twin",
        "rotacal simulate encoder --out run.npz        # a capture and its truth",
        "rotacal motion encoder run.npz --lines 36000  # calibrate from it",
        "rotacal COMMAND --help                        # options, an example",
    ),
)
@click.version_option(package_name="rotacal")
def cli() -> None:
    """rotacal — calibration of rotary tables and the gyroscopes tested on them.

    Start with `rotacal demo`, then point an analysis command at your own capture (CSV, text,
    NPZ, HDF5 or NI TDMS). Bad input ends with exit code 2 and one line naming the fault.
    """


def main(argv: Sequence[str] | None = None) -> None:
    """Entry point of the console script."""
    cli.main(args=list(argv) if argv is not None else None, prog_name="rotacal")
