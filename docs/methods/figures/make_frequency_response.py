"""Draw docs/methods/figures/frequency-response.png: the Bode figure of a twin gyro's sweep.

Run from the repository's root: ``PYTHONPATH=src python docs/methods/figures/make_frequency_response.py``.
Eight captures of ``rotacal.sim.simulate_gyro_sine`` (fn = 8 Hz, ζ = 0.5) analysed by
``calibrate_frequency_response``, as ``rotacal gyro frequency-response --report`` draws them.
"""

from __future__ import annotations

from pathlib import Path

from rotacal.gyro.frequency_response import calibrate_frequency_response
from rotacal.report.frequency_response import bode_matplotlib
from rotacal.sim.gyro_sine import simulate_gyro_sine

HERE = Path(__file__).resolve().parent
FREQUENCIES_HZ = (1, 2, 4, 6, 8, 10, 13, 16)


def main() -> None:
    caps = [simulate_gyro_sine(f, seed=f) for f in FREQUENCIES_HZ]
    result = calibrate_frequency_response([c.columns for c in caps], lines=3600)
    fig = bode_matplotlib(result)
    fig.savefig(HERE / "frequency-response.png", dpi=96, metadata={"Software": None})


if __name__ == "__main__":
    main()
