"""Draw docs/methods/figures/turntable-identify.png: a twin table's identified errors against an
allocation's bounds, as ``rotacal turntable identify --report`` draws them.

Run from the repository's root: ``PYTHONPATH=src python docs/methods/figures/make_identify_figure.py``.
The twin (``rotacal.sim.simulate_orientation_errors``: 8 × 8 positions, 0.5″ reading noise, α_x2
made 25″) is identified and compared with bounds of 0.3′ (18″) for every error.
"""

from __future__ import annotations

import base64
from pathlib import Path

from rotacal.report.turntable_identify import estimates_figure
from rotacal.sim import simulate_orientation_errors
from rotacal.turntable import identify_turntable

HERE = Path(__file__).resolve().parent
COLUMNS = ("phi1_deg", "phi2_deg", "dpsi_arcsec", "dtheta_arcsec", "dgamma_arcsec")


def main() -> None:
    cap = simulate_orientation_errors(errors_arcsec={"alpha_x2": 25.0}, seed=4)
    bounds = dict.fromkeys(cap.truth["errors_arcsec"], 18.0) | {"eta": None}
    result = identify_turntable(
        *(cap.columns[c] for c in COLUMNS), bounds_arcsec=bounds, bounds_source="0.3′ each"
    )
    figure = estimates_figure(result)
    (HERE / "turntable-identify.png").write_bytes(base64.b64decode(figure.png_base64))


if __name__ == "__main__":
    main()
