"""``rotacal simulate angle``: angle or counter readings of a table, for ``motion angle`` and ``rate``.

Registered on the ``simulate`` group by the import at the end of :mod:`rotacal.cli.simulate`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import click

from ._help import example
from .simulate import _motion_sim_options, _sim_motion, _sim_write, simulate


@simulate.command(
    "angle",
    epilog=example(
        "rotacal simulate angle --counter-bits 16 --out counts.csv",
        "rotacal simulate angle --reading angle --resolution-deg 0.0001 --out readout.csv",
        "rotacal simulate angle --rate-deg-s 300 --duration-s 12 --out spin.npz",
    ),
)
@_motion_sim_options
@click.option(
    "--rate-deg-s",
    type=float,
    default=None,
    help="Turn at this constant rate (deg/s) instead of the sinusoidal motion (for `rate`).",
)
@click.option(
    "--fluctuation", type=float, default=0.0, show_default=True, help="Relative rate fluctuation."
)
@click.option(
    "--fluctuation-hz", type=float, default=1.0, show_default=True, help="Its frequency (Hz)."
)
@click.option(
    "--reading",
    type=click.Choice(["count", "angle"]),
    default="count",
    show_default=True,
    help="Log an up/down counter (count) or an angle readout (angle_deg).",
)
@click.option("--counts-per-rev", type=int, default=144_000, show_default=True, help="N.")
@click.option(
    "--counter-bits",
    type=click.Choice(["8", "16", "24", "32", "64"]),
    default="16",
    show_default=True,
    help="Width of the counter's register.",
)
@click.option("--signed", is_flag=True, help="A two's complement register.")
@click.option(
    "--start-count",
    type=int,
    default=None,
    help="Count at θ = 0 [default: 40 below the register's end, so that it wraps].",
)
@click.option(
    "--resolution-deg",
    type=float,
    default=0.0,
    show_default=True,
    help="Quantum of the angle readout (deg; 0: unrounded).",
)
@click.option(
    "--noise-deg", type=float, default=0.0, show_default=True, help="White noise on θ (deg rms)."
)
@click.option("--drop-rows", type=int, default=0, show_default=True, help="Samples lost.")
@click.option("--repeat-rows", type=int, default=0, show_default=True, help="Rows written twice.")
def simulate_angle_cmd(out: str, harmonic_items: Sequence[str], overwrite: bool, **kw: Any) -> None:
    """Angle readout or counter on a table, moving or turning.

    Columns time_s and count (a register of --counter-bits that wraps around) or angle_deg;
    the DAQ may lose samples and write rows twice. The truth holds the motion and where the
    faults are.
    """
    kw["counter_bits"] = int(kw["counter_bits"])
    if kw["fs_hz"] is None:
        kw["fs_hz"] = 2000.0
    if kw["rate_deg_s"] is not None:
        from rotacal.sim.angle import simulate_angle

        for key in (
            "amplitude_deg",
            "frequency_hz",
            "stagnation_s",
            "creep_deg",
            "backlash_deg",
            "vibration_deg",
            "vibration_hz",
            "drift_deg_s",
        ):
            kw.pop(key)
        _sim_write(simulate_angle(**kw), out, overwrite)
        return
    for key in ("rate_deg_s", "fluctuation", "fluctuation_hz"):
        kw.pop(key)
    _sim_write(_sim_motion("angle", harmonic_items, kw), out, overwrite)
