"""Where a result came from: the ``provenance`` key of every JSON result (INTERFACE.md).

``provenance`` holds ``rotacal_version``, ``command`` (e.g. ``"gyro scale-factor"``), ``options``
(as given, with defaults filled in) and ``inputs`` (each ``{path, sha256, bytes}``). It holds no
wall-clock time, host or user, so that the same inputs give a byte-identical JSON.
"""

from __future__ import annotations

import hashlib
import os
import threading
from collections.abc import Iterable, Mapping
from concurrent.futures import Future
from pathlib import Path
from typing import Any

__all__ = ["file_record", "prefetch_sha256", "provenance_record", "sha256_file"]

#: Files are hashed in blocks of this many bytes: a capture of any size in flat memory.
HASH_BLOCK_BYTES = 1 << 20


#: Hashes started ahead (:func:`prefetch_sha256`), by the file's identity when they started.
_PREFETCHED: dict[tuple[str, int, int], Future[str]] = {}


def _identity(path: str | os.PathLike[str]) -> tuple[str, int, int] | None:
    """(real path, size, modification time in ns), or None when the file cannot be looked at."""
    try:
        st = os.stat(path)
        return os.path.realpath(path), st.st_size, st.st_mtime_ns
    except OSError:
        return None


def prefetch_sha256(paths: Iterable[str | os.PathLike[str]]) -> None:
    """Start hashing each file in a background thread while the command analyses it.

    hashlib lets other threads run while it hashes a block, so on a machine with a free core the
    hash of a large capture costs no wall time; :func:`sha256_file` then takes the result, unless
    the file changed since (size or modification time), when it hashes the file again.
    """
    for path in paths:
        key = _identity(path)
        if key is None or key in _PREFETCHED or not os.path.isfile(key[0]):
            continue
        future: Future[str] = Future()

        def work(p: str = key[0], f: Future[str] = future) -> None:
            try:
                f.set_result(_hash(p))
            except BaseException as exc:  # handed to the caller that waits for it
                f.set_exception(exc)

        _PREFETCHED[key] = future
        threading.Thread(target=work, name="rotacal-sha256", daemon=True).start()


def sha256_file(path: str | os.PathLike[str]) -> str:
    """The SHA-256 of a file's bytes (hex), read in blocks of 1 MiB (never whole into memory);
    the result of :func:`prefetch_sha256` when it hashed the same, unchanged file."""
    key = _identity(path)
    future = _PREFETCHED.pop(key, None) if key is not None else None
    if future is not None:
        return future.result()
    return _hash(path)


def _hash(path: str | os.PathLike[str]) -> str:
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
