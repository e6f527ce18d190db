"""``rotacal gyro scale-factor`` on several captures: one file per set rate, or several logs.

Without ``--rate-from-name``/``--rates`` every capture holds ``rate_deg_s`` and ``output`` and
their rows are pooled. With them, each capture is one set rate (from its name or the table) and
only its ``output`` is read; ``--rest-from`` runs that start and end at rest add the 0 °/s point.

:func:`read_rate_rows` loads the rows; :func:`rate_row_chunks` streams the same rows, file after
file, for :func:`rotacal.gyro.calibrate_scale_factor_chunked` (long logs), and
:func:`rate_row_count` tells how many there are without reading them.
"""

from __future__ import annotations

import contextlib
import functools
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import click
import numpy as np

from rotacal.errors import CaptureError, ConfigError

from ._common import INPUT_FILE, _naming_file, _read, _status
from ._reading import current_read_options

F = TypeVar("F", bound=Callable[..., Any])


def rate_file_options(func: F) -> F:
    """Add ``--rate-from-name``, ``--rates``, ``--rest-from``, ``--rest-band-deg-s`` and
    ``--rest-guard-samples``; the command receives them as one dict ``rate_files``."""

    @functools.wraps(func)
    def command(*args: Any, **kwargs: Any) -> Any:
        keys = ("rate_from_name", "rates_path", "rest_from", "rest_band_deg_s", "rest_guard")
        kwargs["rate_files"] = {k: kwargs.pop(k) for k in keys}
        return func(*args, **kwargs)

    options = [
        click.option(
            "--rate-from-name",
            is_flag=True,
            help="Each CAPTURE is one set rate, stated by its file name: p10.dat = +10 °/s, "
            "m10.dat = −10 °/s, +10.csv, -10.5.txt, 10dps.dat; only 'output' is read.",
        ),
        click.option(
            "--rates",
            "rates_path",
            type=INPUT_FILE,
            metavar="TABLE.csv",
            help="Each CAPTURE is one set rate, given by this table of rows 'file,rate_deg_s' "
            "(it wins over --rate-from-name for the files it lists).",
        ),
        click.option(
            "--rest-from",
            "rest_from",
            multiple=True,
            type=INPUT_FILE,
            metavar="FILE",
            help="A run that starts at rest, turns and stops (repeatable): its samples at rest "
            "form the 0 °/s point (with --rate-from-name or --rates).",
        ),
        click.option(
            "--rest-band-deg-s",
            type=float,
            default=0.5,
            show_default=True,
            help="With --rest-from: rest is where the output indicates a rate within ± this "
            "(through the line fitted to the set rates).",
        ),
        click.option(
            "--rest-guard-samples",
            "rest_guard",
            type=int,
            default=3,
            show_default=True,
            help="With --rest-from: samples dropped on each side of the motion (its ramps).",
        ),
    ]
    wrapped: Any = command
    for option in reversed(options):
        wrapped = option(wrapped)
    return wrapped


@contextlib.contextmanager
def _hint_rate_options(files: int) -> Iterator[None]:
    """Several captures without a rate_deg_s column: say how to give each file's set rate."""
    try:
        yield
    except CaptureError as e:
        if files < 2 or "'rate_deg_s'" not in str(e):
            raise
        raise CaptureError(
            f"{e}; or, when each file holds one set rate, give it with --rate-from-name or --rates"
        ) from None


def _output_of(path: str, columns: Sequence[str], group: str | None) -> np.ndarray:
    with _naming_file(path):
        return np.asarray(_read(path, ["output"], columns, group)["output"])


def _refuse_repeats(paths: Sequence[str]) -> None:
    """A file given twice would count its samples twice and shrink the stated uncertainty."""
    seen: dict[Path, str] = {}
    for path in paths:
        key = Path(path).resolve()
        if key in seen:
            again = f" (as {seen[key]})" if seen[key] != path else ""
            raise ConfigError(
                f"{path} is given twice{again}: its samples would count twice; give each file once"
            )
        seen[key] = path


def _by_file(rate_files: dict[str, Any]) -> bool:
    """Each capture is one set rate (``--rate-from-name`` or ``--rates``)."""
    return bool(rate_files["rate_from_name"] or rate_files["rates_path"] is not None)


def _file_rates(captures: Sequence[str], rate_files: dict[str, Any]) -> list[float]:
    """The set rate of each capture (°/s), from its name or the ``--rates`` table."""
    from rotacal.gyro.rate_sets import read_rates_table, set_rates

    table = None
    if rate_files["rates_path"] is not None:
        table = read_rates_table(rate_files["rates_path"])
    return set_rates(
        captures,
        from_name=rate_files["rate_from_name"],
        table=table,
        table_name=str(rate_files["rates_path"]),
    )


