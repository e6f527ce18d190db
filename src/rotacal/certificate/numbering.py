"""Certificate numbers drawn with ``number = "auto"``: the next free number of the laboratory's
series, never one already issued.

Until the records store exists (it will draw numbers from its database), the series lives in a
small counter file in the user's data folder (``platformdirs``; ``ROTACAL_DATA_DIR`` overrides it).
A number is *reserved* under an exclusive lock on that file and *consumed* only when the
certificate is complete: a failing certification leaves the counter as it was, and concurrent
``rotacal certify`` processes on one computer never get the same number.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import json
import os
import sys
from collections.abc import Iterator
from pathlib import Path

from rotacal.errors import ConfigError

__all__ = ["DEFAULT_FORMAT", "counter_path", "reserve_number"]

#: The default series: RC-<year of issue>-<four-digit count, from 1 each year>.
DEFAULT_FORMAT = "RC-{year}-{count:04d}"


def data_dir() -> Path:
    """The folder where rotacal keeps its state: ``ROTACAL_DATA_DIR`` or the user's data folder."""
    given = os.environ.get("ROTACAL_DATA_DIR")
    if given:
        return Path(given)
    import platformdirs

    return Path(platformdirs.user_data_dir("rotacal", appauthor=False))


def counter_path() -> Path:
    """The counter file of the certificate numbers."""
    return data_dir() / "certificate-numbers.json"


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    """An exclusive lock on ``path`` + ".lock" for the duration of the block (POSIX ``flock``;
    Windows ``msvcrt.locking``). The lock goes with the process if it dies."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path.with_name(path.name + ".lock"), "a+b") as handle:
        if sys.platform == "win32":  # pragma: no cover - not this platform
            import msvcrt

            handle.seek(0)
            msvcrt.locking(handle.fileno(), msvcrt.LK_LOCK, 1)
            yield
        else:
            import fcntl

            fcntl.flock(handle.fileno(), fcntl.LOCK_EX)
            try:
                yield
            finally:
                fcntl.flock(handle.fileno(), fcntl.LOCK_UN)


def _read(path: Path) -> dict:
    try:
        state = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return {"format": DEFAULT_FORMAT, "last": {}}
    except (OSError, ValueError) as e:
        raise ConfigError(
            f"{path}: the certificate counter cannot be read ({e}); repair or remove it "
            "(numbers already issued must not be drawn again)"
        ) from None
    if not isinstance(state, dict) or not isinstance(state.get("last", {}), dict):
        raise ConfigError(f"{path}: not a certificate counter; repair or remove it")
    return state


@contextlib.contextmanager
def reserve_number(issue_date: dt.date) -> Iterator[str]:
    """Reserve the next number of the series for a certificate issued on ``issue_date``.

    Yields the number while holding the counter's lock; the number is consumed when the block
    ends without an exception and left free when it raises. Keep the block short: it is the
    part of certification that runs one at a time (rendering and publishing the certificate).
    """
    path = counter_path()
    with _locked(path):
        state = _read(path)
        fmt = str(state.get("format") or DEFAULT_FORMAT)
        year = str(issue_date.year)
        count = int(state["last"].get(year, 0)) + 1
        try:
            number = fmt.format(year=year, count=count)
        except (KeyError, IndexError, ValueError) as e:
            raise ConfigError(
                f"{path}: the number format {fmt!r} is not usable ({e}); it may use {{year}} and "
                "{count}"
            ) from None
        yield number
        state["last"][year] = count
        state["format"] = fmt
        temporary = path.with_name(path.name + ".new")
        temporary.write_text(json.dumps(state, indent=2) + "\n", encoding="utf-8")
        os.replace(temporary, path)
