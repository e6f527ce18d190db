"""The ``rotacal`` command: thin shells over the public functions, one module per command group.

A user's mistake (bad file, missing column, impossible option) ends with ONE line on stderr and exit
code 2. Unexpected internal errors end with one line and exit code 1; set ROTACAL_DEBUG=1 to see the
traceback.
"""

from rotacal.errors import CaptureError

from . import (  # noqa: F401  (registers the commands)
    allan,
    certify,
    gyro,
    inspect,
    motion,
    pulses,
    records,
    simulate,
    turntable,
)
from ._app import cli, main

__all__ = ["CaptureError", "cli", "main"]