def _check_rest_options(rate_files: dict[str, Any], rates: Sequence[float] | None) -> None:
    if not rate_files["rest_from"]:
        return
    if rates is None:
        raise ConfigError(
            "--rest-from adds a 0 °/s point to a set of one file per set rate: give "
            "--rate-from-name or --rates too"
        )
    if rate_files["rest_band_deg_s"] <= 0 or rate_files["rest_guard"] < 0:
        raise ConfigError("--rest-band-deg-s must be > 0 and --rest-guard-samples ≥ 0")
    if len(set(rates)) < 2:
        raise ConfigError("--rest-from needs plateaus at two set rates at least")


def read_rate_rows(
    captures: Sequence[str],
    columns: Sequence[str],
    group: str | None,
    rate_files: dict[str, Any],
) -> tuple[np.ndarray, np.ndarray]:
    """The (set rate in °/s, output) rows of the captures, as the scale-factor analysis takes."""
    from rotacal.gyro.rate_sets import rest_samples

    _refuse_repeats([*captures, *rate_files["rest_from"]])
    if not _by_file(rate_files):
        _check_rest_options(rate_files, None)
        rows = []
        for path in captures:
            with _naming_file(path), _hint_rate_options(len(captures)):
                cap = _read(path, ["rate_deg_s", "output"], columns, group)
            rows.append((np.asarray(cap["rate_deg_s"]), np.asarray(cap["output"])))
        return np.concatenate([r for r, _ in rows]), np.concatenate([o for _, o in rows])
    rates = _file_rates(captures, rate_files)
    outputs = [_output_of(path, columns, group) for path in captures]
    rate = np.concatenate([np.full(o.shape[0], r) for r, o in zip(rates, outputs, strict=True)])
    output = np.concatenate(outputs)
    if rate_files["rest_from"]:
        _check_rest_options(rate_files, rates)
        # the straight line through the plateaus' means tells which output means rest
        means = [float(np.mean(o)) for o in outputs]
        scale_factor, bias = np.polyfit(rates, means, 1)
        rest = [
            rest_samples(
                _output_of(path, columns, group),
                scale_factor=float(scale_factor),
                bias=float(bias),
                band_deg_s=rate_files["rest_band_deg_s"],
                guard_samples=rate_files["rest_guard"],
                name=Path(path).name,
            )
            for path in rate_files["rest_from"]
        ]
        rate = np.concatenate([rate, np.zeros(sum(r.shape[0] for r in rest))])
        output = np.concatenate([output, *rest])
    return rate, output


# ------------------------------------------------------------------------------------ streaming
#: Rows per chunk of a streamed log (2·10⁶: 32 MB of the two columns, ~0.3 GB of work arrays).
CHUNK_ROWS = 2_000_000


def _file_chunks(
    path: str, names: Sequence[str], columns: Sequence[str], group: str | None
) -> Iterator[Mapping[str, np.ndarray]]:
    """The named canonical columns of one file in chunks (the reader hands each chunk's mapped
    pages back once the next one is asked for: flat memory over a long file)."""
    from rotacal.io import iter_capture_chunks, parse_column_mapping

    yield from iter_capture_chunks(
        path,
        list(names),
        chunk_rows=CHUNK_ROWS,
        mapping=parse_column_mapping(columns),
        group=group,
        read_options=current_read_options(),
    )


def _length(path: str, column: str, columns: Sequence[str], group: str | None) -> int:
    from rotacal.io import capture_length, parse_column_mapping

    with _naming_file(path):
        return capture_length(
            path,
            column,
            mapping=parse_column_mapping(columns),
            group=group,
            read_options=current_read_options(),
        )


def rate_row_count(
    captures: Sequence[str], columns: Sequence[str], group: str | None, rate_files: dict[str, Any]
) -> int:
    """Rows the analysis will take from the captures (the rest runs counted whole); the options
    are checked first, as :func:`read_rate_rows` does."""
    _refuse_repeats([*captures, *rate_files["rest_from"]])
    if not _by_file(rate_files):
        _check_rest_options(rate_files, None)
    column = "output" if _by_file(rate_files) else "rate_deg_s"
    with _hint_rate_options(len(captures)):
        n = sum(_length(path, column, columns, group) for path in captures)
    return n + sum(_length(p, "output", columns, group) for p in rate_files["rest_from"])


