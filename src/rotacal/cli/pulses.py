"""``rotacal selfcal`` and ``rotacal rate``: the multi-head encoder (Kokuyama et al. 2015)."""

from __future__ import annotations

import contextlib
import json
import math
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import click

from rotacal.columns import HEAD_NAME
from rotacal.errors import CaptureError, ConfigError
from rotacal.numbers import element_of, format_plain, quantity_of

from ._app import cli
from ._common import (
    INPUT_FILE,
    _analysis_options,
    _check_outputs,
    _emit_warnings,
    _names_capture,
    _naming_file,
    _read_heads,
    _sample_progress,
    _status,
    _summary_wanted,
    _write_json,
    _write_report,
)
from ._dask import dask_options, run_on_dask, split_wanted
from ._help import example
from ._rate_angle import angle_readings  # time_s with angle_deg or count
from ._rate_windows import add_windows, print_windows, window_option, window_sections
from ._reading import current_read_options

_PULSES_PER_REV = click.option(
    "--pulses-per-rev", type=int, required=True, help="m: pulses per revolution of one head."
)
#: Pulses of one head above which ``rotacal rate`` streams it from the file by default.
_IN_MEMORY_MAX_PULSES = 20_000_000
_KOKUYAMA2015_TITLE = (
    "Kokuyama et al. (2015): angular-velocity standard with a self-calibratable encoder"
)


#: Above this many pulse times (all heads) ``rotacal selfcal`` reads the heads in chunks: in
#: memory it holds ~50 bytes per pulse time (the trains, the delays, the angle differences).
_SELFCAL_IN_MEMORY_MAX = 10_000_000
#: Pulse times read at a time from each head on the chunked path.
_SELFCAL_CHUNK_ROWS = 1 << 19


