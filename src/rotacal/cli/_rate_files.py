"""``rotacal gyro scale-factor`` on several captures: one file per set rate, or several logs.

Without ``--rate-from-name``/``--rates`` every capture holds ``rate_deg_s`` and ``output`` and
their rows are pooled. With them, each capture is one set rate (from its name or the table) and
only its ``output`` is read; ``--rest-from`` runs that start and end at rest add the 0 °/s point.
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, TypeVar

import click
import numpy as np

from rotacal.errors import CaptureError, ConfigError

from ._common import INPUT_FILE, _naming_file, _read

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


def read_rate_rows(
    captures: Sequence[str],
    columns: Sequence[str],
    group: str | None,
    rate_files: dict[str, Any],
) -> tuple[np.ndarray, np.ndarray]:
    """The (set rate in °/s, output) rows of the captures, as the scale-factor analysis takes."""
    from rotacal.gyro.rate_sets import read_rates_table, rest_samples, set_rates

    _refuse_repeats([*captures, *rate_files["rest_from"]])
    by_file = rate_files["rate_from_name"] or rate_files["rates_path"] is not None
    if not by_file:
        if rate_files["rest_from"]:
            raise ConfigError(
                "--rest-from adds a 0 °/s point to a set of one file per set rate: give "
                "--rate-from-name or --rates too"
            )
        rows = []
        for path in captures:
            with _naming_file(path), _hint_rate_options(len(captures)):
                cap = _read(path, ["rate_deg_s", "output"], columns, group)
            rows.append((np.asarray(cap["rate_deg_s"]), np.asarray(cap["output"])))
        return np.concatenate([r for r, _ in rows]), np.concatenate([o for _, o in rows])
    table = None
    if rate_files["rates_path"] is not None:
        table = read_rates_table(rate_files["rates_path"])
    rates = set_rates(
        captures,
        from_name=rate_files["rate_from_name"],
        table=table,
        table_name=str(rate_files["rates_path"]),
    )
    outputs = [_output_of(path, columns, group) for path in captures]
    rate = np.concatenate([np.full(o.shape[0], r) for r, o in zip(rates, outputs, strict=True)])
    output = np.concatenate(outputs)
    if rate_files["rest_from"]:
        if rate_files["rest_band_deg_s"] <= 0 or rate_files["rest_guard"] < 0:
            raise ConfigError("--rest-band-deg-s must be > 0 and --rest-guard-samples ≥ 0")
        # the straight line through the plateaus' means tells which output means rest
        means = [float(np.mean(o)) for o in outputs]
        if len(set(rates)) < 2:
            raise ConfigError("--rest-from needs plateaus at two set rates at least")
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