def _at_rest(
    path: str, columns: Sequence[str], group: str | None, line: tuple[float, float], rf: dict
) -> tuple[int, int, int]:
    """(rows, end of the rest before the motion, start of the rest after it) of a ``--rest-from``
    run, read in chunks: :func:`rotacal.gyro.rate_sets.rest_samples`'s rule on the whole run."""
    scale_factor, bias = line
    band, guard = rf["rest_band_deg_s"], rf["rest_guard"]
    first = last = -1
    n = 0
    with _naming_file(path):
        for chunk in _file_chunks(path, ["output"], columns, group):
            moving = np.flatnonzero(np.abs((chunk["output"] - bias) / scale_factor) >= band)
            if moving.size:
                first = n + int(moving[0]) if first < 0 else first
                last = n + int(moving[-1])
            n += chunk["output"].size
    name = Path(path).name
    if first < 0:
        raise CaptureError(
            f"{name}: the output never leaves ±{band:g} °/s of rest, so the run shows no "
            "motion; --rest-from takes runs that start at rest, turn and stop"
        )
    head, tail = max(first - guard, 0), min(last + 1 + guard, n)
    if head == 0 and tail == n:
        raise CaptureError(
            f"{name}: no sample at rest before or after the motion; --rest-from takes runs that "
            "start at rest, turn and stop"
        )
    return n, head, tail


def rate_row_chunks(
    captures: Sequence[str],
    columns: Sequence[str],
    group: str | None,
    rate_files: dict[str, Any],
) -> Callable[[Sequence[str]], Iterator[Mapping[str, np.ndarray]]]:
    """The rows of :func:`read_rate_rows` as a chunk source for
    :func:`rotacal.gyro.calibrate_scale_factor_chunked`: each call streams the captures in turn
    (with one file per set rate, a pass over the set rates alone reads no file). With
    ``--rest-from``, the plateaus' means and each run's rest are found first, in passes of their
    own."""
    _refuse_repeats([*captures, *rate_files["rest_from"]])
    if not _by_file(rate_files):
        _check_rest_options(rate_files, None)

        def pooled(names: Sequence[str]) -> Iterator[Mapping[str, np.ndarray]]:
            for path in captures:
                with _naming_file(path), _hint_rate_options(len(captures)):
                    yield from _file_chunks(path, names, columns, group)

        return pooled
    rates = _file_rates(captures, rate_files)
    _check_rest_options(rate_files, rates)
    lengths = [_length(path, "output", columns, group) for path in captures]
    rest: list[tuple[str, int, int, int]] = []
    if rate_files["rest_from"]:
        with _status("finding the rest in the --rest-from runs"):
            means = [_mean_output(path, columns, group) for path in captures]
            scale_factor, bias = np.polyfit(rates, means, 1)
            line = (float(scale_factor), float(bias))
            rest = [
                (p, *_at_rest(p, columns, group, line, rate_files)) for p in rate_files["rest_from"]
            ]

    def rated(
        path: str, rate: float, n: int, names: Sequence[str], keep: tuple[int, int]
    ) -> Iterator[Mapping[str, np.ndarray]]:
        """One file's rows at ``rate``, those before ``keep[0]`` and from ``keep[1]`` on; only the
        set rates, without reading the file, when no output is asked for."""
        if "output" not in names:
            for lo, hi in ((0, keep[0]), (keep[1], n)):
                for start in range(lo, hi, CHUNK_ROWS):
                    yield {"rate_deg_s": np.full(min(CHUNK_ROWS, hi - start), rate)}
            return
        row = 0
        with _naming_file(path):
            for chunk in _file_chunks(path, ["output"], columns, group):
                out = chunk["output"]
                size = out.size
                if row < keep[1] and row + size > keep[0]:  # overlaps the motion: dropped
                    idx = np.arange(row, row + size)
                    out = out[(idx < keep[0]) | (idx >= keep[1])]
                row += size
                yield {"rate_deg_s": np.full(out.size, rate), "output": out}

    def by_file(names: Sequence[str]) -> Iterator[Mapping[str, np.ndarray]]:
        for path, rate, n in zip(captures, rates, lengths, strict=True):
            yield from rated(path, rate, n, names, (n, n))
        for path, n, head, tail in rest:
            yield from rated(path, 0.0, n, names, (head, tail))

    return by_file


def _mean_output(path: str, columns: Sequence[str], group: str | None) -> float:
    """The mean output of one plateau file, read in chunks."""
    total, n = 0.0, 0
    with _naming_file(path):
        for chunk in _file_chunks(path, ["output"], columns, group):
            total += float(np.sum(chunk["output"]))
            n += chunk["output"].size
    return total / n if n else math.nan
