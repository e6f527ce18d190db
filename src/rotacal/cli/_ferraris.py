"""What ``gyro rotations`` and ``gyro accelerometer`` share: the section file, the gravity options,
the capture's gyro and accelerometer columns, and the lines of the summary."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, TypeVar

import click
import numpy as np

from rotacal.errors import CaptureError, ConfigError
from rotacal.numbers import elements_of

from ._common import INPUT_FILE, _status
from ._reading import current_read_options

F = TypeVar("F", bound=Callable[..., Any])


def sections_option(func: F) -> F:
    """``--sections FILE.json`` (required)."""
    return click.option(
        "--sections",
        "sections_path",
        type=INPUT_FILE,
        required=True,
        help="JSON of sample ranges: imucal's Ferraris list (x_p … z_a, x_rot, y_rot, z_rot), "
        "{'rotations': {'x': [start, stop], …}, 'static': {…}}, or a twin's truth file.",
    )(func)


def gravity_options(func: F) -> F:
    """``--latitude-deg``, ``--gravity-m-s2``, ``--position-u-deg``."""
    for opt in reversed(
        [
            click.option(
                "--latitude-deg",
                type=float,
                default=None,
                help="Latitude of the session (deg): the vertical Earth rate is removed and g is "
                "the normal gravity there. [default: Earth rate in the uncertainty, g = 9.80665]",
            ),
            click.option(
                "--gravity-m-s2",
                type=float,
                default=None,
                help="Local gravity (m/s²) [normal gravity at --latitude-deg, else 9.80665; "
                "imucal uses 9.81].",
            ),
            click.option(
                "--position-u-deg",
                type=float,
                default=0.0,
                show_default=True,
                help="Standard uncertainty of each static position's tilt (deg), Type B.",
            ),
        ]
    ):
        func = opt(func)
    return func


#: Output units that are °/s: the nominal sensitivity is then 1.
DEG_S_UNITS = ("deg/s", "°/s", "dps", "degree/s")


def nominal_scale_option(func: F) -> F:
    """``--nominal-scale``."""
    return click.option(
        "--nominal-scale",
        type=float,
        default=None,
        help="Nominal gyro sensitivity (output unit per deg/s): each turn must then come within "
        "10 % of the set angle, which catches a partial turn. [1 when --output-unit is deg/s]",
    )(func)


def read_sections(path: str) -> tuple[dict[str, Any], float | None]:
    """(the sections, the angle the file states or None): imucal's list, a
    ``{"rotations", "static"}`` mapping, or a twin's truth (its ``sections`` or those keys)."""
    try:
        spec = json.loads(Path(path).read_text(encoding="utf-8"))
    except OSError as e:
        raise ConfigError(f"--sections {path}: cannot read it ({e.strerror})") from None
    except json.JSONDecodeError as e:
        raise ConfigError(f"--sections {path} is not JSON ({e.msg}, line {e.lineno})") from None
    if not isinstance(spec, dict):
        raise ConfigError(f"--sections {path} must hold a JSON object of sample ranges")
    angle = spec.get("angle_deg")
    if angle is not None and (isinstance(angle, bool) or not isinstance(angle, (int, float))):
        raise ConfigError(
            f"--sections {path}: angle_deg must be a number of degrees, got {angle!r}; fix it or "
            "give --angle-deg"
        )
    sections = spec["sections"] if isinstance(spec.get("sections"), dict) else spec
    return sections, angle


def read_triads(
    capture: str, columns: Sequence[str], group: str | None, *, gyro: bool = True
) -> tuple[Any, np.ndarray | None, np.ndarray | None]:
    """(the capture, gyro (n, 3) or None, accelerometer (n, 3) or None) by canonical names
    ux, uy, uz and ax, ay, az (``--column acc_x=ax`` maps imucal's)."""
    from rotacal.gyro.accel_triad import ACCEL_OUTPUT_COLUMNS
    from rotacal.gyro.triad import TRIAD_OUTPUT_COLUMNS
    from rotacal.io import parse_column_mapping, read_capture

    with _status(f"reading {capture}"):
        cap = read_capture(
            capture,
            mapping=parse_column_mapping(columns),
            group=group,
            read_options=current_read_options(),
        )

    def triad(names: Sequence[str], what: str, example: str) -> np.ndarray | None:
        have = [c in cap.columns for c in names]
        if any(have) and not all(have):
            missing = names[have.index(False)]
            raise CaptureError(
                f"{Path(capture).name} has no column {missing!r} of the {what}; map it with "
                f"--column {example}"
            )
        return np.column_stack([cap[c] for c in names]) if all(have) else None

    g = triad(TRIAD_OUTPUT_COLUMNS, "gyro outputs", "gyr_x=ux (and uy, uz)")
    a = triad(ACCEL_OUTPUT_COLUMNS, "accelerometer outputs", "acc_x=ax (and ay, az)")
    need, what = (g, "ux") if gyro else (a, "ax")
    if need is None:
        raise CaptureError(
            f"{Path(capture).name} has no column {what!r}; map the "
            + (
                "gyro outputs with --column gyr_x=ux (and uy, uz)"
                if gyro
                else "accelerometer outputs with --column acc_x=ax (and ay, az)"
            )
        )
    return cap, g, a


def echo_matrix(data: dict[str, Any], key: str, title: str, unit: str) -> None:
    """A 3×3 result, row by row, each element with its U."""
    click.echo(f"{title} ({unit}), rows x, y, z:")
    for row in range(3):
        click.echo(f"   {elements_of(data, key, [(row, col) for col in range(3)])}")


def echo_vector(data: dict[str, Any], key: str, label: str, unit: str) -> None:
    """A 3-vector result on one line, each element with its U."""
    click.echo(f"{label:<18}{elements_of(data, key, [(i,) for i in range(3)], unit)}")