@cli.command(
    "selfcal",
    epilog=example("rotacal selfcal heads.h5 --pulses-per-rev 18000 --json selfcal.json"),
)
@click.argument("capture", type=INPUT_FILE)
@_PULSES_PER_REV
@click.option(
    "--rotation",
    type=click.Choice(["auto", "forward", "reverse"]),
    default="auto",
    show_default=True,
    help="Whether head i lies i·360/n ahead of head 0 in the sense of rotation (forward).",
)
@click.option(
    "--chunked/--in-memory",
    default=None,
    help="Read the heads in chunks (flat memory, two passes over the file) or load them whole "
    "(heads padded with empty cells or trailing NaNs need it) "
    f"[default: chunked above {_SELFCAL_IN_MEMORY_MAX:.0e} pulse times in all, except CSV].",
)
@dask_options("the fit by blocks of revolutions; NPZ without compression, HDF5 or TDMS")
@_analysis_options
@_names_capture
def selfcal_cmd(
    capture: str,
    pulses_per_rev: int,
    rotation: str,
    chunked: bool | None,
    workers: int | None,
    scheduler: str | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Scale deviation of a multi-head encoder.

    Columns head_0 … head_{n-1}: the pulse times (s) of each head. The equal-division-averaged
    method compares the heads at the same instant; harmonics that are multiples of n stay
    undetectable, as the result says (Kokuyama et al. 2015).
    """
    from rotacal.encoder.selfcal import self_calibrate

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    lengths = None
    split = split_wanted(workers, scheduler, chunked)
    if chunked is None and not split and Path(capture).suffix.lower() in (".csv", ".txt"):
        chunked = False  # CSV pulse files pad short heads with empty cells: read in memory
    if chunked is None and not split:
        lengths = _head_lengths(capture, columns, group)
        chunked = sum(lengths.values()) > _SELFCAL_IN_MEMORY_MAX
    if split:
        result = _selfcal_dask(
            capture, columns, group, (workers, scheduler), pulses_per_rev, rotation, kw.pop("specs")
        )
    elif chunked:
        result = _selfcal_chunked(
            capture, columns, group, lengths, pulses_per_rev, rotation, kw.pop("specs")
        )
    else:
        heads = _read_heads(capture, columns, group)
        with _status("self-calibrating"):
            result = self_calibrate(
                heads,
                pulses_per_rev=pulses_per_rev,
                rotation=rotation,  # type: ignore[arg-type]
                specs=kw.pop("specs"),
            )
    _emit_warnings(result)
    data = result.to_dict()
    _write_json(data, json_path)
    if report_path:
        from rotacal.report.pulses import selfcal_section

        _write_report(
            "Self-calibration of a multi-head encoder",
            _KOKUYAMA2015_TITLE + " — equal-division-averaged method",
            [selfcal_section(result)],
            capture,
            report_path,
            warnings=result.warnings,
        )
    if _summary_wanted():
        click.echo(f"heads x pulses/rev    {result.heads} x {result.pulses_per_rev}")
        click.echo(f"revolutions averaged  {result.revolutions_used}")
        click.echo(f"deviation p-p         {quantity_of(data, 'deviation_pp_arcsec', 'arcsec')}")
        click.echo(f"deviation rms         {quantity_of(data, 'deviation_rms_arcsec', 'arcsec')}")
        if result.repeatability_rms_arcsec is not None:
            repeatability = format_plain(result.repeatability_rms_arcsec, "arcsec", digits=3)
            click.echo(f"repeatability rms     {repeatability}")
        closure = format_plain(result.closure_residual_rms_arcsec, "arcsec", digits=3)
        click.echo(f"closure residual rms  {closure}")
        click.echo(f"note                  {result.undetectable_harmonics_note}")
        for note in result.notes:
            click.echo(f"note                  {note}")


def _head_lengths(capture: str, columns: Sequence[str], group: str | None) -> dict[str, int]:
    """The pulses of every head column (``head_0`` … in order), from the file's metadata where
    it has them."""
    from rotacal.encoder.pulses import head_columns
    from rotacal.io import capture_columns, capture_length, parse_column_mapping

    mapping = parse_column_mapping(columns)
    options = current_read_options()
    names = capture_columns(capture, mapping=mapping, group=group, read_options=options)
    heads = [n for n in names if HEAD_NAME.match(n)]
    head_columns({n: () for n in heads})  # numbered head_0 … head_{n-1} without a hole
    heads.sort(key=lambda n: int(n.split("_")[1]))
    return {
        n: capture_length(capture, n, mapping=mapping, group=group, read_options=options)
        for n in heads
    }


def _selfcal_chunked(
    capture: str,
    columns: Sequence[str],
    group: str | None,
    lengths: dict[str, int] | None,
    pulses_per_rev: int,
    rotation: str,
    specs: Any,
) -> Any:
    """The self-calibration of heads read in chunks, one reader per head (heads are ragged)."""
    from rotacal.encoder.selfcal_stream import self_calibrate_chunked
    from rotacal.io import iter_capture_chunks, parse_column_mapping

    if lengths is None:
        lengths = _head_lengths(capture, columns, group)
    mapping = parse_column_mapping(columns)
    options = current_read_options()

    def one_head(name: str) -> Iterator[Any]:
        chunks = iter_capture_chunks(
            capture,
            [name],
            chunk_rows=_SELFCAL_CHUNK_ROWS,
            mapping=mapping,
            group=group,
            read_options=options,
        )
        # NaN is refused as it is read (the reader checks each chunk's bytes as it goes: a head
        # padded with trailing NaNs is read with --in-memory, which drops the padding)
        return (chunk[name] for chunk in chunks)

    with (
        _sample_progress(2 * sum(lengths.values()), "self-calibration (chunked)") as progress,
        _nan_padding_hint(),
    ):
        return self_calibrate_chunked(
            lambda: [one_head(name) for name in lengths],
            pulses_per_rev=pulses_per_rev,
            rotation=rotation,  # type: ignore[arg-type]
            specs=specs,
            progress=progress,
        )


@contextlib.contextmanager
def _nan_padding_hint() -> Iterator[None]:
    """A NaN met by a chunked reading may pad a shorter head: say how to read it."""
    try:
        yield
    except CaptureError as e:
        if "not a finite number" not in str(e):
            raise
        raise CaptureError(f"{e} (if NaNs pad a shorter head: give --in-memory)") from None


def _selfcal_dask(
    capture: str,
    columns: Sequence[str],
    group: str | None,
    where: tuple[int | None, str | None],
    pulses_per_rev: int,
    rotation: str,
    specs: Any,
) -> Any:
    """The self-calibration split over a Dask cluster's workers
    (:func:`rotacal.batch.capture_selfcal.self_calibrate_on_dask`), with a bar over the tasks."""
    from rotacal.batch.capture_selfcal import self_calibrate_on_dask
    from rotacal.encoder.selfcal_stream import BLOCK_PULSES
    from rotacal.io import parse_column_mapping

    lengths = _head_lengths(capture, columns, group)
    reading: dict[str, Any] = {
        "mapping": parse_column_mapping(columns),
        "group": group,
        "read_options": current_read_options(),
    }
    n0 = next(iter(lengths.values()), 0)
    blocks = -(-n0 // max(1, BLOCK_PULSES // max(pulses_per_rev, 1) * pulses_per_rev))
    with _naming_file(capture), _nan_padding_hint():
        return run_on_dask(
            where,
            len(lengths) - 1 + blocks,  # ≤ a task per head i ≥ 1, then one per block of revolutions
            "self-calibration",
            lambda client, progress: self_calibrate_on_dask(
                capture,
                client=client,
                heads=len(lengths),
                pulses_per_rev=pulses_per_rev,
                rotation=rotation,  # type: ignore[arg-type]
                specs=specs,
                **reading,
                chunk_rows=_SELFCAL_CHUNK_ROWS,
                progress=progress,
            ),
            capture=capture,
            columns=list(lengths)[:1],
            rows=sum(lengths.values()),
            reading=reading,
            unit="pulse times",
        )


@cli.command(
    "rate",
    epilog=example(
        "rotacal rate heads.h5 --pulses-per-rev 18000 --selfcal selfcal.json --set-rate-deg-s 300"
    ),
)
@click.argument("capture", type=INPUT_FILE)
@_PULSES_PER_REV
@click.option(
    "--selfcal",
    "selfcal_path",
    type=INPUT_FILE,
    default=None,
    help="A `rotacal selfcal --json` result to compensate with [default: self-calibrate CAPTURE "
    "when it has several heads].",
)
@click.option(
    "--head", default="0", show_default=True, help="Head whose pulses give the rate, or 'all'."
)
@click.option(
    "--average", type=int, default=10, show_default=True, help="Pulse intervals per rate point."
)
@click.option(
    "--set-rate-deg-s",
    type=float,
    default=None,
    help="Commanded rate of the table (deg/s), for the bias.",
)
@click.option(
    "--no-compensation", is_flag=True, help="Use the nominal pitch only (no self-calibration)."
)
@click.option(
    "--chunked/--in-memory",
    default=None,
    help="Stream from the file (flat memory; head 0 or the only head, several heads "
    "self-calibrated in chunks too) or load the capture whole (--head all, another head of "
    "several, heads padded with empty cells or NaNs need it) "
    f"[default: chunked above {_IN_MEMORY_MAX_PULSES:.0e} pulses of the head, or "
    f"{_SELFCAL_IN_MEMORY_MAX:.0e} in all to self-calibrate, except CSV].",
)
@window_option
@dask_options("one head as the streamed path takes it; NPZ without compression, HDF5 or TDMS")
@_analysis_options
@_names_capture
@angle_readings
def rate_cmd(
    capture: str,
    pulses_per_rev: int,
    selfcal_path: str | None,
    head: str,
    average: int,
    set_rate_deg_s: float | None,
    no_compensation: bool,
    chunked: bool | None,
    window_deg: list[float] | None,
    workers: int | None,
    scheduler: str | None,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Table rate from pulse timing: mean, stability, s(φ).

    Columns head_0 … head_{n-1} (pulse times, s): the angular velocity, its bias against the
    set rate, its stability and the root Allan variance versus angle s(φ) (Kokuyama et al. 2015).
    """
    from rotacal.table.rate import calibrate_rate

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    selfcal: Any = None
    if selfcal_path is not None:
        try:
            selfcal = json.loads(Path(selfcal_path).read_text(encoding="utf-8"))
        except OSError as e:
            raise ConfigError(f"--selfcal {selfcal_path}: cannot read it ({e.strerror})") from None
        except json.JSONDecodeError as e:
            raise ConfigError(
                f"--selfcal {selfcal_path} is not JSON ({e.msg}, line {e.lineno})"
            ) from None
        if not isinstance(selfcal, dict):
            raise ConfigError(f"--selfcal {selfcal_path} is not a `rotacal selfcal --json` result")
    split = split_wanted(workers, scheduler, chunked)
    if chunked is None and not split:
        chunked = _stream_by_default(capture, columns, group, head, selfcal, no_compensation)
    settings: dict[str, Any] = {
        "pulses_per_rev": pulses_per_rev,
        "selfcal": selfcal,
        "head": head,
        "average": average,
        "set_rate_deg_s": set_rate_deg_s,
        "compensate": not no_compensation,
        "specs": kw.pop("specs"),
    }
    if split:
        result = _dask_rate(capture, columns, group, workers, scheduler, **settings)
    elif chunked:
        result = _streamed_rate(capture, columns, group, **settings)
    else:
        heads = _read_heads(capture, columns, group)
        with _status("timing the pulses"):
            result = calibrate_rate(heads, **settings)
    result = add_windows(
        result, window_deg, capture=capture, columns=columns, group=group, settings=settings
    )
    _finish_rate(result, capture, json_path, report_path)


def _head_file(
    capture: str, columns: Sequence[str], group: str | None, head: str
) -> tuple[Any, Any, int, int]:
    """The column mapping, reading options, number of heads and the pulses of ``head`` (0 when
    its length cannot be read: the analysis then names what is wrong)."""
    from rotacal.io import capture_length, parse_column_mapping
    from rotacal.table.rate_file import file_heads

    mapping = parse_column_mapping(columns)
    read_options = current_read_options()
    with _naming_file(capture):
        heads = file_heads(capture, mapping=mapping, group=group)
    column = head if head.startswith("head_") else f"head_{head}"
    try:
        n = capture_length(capture, column, mapping=mapping, group=group, read_options=read_options)
    except (CaptureError, ConfigError):
        n = 0
    return mapping, read_options, heads, n


def _stream_by_default(
    capture: str,
    columns: Sequence[str],
    group: str | None,
    head: str,
    selfcal: Any,
    no_compensation: bool,
) -> bool:
    """Whether the capture is large and the streamed path can take it: head 0's times (or the
    one head's) with a given deviation, nothing to compensate, or every head self-calibrated
    in chunks; another head of several to compensate, or the head average, stay in memory."""
    if head == "all":
        return False
    _, _, heads, n = _head_file(capture, columns, group, head)
    if heads >= 2 and not no_compensation and selfcal is None:
        if head not in ("0", "head_0") or Path(capture).suffix.lower() in (".csv", ".txt"):
            return False  # pairs heads in memory; CSV pads short heads with empty cells
        every = sum(_head_lengths(capture, columns, group).values())
        return n > _IN_MEMORY_MAX_PULSES or every > _SELFCAL_IN_MEMORY_MAX
    if heads >= 2 and not no_compensation and head not in ("0", "head_0"):
        return False
    return n > _IN_MEMORY_MAX_PULSES


def _streamed_rate(capture: str, columns: Sequence[str], group: str | None, **kw: Any) -> Any:
    """calibrate_rate_file with a progress bar over the pulses read (every pass)."""
    from rotacal.table.rate_file import calibrate_rate_file

    mapping, read_options, heads, n = _head_file(capture, columns, group, str(kw["head"]))
    compensating = kw["compensate"] and (kw["selfcal"] is not None or heads >= 2)
    total = (3 if compensating else 2) * n
    if kw["compensate"] and kw["selfcal"] is None and heads >= 2:  # two passes over every head
        total += 2 * sum(_head_lengths(capture, columns, group).values())
    with _naming_file(capture), _sample_progress(total, "rate (streamed)") as progress:
        done = [0]

        def step(pulses: int) -> None:
            done[0] += pulses
            progress(done[0])

        return calibrate_rate_file(
            capture, mapping=mapping, group=group, read_options=read_options, progress=step, **kw
        )


def _dask_rate(
    capture: str,
    columns: Sequence[str],
    group: str | None,
    workers: int | None,
    scheduler: str | None,
    **kw: Any,
) -> Any:
    """The rate of a capture whose passes are split over a Dask cluster's workers
    (:func:`rotacal.batch.capture_rate.calibrate_rate_on_dask`), with a bar over the tasks."""

    from rotacal.batch.capture_rate import calibrate_rate_on_dask
    from rotacal.table.rate_file import CHUNK_PULSES

    mapping, read_options, heads, n = _head_file(capture, columns, group, str(kw["head"]))
    head = str(kw["head"])
    reading = {"mapping": mapping, "group": group, "read_options": read_options}
    aligning = kw["compensate"] and (kw["selfcal"] is not None or heads >= 2)
    with _naming_file(capture):
        return run_on_dask(
            (workers, scheduler),
            (3 if aligning else 2) * (-(-n // CHUNK_PULSES)) + 1,  # rounds of blocks, checksum
            "rate",
            lambda client, progress: calibrate_rate_on_dask(
                capture, client=client, **reading, progress=progress, **kw
            ),
            capture=capture,
            columns=[head if head.startswith("head_") else f"head_{head}"],
            rows=n,
            reading=reading,
            unit="pulses",
        )


def _finish_rate(result: Any, capture: str, json_path: Any, report_path: Any) -> None:
    """Warnings, JSON, report and the summary of a rate result."""
    _emit_warnings(result)
    data = result.to_dict()
    _write_json(data, json_path)
    if report_path:
        from rotacal.report.pulses import rate_section, selfcal_section

        sections = [rate_section(result)]
        if result.selfcal is not None:
            sections.append(selfcal_section(result.selfcal))
        sections.extend(window_sections(result))
        _write_report(
            "Angular-velocity stability of a rate table",
            _KOKUYAMA2015_TITLE,
            sections,
            capture,
            report_path,
            warnings=result.warnings,
        )
    if _summary_wanted():
        _print_rate(result, data)


def _print_rate(result: Any, data: dict[str, Any]) -> None:
    mean_rate = quantity_of(data, "mean_rate_deg_s", "deg/s", digits=10)
    click.echo(f"mean rate          {mean_rate} ({result.head})")
    if result.rate_bias_percent is not None:
        click.echo(
            f"bias               {quantity_of(data, 'rate_bias_deg_s', 'deg/s')} "
            f"({quantity_of(data, 'rate_bias_percent', '%')})"
        )
    compensated = " (compensated)" if result.compensated else ""
    click.echo(
        f"rate deviation rms {quantity_of(data, 'rate_deviation_rms_percent', '%')}{compensated}"
    )
    click.echo(
        f"rate deviation max {quantity_of(data, 'rate_deviation_peak_percent', '%')}{compensated}"
    )
    for i, phi in enumerate(result.allan_angle_deg):
        if (
            abs(math.log10(phi)) < 0.04
            or abs(math.log10(phi / 10)) < 0.04
            or abs(math.log10(phi / 360)) < 0.01
        ):
            s_phi = element_of(_percent_of(data, "allan_relative"), "allan_relative", (i,), "%")
            click.echo(f"s({phi:.4g} deg)".ljust(19) + s_phi)
    print_windows(result)
    for note in result.notes:
        click.echo(f"note               {note}")


def _percent_of(data: dict[str, Any], key: str) -> dict[str, Any]:
    """The keys of a relative quantity (a fraction) of ``data`` in percent, for the terminal."""

    def scaled(x: Any) -> Any:
        if isinstance(x, list):
            return [scaled(v) for v in x]
        return None if x is None else 100.0 * x

    out = dict(data)
    for name in (key, f"{key}_U", f"{key}_interval"):
        if name in data:
            out[name] = scaled(data[name])
    return out
