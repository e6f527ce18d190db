"""The publications rotacal's methods come from, cited as a reader expects: author, year and title.

Reports, certificates and the documentation cite a method by :func:`cite` ("Feng et al. (2023)")
and list the full entries (:meth:`Reference.full`) at the end; never by a file name of ours. Where
our copy of a paper does not give its authors, the venue stands in their place, and the full entry
says so.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable

__all__ = ["REFERENCES", "Reference", "cite", "reference_list"]


@dataclasses.dataclass(frozen=True)
class Reference:
    """One publication.

    Attributes
    ----------
    key : str
        The short key rotacal's code uses (``"feng2023"``).
    authors : str
        Authors as printed ("Feng R., Yan J., …"); empty when our copy does not give them.
    short_authors : str
        How the citation names them ("Feng et al."); the venue or body when there are none.
    year : str
        Year of publication ("" when our copy does not give it).
    title : str
        Title.
    venue : str
        Journal, proceedings or publisher, with volume and pages.
    doi : str
        DOI, where there is one.
    """

    key: str
    authors: str
    short_authors: str
    year: str
    title: str
    venue: str
    doi: str = ""

    def short(self) -> str:
        """The citation in running text: ``Feng et al. (2023)``."""
        return f"{self.short_authors} ({self.year})" if self.year else self.short_authors

    def full(self) -> str:
        """The entry of a references list: authors (year). Title. Venue. doi."""
        doi = f" doi:{self.doi}" if self.doi else ""
        year = f" ({self.year})" if self.year else ""
        if not self.authors and self.short_authors[:1].islower():
            # cited by a description ("the GyroWheel study"), not a name: the entry starts with
            # the work's title
            return f"{self.title}. {self.venue}.{doi}"
        who = self.authors or self.short_authors
        return f"{who}{year}. {self.title}. {self.venue}.{doi}"


def _r(
    key: str, authors: str, short: str, year: str, title: str, venue: str, doi: str = ""
) -> Reference:
    return Reference(key, authors, short, year, title, venue, doi)


#: Every publication a report or a docstring of rotacal cites, by key.
REFERENCES: dict[str, Reference] = {
    r.key: r
    for r in (
        _r(
            "feng2023",
            "Feng R., Yan J., Wu Y., Yu N., Yin X.",
            "Feng et al.",
            "2023",
            "Methods for comprehensive calibration of a low-frequency angular acceleration "
            "rotary table",
            "Sensors 23(10), 4876",
            "10.3390/s23104876",
        ),
        _r(
            "gyrowheel",
            "",
            "the GyroWheel study",
            "",
            "Error analysis for GyroWheel calibration tests and error allocation of the test "
            "turntable (authors and year not given in our copy)",
            "International Journal of Aerospace Engineering (Hindawi), article 6524782",
        ),
        _r(
            "robot2023",
            "",
            "IEEE A&E Systems Magazine",
            "2023",
            "Calibration method of MEMS gyroscopes using a robot manipulator (authors not given "
            "in our copy)",
            "IEEE Aerospace and Electronic Systems Magazine, March 2023, pp. 20–27",
        ),
        _r(
            "kokuyama2015",
            "Kokuyama W., Watanabe T., Nozato H., Ota A.",
            "Kokuyama et al.",
            "2015",
            "Development of angular velocity calibration facility using self-calibratable rotary "
            "encoder",
            "Proceedings of the XXI IMEKO World Congress, Prague",
        ),
        _r(
            "ieee1057",
            "",
            "IEEE Std 1057",
            "2017",
            "IEEE standard for digitizing waveform recorders",
            "IEEE Std 1057-2017, §4.1.4 (sine-wave fitting)",
        ),
        _r(
            "ieee952",
            "",
            "IEEE Std 952",
            "2020",
            "IEEE standard specification format guide and test procedure for single-axis "
            "interferometric fiber optic gyros",
            "IEEE Std 952-2020, Annex C (Allan variance)",
        ),
        _r(
            "ieee1431",
            "",
            "IEEE Std 1431",
            "2004",
            "IEEE standard specification format guide and test procedure for Coriolis vibratory "
            "gyros",
            "IEEE Std 1431-2004",
        ),
        _r(
            "gum",
            "",
            "JCGM 100",
            "2008",
            "Evaluation of measurement data — Guide to the expression of uncertainty in "
            "measurement (GUM)",
            "Joint Committee for Guides in Metrology, JCGM 100:2008",
        ),
        _r(
            "gum_s1",
            "",
            "JCGM 101",
            "2008",
            "Evaluation of measurement data — Supplement 1 to the GUM: propagation of "
            "distributions using a Monte Carlo method",
            "Joint Committee for Guides in Metrology, JCGM 101:2008",
        ),
        _r(
            "ilac_p14",
            "",
            "ILAC-P14",
            "2020",
            "ILAC policy for measurement uncertainty in calibration",
            "ILAC-P14:09/2020",
        ),
        _r(
            "ilac_g8",
            "",
            "ILAC-G8",
            "2019",
            "Guidelines on decision rules and statements of conformity",
            "ILAC-G8:09/2019",
        ),
        _r(
            "ilac_g24",
            "",
            "ILAC-G24",
            "2022",
            "Guidelines for the determination of recalibration intervals of measuring equipment",
            "ILAC-G24:2022 / OIML D 10:2022",
        ),
        _r(
            "ncsl_rp1",
            "",
            "NCSLI RP-1",
            "2010",
            "Establishment and adjustment of calibration intervals",
            "NCSL International, Recommended Practice RP-1, 4th edition",
        ),
        _r(
            "iso_ts28037",
            "",
            "ISO/TS 28037",
            "2010",
            "Determination and use of straight-line calibration functions",
            "ISO/TS 28037:2010",
        ),
        _r(
            "birge1932",
            "Birge R. T.",
            "Birge",
            "1932",
            "The calculation of errors by the method of least squares",
            "Physical Review 40(2), 207–227",
            "10.1103/PhysRev.40.207",
        ),
        _r(
            "fmvss126",
            "",
            "FMVSS 126",
            "2007",
            "Electronic stability control systems",
            "US Federal Motor Vehicle Safety Standard No. 126, 49 CFR 571.126",
        ),
        _r(
            "heydemann1981",
            "Heydemann P. L. M.",
            "Heydemann",
            "1981",
            "Determination and correction of quadrature fringe measurement errors in "
            "interferometers",
            "Applied Optics 20(19), 3382–3384",
            "10.1364/AO.20.003382",
        ),
        _r(
            "ferraris1995",
            "Ferraris F., Grimaldi U., Parvis M.",
            "Ferraris et al.",
            "1995",
            "Procedure for effortless in-field calibration of three-axis rate gyros and "
            "accelerometers",
            "Sensors and Materials 7(5), 311–330",
        ),
        _r(
            "iso230_7",
            "",
            "ISO 230-7",
            "2015",
            "Test code for machine tools — Part 7: Geometric accuracy of axes of rotation",
            "ISO 230-7:2015",
        ),
        # --- stability variances (the Allan variance's uncertainty) ---
        _r(
            "greenhall2003",
            "Greenhall C. A., Riley W. J.",
            "Greenhall and Riley",
            "2003",
            "Uncertainty of stability variances based on finite differences",
            "Proc. 35th Annual Precise Time and Time Interval (PTTI) Meeting, 267–280",
        ),
        _r(
            "riley2008",
            "Riley W. J.",
            "Riley",
            "2008",
            "Handbook of frequency stability analysis",
            "NIST Special Publication 1065, §5.2 (the Allan family of variances) and §5.3 (edf)",
        ),
        _r(
            "clopper1934",
            "Clopper C. J., Pearson E. S.",
            "Clopper and Pearson",
            "1934",
            "The use of confidence or fiducial limits illustrated in the case of the binomial",
            "Biometrika 26(4), 404–413",
            "10.1093/biomet/26.4.404",
        ),
        _r(
            "david2003",
            "David H. A., Nagaraja H. N.",
            "David and Nagaraja",
            "2003",
            "Order Statistics, 3rd ed. (§7.1, distribution-free confidence intervals for quantiles)",
            "Wiley, Hoboken",
            "10.1002/0471722162",
        ),
        _r(
            "ieee528",
            "",
            "IEEE Std 528",
            "2001",
            "IEEE standard for inertial sensor terminology",
            "IEEE Std 528-2001",
        ),
        _r(
            "iso230_2",
            "",
            "ISO 230-2",
            "2014",
            "Test code for machine tools — Part 2: Determination of accuracy and repeatability of "
            "positioning of numerically controlled axes",
            "International Organization for Standardization, ISO 230-2:2014",
        ),
        _r(
            "evans1996",
            "Evans C. J., Hocken R. J., Estler W. T.",
            "Evans et al.",
            "1996",
            "Self-calibration: reversal, redundancy, error separation, and 'absolute testing'",
            "CIRP Annals 45(2), 617–634",
        ),
    )
}


def cite(key: str) -> str:
    """The in-text citation of a reference key: ``cite("feng2023")`` → ``Feng et al. (2023)``."""
    return REFERENCES[key].short()


def reference_list(keys: Iterable[str]) -> list[Reference]:
    """The references of ``keys`` (each once, in order of first citation), for a references list."""
    seen: dict[str, Reference] = {}
    for key in keys:
        if key not in seen:
            seen[key] = REFERENCES[key]
    return list(seen.values())
