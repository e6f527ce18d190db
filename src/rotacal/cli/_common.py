"""Pieces every command shares: progress bars, outputs, reading options and captures."""

from __future__ import annotations

import contextlib
import functools
import os
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import click

from rotacal.errors import CaptureError, ConfigError

from ._reading import current_read_options, reading_options

if TYPE_CHECKING:
    from rotacal.io.outputs import InputFile

F = TypeVar("F", bound=Callable[..., Any])


def _stderr_may_be_terminal() -> bool:
    """False when rich would not draw on stderr either (not a TTY, and neither FORCE_COLOR nor
    TTY_INTERACTIVE set): then the progress bars and spinners skip importing rich (~40 ms)."""
    env = os.environ
    if env.get("TTY_INTERACTIVE") == "1" or env.get("FORCE_COLOR") is not None:
        return True
    isatty = getattr(sys.stderr, "isatty", None)
    return bool(isatty is not None and isatty())


@contextlib.contextmanager
def _progress(total: int, description: str) -> Iterator[Callable[[str], None]]:
    """A progress bar on a terminal (stderr), silent otherwise. Yields ``advance(label)``."""
    if not _stderr_may_be_terminal():
        yield lambda label: None
        return
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
    if not _stderr_may_be_terminal():
        yield lambda done: None
        return
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
    if not _stderr_may_be_terminal():
        yield
        return
    from rich.console import Console

    console = Console(stderr=True)
    if not console.is_terminal:
        yield
        return
    with console.status(message):
        yield


class _InputFileType(click.Path):
    """A file the command reads (declare every one with ``type=INPUT_FILE``).

    Converting the value records it in the context, and every output of the command is checked
    against all that were recorded: no ``--json``/``--report`` can replace an input, through a
    symbolic or a hard link, with ``--overwrite`` or not.
    """

    def __init__(self) -> None:
        super().__init__(dir_okay=False)

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        path = super().convert(value, param, ctx)
        if ctx is not None and param is not None:
            from rotacal.io.outputs import InputFile

            name = param.opts[0] if isinstance(param, click.Option) else param.human_readable_name
            text = os.fsdecode(path)
            ctx.meta.setdefault(_INPUTS_KEY, []).append(InputFile(text, f"{name} {text}"))
            # the path as given, for the provenance (a callback may turn the value into more)
            ctx.meta.setdefault(_INPUT_PATHS_KEY, {}).setdefault(param.name, []).append(text)
        return path


#: The type of every parameter that names a file the command reads.
INPUT_FILE = _InputFileType()
_INPUTS_KEY = "rotacal.inputs"
_OVERWRITE_KEY = "rotacal.overwrite"
_JSON_TO_STDOUT_KEY = "rotacal.json_to_stdout"
_INPUT_PATHS_KEY = "rotacal.input_paths"


def _declared_inputs() -> tuple[InputFile, ...]:
    """The files the running command reads (every parameter of type INPUT_FILE that was given)."""
    ctx = click.get_current_context(silent=True)
    return tuple(ctx.meta.get(_INPUTS_KEY, ())) if ctx is not None else ()


def _overwrite_given() -> bool:
    ctx = click.get_current_context(silent=True)
    return bool(ctx.meta.get(_OVERWRITE_KEY, False)) if ctx is not None else False


#: The extensions a ``--report`` may have (the report is HTML) and a ``--json`` may have.
REPORT_EXTENSIONS = (".html", ".htm")
JSON_EXTENSIONS = (".json",)


