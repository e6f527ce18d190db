"""``rotacal gyro scale-factor`` on a continuous log: the options, the choice of path and the read.

A capture with ``time_s``, ``rate_deg_s`` and ``output`` (optional ``temperature_c``) is one long
rate-table log: :func:`rotacal.gyro.scale_factor_log.calibrate_scale_factor_log` finds its
plateaus and fits them. A log of up to ``LOG_IN_MEMORY_MAX_ROWS`` rows is read whole; a longer
one (or any with ``--chunked``) is streamed: the detection and the fit run as passes over the
file in chunks (:func:`rotacal.gyro.scale_factor_log.calibrate_scale_factor_log_chunked`), so
memory stays flat whatever its length, and the result is the in-memory one to 1e-9.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterator, Sequence
from typing import Any, TypeVar

import click
import numpy as np

from rotacal.errors import ConfigError

from ._common import _status

F = TypeVar("F", bound=Callable[..., Any])

#: Logs longer than this stream: the in-memory detection holds the columns and a few arrays of
#: the log's length (~150 bytes a row), the streamed one a chunk, and is the faster from 10⁶
#: rows on (benchmarks/bench_gyro_log_stream.py: 3.5 s against 12.5 s at 10⁷).
LOG_IN_MEMORY_MAX_ROWS = 1_000_000
#: Rows per chunk of the streamed log (4 columns of float64: 64 MB).
_CHUNK_ROWS = 2_000_000
#: Passes over the log of the streamed analysis (for its progress bar): six of the detection,
#: one of the fit over the output.
_PASSES = 7

_KEYS = ("plateaus", "settle_s", "plateau_window_s", "min_plateau_s")


def option_group(name: str, keys: Sequence[str], options: Sequence[Any]) -> Callable[[F], F]:
    """A decorator adding the click ``options`` whose parameters are ``keys``; the command
    receives them as one dict, its keyword ``name``."""

    def decorate(func: F) -> F:
        @functools.wraps(func)
        def command(*args: Any, **kwargs: Any) -> Any:
            kwargs[name] = {k: kwargs.pop(k) for k in keys}
            return func(*args, **kwargs)

        wrapped: Any = command
        for option in reversed(options):
            wrapped = option(wrapped)
        return wrapped

    return decorate


def log_options(func: F) -> F:
    """Add ``--plateaus/--no-plateaus``, ``--settle-s``, ``--plateau-window-s`` and
    ``--min-plateau-s``; the command receives them as one dict ``log_opts``."""
    options = [
        click.option(
            "--plateaus/--no-plateaus",
            default=None,
            help="Treat the capture as one continuous log and find the table's plateaus (or "
            "not) [default: when one capture has a time_s column].",
        ),
        click.option(
            "--settle-s",
            type=float,
            default=None,
            help="Continuous log: seconds dropped from each plateau's start [default: the "
            "DUT's settling read from the output, at least one window].",
        ),
        click.option(
            "--plateau-window-s",
            type=float,
            default=None,
            help="Continuous log: window of the step detector (s) [default: 1].",
        ),
        click.option(
            "--min-plateau-s",
            type=float,
            default=None,
            help="Continuous log: shortest plateau used after settling (s) [default: 5 windows].",
        ),
    ]
    return option_group("log_opts", _KEYS, options)(func)


def continuous_log(
    captures: Sequence[str],
    rate_files: dict[str, Any],
    columns: Sequence[str],
    group: str | None,
    log_opts: dict[str, Any],
    where: tuple[int | None, str | None],
) -> bool:
    """Whether the captures are one continuous log (``--plateaus``, or one capture with time_s)."""
    from rotacal.io import capture_columns, parse_column_mapping

    from ._reading import current_read_options

    wanted = log_opts["plateaus"]
    single = len(captures) == 1 and not (
        rate_files["rate_from_name"] or rate_files["rates_path"] is not None
    )
    if wanted is None and single and not rate_files["rest_from"]:
        names = capture_columns(
            captures[0],
            mapping=parse_column_mapping(columns),
            group=group,
            read_options=current_read_options(),
        )
        wanted = "time_s" in names
    given = [k for k in _KEYS[1:] if log_opts[k] is not None]
    if not wanted:
        if given:
            raise ConfigError(
                f"--{given[0].replace('_', '-')} applies to a continuous log (one capture with "
                "time_s, rate_deg_s and output); drop it or give --plateaus"
            )
        return False
    if not single or rate_files["rest_from"]:
        raise ConfigError(
            "--plateaus reads one continuous log: give one capture, without --rate-from-name, "
            "--rates or --rest-from"
        )
    if any(w is not None for w in where):
        raise ConfigError(
            "a continuous log is analysed in this process: drop --workers/--scheduler"
        )
    return True


def scale_factor_from_log(
    capture: str,
    columns: Sequence[str],
    group: str | None,
    options: dict[str, Any],
    log_opts: dict[str, Any],
    chunked: bool | None,
) -> Any:
    """Run :func:`calibrate_scale_factor_log` on the log's columns read whole, or its chunked
    twin on the file streamed in chunks (``chunked``; None: when the log is long)."""
    from rotacal.gyro.scale_factor_log import calibrate_scale_factor_log
    from rotacal.io import capture_columns, capture_length, parse_column_mapping, read_capture

    from ._common import _naming_file
    from ._reading import current_read_options

    mapping, reading = parse_column_mapping(columns), current_read_options()
    names = capture_columns(capture, mapping=mapping, group=group, read_options=reading)
    needed = ["time_s", "rate_deg_s", "output"]
    needed += ["temperature_c"] if "temperature_c" in names else []
    search = {
        "settle_s": log_opts["settle_s"],
        "window_s": log_opts["plateau_window_s"],
        "min_plateau_s": log_opts["min_plateau_s"],
    }
    rows = None
    if chunked is not False:
        with _naming_file(capture):
            rows = capture_length(
                capture, "time_s", mapping=mapping, group=group, read_options=reading
            )
        chunked = chunked or rows > LOG_IN_MEMORY_MAX_ROWS
    if chunked:
        source = _file_chunks(capture, mapping, group, reading)
        with _naming_file(capture), _log_progress(int(rows or 0)) as (find, fit):
            return _chunked(source, rows, "temperature_c" in needed, search, options, find, fit)
    with _naming_file(capture), _status(f"reading {capture}"):
        cap = read_capture(
            capture, columns=needed, mapping=mapping, group=group, read_options=reading
        )
    with _naming_file(capture), _status("finding the plateaus and fitting"):
        return calibrate_scale_factor_log(
            cap["time_s"],
            cap["rate_deg_s"],
            cap["output"],
            temperature_c=cap.columns.get("temperature_c"),
            chunked=chunked,
            **search,
            **options,
        )


def _chunked(
    source: Any,
    rows: int | None,
    temperature: bool,
    search: dict[str, Any],
    options: dict[str, Any],
    find: Callable[[int], None],
    fit: Callable[[int], None],
) -> Any:
    from rotacal.gyro.scale_factor_log import calibrate_scale_factor_log_chunked

    return calibrate_scale_factor_log_chunked(
        source,
        rows=rows,
        temperature=temperature,
        progress=find,
        fit_progress=fit,
        **search,
        **options,
    )


@contextlib.contextmanager
def _log_progress(rows: int) -> Iterator[tuple[Callable[[int], None], Callable[[int], None]]]:
    """One bar over the streamed analysis's passes: the detection's, then the fit's."""
    from ._common import _sample_progress

    total = _PASSES * rows
    with _sample_progress(total, "plateaus and fit (streamed)") as bar:
        seen = [0]

        def find(done: int) -> None:
            seen[0] = done
            bar(min(done, total))

        yield find, lambda done: bar(min(seen[0] + done // 2, total))


def _file_chunks(
    path: str, mapping: dict[str, str], group: str | None, reading: Any
) -> Callable[[Sequence[str]], Iterator[dict[str, np.ndarray]]]:
    """A log chunk source over a capture file: each call streams the named columns with
    :func:`rotacal.io.iter_capture_chunks` (memory-mapped where the format allows, the pages of
    each chunk handed back); columns once read through with the reader's checks are not checked
    again."""
    from rotacal.io import iter_capture_chunks

    verified: set[str] = set()

    def chunks(names: Sequence[str]) -> Iterator[dict[str, np.ndarray]]:
        yield from iter_capture_chunks(
            path,
            list(names),
            chunk_rows=_CHUNK_ROWS,
            mapping=mapping,
            group=group,
            read_options=reading,
            verified=set(names) <= verified,
        )
        verified.update(names)  # reached only when the pass ran to the end

    return chunks


def log_sections(result: Any) -> list[Any]:
    """The plateau figure's section of a continuous log's result (none for a rate-table one)."""
    if not hasattr(result, "plateaus"):
        return []
    from rotacal.report.gyro_plateaus import plateaus_section

    return [plateaus_section(result)]
