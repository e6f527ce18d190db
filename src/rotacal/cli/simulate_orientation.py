"""``rotacal simulate orientation``: a turntable's orientation errors at many positions, for
``turntable identify``.

Registered on the ``simulate`` group by the import at the end of :mod:`rotacal.cli.simulate`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import click

from rotacal.errors import ConfigError

from ._help import example
from .simulate import _sim_common, _sim_write, simulate


def _named_values(items: Sequence[str]) -> dict[str, float]:
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise ConfigError(
                f"--error {item!r}: give NAME=ARCSEC, e.g. --error alpha_x2=-7.5."
            ) from None
        if not sep:
            raise ConfigError(f"--error {item!r}: give NAME=ARCSEC, e.g. --error alpha_x2=-7.5.")
    return out


@simulate.command(
    "orientation",
    epilog=example(
        "rotacal simulate orientation --out errors.csv",
        "rotacal simulate orientation --inner-steps 1 --error alpha_x2=20 --out fixed.csv",
    ),
)
@_sim_common
@click.option(
    "--error",
    "errors",
    multiple=True,
    metavar="NAME=ARCSEC",
    help="A table error (names of orientation_error; repeatable) [the twin's table].",
)
@click.option("--outer-steps", type=int, default=None, help="Outer-axis positions per turn [8].")
@click.option(
    "--inner-steps", type=int, default=None, help="Inner-axis positions per turn (1: fixed) [8]."
)
@click.option("--noise-arcsec", type=float, default=None, help="Reading noise, rms (arcsec) [0.5].")
def simulate_orientation_errors_cmd(
    out: str, overwrite: bool, errors: Sequence[str], **kw: Any
) -> None:
    """Orientation errors of a two-axis turntable.

    Columns phi1_deg, phi2_deg, dpsi_arcsec, dtheta_arcsec, dgamma_arcsec: the orientation
    error of the instrument on the GyroWheel study's table (eqs. 17–24, proper rotations) at a
    grid of positions, with reading noise; the table's errors are in FILE.truth.json.
    """
    from rotacal.sim import simulate_orientation_errors

    options = {k: v for k, v in kw.items() if v is not None}
    if errors:
        options["errors_arcsec"] = _named_values(errors)
    _sim_write(simulate_orientation_errors(**options), out, overwrite)
