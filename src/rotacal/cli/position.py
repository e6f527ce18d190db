"""``rotacal position``: position accuracy of an indexing table against a reference (ISO 230-2).

Loaded through :data:`rotacal.cli._app.COMMAND_MODULES` (``"position": "position"``).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click

from rotacal.errors import CaptureError, ConfigError

from ._app import cli
from ._common import (
    INPUT_FILE,
    _analysis_options,
    _check_outputs,
    _names_capture,
    _publish,
    _read,
    _status,
    _summary_wanted,
)
from ._help import example


def _selfcal_mapping(path: str) -> dict[str, Any]:
    """The ``rotacal selfcal --json`` result in ``path`` (one line on any fault)."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as e:
        raise ConfigError(f"--selfcal {path}: cannot read it ({e.strerror})") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise ConfigError(f"--selfcal {path}: not a JSON file ({e})") from None
    if not isinstance(data, dict) or "deviation_arcsec" not in data:
        raise ConfigError(
            f"--selfcal {path}: no deviation_arcsec in it; give a `rotacal selfcal --json` result"
        )
    return data


def _numbers(text: str | None) -> list[float] | None:
    """``--polygon-face-errors-arcsec`` as numbers (one line when one is not a number)."""
    if text is None:
        return None
    try:
        return [float(v) for v in text.replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise ConfigError(
            f"--polygon-face-errors-arcsec {text}: give numbers separated by commas"
        ) from None


@cli.command(
    "position",
    epilog=example(
        "rotacal position pos.csv --harmonics 4 --report pos.html",
        "rotacal position poly.csv --polygon-faces 12 --json poly.json",
        "rotacal position own.csv --selfcal selfcal.json --reference-u-arcsec 0.05",
    ),
)
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--harmonics",
    type=int,
    default=4,
    show_default=True,
    help="Highest Fourier order fitted to the error curve (0: none).",
)
@click.option(
    "--polygon-faces",
    type=int,
    default=None,
    help="The reference is an autocollimator on a polygon of N faces: error_arcsec holds its "
    "readings, positions are k·360/N.",
)
@click.option(
    "--polygon-step-faces",
    type=int,
    default=None,
    help="Faces the polygon was turned on the table between runs (when there is no face "
    "column) [0: never turned].",
)
@click.option(
    "--polygon-face-errors-arcsec",
    default=None,
    metavar="F0,F1,…",
    help="The polygon's face errors from its certificate (arcsec, faces 0 … N-1): the readings "
    "are corrected by them instead of separating them.",
)
@click.option(
    "--polygon-face-u-arcsec",
    type=float,
    default=0.0,
    show_default=True,
    help="Standard uncertainty of those face errors (arcsec).",
)
@click.option(
    "--reference-u-arcsec",
    type=float,
    default=0.0,
    show_default=True,
    help="Standard uncertainty of the reference at one position (arcsec, Type B); a reference "
    "encoder's --specs encoder.graduation_error_arcsec adds to it.",
)
@click.option(
    "--selfcal",
    "selfcal_path",
    type=INPUT_FILE,
    default=None,
    help="A `rotacal selfcal --json` result of the reference encoder: its graduation "
    "deviation corrects reference_deg.",
)
@click.option(
    "--selfcal-zero-deg",
    type=float,
    default=0.0,
    show_default=True,
    help="The reference's reading at line 0 of that self-calibration (deg).",
)
@_analysis_options
@_names_capture
def position_cmd(
    capture: str,
    harmonics: int,
    polygon_faces: int | None,
    polygon_step_faces: int | None,
    polygon_face_errors_arcsec: str | None,
    polygon_face_u_arcsec: float,
    reference_u_arcsec: float,
    selfcal_path: str | None,
    selfcal_zero_deg: float,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Position accuracy of an indexing table (ISO 230-2).

    Columns position_deg (target position) and either reference_deg (a reference encoder's
    reading) or error_arcsec (the deviation, or an autocollimator's reading with
    --polygon-faces); optional run, direction (+1/-1) and face. Gives the error curve, its
    peak-to-peak and harmonics, and ISO 230-2's systematic deviation, repeatability (4s),
    reversal value and accuracy A, each with u.
    """
    from rotacal.position import position_accuracy

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    selfcal = _selfcal_mapping(selfcal_path) if selfcal_path is not None else None
    cap = _read(capture, None, columns, group)  # type: ignore[arg-type]
    names = ", ".join(cap.columns)
    if "position_deg" not in cap.columns:
        raise CaptureError(
            f"no column 'position_deg' (columns: {names}); map yours with "
            "--column NAME=position_deg"
        )
    from rotacal.columns import POSITION_OPTIONAL

    wanted = ("reference_deg", "error_arcsec", *POSITION_OPTIONAL)
    found = {name: cap.columns[name] for name in wanted if name in cap.columns}
    if "reference_deg" not in found and "error_arcsec" not in found:
        raise CaptureError(
            f"no column 'reference_deg' or 'error_arcsec' (columns: {names}): "
            "give the reference's reading or the deviation (--column NAME=reference_deg)"
        )
    if "reference_deg" in found and "error_arcsec" in found:
        raise CaptureError(
            "both reference_deg and error_arcsec are present: keep one (--column maps others away)"
        )
    specs = kw.pop("specs")
    if specs is not None and "reference_deg" in found:
        # a reference encoder's reading error (Type B) as the lab's specifications state it
        stated = specs.get("encoder.graduation_error_arcsec")
        if stated is not None:
            reference_u_arcsec = math.hypot(reference_u_arcsec, stated.std)
    with _status("evaluating the positions"):
        result = position_accuracy(
            cap.columns["position_deg"],
            harmonics=harmonics,
            polygon_faces=polygon_faces,
            polygon_step_faces=polygon_step_faces,
            polygon_face_errors_arcsec=_numbers(polygon_face_errors_arcsec),
            polygon_face_u_arcsec=polygon_face_u_arcsec,
            reference_u_arcsec=reference_u_arcsec,
            selfcal=selfcal,
            selfcal_zero_deg=selfcal_zero_deg,
            **found,
        )
    _publish(
        result,
        json_path,
        report_path,
        capture,
        "Position accuracy",
        "Error curve, harmonics and ISO 230-2 positioning values of a rotary axis",
        ("position", "position_section"),
    )
    if _summary_wanted():
        for line in result.summary_lines():
            click.echo(line)
