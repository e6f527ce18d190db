"""``rotacal simulate gyro-triad-log``: one log of rotation runs, for ``gyro triad --runs``.

Registered on the ``simulate`` group by the import at the end of :mod:`rotacal.cli.simulate`.
"""

from __future__ import annotations

from typing import Any

import click

from ._help import example
from .simulate import _sim_common, _sim_write, simulate


@simulate.command(
    "gyro-triad-log",
    epilog=example("rotacal simulate gyro-triad-log --run-s 75 --out runs.npz"),
)
@_sim_common
@click.option("--run-s", type=float, default=None, help="Seconds of each rotation run [60].")
@click.option("--rest-s", type=float, default=None, help="Seconds of rest before each run [2].")
@click.option(
    "--g-sensitivity",
    type=float,
    default=None,
    help="g-sensitivity on the diagonal (deg/s per g; 0: none) [a 3x3 matrix, 0.15-0.25].",
)
@click.option("--noise-std", type=float, default=None, help="Output noise, rms (deg/s) [0.1].")
@click.option("--fs-hz", type=float, default=None, help="Sample rate (Hz) [100].")
def simulate_gyro_triad_log_cmd(out: str, overwrite: bool, **kw: Any) -> None:
    """Log of a three-axis gyro's one-minute rotation runs.

    Columns time_s, wx_deg_s, wy_deg_s, wz_deg_s (the set rate, 0 at rest) and ux, uy, uz: runs
    about x, y, z at 6, 18, 30, 60, 90 deg/s in both directions with rests between, the outputs
    carrying a g-sensitivity to gravity turning with the table; K, b and G in FILE.truth.json.
    """
    from rotacal.sim import simulate_gyro_triad_log

    options = {k: v for k, v in kw.items() if v is not None}
    _sim_write(simulate_gyro_triad_log(**options), out, overwrite)
