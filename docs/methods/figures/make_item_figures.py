"""Draw the figure of the IEEE Std 952/1431 items page (docs/methods/figures/gyro-small-steps.svg).

Run from the repository's root: ``PYTHONPATH=src python docs/methods/figures/make_item_figures.py``.
The figure is the report's own, drawn from the gyro-steps twin (threshold 0.007 °/s, resolution
0.0042 °/s), so a change of the simulator or of the analysis shows in it.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from rotacal.gyro.threshold import small_step_test
from rotacal.report.gyro_steps import small_step_plot
from rotacal.sim import simulate_gyro_steps

HERE = Path(__file__).resolve().parent
# fixed SVG ids and no date: the file only changes when the drawing does
matplotlib.rcParams["svg.hashsalt"] = "rotacal-methods"


def main() -> None:
    cap = simulate_gyro_steps()
    result = small_step_test(
        cap.columns["rate_deg_s"], cap.columns["output"], scale_factor=cap.truth["scale_factor"]
    )
    small_step_plot(result).savefig(HERE / "gyro-small-steps.svg", metadata={"Date": None})


if __name__ == "__main__":
    main()
