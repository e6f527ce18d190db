"""Report section for one deviation of the Allan family (``rotacal allan --deviation``)."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from rotacal.numbers import fixed
from rotacal.references import cite
from rotacal.report.html import Figure, Section, figure_from_matplotlib
from rotacal.report.wording import paragraph
from rotacal.signal.deviations import DEVIATION_NAMES, StabilityDeviation

__all__ = ["deviation_section"]

#: What each deviation shows a test engineer, for the section's paragraph.
_WHY = {
    "mdev": "averages the second differences over each cluster before squaring: its slope "
    "separates white angle noise (−3/2) from flicker angle noise (−1), which the Allan deviation "
    "cannot (both −1)",
    "hdev": "takes third differences, so a constant rate ramp (linear drift of the rate) does not "
    "enter it: noise that the ramp hides in the Allan deviation shows",
    "tdev": "is τ·MDEV/√3, the angle (phase) stability after averaging over τ; white angle noise "
    "gives slope −½, angle random walk +½",
    "totdev": "is the Allan deviation of the record extended by reflection at both ends: at long "
    "τ it scatters less than the Allan deviation, for the same expected value",
}


def _figure(dev: StabilityDeviation, adev: tuple[np.ndarray, np.ndarray] | None) -> Figure:
    tau = np.asarray(dev.tau_s)
    unit = "°" if dev.kind == "tdev" else "°/s"
    name = DEVIATION_NAMES[dev.kind]
    fig, ax = plt.subplots(figsize=(7.8, 4.8))
    level = f"{100 * dev.confidence:.0f} %"
    ax.fill_between(
        tau, dev.low, dev.high, color="#f2c18d", alpha=0.55, lw=0, label=f"{level} interval"
    )
    ax.loglog(tau, dev.deviation, color="#c0580f", lw=1.5, label=name)
    if adev is not None and dev.kind != "tdev":
        ax.loglog(
            adev[0],
            adev[1],
            color="#1f5f99",
            lw=1.0,
            alpha=0.7,
            label="overlapping Allan deviation",
        )
    ax.set_xlabel("averaging time τ (s)")
    ax.set_ylabel(f"{dev.kind.upper()}(τ) ({unit})")
    ax.grid(True, which="both", color="#e3e7eb", linewidth=0.6)
    ax.spines[["top", "right"]].set_visible(False)
    ax.legend(loc="best", fontsize=8, frameon=False)
    return figure_from_matplotlib(
        fig,
        f"{name[0].upper()}{name[1:]} with its {level} interval",
        f"{dev.n_samples} samples at {fixed(dev.fs_hz)} Hz. Shaded: the χ² interval with the "
        f"equivalent degrees of freedom of {cite('greenhall2003')} for the noise exponent "
        f"α = {dev.noise_alpha}"
        + (" (white rate noise)" if dev.noise_alpha == 0 else "")
        + ("; the total deviation's from NIST SP 1065 Table 8." if dev.kind == "totdev" else "."),
    )


def deviation_section(
    dev: StabilityDeviation, adev: tuple[np.ndarray, np.ndarray] | None = None
) -> Section:
    """The deviation's figure (beside the Allan deviation ``adev`` = (τ, σ), when given) and a
    paragraph saying what it shows and where its formula comes from."""
    name = DEVIATION_NAMES[dev.kind]
    text = (
        f"The {name} ({cite('riley2008')}, §5.2) {_WHY.get(dev.kind, 'is the reference curve')}. "
        f"It is computed at {dev.tau_s.size} averaging times from {fixed(dev.tau_s[0])} s to "
        f"{fixed(dev.tau_s[-1])} s."
    )
    return Section(
        title=f"Stability: {name}",
        paragraphs=[text, *(paragraph(n) for n in dev.notes)],
        figures=[_figure(dev, adev)],
        references=["riley2008", "greenhall2003"],
        anchor=f"deviation-{dev.kind}",
    )
