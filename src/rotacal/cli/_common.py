"""Pieces every command shares: progress bars, outputs, reading options and captures."""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any, TypeVar

import click

from rotacal.errors import CaptureError, ConfigError

F = TypeVar("F", bound=Callable[..., Any])


@contextlib.contextmanager
def _progress(total: int, description: str) -> Iterator[Callable[[str], None]]:
    """A progress bar on a terminal (stderr), silent otherwise. Yields ``advance(label)``."""
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    console = Console(stderr=True)
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total}"),
        TimeElapsedColumn(),
        console=console,
        disable=not console.is_terminal,
        transient=True,
    ) as bar:
        task = bar.add_task(description, total=total)

        def advance(label: str) -> None:
            bar.update(task, advance=1, description=f"{description}: {label}")

        yield advance


#: Above this many samples the encoder capture is streamed in chunks (its memory then stays flat;
#: in memory the pipeline holds ~8 float64 copies of the capture).
_IN_MEMORY_MAX_SAMPLES = 30_000_000


@contextlib.contextmanager
def _sample_progress(total: int, description: str) -> Iterator[Callable[[int], None]]:
    """A progress bar over samples processed, on a terminal (stderr); silent otherwise."""
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    console = Console(stderr=True)
    with Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f} %"),
        TimeRemainingColumn(),
        console=console,
        disable=not console.is_terminal,
        transient=True,
    ) as bar:
        task = bar.add_task(description, total=total)
        yield lambda done: bar.update(task, completed=done)


@contextlib.contextmanager
def _status(message: str) -> Iterator[None]:
    """A spinner with a message on a terminal (stderr) while a long step runs; silent otherwise."""
    from rich.console import Console

    console = Console(stderr=True)
    if not console.is_terminal:
        yield
        return
    with console.status(message):
        yield


def _check_outputs(json_path: str | None, report_path: str | None, overwrite: bool) -> None:
    """Refuse outputs that would replace an existing file (unless --overwrite) or each other."""
    if report_path == "-":
        raise ConfigError("--report needs a file name (the report is HTML, not for stdout)")
    if json_path and report_path and json_path != "-":
        if Path(json_path).resolve() == Path(report_path).resolve():
            raise ConfigError("--json and --report name the same file; give them different names")
    for option, target in (("--json", json_path), ("--report", report_path)):
        if not target or target == "-":
            continue
        if Path(target).is_dir():
            raise ConfigError(f"{option} {target} is a folder; give a file name")
        if not overwrite and Path(target).exists():
            raise ConfigError(f"{option} {target} exists; choose another name or pass --overwrite")


def _write_json(data: Any, target: str | None, protect: Sequence[Path] = ()) -> None:
    if target is None:
        return
    from rotacal.results import to_jsonable

    text = json.dumps(to_jsonable(data), indent=2, allow_nan=False)
    if target == "-":
        click.echo(text)
        return
    path = Path(target)
    _refuse_overwrite(path, protect, "--json")
    if not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text + "\n", encoding="utf-8")


def _refuse_overwrite(path: Path, protect: Sequence[Path], option: str) -> None:
    for p in protect:
        if path.exists() and p.exists() and path.resolve() == p.resolve():
            raise ConfigError(
                f"{option} {path} would overwrite the input file {p}; choose another name"
            )


def _load_specs_option(ctx: click.Context, param: click.Parameter, value: str | None) -> Any:
    """``--specs FILE.toml`` → InstrumentSpecs (one line on any fault, before the capture is read)."""
    if value is None:
        return None
    from rotacal.uncertainty.specs import load_specs

    if not Path(value).is_file():
        raise ConfigError(f"--specs {value}: no such file")
    return load_specs(Path(value))


def _analysis_options(func: F) -> F:
    """Options every analysis command takes."""
    options = [
        click.option(
            "--json", "json_path", metavar="PATH", help="Write the results as JSON ('-' = stdout)."
        ),
        click.option(
            "--report",
            "report_path",
            metavar="PATH.html",
            help="Write a self-contained HTML report.",
        ),
        click.option(
            "--column",
            "columns",
            multiple=True,
            metavar="OLD=NEW",
            help="Map a column of the file onto a canonical name (repeatable).",
        ),
        click.option("--group", default=None, help="HDF5 group or TDMS group holding the columns."),
        click.option("--overwrite", is_flag=True, help="Replace existing --json/--report files."),
        click.option(
            "--specs",
            "specs",
            metavar="FILE.toml",
            callback=_load_specs_option,
            expose_value=True,
            help="Instrument specifications (Type B inputs of the uncertainty budgets; see "
            "'rotacal specs example').",
        ),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def _clipping_option(func: F) -> F:
    """``--allow-clipped`` (every analysis of a sensor output that can clip)."""
    return click.option(
        "--allow-clipped",
        is_flag=True,
        help="Analyse a capture with samples at the rails (a saturated sensor or ADC) anyway; "
        "the results name the clipping in their warnings. Refused by default.",
    )(func)


@contextlib.contextmanager
def _in_file(path: str, option: str = "") -> Iterator[None]:
    """Name the capture file in a clipping refusal (the analysis names only the column)."""
    from rotacal.signal.clipping import ClippedSignalError

    try:
        yield
    except ClippedSignalError as e:
        where = f"{option} {path}" if option else Path(path).name
        raise ClippedSignalError(f"{where}: {e}", e.clippings) from None


def _read(path: str, needed: list[str], columns: Sequence[str], group: str | None) -> Any:
    from rotacal.io import parse_column_mapping, read_capture

    with _status(f"reading {path}"):
        return read_capture(
            path, columns=needed, mapping=parse_column_mapping(columns), group=group
        )


def _read_heads(path: str, columns: Sequence[str], group: str | None) -> Any:
    from rotacal.encoder.pulses import head_columns
    from rotacal.io import parse_column_mapping, read_capture

    with _status(f"reading {path}"):
        cap = read_capture(path, mapping=parse_column_mapping(columns), group=group, ragged=True)
    try:
        return head_columns(cap.columns)
    except CaptureError as e:
        raise CaptureError(f"{Path(path).name}: {e}") from None


def _emit_warnings(result: Any) -> None:
    """Print each of the result's ``warnings`` as one ``rotacal: warning:`` line on stderr."""
    for line in getattr(result, "warnings", ()):
        click.echo(f"rotacal: warning: {' '.join(str(line).split())}", err=True)


def _write_report(
    title: str,
    subtitle: str,
    sections: list[Any],
    capture: str,
    report_path: str | None,
    warnings: Sequence[str] = (),
) -> None:
    if not report_path:
        return
    from rotacal.report.html import Report, write_html

    report = Report(
        title=title,
        subtitle=subtitle,
        sections=sections,
        inputs={"capture": capture},
        warnings=list(warnings),
    )
    _refuse_overwrite(Path(report_path), (Path(capture),), "--report")
    with _status("drawing the report"):
        write_html(report, report_path)
