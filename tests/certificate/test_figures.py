"""The certificate's figures: one or two per measurement, deterministic vector SVG, and the noise
term lines of the Allan figure as IEEE Std 952 states them."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from rotacal.certificate.content import CertificateContent
from rotacal.certificate.figures import draw_figures, noise_term_lines

pytestmark = pytest.mark.xdist_group("certificate")

_SVG = "{http://www.w3.org/2000/svg}"
#: Commands whose JSON holds nothing a figure would add to the numbers (a rotation's angle is
#: matched exactly by construction).
_NO_FIGURE = {"gyro rotations"}
#: What each command's figure shows (the last part of its file name): the curve a reader checks.
_SHOWS = {
    "motion encoder": "harmonics",
    "motion lts": "harmonics",
    "motion fog": "harmonics",
    "selfcal": "scale-deviation",
    "rate": "rate-stability",
    "gyro scale-factor": "nonlinearity",
    "gyro triad": "residuals",
    "gyro multiposition": "residuals",
    "allan": "allan-deviation",
}


@pytest.fixture(scope="module")
def drawn(kind_content: dict[str, CertificateContent]) -> dict[str, list]:
    return {
        command: draw_figures(content.measurements[0]) for command, content in kind_content.items()
    }


def test_every_command_gets_its_figures(
    drawn: dict[str, list], kind_content: dict[str, CertificateContent]
) -> None:
    for command, figures in drawn.items():
        index = kind_content[command].measurements[0].index
        if command in _NO_FIGURE:
            assert figures == []
            continue
        assert [name for name, _, _ in figures] == [f"figure-{index}-1-{_SHOWS[command]}.svg"]
        for _, caption, svg in figures:
            assert caption.endswith(".") and len(caption) > 40
            root = ET.fromstring(svg)
            assert not list(root.iter(f"{_SVG}image")), f"{command}: a raster image"
            assert not list(root.iter(f"{_SVG}text")), f"{command}: text needs a font"
            assert b"<dc:date>" not in svg


@pytest.mark.parametrize("command", ["allan", "selfcal"])
def test_two_draws_give_the_same_bytes(
    command: str, drawn: dict[str, list], kind_content: dict[str, CertificateContent]
) -> None:
    assert draw_figures(kind_content[command].measurements[0]) == drawn[command]


def test_noise_term_lines_read_their_coefficient_where_ieee_952_says() -> None:
    """σ(τ) = N/√τ reads N at τ = 1 h; K·√(τ/3) reads K at τ = 3 h; R·τ/√2 reads R at τ = √2 h;
    √3·Q/τ reads Q (in °, σ in °/h) at τ = √3 h; B's floor is B·√(2 ln 2/π) = 0.664·B."""
    terms = {
        "arw_deg_rt_h": 0.3,
        "rrw_deg_h_rt_h": 2.0,
        "rate_ramp_deg_h2": 5.0,
        "quantization_deg": 1e-4,
        "bias_instability_deg_h": 4.0,
    }
    lines = noise_term_lines(terms, np.array([3600.0, 3 * 3600.0, math.sqrt(2) * 3600.0]))
    assert lines["arw_deg_rt_h"][0] == pytest.approx(0.3, rel=1e-12)
    assert lines["rrw_deg_h_rt_h"][1] == pytest.approx(2.0, rel=1e-12)
    assert lines["rate_ramp_deg_h2"][2] == pytest.approx(5.0, rel=1e-12)
    q = noise_term_lines(terms, np.array([math.sqrt(3) * 3600.0]))["quantization_deg"]
    assert q[0] == pytest.approx(1e-4, rel=1e-12)
    assert np.all(lines["bias_instability_deg_h"] == pytest.approx(0.6643 * 4.0, rel=1e-4))


def test_angle_random_walk_line_meets_the_measured_white_noise(
    kind_content: dict[str, CertificateContent],
) -> None:
    """At the shortest τ white rate noise rules the measured Allan deviation: the ARW line drawn
    from N must lie on it (a unit slip of 60 or 3600 would put it decades off)."""
    results = kind_content["allan"].measurements[0].results
    tau = np.asarray(results["tau_s"][:3])
    measured_deg_h = np.asarray(results["adev_deg_s"][:3]) * 3600.0
    line = noise_term_lines({"arw_deg_rt_h": results["arw_deg_rt_h"]}, tau)["arw_deg_rt_h"]
    assert line == pytest.approx(measured_deg_h, rel=0.05)