def _check_extensions(json_path: str | None, report_path: str | None) -> None:
    """Refuse an output whose name says another format than rotacal writes into it."""
    json_ext = Path(json_path).suffix.lower() if json_path not in (None, "-") else None
    report_ext = Path(report_path).suffix.lower() if report_path is not None else None
    if json_ext in REPORT_EXTENSIONS and report_ext in JSON_EXTENSIONS:
        raise ConfigError(
            f"--json {json_path} and --report {report_path} look swapped: --json writes JSON "
            "(name it .json) and --report writes HTML (name it .html)"
        )
    if report_ext is not None and report_ext not in REPORT_EXTENSIONS:
        if report_ext == ".pdf":
            raise ConfigError(
                f"--report {report_path}: the report is HTML, and PDF certificates are not "
                "available yet (they will come from 'rotacal certify'); name the report .html "
                "(a browser prints it to PDF)"
            )
        raise ConfigError(
            f"--report {report_path}: the report is HTML; give a name ending in .html or .htm"
        )
    if json_ext is not None and json_ext not in JSON_EXTENSIONS:
        raise ConfigError(
            f"--json {json_path}: the results are JSON; give a name ending in .json "
            "(or '-' for the terminal)"
        )


def _check_toml_output(out: str) -> None:
    """Refuse a ``--out`` for a TOML example not named ``.toml`` (commands read it by that name)."""
    if Path(out).suffix.lower() != ".toml":
        raise ConfigError(f"--out {out}: the example is TOML; give a name ending in .toml")


def _check_outputs(json_path: str | None, report_path: str | None, overwrite: bool) -> None:
    """The pre-flight, before any analysis: refuse outputs that cannot or may not be written.

    Refused: a --report not named .html/.htm and a --json not named .json (or '-'), an output
    naming an input of the command (always), an existing file (unless --overwrite), --json and
    --report naming one file, a folder, a path under a regular file, a folder without write
    permission, a dangling symbolic link. Remembers ``overwrite`` and whether the JSON goes to
    stdout for the writes.
    """
    from rotacal.io.outputs import check_outputs

    if report_path == "-":
        raise ConfigError("--report needs a file name (the report is HTML, not for stdout)")
    ctx = click.get_current_context(silent=True)
    if ctx is not None:
        ctx.meta[_OVERWRITE_KEY] = overwrite
        ctx.meta[_JSON_TO_STDOUT_KEY] = json_path == "-"
    targets = [
        (target, f"{option} {target}")
        for option, target in (("--json", json_path), ("--report", report_path))
        if target is not None and target != "-"
    ]
    # an output that would replace an input is named first: the worst of the mistakes
    check_outputs(targets, overwrite=overwrite, inputs=_declared_inputs(), make_folders=True)
    _check_extensions(json_path, report_path)
    if json_path is not None and ctx is not None:
        from rotacal.provenance import prefetch_sha256

        # the JSON's provenance hashes the inputs: start now, beside the analysis
        paths = ctx.meta.get(_INPUT_PATHS_KEY, {})
        prefetch_sha256(p for given in paths.values() for p in given)


def _wrote(path: str | os.PathLike[str]) -> None:
    """Say on stderr that an output file is complete: one ``wrote PATH`` line per file.

    Every command calls it once for each file it wrote, after the file got its name (never for
    ``--json -``). stdout stays for results.
    """
    click.echo(f"wrote {os.fspath(path)}", err=True)


def _summary_wanted() -> bool:
    """Whether the command prints its summary on stdout: unless the JSON goes there."""
    ctx = click.get_current_context(silent=True)
    return not (ctx is not None and ctx.meta.get(_JSON_TO_STDOUT_KEY, False))


def _write_json(data: Any, target: str | None) -> None:
    """Write a result's JSON (``data``: its ``to_dict()``) with ``warnings`` and ``provenance``.

    ``provenance`` (INTERFACE.md "Every result") is added here, where the command is known: the
    result objects of the Python API stay free of it.
    """
    if target is None:
        return
    from rotacal.io.outputs import write_output
    from rotacal.results import to_jsonable

    from ._json_text import dumps_indented
    from ._provenance import provenance

    data = dict(data)
    data.setdefault("warnings", [])
    data["provenance"] = provenance()
    text = dumps_indented(to_jsonable(data))
    if target == "-":
        click.echo(text)
        return
    write_output(
        target,
        text + "\n",
        label=f"--json {target}",
        overwrite=_overwrite_given(),
        inputs=_declared_inputs(),
        make_folders=True,
    )
    _wrote(target)


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
        click.option(
            "--overwrite",
            is_flag=True,
            help="Replace existing --json/--report files (never an input of the command).",
        ),
        click.option(
            "--specs",
            "specs",
            type=INPUT_FILE,
            metavar="FILE.toml",
            callback=_load_specs_option,
            expose_value=True,
            help="Instrument specifications (Type B inputs of the uncertainty budgets; see "
            "'rotacal specs example').",
        ),
    ]
    func = reading_options(func)
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


