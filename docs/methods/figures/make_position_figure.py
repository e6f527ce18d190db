"""Draw the figure of the position-accuracy page (docs/methods/figures/position-polygon.svg).

Run from the repository's root: ``PYTHONPATH=src python docs/methods/figures/make_position_figure.py``.
The figure is the report's own, drawn from the position twin on a 12-face polygon turned one face
per run, so a change of the simulator or of the analysis shows in it.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from rotacal.position import position_accuracy
from rotacal.report.position import position_plot
from rotacal.sim import simulate_position

HERE = Path(__file__).resolve().parent
# fixed SVG ids and no date: the file only changes when the drawing does
matplotlib.rcParams["svg.hashsalt"] = "rotacal-methods"


def main() -> None:
    c = simulate_position(reference="polygon", positions=12, runs=6).columns
    result = position_accuracy(
        c["position_deg"],
        error_arcsec=c["error_arcsec"],
        run=c["run"],
        direction=c["direction"],
        face=c["face"],
        polygon_faces=12,
        harmonics=3,
    )
    position_plot(result).savefig(HERE / "position-polygon.svg", metadata={"Date": None})


if __name__ == "__main__":
    main()
