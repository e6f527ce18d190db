"""The sections of a rotation recording: which rows are static and which turn about which axis.

A Ferraris recording (Ferraris et al. 1995; imucal's section names) holds six static positions
and three rotations; any other recording names its sections by row ranges, each rotation with its
axis (a letter or a unit vector) and its set angle. :func:`ferraris_sections` turns imucal's
section table into that form; :mod:`rotacal.gyro.rotations` checks and integrates the sections.

References
----------
Ferraris F., Grimaldi U., Parvis M. (1995), Procedure for effortless in-field calibration of
three-axial rate gyro and accelerometers, Sensors and Materials 7(5):311–330.
Küderle A. et al. (2022), imucal — a Python library to calibrate 6 DOF IMUs, JOSS 7(73):4338.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from rotacal.errors import ConfigError
from rotacal.signal._values import (
    check_setting,
)

__all__ = [
    "FERRARIS_ANGLE_DEG",
    "FERRARIS_ROTATIONS",
    "FERRARIS_STATIC",
    "ferraris_sections",
    "sections_from_labels",
]

#: Section names of a Ferraris recording (imucal's): six static positions and three rotations.
FERRARIS_STATIC = ("x_p", "x_a", "y_p", "y_a", "z_p", "z_a")
FERRARIS_ROTATIONS = {"x_rot": "x", "y_rot": "y", "z_rot": "z"}
#: Set angle of a Ferraris rotation (deg, right-hand rule): one clockwise turn seen from the tip
#: of the +axis, as imucal's protocol does it (its ``expected_angle=-360``).
FERRARIS_ANGLE_DEG = -360.0

_AXES = "xyz"
_MIN_SECTION = 2


def _range(name: str, value: Any, n: int) -> tuple[int, int]:
    """(start, stop) from a pair or an imucal-style {"start": …, "end": …} mapping."""
    if isinstance(value, Mapping):
        if "start" not in value or not ("end" in value or "stop" in value):
            raise ConfigError(f"section {name} must give 'start' and 'end' sample indices.")
        pair: Any = (value["start"], value.get("end", value.get("stop")))
    else:
        pair = value
    try:
        start, stop = pair
        fs_, fe_ = float(start), float(stop)
    except (TypeError, ValueError):
        raise ConfigError(
            f"section {name} must be a (start, stop) pair of sample indices, got {value!r}."
        ) from None
    if not (fs_.is_integer() and fe_.is_integer()):
        raise ConfigError(f"section {name} must use integer sample indices, got {value!r}.")
    s, e = int(fs_), int(fe_)
    if not 0 <= s < e <= n:
        raise ConfigError(
            f"section {name} = [{s}, {e}) must satisfy 0 ≤ start < stop ≤ {n} (the recording's "
            "length); fix the section list."
        )
    if e - s < _MIN_SECTION:
        raise ConfigError(f"section {name} = [{s}, {e}) has fewer than {_MIN_SECTION} samples.")
    return s, e


def _axis_vector(name: str, axis: Any) -> tuple[str, np.ndarray]:
    if isinstance(axis, str):
        a = axis.strip().lower()
        sign = -1.0 if a.startswith("-") else 1.0
        a = a.lstrip("+-")
        if a not in ("x", "y", "z"):
            raise ConfigError(
                f"rotation {name}: axis must be 'x', 'y', 'z' (optionally signed) or a 3-vector, "
                f"got {axis!r}."
            )
        v = np.zeros(3)
        v[_AXES.index(a)] = sign
        return axis.strip(), v
    v = np.asarray(axis, dtype=float).ravel()
    if v.size != 3 or not np.isfinite(v).all() or not np.linalg.norm(v) > 0:
        raise ConfigError(f"rotation {name}: axis must be a non-zero 3-vector, got {axis!r}.")
    v = v / np.linalg.norm(v)
    return "(" + ", ".join(f"{c:.6g}" for c in v) + ")", v


def _parse_rotations(
    rotations: Any, angle_deg: float, n: int
) -> list[tuple[str, str, np.ndarray, int, int, float]]:
    """[(name, axis label, unit axis, start, stop, angle_deg)]."""
    out = []
    if isinstance(rotations, Mapping):
        items: list[Any] = [(str(ax), ax, rng, angle_deg) for ax, rng in rotations.items()]
    elif isinstance(rotations, Sequence) and not isinstance(rotations, str):
        items = []
        for i, rot in enumerate(rotations):
            if not isinstance(rot, Sequence) or isinstance(rot, str) or len(rot) not in (3, 4):
                raise ConfigError(
                    f"rotation {i} must be (axis, start, stop) or (axis, start, stop, angle_deg), "
                    f"got {rot!r}."
                )
            ang = rot[3] if len(rot) == 4 else angle_deg
            items.append((f"{i} ({rot[0]})", rot[0], (rot[1], rot[2]), ang))
    else:
        raise ConfigError(
            "rotations must map axes to (start, stop) sample ranges, e.g. {'x': (700, 1000), …}, "
            "or be a list of (axis, start, stop[, angle_deg])."
        )
    for name, ax, rng, ang in items:
        label, vec = _axis_vector(name, ax)
        s, e = _range(f"rotation {name}", rng, n)
        try:
            a = float(ang)
        except (TypeError, ValueError):
            raise ConfigError(
                f"rotation {name}: angle_deg must be a number, got {ang!r}."
            ) from None
        if not math.isfinite(a) or a == 0:
            raise ConfigError(
                f"rotation {name}: angle_deg must be finite and non-zero, got {ang!r}."
            )
        check_setting(f"rotation {name}: angle_deg", a, positive=False, unit="deg")
        out.append((name, label, vec, s, e, a))
    if not out:
        raise ConfigError("give at least three rotation sections (about x, y and z).")
    return out


def _parse_static(static: Any, n: int) -> list[tuple[str, int, int]]:
    if static is None:
        return []
    if isinstance(static, Mapping):
        return [(str(k), *_range(f"static {k}", v, n)) for k, v in static.items()]
    if isinstance(static, Sequence) and not isinstance(static, str):
        return [(str(i), *_range(f"static {i}", v, n)) for i, v in enumerate(static)]
    raise ConfigError(
        "static must map names to (start, stop) sample ranges or be a list of (start, stop)."
    )


def ferraris_sections(
    section_list: Mapping[str, Any],
) -> tuple[dict[str, tuple[int, int]], dict[str, tuple[int, int]]]:
    """Rotation and static sections from a Ferraris section list (imucal's names).

    Parameters
    ----------
    section_list : mapping
        ``x_p, x_a, y_p, y_a, z_p, z_a`` (static) and ``x_rot, y_rot, z_rot`` (rotations) to
        ``{"start": i, "end": j}`` or ``(i, j)``: half-open sample ranges [i, j), as imucal
        stores them (``example_ferraris_session_list.json``).

    Returns
    -------
    rotations : dict
        ``{"x": (start, stop), "y": …, "z": …}`` for :func:`calibrate_triad_rotations`.
    static : dict
        ``{"x_p": (start, stop), …}``.

    References
    ----------
    Ferraris F., Grimaldi U., Parvis M. (1995), Sensors and Materials 7(5):311–330 (the six
    static positions and three rotations).
    """
    if not isinstance(section_list, Mapping):
        raise ConfigError("section_list must map section names (x_p, …, z_rot) to ranges.")
    missing = [k for k in (*FERRARIS_STATIC, *FERRARIS_ROTATIONS) if k not in section_list]
    if missing:
        raise ConfigError(
            f"the section list lacks {', '.join(missing)}; a Ferraris recording needs "
            f"{', '.join((*FERRARIS_STATIC, *FERRARIS_ROTATIONS))}."
        )

    def pair(k: str) -> tuple[int, int]:
        v = section_list[k]
        if isinstance(v, Mapping):
            return int(v["start"]), int(v.get("end", v.get("stop")))
        return int(v[0]), int(v[1])

    rotations = {ax: pair(k) for k, ax in FERRARIS_ROTATIONS.items()}
    static = {k: pair(k) for k in FERRARIS_STATIC}
    return rotations, static


def sections_from_labels(labels: Any) -> dict[str, tuple[int, int]]:
    """Sample ranges from a section label per row (imucal's annotated sessions: the section name
    as the first index level, e.g. ``annotated_session.csv``'s ``part`` column).

    Parameters
    ----------
    labels : array_like of str, (n,)
        The section of each row; each name must occupy one contiguous block of rows.

    Returns
    -------
    dict
        name → half-open range [start, stop), in the order the sections first appear.

    Raises
    ------
    ConfigError
        A name whose rows are not one contiguous block.
    """
    lab = np.asarray(labels).astype(str).reshape(-1)
    out: dict[str, tuple[int, int]] = {}
    for name in dict.fromkeys(lab.tolist()):
        idx = np.flatnonzero(lab == name)
        if idx[-1] - idx[0] + 1 != idx.size:
            raise ConfigError(
                f"section {name} is not one contiguous block of rows (rows {idx[0]} to {idx[-1]} "
                f"hold {idx.size} of its rows); label each section once."
            )
        out[name] = (int(idx[0]), int(idx[-1]) + 1)
    return out