def _read(
    path: str, needed: list[str], columns: Sequence[str], group: str | None, deferred: bool = False
) -> Any:
    """The capture's columns; with ``deferred`` (capture, checks) of
    :func:`rotacal.io.read_capture_deferred`: the checks run on while the caller analyses."""
    from rotacal.io import parse_column_mapping, read_capture, read_capture_deferred

    with _status(f"reading {path}"):
        return (read_capture_deferred if deferred else read_capture)(
            path,
            columns=needed,
            mapping=parse_column_mapping(columns),
            group=group,
            read_options=current_read_options(),
        )


def _read_heads(path: str, columns: Sequence[str], group: str | None) -> Any:
    from rotacal.encoder.pulses import head_columns
    from rotacal.io import parse_column_mapping, read_capture

    with _status(f"reading {path}"):
        cap = read_capture(
            path,
            mapping=parse_column_mapping(columns),
            group=group,
            ragged=True,
            read_options=current_read_options(),
        )
    with _naming_file(path):
        return head_columns(cap.columns)


@contextlib.contextmanager
def _naming_file(path: str, option: str = "") -> Iterator[None]:
    """Put the file's name (after ``option`` when it came from one, e.g. ``--correction-from``)
    before a CaptureError raised inside (the API knows arrays, not files)."""
    try:
        yield
    except CaptureError as e:
        name = f"{option} {path}" if option else Path(path).name
        if getattr(e, "file_named", False) or name in str(e):
            e.file_named = True  # type: ignore[attr-defined]  # an outer _naming_file keeps it
            raise
        named = CaptureError(f"{name}: {e}")
        named.file_named = True  # type: ignore[attr-defined]  # an outer _naming_file keeps it
        raise named from None


def _names_capture(func: F) -> F:
    """A command decorator: CaptureErrors name the command's CAPTURE (or CONFIG) file.

    A command given several captures (``more_captures``) names the file at fault where it reads
    it; an error about the whole set names none of them."""

    @functools.wraps(func)
    def command(*args: Any, **kwargs: Any) -> Any:
        if kwargs.get("more_captures"):
            return func(*args, **kwargs)
        with _naming_file(kwargs["capture"] if "capture" in kwargs else kwargs["config"]):
            return func(*args, **kwargs)

    return command  # type: ignore[return-value]


def _publish(
    result: Any,
    json_path: str | None,
    report_path: str | None,
    capture: str,
    title: str,
    subtitle: str,
    section: tuple[str, str],
    more: Callable[[], Sequence[Any]] = lambda: (),
) -> dict[str, Any]:
    """What every analysis command does with its result: its warnings on stderr, its JSON, and
    with ``report_path`` its report — ``section`` names the report's section function as
    (module of ``rotacal.report``, function), imported only when a report is asked for and called
    with the result; ``more()`` gives further sections after it. Returns the JSON's data."""
    import importlib

    _emit_warnings(result)
    data = result.to_dict()
    _write_json(data, json_path)
    if report_path:
        module, name = section
        draw = getattr(importlib.import_module(f"rotacal.report.{module}"), name)
        sections = [draw(result), *more()]
        _write_report(title, subtitle, sections, capture, report_path, warnings=result.warnings)
    return data


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

    # the title names the analysis and what it analysed: a printed page must say which capture
    named = Path(capture).name if capture and "," not in capture else capture
    report = Report(
        title=f"{title}: {named}" if named else title,
        subtitle=subtitle,
        sections=sections,
        inputs={"capture": capture},
        warnings=list(warnings),
    )
    with _status("drawing the report"):
        write_html(
            report,
            report_path,
            overwrite=_overwrite_given(),
            inputs=_declared_inputs(),
            label=f"--report {report_path}",
        )
    _wrote(report_path)
