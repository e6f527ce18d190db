"""``rotacal allan``: Allan deviation and IEEE 952 noise terms."""

from __future__ import annotations

import contextlib
import dataclasses
from collections.abc import Iterable, Iterator, Sequence
from pathlib import Path
from typing import Any

import click

from rotacal.errors import CaptureError, ConfigError
from rotacal.numbers import quantity_of

from ._app import cli
from ._common import (
    _IN_MEMORY_MAX_SAMPLES,
    INPUT_FILE,
    _analysis_options,
    _check_outputs,
    _clipping_option,
    _emit_warnings,
    _names_capture,
    _sample_progress,
    _status,
    _summary_wanted,
    _write_json,
    _write_report,
)
from ._dask import dask_options, run_on_dask, split_wanted
from ._help import example
from ._reading import current_read_options


@cli.command(
    "allan",
    epilog=example(
        "rotacal allan static.npz --report noise.html",
        "rotacal allan gyro.csv --column gyro_z --fs-hz 100 --taus all",
        "rotacal allan rlg.csv --column angle_deg --angle",
        "rotacal allan gyro.csv --column gyro_z --deviation mdev --report mdev.html",
    ),
)
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--fs-hz", type=float, default=None, help="Sampling rate (Hz), when there is no time_s column."
)
@click.option(
    "--unit",
    type=click.Choice(["deg/s", "rad/s", "deg/h", "other"]),
    default="deg/s",
    show_default=True,
    help="Unit of the rate column (the named noise terms are in deg).",
)
@click.option(
    "--taus",
    type=click.Choice(["log", "octave", "decade", "all"]),
    default=None,
    help="τ grid: 'all' computes every cluster size (O(N log² N)); 'log' and 'all' need the "
    "record in memory. [default: log; octave for a capture read in chunks]",
)
@click.option(
    "--deviation",
    type=click.Choice(["adev", "mdev", "hdev", "tdev", "totdev"]),
    default="adev",
    show_default=True,
    help="Deviation to report beside the noise terms: overlapping Allan, modified Allan, "
    "overlapping Hadamard, time (in deg) or total; with its edf and 68 % interval. Read in "
    "chunks with the noise (octave or decade τ); not split over Dask workers.",
)
@click.option(
    "--chunked/--in-memory",
    default=None,
    help="Read the capture in chunks (flat memory; τ at octaves or decades) or load it whole "
    f"[default: chunked above {_IN_MEMORY_MAX_SAMPLES:.0e} samples].",
)
@dask_options("NPZ without compression, HDF5 or TDMS; τ at octaves or decades")
@click.option(
    "--angle",
    "is_angle",
    is_flag=True,
    help="The column holds an angle, the rate's integral (deg for --unit deg/s; an integrating "
    "gyro's output, or phase data with --unit other); it is differenced to a rate.",
)
@_clipping_option
@_analysis_options
@_names_capture
def allan_cmd(
    capture: str,
    fs_hz: float | None,
    unit: str,
    taus: str | None,
    deviation: str,
    chunked: bool | None,
    workers: int | None,
    scheduler: str | None,
    is_angle: bool,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Allan deviation and noise terms of a gyro's rate.

    The overlapping Allan deviation over τ and the noise terms of IEEE Std 952-1997 Annex C
    (angle random walk, bias instability, rate random walk, quantization, rate ramp).
    --column NAME picks the rate column (default rate_deg_s); --column OLD=NEW maps names as
    everywhere else. A time_s column, when present, gives the sampling rate. With --angle the
    column is an angle record (an integrating gyro, or phase data), differenced to a rate.
    """
    from rotacal.gyro.noise import gyro_noise, gyro_noise_from_angle
    from rotacal.io import capture_columns, capture_length, parse_column_mapping, read_capture
    from rotacal.io._common import name_list

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    names = [c for c in columns if "=" not in c]
    mappings = [c for c in columns if "=" in c]
    if len(names) > 1:
        raise ConfigError(f"--column names one rate column; got {', '.join(names)}")
    rate_column = names[0] if names else "rate_deg_s"
    mapping = parse_column_mapping(mappings)
    read_options = current_read_options()
    available = capture_columns(capture, mapping=mapping, group=group, read_options=read_options)
    if rate_column not in available:
        raise CaptureError(
            f"{Path(capture).name} has no column {rate_column!r} (it has "
            f"{name_list(available)}); name the rate column with --column NAME"
        )
    # only the columns the analysis uses: other arrays of the file may have other lengths
    wanted = [rate_column, *(["time_s"] if "time_s" in available else [])]
    options = {"fs_hz": fs_hz, "unit": unit, "taus": taus}
    options |= {"specs": kw["specs"], "allow_clipped": kw["allow_clipped"]}
    reading = {"mapping": mapping, "group": group, "read_options": read_options}
    stream = _Stream(capture, rate_column, reading, options, is_angle, deviation)
    n = None
    if split_wanted(workers, scheduler, chunked):
        result = _dask_noise(stream, workers, scheduler)
        _finish(result, capture, json_path, report_path)
        return
    if chunked is None:
        n = capture_length(
            capture, rate_column, mapping=mapping, group=group, read_options=read_options
        )
        chunked = n > _IN_MEMORY_MAX_SAMPLES
    if chunked:
        result, family = _chunked_noise(stream, n, wanted)
        _finish(result, capture, json_path, report_path, family)
        return
    with _status(f"reading {capture}"):
        cap = read_capture(
            capture,
            columns=list(dict.fromkeys(wanted)),
            mapping=mapping,
            group=group,
            read_options=read_options,
        )
    time_s = cap.columns.get("time_s")
    if time_s is None and fs_hz is None:
        raise ConfigError(f"{Path(capture).name} has no time_s column: give --fs-hz")
    with _status("computing the Allan deviation"):
        result = (gyro_noise_from_angle if is_angle else gyro_noise)(
            cap[rate_column],
            fs_hz=fs_hz,
            time_s=time_s,
            unit=unit,
            taus=taus or "log",
            column=rate_column,
            specs=kw["specs"],
            allow_clipped=kw["allow_clipped"],
        )
    family = None
    if deviation != "adev":
        family = _family_deviation(
            cap[rate_column], result, deviation, taus or "log", is_angle, kw["allow_clipped"]
        )
    _finish(result, capture, json_path, report_path, family)


def _family_deviation(
    values: Any, result: Any, kind: str, taus: str, is_angle: bool, allow_clipped: bool
) -> Any:
    """The ``--deviation`` of the record at the sampling rate the noise analysis found
    (:func:`rotacal.signal.deviations.stability_deviation`; an angle column as phase data)."""
    from rotacal.signal.deviations import stability_deviation

    with _status(f"computing the {kind}"):
        return stability_deviation(
            values,
            fs=result.fs_hz,
            kind=kind,
            taus=taus,
            data_type="phase" if is_angle else "rate",
            allow_clipped=allow_clipped,
        )


#: Rows read at a time on the chunked path, and the phase values it carries (32 MB; longer τ
#: are summed from a temporary file): ~200 MB in all.
_CHUNK_ROWS = 1 << 22
_CHUNK_HISTORY = 1 << 22


@dataclasses.dataclass(frozen=True)
class _Stream:
    """What the command's two streamed paths share: the capture, how it is read, and the
    analysis's options."""

    capture: str
    column: str
    reading: dict[str, Any]  # mapping, group and read_options of rotacal.io's readers
    options: dict[str, Any]  # fs_hz, unit, taus, specs, allow_clipped
    is_angle: bool
    deviation: str = "adev"

    @property
    def taus(self) -> str | None:
        return self.options["taus"]

    def check(self, how: str) -> None:
        """Refuse what needs the whole record in memory."""
        if self.taus in ("all", "log"):
            raise ConfigError(
                f"--taus {self.taus} needs the whole record in memory; this capture is {how}: "
                "give --taus octave or decade, or --in-memory (if the record fits in memory)"
            )
        if self.is_angle:
            raise ConfigError(
                "--angle is analysed in memory only; give --in-memory (if the record fits in "
                "memory), or difference the angle to a rate column first"
            )

    def analysis(self) -> dict[str, Any]:
        """The keyword arguments of the streamed analyses (τ at octaves by default)."""
        return {**self.options, "column": self.column, "taus": self.taus or "octave"}

    def noted(self, result: Any, how: str) -> Any:
        """``result`` with a note of the octave grid when the user asked for none."""
        if self.taus is None:  # the log grid, the default in memory, needs the length first
            note = f"{how}: τ at octaves (--taus octave)"
            result = dataclasses.replace(result, notes=[note, *result.notes])
        return result


def _chunked_noise(stream: _Stream, n: int | None, wanted: list[str]) -> tuple[Any, Any]:
    """The noise of a capture read in chunks (:func:`rotacal.gyro.noise_stream.gyro_noise_chunks`)
    and the ``--deviation`` other than the ADEV, summed in the same reading pass
    (:class:`rotacal.signal.deviations_stream.ChunkedDeviation`; None for the ADEV)."""
    from rotacal.gyro.noise_stream import gyro_noise_chunks
    from rotacal.io import capture_length, iter_capture_chunks
    from rotacal.signal.deviations_stream import ChunkedDeviation

    stream.check("read in chunks")
    if n is None:
        n = capture_length(stream.capture, stream.column, **stream.reading)
    chunks = iter_capture_chunks(stream.capture, wanted, chunk_rows=_CHUNK_ROWS, **stream.reading)
    kind = stream.deviation
    deviation = None
    with contextlib.ExitStack() as stack:
        family = None
        if kind != "adev":
            family = stack.enter_context(
                ChunkedDeviation(
                    kind,
                    taus=stream.analysis()["taus"],
                    history=_CHUNK_HISTORY,
                    column=stream.column,
                )
            )
            chunks = _feeding(chunks, family, stream.column)
        with _sample_progress(2 * n, "Allan deviation (chunked)") as progress:
            result = gyro_noise_chunks(
                chunks, **stream.analysis(), history=_CHUNK_HISTORY, progress=progress
            )
        if family is not None:
            with _status(f"computing the {kind}"):
                deviation = family.result(fs=result.fs_hz)
    return stream.noted(result, f"read in chunks ({n} samples)"), deviation


def _feeding(chunks: Iterable[Any], family: Any, column: str) -> Iterator[Any]:
    """The chunks, each fed to ``family`` once the noise analysis has taken (and checked) it."""
    for chunk in chunks:
        yield chunk
        family.add(chunk[column])


def _dask_noise(stream: _Stream, workers: int | None, scheduler: str | None) -> Any:
    """The noise of a capture split over a Dask cluster's workers
    (:func:`rotacal.batch.capture_noise.gyro_noise_on_dask`)."""
    from rotacal.batch.capture_noise import CHUNK_ROWS, gyro_noise_on_dask
    from rotacal.io import capture_length

    if stream.deviation != "adev":
        raise ConfigError(
            f"--deviation {stream.deviation} is not computed on Dask workers (they sum the "
            "adev): drop --workers/--scheduler (the capture is then read in chunks in this "
            "process), or give --deviation adev"
        )
    stream.check("split over workers")
    n = capture_length(stream.capture, stream.column, **stream.reading)
    result = run_on_dask(
        (workers, scheduler),
        2 * (-(-n // CHUNK_ROWS)) + 1,  # at most: two rounds of blocks and the checksums
        "Allan deviation",
        lambda client, progress: gyro_noise_on_dask(
            stream.capture,
            client=client,
            **stream.analysis(),
            **stream.reading,
            history=_CHUNK_HISTORY,
            progress=progress,
        ),
        capture=stream.capture,
        columns=[stream.column],
        rows=n,
        reading=stream.reading,
    )
    return stream.noted(result, "split over workers")


def _finish(
    result: Any,
    capture: str,
    json_path: str | None,
    report_path: str | None,
    family: Any = None,
) -> None:
    """Warnings, JSON, report and the terminal summary of one noise result (and of the
    ``--deviation`` other than the ADEV, ``family``)."""
    _emit_warnings(result)
    data = result.to_dict()
    if family is not None:
        from rotacal.signal.deviations import deviation_keys

        data |= deviation_keys(family)
    _write_json(data, json_path)
    if report_path:
        from rotacal.report.noise import noise_section

        sections = [noise_section(result)]
        if family is not None:
            from rotacal.report.deviation import deviation_section

            sections.append(deviation_section(family, (data["tau_s"], data["adev_deg_s"])))
        _write_report(
            "Gyro noise: Allan deviation",
            "IEEE Std 952-1997 Annex C: overlapping Allan deviation and noise terms",
            sections,
            capture,
            report_path,
            warnings=result.warnings,
        )
    if _summary_wanted():
        for label, key, unit in (
            ("angle random walk", "arw_deg_rt_h", "deg/rt-h"),
            ("bias instability", "bias_instability_deg_h", "deg/h"),
            ("rate random walk", "rrw_deg_h_rt_h", "deg/h/rt-h"),
            ("quantization", "quantization_deg", "deg"),
            ("rate ramp", "rate_ramp_deg_h2", "deg/h^2"),
        ):
            text = "not seen" if data.get(key) is None else quantity_of(data, key, unit, digits=4)
            click.echo(f"{label:<18} {text}")
        for note in result.notes:
            click.echo(f"note               {note}")
        if family is not None:
            unit = "deg" if family.kind == "tdev" else "deg/s"
            click.echo(
                f"{family.kind:<18} {family.deviation[0]:.4g} {unit} at τ = {family.tau_s[0]:.4g} s "
                f"… {family.deviation[-1]:.4g} {unit} at τ = {family.tau_s[-1]:.4g} s "
                f"({family.tau_s.size} τ, 68 % intervals in the JSON)"
            )
