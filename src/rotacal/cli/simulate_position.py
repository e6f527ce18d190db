"""``rotacal simulate position``: a position test of an indexing table, for ``rotacal position``.

Registered on the ``simulate`` group by the import at the end of :mod:`rotacal.cli.simulate`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import click

from rotacal.errors import ConfigError

from ._help import example
from .simulate import _sim_common, _sim_write, simulate


def _triples(items: Sequence[str], option: str) -> list[tuple[float, float, float]]:
    """``ORDER:AMPLITUDE_ARCSEC:PHASE_DEG`` items as numbers."""
    out = []
    for item in items:
        parts = item.split(":")
        try:
            h, c, phi = (float(p) for p in parts)
        except ValueError:
            raise ConfigError(
                f"{option} {item}: give ORDER:AMPLITUDE_ARCSEC:PHASE_DEG, e.g. 1:6:30"
            ) from None
        out.append((h, c, phi))
    return out


@simulate.command(
    "position",
    epilog=example(
        "rotacal simulate position --out pos.csv",
        "rotacal simulate position --reference polygon --positions 12 --runs 12 --out poly.csv",
        "rotacal simulate position --harmonic 1:8:0 --harmonic 3:1:45 --out pos.csv",
    ),
)
@_sim_common
@click.option("--positions", type=int, default=None, help="Target positions over 360° [24].")
@click.option("--runs", type=int, default=None, help="Runs (approaches per position) [5].")
@click.option(
    "--bidirectional/--unidirectional", default=True, help="Approach in both senses [both]."
)
@click.option(
    "--harmonic",
    "harmonic_items",
    multiple=True,
    metavar="H:C:PHI",
    help="A harmonic of the table's error: order, amplitude (arcsec), phase (deg); repeatable "
    "[1:6:30 2:2.5:-60 3:1.2:100 4:0.6:0].",
)
@click.option("--reversal-arcsec", type=float, default=None, help="Reversal value B [1.5].")
@click.option("--noise-arcsec", type=float, default=None, help="Noise per stop, rms [0.3].")
@click.option(
    "--reference",
    type=click.Choice(["encoder", "polygon", "deviation"]),
    default=None,
    help="What reads the table: reference_deg, a polygon's error_arcsec, or the deviation "
    "[encoder].",
)
@click.option(
    "--graduation",
    "graduation_items",
    multiple=True,
    metavar="H:C:PHI",
    help="A harmonic of the reference encoder's graduation error (repeatable) [none].",
)
@click.option(
    "--polygon-step-faces", type=int, default=None, help="Faces the polygon turns per run [1]."
)
@click.option("--face-error-arcsec", type=float, default=None, help="rms of the face errors [1.0].")
def simulate_position_cmd(
    out: str,
    overwrite: bool,
    harmonic_items: Sequence[str],
    graduation_items: Sequence[str],
    **kw: Any,
) -> None:
    """An indexing table's position test against a reference.

    Columns position_deg, run, direction and reference_deg (a reference encoder), or
    error_arcsec and face (an autocollimator on a polygon; positions = faces), or error_arcsec
    (the deviation): the table's error is a few harmonics, a reversal and white noise; the truth
    holds them, the face errors and, for an encoder, its graduation as a `selfcal` curve.
    """
    from rotacal.sim.position import simulate_position

    options = {k: v for k, v in kw.items() if v is not None}
    if harmonic_items:
        options["harmonics"] = _triples(harmonic_items, "--harmonic")
    if graduation_items:
        options["graduation"] = _triples(graduation_items, "--graduation")
    _sim_write(simulate_position(**options), out, overwrite)
