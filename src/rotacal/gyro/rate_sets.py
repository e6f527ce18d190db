"""A rate-table test recorded as one file per set rate, and the 0 °/s point from runs at rest.

Many rate tables and DAQ programs write one file per plateau (``p10.dat`` at +10 °/s,
``m10.dat`` at −10 °/s …) with the DUT's output only: the set rate is in the file's name or in
the lab's notes. This module turns such a set into the rows the scale-factor analysis of Kokuyama et al. (2015)
(:func:`rotacal.gyro.calibrate_scale_factor`) takes: every sample of a file is one row at the
file's set rate, so each file becomes one rate point whose mean, standard deviation and Type A
uncertainty come from its samples.

A file whose name does not state a rate is refused, never guessed: a run that turns through an
angle (``p10_1turn.dat``) is not a plateau. Such a run that starts and ends at rest can give the
0 °/s point instead (:func:`rest_samples`).
"""

from __future__ import annotations

import csv
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from rotacal.errors import CaptureError, ConfigError

#: file-name stems that state a set rate: an optional sign (+, -, or p = plus, m = minus, pos, neg,
#: plus, minus with an optional "_" after it), a number, an optional unit (dps, deg_s, degps);
#: nothing else ("p-10" names no rate: its two signs disagree)
_RATE_NAME = re.compile(
    r"^(?:(?P<sign>[+-])|(?P<word>p|m|pos|neg|plus|minus)_?)?(?P<value>\d+(?:\.\d+)?)"
    r"(?:[_-]?(?:dps|deg_?s|degps|deg-s))?$",
    re.IGNORECASE,
)
_NEGATIVE = {"-", "m", "neg", "minus"}
NAME_FORMS = "p10, m10 (p/m: plus/minus), +10, -10.5, 10dps"


def set_rate_from_name(path: str | Path) -> float:
    """The set rate (°/s) a file's name states: ``p10.dat`` → +10, ``m10.dat`` → −10.

    The name without its extensions must be exactly a signed number (see ``NAME_FORMS``).

    Raises
    ------
    ConfigError
        Naming the file, for a name that states no rate (``p10_1turn.dat``).
    """
    p = Path(path)
    name = p.name[:-3] if p.name.lower().endswith(".gz") else p.name
    stem = Path(name).stem
    m = _RATE_NAME.match(stem)
    if m is None:
        raise ConfigError(
            f"{p.name}: its name does not state a set rate (--rate-from-name reads names like "
            f"{NAME_FORMS}); rename it, give its rate in --rates TABLE, or leave it out (a run "
            "that starts and ends at rest can give the 0 °/s point with --rest-from)"
        )
    value = float(m.group("value"))
    sign = (m.group("sign") or m.group("word") or "").lower()
    return -value if sign in _NEGATIVE else value


def read_rates_table(path: str | Path) -> dict[str, float]:
    """A table of file name → set rate (°/s): two cells per row, comma, semicolon or tab.

    A first row whose second cell is not a number is a header; ``#`` lines are comments. Names
    are matched against the files' names (without folders).

    Raises
    ------
    ConfigError
        Naming the table and the row: not two cells, a rate that is not a number, a name twice.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except OSError as e:
        raise ConfigError(f"--rates {p}: cannot read it ({e.strerror})") from None
    except UnicodeDecodeError:
        raise ConfigError(f"--rates {p} is not UTF-8 text; save it as UTF-8 CSV") from None
    lines = [(n, line) for n, line in enumerate(text.splitlines(), 1) if line.strip()]
    lines = [(n, line) for n, line in lines if not line.lstrip().startswith("#")]
    if not lines:
        raise ConfigError(f"--rates {p} holds no rows; write one 'file,rate_deg_s' row per file")
    delimiter = next((d for d in ("\t", ";", ",") if d in lines[0][1]), ",")
    table: dict[str, float] = {}
    for k, (n, line) in enumerate(lines):
        cells = [c.strip() for c in next(csv.reader([line], delimiter=delimiter))]
        if len(cells) != 2 or not cells[0]:
            raise ConfigError(
                f"--rates {p.name} line {n} has {len(cells)} cells; write 'file{delimiter}rate_deg_s'"
            )
        try:
            rate = float(cells[1])
        except ValueError:
            if k == 0:
                continue  # the header
            raise ConfigError(
                f"--rates {p.name} line {n}: {cells[1]!r} is not a rate in °/s; fix that row"
            ) from None
        name = Path(cells[0]).name
        if name in table:
            raise ConfigError(f"--rates {p.name} line {n} gives {name!r} a second time; keep one")
        table[name] = rate
    return table


def set_rates(
    paths: Sequence[str],
    *,
    from_name: bool,
    table: Mapping[str, float] | None,
    table_name: str = "",
) -> list[float]:
    """The set rate (°/s) of each file: from ``table`` when it lists the file, else its name."""
    rates = []
    for path in paths:
        name = Path(path).name
        if table is not None and name in table:
            rates.append(float(table[name]))
        elif from_name:
            rates.append(set_rate_from_name(path))
        else:
            raise ConfigError(
                f"{name} is not in --rates {table_name}; add a row '{name},RATE_DEG_S' "
                "(or add --rate-from-name when its name states the rate)"
            )
    return rates


def rest_samples(
    output: np.ndarray,
    *,
    scale_factor: float,
    bias: float,
    band_deg_s: float,
    guard_samples: int,
    name: str = "",
) -> np.ndarray:
    """The samples of a run that starts and ends at rest: those before it moves and after it stops.

    The run moves where the rate its output indicates, (output − bias)/scale_factor, leaves the
    band ±``band_deg_s``; the samples from ``guard_samples`` before the first such sample to
    ``guard_samples`` after the last are the motion (its start and end ramps inside the band
    included) and are dropped.

    Parameters
    ----------
    output : array
        The DUT's output through the run (output units).
    scale_factor, bias : float
        A preliminary line (output unit per °/s, output unit), e.g. fitted to the plateaus.
    band_deg_s : float
        Rates within ± this (°/s) count as rest.
    guard_samples : int
        Samples dropped on each side of the motion.

    Raises
    ------
    CaptureError
        When the run never leaves the band (it shows no motion: not a run at rest around a
        turn) or leaves no rest before or after it.
    """
    indicated = (np.asarray(output, dtype=np.float64) - bias) / scale_factor
    moving = np.flatnonzero(np.abs(indicated) >= band_deg_s)
    if moving.size == 0:
        raise CaptureError(
            f"{name}: the output never leaves ±{band_deg_s:g} °/s of rest, so the run shows no "
            "motion; --rest-from takes runs that start at rest, turn and stop"
        )
    head = output[: max(int(moving[0]) - guard_samples, 0)]
    tail = output[int(moving[-1]) + 1 + guard_samples :]
    if head.size == 0 and tail.size == 0:
        raise CaptureError(
            f"{name}: no sample at rest before or after the motion; --rest-from takes runs that "
            "start at rest, turn and stop"
        )
    return np.concatenate([head, tail])
