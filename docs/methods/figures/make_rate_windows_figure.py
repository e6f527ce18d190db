"""Draw docs/methods/figures/rate-windows.png: the window rates of a twin rate table.

Run from the repository's root: ``PYTHONPATH=src python docs/methods/figures/make_rate_windows_figure.py``.
A 12-head, 18,000-line encoder on a table at 300 °/s (``rotacal.sim.simulate_pulses``, 12
revolutions, 0.01 % rate fluctuation at the revolution frequency, 2.3 Hz and 7.9 Hz), its scale
self-calibrated from the same capture, the windows of 1°, 10° and 360° of head 0 compensated with
it, as ``rotacal rate … --window-deg 1,10,360 --report`` draws them.
"""

from __future__ import annotations

import base64
from pathlib import Path

from rotacal.encoder.selfcal import self_calibrate
from rotacal.report.rate_windows import rate_windows_figure
from rotacal.sim.pulses import simulate_pulses
from rotacal.table.rate_windows import rate_windows

HERE = Path(__file__).resolve().parent


def main() -> None:
    cap = simulate_pulses(heads=12, pulses_per_rev=18000, rate_deg_s=300.0, revolutions=12.0)
    heads = [cap.columns[f"head_{i}"] for i in range(12)]
    selfcal = self_calibrate(heads, pulses_per_rev=18000)
    windows = rate_windows(
        heads[0],
        pulses_per_rev=18000,
        windows_deg=[1, 10, 360],
        set_rate_deg_s=300.0,
        deviation_arcsec=selfcal.deviation_arcsec,
        deviation_u_arcsec=selfcal.deviation_u_arcsec,
    )
    png = base64.b64decode(rate_windows_figure(windows).png_base64)
    (HERE / "rate-windows.png").write_bytes(png)
    for key in windows.window_count:
        print(
            key,
            windows.rate_stability_percent[key],
            windows.rate_stability_percent_u[key],
            windows.rate_stability_peak_percent[key],
            windows.rate_accuracy_percent[key],
        )


if __name__ == "__main__":
    main()
