"""The ``rotacal`` command: thin shells over the public functions, one module per command group.

A user's mistake (bad file, missing column, impossible option) ends with ONE line on stderr and exit
code 2. Unexpected internal errors end with one line and exit code 1; set ROTACAL_DEBUG=1 to see the
traceback.
"""

from rotacal.errors import CaptureError

from ._app import cli, main

# The command modules (allan, motion, …) are imported when their command is used (see
# _app.COMMAND_MODULES): `import rotacal.cli.motion` or `cli.get_command(ctx, "motion")`.

__all__ = ["CaptureError", "cli", "main"]


def __getattr__(name: str) -> object:
    """``rotacal.cli.motion`` and the other command modules, imported on first use (PEP 562)."""
    import importlib

    from ._app import COMMAND_MODULES

    if name in COMMAND_MODULES.values():
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
