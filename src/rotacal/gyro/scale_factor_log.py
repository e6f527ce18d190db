"""Scale factor from a continuous rate-table log: plateaus found, then the rate-table fit.

:func:`calibrate_scale_factor_log` finds the plateaus of the table's rate
(:func:`rotacal.gyro.plateaus.find_plateaus`), makes each used plateau one rate point (its mean
table rate on each of its rows, its output samples after settling) and hands those rows to the
rate-table analysis (:func:`rotacal.gyro.calibrate_scale_factor`, Kokuyama et al. 2015, §4; the
point means with their standard errors, the unweighted line, NL, the budgets). A long log's rows
go to :func:`rotacal.gyro.calibrate_scale_factor_chunked` plateau by plateau instead (no copy of
the used rows; the same result to 1e-9). The result is the rate-table result plus ``plateaus``,
``plateaus_rejected`` and ``settle_s``, and the plateaus' rejections in ``warnings``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import CaptureError
from rotacal.gyro.plateaus import Plateau, PlateauSearch, plateau_rates, plateau_rows
from rotacal.gyro.plateaus_stream import LogChunks, find_plateaus_chunked, log_chunks
from rotacal.gyro.scale_factor import calibrate_scale_factor
from rotacal.gyro.scale_factor_result import ScaleFactorResult
from rotacal.gyro.scale_factor_stream import calibrate_scale_factor_chunked

__all__ = [
    "LogScaleFactorResult",
    "calibrate_scale_factor_log",
    "calibrate_scale_factor_log_chunked",
]

#: Used rows above this go to the chunked fit, plateau slice by plateau slice.
_IN_MEMORY_MAX_ROWS = 1_000_000


@dataclasses.dataclass(frozen=True)
class LogScaleFactorResult(ScaleFactorResult):
    """:class:`~rotacal.gyro.scale_factor_result.ScaleFactorResult` of a continuous log.

    Adds ``plateaus`` (the used ones: ``start_s``, ``end_s`` of the rows used after settling, s;
    ``rate_deg_s`` their mean table rate, °/s; ``samples``; ``rate_std_deg_s``, °/s;
    ``temperature_c`` their mean temperature when the log has one, °C), ``plateaus_rejected``
    (the same with ``reason``), ``settle_s`` (s dropped from each plateau's start) and
    ``settle_source`` (``"given"`` or ``"output"``: read from the DUT's settling), and
    ``plateau_detection`` (window, σ of the table rate, threshold). ``_log`` keeps a strided
    copy of the log (time, rate, output) and ``_spans`` every plateau's span for the figure.
    """

    plateaus: tuple[dict[str, Any], ...] = ()
    plateaus_rejected: tuple[dict[str, Any], ...] = ()
    settle_s: float = 0.0
    settle_source: str = ""
    plateau_detection: dict[str, float] = dataclasses.field(default_factory=dict)
    _log: tuple[np.ndarray, np.ndarray, np.ndarray] | None = dataclasses.field(
        default=None, repr=False, compare=False
    )
    _spans: tuple[tuple[float, float, float, bool], ...] = dataclasses.field(
        default=(), repr=False, compare=False
    )


def _plateau_dict(p: Plateau, temperature: float | None) -> dict[str, Any]:
    d = p.to_dict()
    d.pop("warnings", None)
    if not p.reason:
        d.pop("reason")
    if temperature is not None:
        d["temperature_c"] = temperature
    return d


def _slices(search: PlateauSearch, output: Any) -> Any:
    """A chunk source (:func:`rotacal.gyro.calibrate_scale_factor_chunked`) over the used
    plateaus' rows, each with its plateau's mean rate: ``output`` is the column in memory or a
    log chunk source (read only when the pass asks for the output)."""
    spans, rates = search._rows, [p.rate_deg_s for p in search.plateaus]

    def pieces(
        names: Sequence[str], y: np.ndarray | None, offset: int, end: int
    ) -> Iterator[dict[str, Any]]:
        for (a, b), rate in zip(spans, rates, strict=True):
            a, b = max(int(a), offset), min(int(b), end)
            for s in range(a, b, _IN_MEMORY_MAX_ROWS):
                e = min(s + _IN_MEMORY_MAX_ROWS, b)
                cols = {"rate_deg_s": np.full(e - s, rate)}
                if y is not None:
                    cols["output"] = y[s - offset : e - offset]
                yield {k: cols[k] for k in names}

    def chunks(names: Sequence[str]) -> Iterator[Mapping[str, np.ndarray]]:
        if "output" not in names:  # the set rates: no need to read the log
            yield from pieces(names, None, 0, int(spans[-1, 1]))
        elif not callable(output):
            yield from pieces(names, output, 0, output.size)
        else:
            offset = 0
            for chunk in output(("output",)):
                y = np.asarray(chunk["output"], dtype=float).reshape(-1)
                yield from pieces(names, y, offset, offset + y.size)
                offset += y.size

    return chunks


def calibrate_scale_factor_log(
    time_s: np.ndarray,
    rate_deg_s: np.ndarray,
    output: np.ndarray,
    *,
    temperature_c: np.ndarray | None = None,
    settle_s: float | None = None,
    window_s: float | None = None,
    min_plateau_s: float | None = None,
    chunked: bool | None = None,
    **options: Any,
) -> LogScaleFactorResult:
    """Scale factor, bias and nonlinearity of a gyro from one continuous rate-table log.

    Parameters
    ----------
    time_s : array
        Time of each row (s), strictly increasing.
    rate_deg_s : array
        The table's rate on each row (°/s), commanded or measured, stepping through plateaus.
    output : array
        The DUT's output (output units); it may lag and ring after each step.
    temperature_c : array or None
        Temperature of each row (°C): each plateau states its mean.
    settle_s, window_s, min_plateau_s : float or None
        Of :func:`rotacal.gyro.plateaus.find_plateaus` (s).
    chunked : bool or None
        Fit the used rows plateau by plateau (flat memory) or at once; None: by their number.
    **options
        The keywords of :func:`rotacal.gyro.calibrate_scale_factor`.

    Returns
    -------
    LogScaleFactorResult
        The rate-table result with the plateaus, the settling time and the rejections in
        ``warnings``.

    References
    ----------
    Kokuyama et al. (2015), §4; Basseville & Nikiforov (1993), §2.1.
    """
    y = np.asarray(output, dtype=float).reshape(-1)
    if temperature_c is not None:
        temp = np.asarray(temperature_c, dtype=float).reshape(-1)
        if temp.size != y.size:
            raise CaptureError(
                f"column temperature_c has {temp.size} rows but output has {y.size}: one each"
            )
    search = find_plateaus_chunked(
        log_chunks(time_s, rate_deg_s, y, temperature_c),
        rows=y.size,
        temperature=temperature_c is not None,
        **_search_options(settle_s, window_s, min_plateau_s, options),
    )
    used = int(np.sum(search._rows[:, 1] - search._rows[:, 0]))
    if chunked is None:
        chunked = used > _IN_MEMORY_MAX_ROWS
    if chunked:
        fit = calibrate_scale_factor_chunked(_slices(search, y), **options)
    else:
        fit = calibrate_scale_factor(plateau_rates(search), plateau_rows(search, y), **options)
    return _log_result(search, fit)


def calibrate_scale_factor_log_chunked(
    chunks: LogChunks,
    *,
    rows: int | None = None,
    temperature: bool = False,
    settle_s: float | None = None,
    window_s: float | None = None,
    min_plateau_s: float | None = None,
    progress: Callable[[int], None] | None = None,
    fit_progress: Callable[[int], None] | None = None,
    **options: Any,
) -> LogScaleFactorResult:
    """:func:`calibrate_scale_factor_log` on a log read in chunks: the plateaus found in passes
    with carried state (:func:`rotacal.gyro.plateaus_stream.find_plateaus_chunked`), then the fit
    over the plateaus' rows (:func:`rotacal.gyro.calibrate_scale_factor_chunked`), so memory
    stays flat whatever the log's length. The result equals the in-memory one to 1e-9.

    Parameters
    ----------
    chunks : callable
        ``chunks(columns)`` starts a fresh pass over the log and yields mappings of the named
        1-D columns (``time_s`` in s, ``rate_deg_s`` in °/s, ``output``, ``temperature_c`` in °C),
        the same rows every call.
    rows : int or None
        The log's rows when known (None: counted in one more pass).
    temperature : bool
        Whether the log has ``temperature_c``.
    settle_s, window_s, min_plateau_s : float or None
        Of :func:`rotacal.gyro.plateaus.find_plateaus` (s).
    progress, fit_progress : callable, optional
        Called after each chunk with the rows read so far, summed over the passes of the
        detection, and of the fit (the plateaus' rows, twice).
    **options
        The keywords of :func:`rotacal.gyro.calibrate_scale_factor`.

    References
    ----------
    Kokuyama et al. (2015), §4; Basseville & Nikiforov (1993), §2.1.
    """
    search = find_plateaus_chunked(
        chunks,
        rows=rows,
        temperature=temperature,
        progress=progress,
        **_search_options(settle_s, window_s, min_plateau_s, options),
    )
    fit = calibrate_scale_factor_chunked(_slices(search, chunks), progress=fit_progress, **options)
    return _log_result(search, fit)


def _search_options(
    settle_s: float | None,
    window_s: float | None,
    min_plateau_s: float | None,
    options: Mapping[str, Any],
) -> dict[str, Any]:
    return {
        "settle_s": settle_s,
        "window_s": window_s,
        "min_plateau_s": min_plateau_s,
        **{k: options[k] for k in ("rate_tolerance_deg_s",) if k in options},
    }


def _log_result(search: PlateauSearch, fit: ScaleFactorResult) -> LogScaleFactorResult:
    """The fit's result with the plateaus, the settling and the log's figure data."""
    temps = search._temperature_c or (None,) * len(search.plateaus)
    spans = tuple(
        (p.start_s, p.end_s, p.rate_deg_s, not p.reason)
        for p in (*search.plateaus, *search.rejected)
    )
    base = {f.name: getattr(fit, f.name) for f in dataclasses.fields(fit) if f.init}
    base["warnings"] = (*search.warnings, *fit.warnings)
    return LogScaleFactorResult(
        **base,
        plateaus=tuple(_plateau_dict(p, tc) for p, tc in zip(search.plateaus, temps, strict=True)),
        plateaus_rejected=tuple(_plateau_dict(p, None) for p in search.rejected),
        settle_s=search.settle_s,
        settle_source=search.settle_source,
        plateau_detection={
            "window_s": search.window_s,
            "rate_noise_deg_s": search.rate_noise_deg_s,
            "threshold_deg_s": search.threshold_deg_s,
        },
        _log=search._log,
        _spans=spans,
    )
