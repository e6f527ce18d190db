"""``rotacal simulate gyro-sine``: one capture of a gyro's dynamic test, for ``gyro frequency-response``.

Registered on the ``simulate`` group by the import at the end of :mod:`rotacal.cli.simulate`.
"""

from __future__ import annotations

from typing import Any

import click

from ._help import example
from .simulate import _sim_common, _sim_write, simulate


@simulate.command(
    "gyro-sine",
    epilog=example(
        "rotacal simulate gyro-sine --frequency-hz 2 --out f2.csv",
        "rotacal simulate gyro-sine --frequency-hz 10 --natural-frequency-hz 40 "
        "--fs-hz 20000 --out f10.csv",
    ),
)
@_sim_common
@click.option(
    "--frequency-hz", type=float, default=None, help="Frequency of the table's sine (Hz) [2]."
)
@click.option(
    "--rate-amplitude-deg-s",
    type=float,
    default=None,
    help="Amplitude of the table's rate (deg/s) [30].",
)
@click.option(
    "--natural-frequency-hz", type=float, default=None, help="The DUT's natural frequency [8]."
)
@click.option("--damping-ratio", type=float, default=None, help="The DUT's damping ratio ζ [0.5].")
@click.option("--delay-s", type=float, default=None, help="The DUT's pure delay (s) [0].")
@click.option(
    "--noise-deg-s", type=float, default=None, help="The DUT's rate noise, rms (deg/s) [0.05]."
)
@click.option(
    "--reference",
    type=click.Choice(["encoder", "angle"]),
    default=None,
    help="Columns a, b of an encoder, or angle_deg [encoder].",
)
@click.option("--lines", type=int, default=None, help="Encoder lines per revolution [3600].")
@click.option(
    "--fs-hz", type=float, default=None, help="Sampling rate of every column (Hz) [5000]."
)
@click.option("--periods", type=float, default=None, help="Capture length in periods [8].")
def simulate_gyro_sine_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """A second-order gyro on a sinusoidal table, one frequency.

    Columns time_s, a and b (or angle_deg) and rate_deg_s: the DUT H(s) = ωn²/(s² + 2ζωn·s +
    ωn²) in steady state, with white noise; the truth holds H at the frequency, fn, ζ and the
    −3 dB bandwidth, for `rotacal gyro frequency-response`.
    """
    from rotacal.sim.gyro_sine import simulate_gyro_sine

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_sine(**options), out, overwrite)
