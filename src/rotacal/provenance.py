"""Where a result came from: the ``provenance`` key of every JSON result (INTERFACE.md).

``provenance`` holds ``rotacal_version``, ``command`` (e.g. ``"gyro scale-factor"``), ``options``
(as given, with defaults filled in) and ``inputs`` (each ``{path, sha256, bytes}``). It holds no
wall-clock time, host or user, so that the same inputs give a byte-identical JSON.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

__all__ = ["file_record", "provenance_record", "sha256_file"]

#: Files are hashed in blocks of this many bytes: a capture of any size in flat memory.
HASH_BLOCK_BYTES = 1 << 20


def sha256_file(path: str | os.PathLike[str]) -> str:
    """The SHA-256 of a file's bytes (hex), read in blocks of 1 MiB (never whole into memory)."""
    digest = hashlib.sha256()
    buffer = bytearray(HASH_BLOCK_BYTES)
    view = memoryview(buffer)
    with open(path, "rb", buffering=0) as fh:
        while n := fh.readinto(buffer):
            digest.update(view[:n])
    return digest.hexdigest()


def file_record(path: str | os.PathLike[str]) -> dict[str, Any]:
    """``{path, sha256, bytes}`` of an input file; ``path`` as given (not resolved)."""
    return {
        "path": os.fspath(path),
        "sha256": sha256_file(path),
        "bytes": Path(path).stat().st_size,
    }


def provenance_record(
    command: str,
    options: Mapping[str, Any],
    inputs: Iterable[str | os.PathLike[str]] = (),
) -> dict[str, Any]:
    """The ``provenance`` of a result: version, command, options and the hashed input files.

    Parameters
    ----------
    command : str
        The command without the program name, e.g. ``"gyro scale-factor"``.
    options : mapping
        Every option of the command by its command-line name (``"full-scale-deg-s"``), as given
        or defaulted; values must be JSON-ready.
    inputs : iterable of path
        The files the command read; each is listed once, in the order first given.
    """
    from rotacal import __version__

    paths = list(dict.fromkeys(os.fspath(p) for p in inputs))
    return {
        "rotacal_version": __version__,
        "command": command,
        "options": dict(options),
        "inputs": [file_record(p) for p in paths],
    }
