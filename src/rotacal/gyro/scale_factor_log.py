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
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import CaptureError
from rotacal.gyro.plateaus import (
    Plateau,
    PlateauSearch,
    find_plateaus,
    plateau_rates,
    plateau_rows,
)
from rotacal.gyro.scale_factor import calibrate_scale_factor
from rotacal.gyro.scale_factor_result import ScaleFactorResult

__all__ = ["LogScaleFactorResult", "calibrate_scale_factor_log"]

#: Rows of the log kept for its figure (evenly strided): a 24-h log stays a light figure.
_FIGURE_ROWS = 20_000
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


def _slices(search: PlateauSearch, output: np.ndarray) -> Any:
    """A chunk source (:func:`rotacal.gyro.calibrate_scale_factor_chunked`) over the used
    plateaus' rows: views of ``output``, each with its plateau's mean rate."""

    def chunks(names: Sequence[str]) -> Iterator[Mapping[str, np.ndarray]]:
        for (a, b), p in zip(search._rows, search.plateaus, strict=True):
            for s in range(int(a), int(b), _IN_MEMORY_MAX_ROWS):
                e = min(s + _IN_MEMORY_MAX_ROWS, int(b))
                cols = {"rate_deg_s": np.full(e - s, p.rate_deg_s), "output": output[s:e]}
                yield {k: cols[k] for k in names}

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
    from rotacal.gyro.scale_factor_stream import calibrate_scale_factor_chunked

    y = np.asarray(output, dtype=float).reshape(-1)
    search = find_plateaus(
        time_s,
        rate_deg_s,
        y,
        settle_s=settle_s,
        window_s=window_s,
        min_plateau_s=min_plateau_s,
        **{k: options[k] for k in ("rate_tolerance_deg_s",) if k in options},
    )
    temps: list[float | None] = [None] * len(search.plateaus)
    if temperature_c is not None:
        temp = np.asarray(temperature_c, dtype=float).reshape(-1)
        if temp.size != y.size:
            raise CaptureError(
                f"column temperature_c has {temp.size} rows but output has {y.size}: one each"
            )
        temps = [float(np.nanmean(temp[a:b])) for a, b in search._rows]
    used = int(np.sum(search._rows[:, 1] - search._rows[:, 0]))
    if chunked is None:
        chunked = used > _IN_MEMORY_MAX_ROWS
    if chunked:
        fit = calibrate_scale_factor_chunked(_slices(search, y), **options)
    else:
        fit = calibrate_scale_factor(plateau_rates(search), plateau_rows(search, y), **options)
    t = np.asarray(time_s, dtype=float).reshape(-1)
    stride = max(1, t.size // _FIGURE_ROWS)
    rate = np.asarray(rate_deg_s, dtype=float).reshape(-1)
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
        _log=(t[::stride].copy(), rate[::stride].copy(), y[::stride].copy()),
        _spans=spans,
    )
