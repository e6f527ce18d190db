"""The run-level items of ``rotacal gyro scale-factor``: repeatability and temperature coefficients.

Several captures each holding a whole test (``rate_deg_s`` at two rates or more, no
``--rate-from-name``/``--rates``) are runs: each is calibrated alone and the run-to-run
repeatability of S follows (:func:`rotacal.gyro.sf_items.scale_factor_repeatability`). When the
captures have a ``temperature_c`` column, each run's rate points get the mean temperature of
their rows and the temperature coefficients are fitted over all runs' points
(:func:`rotacal.gyro.sf_temperature.temperature_coefficients`); one capture with a
``temperature_c`` column that varies between its points is fitted the same way.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from rotacal.errors import CaptureError

from ._common import _naming_file
from ._reading import current_read_options


def _has_temperature(path: str, columns: Sequence[str], group: str | None) -> bool:
    from rotacal.io import capture_columns, parse_column_mapping

    with _naming_file(path):
        names = capture_columns(
            path,
            mapping=parse_column_mapping(columns),
            group=group,
            read_options=current_read_options(),
        )
    return "temperature_c" in names


def _point_temperatures(
    path: str, result: Any, columns: Sequence[str], group: str | None
) -> np.ndarray:
    """The mean temperature_c (°C) of the rows of each rate point of ``result`` (one capture),
    read in chunks (flat memory on a long log): each row goes to the rate point nearest its set
    rate (the points lie further apart than the grouping tolerance)."""
    from ._rate_files import _file_chunks

    rates = np.asarray(result.rates_deg_s, dtype=float)
    edges = 0.5 * (rates[1:] + rates[:-1])
    sums = np.zeros(rates.size)
    counts = np.zeros(rates.size)
    with _naming_file(path):
        for chunk in _file_chunks(path, ["rate_deg_s", "temperature_c"], columns, group):
            point = np.searchsorted(edges, np.asarray(chunk["rate_deg_s"]))
            sums += np.bincount(point, weights=chunk["temperature_c"], minlength=rates.size)
            counts += np.bincount(point, minlength=rates.size)
    return sums / np.maximum(counts, 1)


def _points(result: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(set rates, means, u of the means) of a result's rate points; a point of one sample takes
    the residual standard deviation of the line."""
    u = np.array([p.standard_error for p in result.points])
    u = np.where(np.isfinite(u) & (u > 0), u, result.residual_std)
    return result.rates_deg_s, np.array([p.mean for p in result.points]), u


def scale_factor_items(
    result: Any,
    captures: Sequence[str],
    rate_files: dict[str, Any],
    columns: Sequence[str],
    group: str | None,
    calibrate_one: Callable[[str], Any],
) -> Any:
    """``result`` with the repeatability (several whole-test captures) and the temperature
    coefficients (a ``temperature_c`` column) added; ``calibrate_one(path)`` calibrates one
    capture as the command does."""
    from rotacal.gyro.sf_items import scale_factor_repeatability
    from rotacal.gyro.sf_temperature import temperature_coefficients

    by_file = rate_files["rate_from_name"] or rate_files["rates_path"] is not None
    if by_file or rate_files["rest_from"]:
        return result  # one test spread over files: no runs
    warm = [_has_temperature(path, columns, group) for path in captures]
    notes: list[str] = []
    runs = [(captures[0], result)]
    repeatability = None
    if len(captures) > 1:
        try:
            runs = []
            for path in captures:
                with _naming_file(path):
                    runs.append((path, calibrate_one(path)))
        except CaptureError as e:
            runs = []
            notes.append(
                f"the captures are not separate runs of the whole test ({e}): no repeatability."
            )
        else:
            repeatability = scale_factor_repeatability(
                np.array([r.scale_factor for _, r in runs]),
                np.array([r.scale_factor_u for _, r in runs]),
            )
    temperature = None
    if any(warm) and runs:
        if not all(warm):
            raise CaptureError(
                "some captures have a temperature_c column and some do not: give it in all of "
                "them (or in none)."
            )
        parts = [(*_points(r), _point_temperatures(path, r, columns, group)) for path, r in runs]
        temperature = temperature_coefficients(
            *(np.concatenate(k) for k in zip(*parts, strict=True))
        )
        if repeatability is not None and temperature.temperature_span_c > 1.0:
            notes.append(
                "the runs were at different temperatures: their repeatability includes the "
                "scale factor's change with temperature."
            )
    return dataclasses.replace(
        result,
        repeatability=repeatability,
        temperature=temperature,
        notes=(*result.notes, *notes),
    )


def _pm(value: float, u: float, unit: str = "", digits: int = 4, more: str = "") -> str:
    """value ± U unit (k = 2, p = 95 %): U = 2u, the normal approximation of the items' u."""
    unit = f" {unit}" if unit else ""
    return f"{value:.{digits}g} ± {2.0 * u:.2g}{unit} (k = 2, p = 95 %){more}"


def item_lines(result: Any) -> list[str]:
    """The summary lines of the items a result holds."""
    lines = []
    sg, rep, t = result.signed, result.repeatability, result.temperature
    if sg is not None:
        pos = _pm(sg.scale_factor_positive, sg.scale_factor_positive_u, digits=8)
        neg = _pm(sg.scale_factor_negative, sg.scale_factor_negative_u, digits=8)
        lines += [
            f"S positive        {pos}",
            f"S negative        {neg}",
            f"asymmetry         {_pm(sg.asymmetry_ppm, sg.asymmetry_ppm_u, 'ppm')}",
        ]
    if rep is not None:
        value, u = rep.scale_factor_repeatability_ppm, rep.scale_factor_repeatability_ppm_u
        lines.append(f"repeatability     {_pm(value, u, 'ppm', 3, f', {rep.runs} runs')}")
    if t is not None:
        k_s = t.scale_factor_temperature_coefficient_ppm_per_c
        k_s_u = t.scale_factor_temperature_coefficient_ppm_per_c_u
        k_b = t.bias_temperature_coefficient_deg_h_per_c
        k_b_u = t.bias_temperature_coefficient_deg_h_per_c_u
        model = f", {t.temperature_model} model"
        lines += [
            f"S temp. coeff.    {_pm(k_s, k_s_u, 'ppm/deg C', more=model)}",
            f"bias temp. coeff. {_pm(k_b, k_b_u, '(deg/h)/deg C')}",
        ]
    return lines
