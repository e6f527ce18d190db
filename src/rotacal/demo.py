"""``rotacal demo``: a calibration campaign on the digital twin, analysed end to end.

It runs the five scenarios of Feng et al. (2023) Table 1 — 0.025°/10 Hz by LTS, 0.1°/5 Hz,
0.25°/3 Hz, 0.5°/2 Hz and 5°/0.5 Hz by the optical shaft encoder, each also by the FOG — and the
angular-velocity standard of Kokuyama et al. (2015): a 12-head, 18 000-pulse self-calibratable
encoder on a table turning at 300 °/s, self-calibrated over 10 revolutions, and the rate's
stability and s(φ); gyro calibrations (scale factor, triad, rotations, multiposition drift, noise);
and the error budget of the gyrowheel paper's two-axis turntable (allocation and a 10⁶-draw Monte
Carlo check). It writes one JSON per analysis (each with ``warnings`` and ``provenance``), one
self-contained HTML report per analysis in ``DIR/reports/`` (each with its summary, figures,
details and references, results beside the twin's truth and the papers' numbers) and
``DIR/report.html``: the index that links them, each with a line saying what it holds and its
headline results.

Every file is made in memory first and written at the end, all together or none
(:func:`rotacal.io.outputs.write_outputs`): a demo that fails leaves no file, and a file of an
earlier demo (or one the user edited) is replaced only with ``overwrite``.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from rotacal import sim
from rotacal.io.outputs import Output, write_outputs
from rotacal.numbers import format_plain, format_quantity
from rotacal.provenance import provenance_record
from rotacal.references import cite
from rotacal.results import to_jsonable
from rotacal.table import (
    MotionResult,
    calibrate_encoder_motion,
    calibrate_fog_motion,
    calibrate_lts_motion,
    compare_schemes,
)

if TYPE_CHECKING:
    from rotacal.report.html import Report, ResultRow, Section, Table
    from rotacal.uncertainty.budget import UncertaintyBudget

__all__ = ["demo_files", "demo_steps", "run_demo"]

_NAMES = {"encoder": "OSE", "lts": "LTS", "fog": "FOG"}
_LONG_NAMES = {
    "encoder": "the optical shaft encoder (OSE)",
    "lts": "the laser triangulation sensor (LTS)",
    "fog": "the fibre-optic gyro (FOG)",
}

#: The JSON files of the demo's folder besides one per scenario and scheme (``_motion_file``).
_FIXED_FILES = (
    "selfcal.json",
    "rate.json",
    "gyro_scale_factor.json",
    "gyro_triad.json",
    "gyro_multiposition.json",
    "gyro_rotations.json",
    "allan.json",
    "turntable_budget.json",
    "summary.json",
)

#: The folder of the per-analysis reports, beside the index ``report.html``.
REPORTS = "reports"
#: The per-analysis reports after the five motion scenarios' (``_motion_report``), in index order.
_FIXED_REPORTS = (
    "table1_comparison.html",
    "rate_standard.html",
    "gyro_scale_factor.html",
    "gyro_triad.html",
    "gyro_rotations.html",
    "gyro_multiposition.html",
    "gyro_noise.html",
    "turntable_budget.html",
)
INDEX = "report.html"


def _motion_file(scenario: dict[str, Any], kind: str) -> str:
    return f"motion_{scenario['name']}_{kind}.json"


def _motion_report(scenario: dict[str, Any]) -> str:
    return f"{REPORTS}/motion_{scenario['name']}.html"


def _report_files() -> list[str]:
    """The reports, index last: the per-analysis ones in the order the index lists them."""
    motion = [_motion_report(sc) for sc in sim.table1_scenarios()]
    return motion + [f"{REPORTS}/{name}" for name in _FIXED_REPORTS] + [INDEX]


def demo_files() -> list[str]:
    """The names of every file `run_demo` writes into its folder (known before it runs), relative
    to the folder: the JSONs, the per-analysis reports in ``reports/``, the index ``report.html``."""
    motion = [
        _motion_file(sc, kind)
        for sc in sim.table1_scenarios()
        for kind in (sc["paper_sensors"][0], "fog")
    ]
    return motion + list(_FIXED_FILES) + _report_files()


class _Files:
    """The demo's files, made in memory and written together at the end."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.outputs: list[Output] = []
        # no wall-clock time: two demos give byte-identical JSONs
        self.provenance = provenance_record("demo", {"out": os.fspath(folder)})

    def json(self, name: str, data: dict[str, Any], indent: int | None = 2) -> None:
        """A JSON result of the demo, with ``warnings`` and ``provenance`` as every result has."""
        data = {**data, "warnings": data.get("warnings", []), "provenance": self.provenance}
        self.outputs.append(Output(self.folder / name, json.dumps(data, indent=indent) + "\n"))


class _Page:
    """One per-analysis report of the demo and its line on the index."""

    def __init__(self, name: str, report: Report, description: str, headline: list[ResultRow]):
        self.name = name
        self.report = report
        self.description = description
        self.headline = headline


def demo_steps() -> int:
    """How many progress steps `run_demo` reports (for a progress bar)."""
    return 2 * len(sim.table1_scenarios()) + 4


def _headline(
    budgets: Mapping[str, UncertaintyBudget],
    keys: Sequence[str],
    names: Mapping[str, str] | None = None,
) -> list[ResultRow]:
    """The index's rows of a result: the budgets of ``keys`` as value ± U (k, p)."""
    from rotacal.report.uncertainty import budget_results

    return budget_results({k: budgets[k] for k in keys if k in budgets}, names=names)


def _report(title: str, subtitle: str, sections: list[Section], **inputs: str) -> Report:
    """A per-analysis report of the demo: its captures are the twin's, its index one folder up."""
    from rotacal.report.html import Report

    return Report(
        title=f"rotacal demo — {title}",
        subtitle=subtitle,
        sections=sections,
        inputs={"captures": "simulated by rotacal's digital twin", **inputs},
        home=f"../{INDEX}",
    )


def _rate_standard(files: _Files) -> tuple[_Page, dict[str, Any]]:
    """The angular-velocity standard of Kokuyama et al. on the twin: self-calibration, rate
    stability, s(φ)."""
    from rotacal.report.html import Section, Table
    from rotacal.report.pulses import rate_section, selfcal_section
    from rotacal.table import calibrate_rate

    capture = sim.simulate_pulses(
        heads=12,
        pulses_per_rev=18000,
        rate_deg_s=300.0,
        revolutions=10.3,
        rate_bias_percent=0.01,
        rate_fluctuation_percent=0.01,
        jitter_s=1e-9,
        seed=2015,
    )
    heads = [capture.columns[f"head_{i}"] for i in range(12)]
    rate = calibrate_rate(heads, pulses_per_rev=18000, set_rate_deg_s=300.0)
    selfcal = rate.selfcal
    assert selfcal is not None  # several heads: calibrate_rate self-calibrates the capture
    files.json("selfcal.json", selfcal.to_dict(), indent=None)
    files.json("rate.json", rate.to_dict())
    truth = capture.truth
    err = selfcal.deviation_arcsec - np.asarray(truth["deviation_detectable_arcsec"])
    err_rms = float(np.sqrt(np.mean(err**2)))
    true_bias = 100 * (truth["mean_rate_whole_revs_deg_s"] - 300.0) / 300.0
    paper = cite("kokuyama2015")

    table = Table(
        ["quantity", "rotacal", "twin's truth", paper],
        [
            [
                "scale deviation, peak-to-peak",
                _with_u(selfcal._budgets, "deviation_pp_arcsec", selfcal.deviation_pp_arcsec),
                f"{format_plain(truth['deviation_detectable_pp_arcsec'], 'arcsec', digits=4)} "
                "(detectable part)",
                "about 6 arcsec (Figure 4)",
            ],
            [
                "scale deviation, rms error against the truth",
                format_plain(err_rms, "arcsec", digits=2),
                "0",
                "—",
            ],
            [
                "repeatability, rms",
                format_plain(selfcal.repeatability_rms_arcsec, "arcsec", digits=2),
                "1 ns timing jitter",
                "about 0.1 arcsec (Figure 5)",
            ],
            [
                "mean rate",
                _with_u(rate._budgets, "mean_rate_deg_s", rate.mean_rate_deg_s),
                format_plain(truth["mean_rate_whole_revs_deg_s"], "°/s", digits=10),
                "300 °/s set",
            ],
            [
                "rate bias against the set rate",
                _with_u(rate._budgets, "rate_bias_percent", rate.rate_bias_percent),
                format_plain(true_bias, "%", digits=3),
                "about 0.01 % (Figure 9)",
            ],
            [
                "rate fluctuation, rms (10-pulse average)",
                _with_u(
                    rate._budgets, "rate_deviation_rms_percent", rate.rate_deviation_rms_percent
                ),
                f"{format_plain(truth['rate_fluctuation_rms_percent'], '%', digits=3)} "
                "(continuous rate)",
                "below 0.01 %",
            ],
        ],
        caption=f"Against the twin's truth and {paper}'s figures",
        note="rotacal's results ± their expanded uncertainty U for p = 95 % (k in the summary).",
    )
    intro = Section(
        title="The twin's angular-velocity standard",
        paragraphs=[
            "A 12-head self-calibratable encoder with 18 000 pulses per revolution (as NMIJ's SelfA) "
            "on a table turning at 300 °/s for 10 revolutions. The twin's scale has eccentricity, "
            "low-order harmonics (also orders 12 and 24, which no 12-head arrangement can see) and "
            "random graduation errors; its heads are misplaced by a few arcsec, start and stop at "
            "different times, and every pulse time has 1 ns of jitter. The table runs 0.01 % fast "
            "with 0.01 % rate fluctuation.",
        ],
        tables=[table],
        references=["kokuyama2015"],
    )
    summary = {
        "deviation_error_rms_arcsec": err_rms,
        "selfcal": {k: v for k, v in selfcal.to_dict().items() if k != "deviation_arcsec"},
        "rate": {
            k: rate.to_dict()[k]
            for k in ("mean_rate_deg_s", "rate_bias_percent", "rate_deviation_rms_percent")
        },
    }
    page = _Page(
        "rate_standard.html",
        _report(
            "angular-velocity standard",
            f"A multi-head encoder self-calibrated at 300 °/s, the rate's stability and s(φ), "
            f"as {paper}",
            [intro, selfcal_section(selfcal), rate_section(rate)],
        ),
        "Self-calibration of a 12-head encoder's scale and the stability of a 300 °/s rate.",
        _headline(selfcal._budgets, ["deviation_pp_arcsec"])
        + _headline(rate._budgets, ["mean_rate_deg_s", "rate_deviation_rms_percent"]),
    )
    return page, summary


def _analyse(kind: str, capture: sim.SimCapture, scenario: dict[str, Any]) -> MotionResult:
    c = capture.columns
    settings = {
        "set_amplitude_deg": scenario["amplitude_deg"],
        "set_frequency_hz": scenario["frequency_hz"],
    }
    if kind == "encoder":
        return calibrate_encoder_motion(
            c["time_s"], c["a"], c["b"], lines=scenario["sensors"]["encoder"]["lines"], **settings
        )
    if kind == "lts":
        return calibrate_lts_motion(
            c["time_s"],
            c["displacement_mm"],
            radius_mm=scenario["sensors"]["lts"]["radius_mm"],
            **settings,
        )
    return calibrate_fog_motion(c["time_s"], c["rate_deg_s"], **settings)


def _with_u(
    budgets: Mapping[str, UncertaintyBudget], key: str, value: float | None, unit: str = ""
) -> str:
    """A result with its U (or interval) as a table cell, in the budget's unit unless ``unit`` is
    given; the plain value where the result has no budget. k is in the summary, p in the note."""
    from rotacal.report.wording import readable

    b = budgets.get(key)
    if b is None:
        return format_plain(value, unit, digits=7)
    return readable(format_quantity(b.value, unit or b.unit, U=b.U, p=b.p, interval=b.interval))


def _truth_table(
    results: list[MotionResult], truth: dict[str, Any], true_reversals: list[int]
) -> Table:
    from rotacal.report.html import Table

    rows = [
        ["amplitude", format_plain(truth["amplitude_deg"], "°", digits=7)]
        + [_with_u(r._budgets, "amplitude_deg", r.amplitude_deg, "°") for r in results],
        ["frequency", format_plain(truth["frequency_hz"], "Hz", digits=9)]
        + [_with_u(r._budgets, "frequency_hz", r.frequency_hz, "Hz") for r in results],
        ["THD", format_plain(truth["thd_percent"], "%", digits=4)]
        + [_with_u(r._budgets, "thd_percent", r.thd_percent, "%") for r in results],
        ["reversing moments found / true (whole capture)", ""]
        + [
            f"{r.reversal_times_s.size} / {n}" for r, n in zip(results, true_reversals, strict=True)
        ],
    ]
    cols = ["quantity", "twin's truth"] + [_NAMES[r.scheme] for r in results]
    return Table(
        cols,
        rows,
        caption="rotacal against the twin's truth (over the analysed periods)",
        note="Each measured value ± its expanded uncertainty U for p = 95 % (for the THD the "
        "95 % coverage interval for the true value): a truth outside it would be a failure of "
        "the method.",
    )


#: A triad's scale factors |K_i| (the length of row i of K), by the keys of their budgets.
_SCALE_FACTORS = {
    f"scale_factors[{i}]": f"scale factor |K{a}| of the {a} gyro" for i, a in enumerate("xyz")
}
#: The diagonal of K (a triad calibrated from rotations states no |K_i|), by the keys of its budgets.
_DIAGONAL = {
    f"scale_misalignment[{i}][{i}]": f"K{a}{a}, the {a} gyro's sensitivity along {a}"
    for i, a in enumerate("xyz")
}


def _gyros(files: _Files) -> tuple[list[_Page], dict[str, Any]]:
    """Gyro calibrations on the twin: scale factor vs FMVSS 126, a 3-axis triad, drift coefficients."""
    from rotacal.gyro import (
        calibrate_multiposition,
        calibrate_scale_factor,
        calibrate_triad_columns,
        calibrate_triad_rotations,
        gyro_noise,
    )
    from rotacal.report.gyro_scale import requirement_rows, scale_factor_section
    from rotacal.report.html import Section
    from rotacal.report.multiposition import multiposition_section
    from rotacal.report.noise import noise_section
    from rotacal.report.triad import rotations_section, triad_section

    rates = sim.simulate_gyro_rates(seed=126)
    sf = calibrate_scale_factor(
        rates.columns["rate_deg_s"],
        rates.columns["output"],
        requirement="fmvss126",
        output_unit="V",
    )
    triad_cap = sim.simulate_gyro_triad(outlier_fraction=0.02, seed=3)
    triad = calibrate_triad_columns(triad_cap.columns)
    multi_cap = sim.simulate_multiposition(axis="x", seed=1)
    multi = calibrate_multiposition(
        multi_cap.columns["phi1_deg"],
        multi_cap.columns["phi2_deg"],
        multi_cap.columns["output_deg_h"],
        axis="x",
        latitude_deg=multi_cap.truth["latitude_deg"],
    )
    rot_cap = sim.simulate_gyro_rotations(seed=4)
    rot = calibrate_triad_rotations(
        np.column_stack([rot_cap.columns[c] for c in ("ux", "uy", "uz")]),
        rot_cap.truth["sensor"]["fs_hz"],
        rot_cap.truth["rotations"],
        static=rot_cap.truth["static"],
    )
    static = sim.simulate_gyro_noise(
        duration_s=8 * 3600,
        arw_deg_rt_h=0.1,
        bias_instability_deg_h=2.0,
        bias_band_s=(0.5, 1e6),
        seed=952,
    )
    noise = gyro_noise(static.columns["rate_deg_s"], time_s=static.columns["time_s"])
    for name, result in (
        ("gyro_scale_factor", sf),
        ("gyro_triad", triad),
        ("gyro_multiposition", multi),
        ("gyro_rotations", rot),
        ("allan", noise),
    ):
        files.json(f"{name}.json", result.to_dict())
    k_err = np.abs(
        np.asarray(triad.scale_misalignment) - np.asarray(triad_cap.truth["scale_misalignment"])
    ).max()
    b_err = np.abs(np.asarray(triad.bias) - np.asarray(triad_cap.truth["bias"])).max()

    def about(text: str, references: list[str]) -> Section:
        return Section(title="What the twin did", paragraphs=[text], references=references)

    scale_intro = about(
        "A single-axis analog yaw-rate sensor turned at 11 rates over ±100 °/s, as in "
        f"{cite('kokuyama2015')} §4, its line fitted and checked against {cite('fmvss126')}.",
        ["kokuyama2015", "fmvss126"],
    )
    triad_intro = about(
        "A MEMS triad turned about each axis at 6…90 °/s in both directions, as in "
        f"{cite('robot2023')}, with 2 % gross outliers injected. The largest error of the "
        f"scale/misalignment matrix K against the twin's truth is {format_plain(k_err, digits=2)}, "
        f"of the bias {format_plain(b_err, '°/s', digits=2)}.",
        ["robot2023"],
    )
    rotations_intro = about(
        "A triad turned through 360° about each axis and left at rest between the turns; its "
        f"matrix and bias follow from the integrated rates ({cite('ferraris1995')}).",
        ["ferraris1995"],
    )
    multi_intro = about(
        "The drift coefficients of a gyro's x axis from 64 turntable positions, with the values of "
        f"{cite('gyrowheel')} Table 1 as the twin's truth.",
        ["gyrowheel"],
    )
    noise_intro = about(
        "8 hours of a gyro at rest with angle random walk 0.1 °/√h and bias instability 2 °/h; "
        f"rotacal reads {format_plain(noise.arw_deg_rt_h, '°/√h', digits=3)} and "
        f"{format_plain(noise.bias_instability_deg_h, '°/h', digits=3)} off its Allan deviation "
        f"({cite('ieee952')}).",
        ["ieee952"],
    )
    pages = [
        _Page(
            "gyro_scale_factor.html",
            _report(
                "gyro scale factor and nonlinearity",
                f"An analog yaw-rate sensor at 11 rates, checked against {cite('fmvss126')}",
                [
                    scale_intro,
                    scale_factor_section(sf, "Scale factor and nonlinearity", truth=rates.truth),
                ],
            ),
            f"The line of a yaw-rate sensor's output against the rate; {cite('fmvss126')}.",
            _headline(sf._budgets, ["scale_factor"]) + requirement_rows(sf),
        ),
        _Page(
            "gyro_triad.html",
            _report(
                "3-axis gyro calibration",
                "A MEMS triad at 6…90 °/s about each axis, with 2 % outliers",
                [triad_intro, triad_section(triad, "3-axis calibration (2 % outliers)")],
            ),
            "Scale factors, misalignments and biases of a triad from turns at set rates.",
            _headline(triad.axis_budgets, list(_SCALE_FACTORS), names=_SCALE_FACTORS),
        ),
        _Page(
            "gyro_rotations.html",
            _report(
                "3-axis gyro calibration from rotations",
                f"Turns through 360° about each axis ({cite('ferraris1995')})",
                [
                    rotations_intro,
                    rotations_section(
                        rot,
                        "3-axis calibration from rotations through 360°",
                        reference={
                            "label": "twin's truth",
                            "scale_misalignment": rot_cap.truth["scale_misalignment"],
                            "bias": rot_cap.truth["bias"],
                        },
                    ),
                ],
            ),
            "Scale factors, misalignments and biases of a triad from whole turns.",
            _headline(rot._budgets, list(_DIAGONAL), names=_DIAGONAL),
        ),
        _Page(
            "gyro_multiposition.html",
            _report(
                "multiposition drift coefficients",
                f"A gyro's x axis in 64 positions ({cite('gyrowheel')})",
                [
                    multi_intro,
                    multiposition_section(
                        multi,
                        "Multiposition drift coefficients (x axis)",
                        truth=multi_cap.truth["drift_coefficients"],
                    ),
                ],
            ),
            "The g-independent and g-sensitive drift terms of one gyro axis.",
            _headline(
                multi._budgets,
                ["drift_coefficients.DF", "drift_coefficients.Dx", "drift_coefficients.Dz"],
                names={
                    "drift_coefficients.DF": "drift independent of g (DF)",
                    "drift_coefficients.Dx": "drift along x per g (Dx)",
                    "drift_coefficients.Dz": "drift along z per g (Dz)",
                },
            ),
        ),
        _Page(
            "gyro_noise.html",
            _report(
                "gyro noise",
                f"8 hours of a gyro at rest, its Allan deviation ({cite('ieee952')})",
                [noise_intro, noise_section(noise, "Noise terms of a gyro at rest")],
            ),
            "Angle random walk and bias instability read off the Allan deviation.",
            _headline(noise._budgets, ["arw_deg_rt_h", "bias_instability_deg_h"]),
        ),
    ]
    summary = {
        "scale_factor_error_relative": sf.scale_factor / rates.truth["ls_scale_factor"] - 1,
        "triad_k_error_max": float(k_err),
        "triad_bias_error_max_deg_s": float(b_err),
        "arw_deg_rt_h": noise.arw_deg_rt_h,
        "bias_instability_deg_h": noise.bias_instability_deg_h,
        "drift_error_max_deg_h": max(
            abs(v - multi_cap.truth["drift_coefficients"][k])
            for k, v in multi.drift_coefficients.items()
        ),
    }
    return pages, summary


def _turntable(files: _Files) -> tuple[_Page, dict[str, Any]]:
    """The gyrowheel paper's two-axis turntable: sensitivities, allocation, 10⁶-draw Monte Carlo."""
    from rotacal.report.turntable import turntable_section
    from rotacal.report.turntable_results import monte_carlo_rows
    from rotacal.turntable import seed_table, turntable_budget

    budget = turntable_budget(seed_table(), runs=1_000_000)
    files.json("turntable_budget.json", budget.to_dict())
    summary = {
        "upper_bounds_arcmin": budget.upper_bounds_arcmin,
        "monte_carlo": budget.monte_carlo,
        "calibration": budget.calibration,
    }
    headline = monte_carlo_rows(budget)
    page = _Page(
        "turntable_budget.html",
        _report(
            "a two-axis turntable's error budget",
            f"The turntable of {cite('gyrowheel')}: sensitivities, allocation, Monte Carlo check",
            [turntable_section(budget)],
        ),
        "How large each geometric error of the turntable may be, checked by 10⁶ random draws.",
        headline,
    )
    return page, summary


def _scenario_page(
    sc: dict[str, Any],
    results: list[MotionResult],
    truth: dict[str, Any],
    true_reversals: list[int],
) -> tuple[_Page, Any]:
    """The report of one Table-1 scenario: its two schemes and their comparison."""
    from rotacal.report.html import Section
    from rotacal.report.motion import comparison_section, motion_figures, motion_section

    primary = results[0].scheme
    comparison = compare_schemes(results[0], results[1])
    label = f"{format_plain(sc['amplitude_deg'])}° / {format_plain(sc['frequency_hz'])} Hz"
    p = sc["paper_thd_percent"]
    combined = p["ose"] if p["ose"] is not None else p["lts"]
    paper_row = (combined, p["fog"], combined - p["fog"])
    intro = Section(
        title="What the twin did",
        paragraphs=[
            f"The {label} motion of {cite('feng2023')} Table 1 on the twin, measured at the same "
            f"time by {_LONG_NAMES[primary]} and by {_LONG_NAMES['fog']}. The twin's inputs were "
            "chosen to resemble the paper's: the harmonic content is tuned so that the true THD "
            "equals the paper's combined-scheme value; each reversal has a stagnation and a creep.",
        ],
        tables=[_truth_table(results, truth, true_reversals)],
        references=["feng2023"],
    )
    primary_section = motion_section(results[0], f"By {_LONG_NAMES[primary]}")
    fog_section = motion_section(results[1], f"By {_LONG_NAMES['fog']}", figures=False)
    # the position error is the primary scheme's figure
    fog_section.figures = motion_figures(results[1], position_error=False)
    sections = [
        intro,
        primary_section,
        fog_section,
        comparison_section([(label, comparison, truth)], paper=[paper_row]),
    ]
    page = _Page(
        _motion_report(sc).split("/", 1)[1],
        _report(
            f"sinusoidal motion {label}",
            f"By {_NAMES[primary]} and FOG on the same run ({cite('feng2023')}, Table 1)",
            sections,
        ),
        f"Amplitude, frequency and THD by {_NAMES[primary]} and by FOG on the same run.",
        _headline(
            results[0]._budgets,
            ["amplitude_deg", "thd_percent"],
            names={
                "amplitude_deg": f"amplitude by {_NAMES[primary]}",
                "thd_percent": f"THD by {_NAMES[primary]}",
            },
        )
        + _headline(results[1]._budgets, ["thd_percent"], names={"thd_percent": "THD by FOG"})
        + _headline(comparison._budgets, ["thd_difference_percent"]),
    )
    return page, (label, comparison, truth, paper_row)


def run_demo(
    out: Path, progress: Callable[[str], None] | None = None, *, overwrite: bool = False
) -> list[Path]:
    """Simulate, analyse and report the Table 1 campaign into the folder ``out``.

    Every file (:func:`demo_files`) is written at the end, all or none; an existing one is
    replaced only with ``overwrite`` (ConfigError otherwise). Returns the paths written, in order.
    """
    from rotacal.report.html import Link, Report, Section, render_html
    from rotacal.report.motion import comparison_section
    from rotacal.report.wording import paragraph

    step = progress or (lambda label: None)
    out = Path(out)
    files = _Files(out)
    rows = []
    paper = []
    pages: list[_Page] = []
    summary: dict[str, Any] = {}
    for sc in sim.table1_scenarios():
        primary = sc["paper_sensors"][0]
        results = []
        true_reversals = []
        for kind in (primary, "fog"):
            capture = sim.simulate(kind, motion=sc["motion"], **sc["sensors"][kind])
            result = _analyse(kind, capture, sc)
            results.append(result)
            t = capture.columns["time_s"]
            true_reversals.append(len(sc["motion"].truth(t[0], t[-1])["reversal_times_s"]))
            files.json(_motion_file(sc, kind), result.to_dict())
            step(f"{sc['name']} by {_NAMES[kind]}")
        truth = sc["motion"].truth(results[0].analysis_start_s, results[0].analysis_stop_s)
        page, (label, comparison, truth, paper_row) = _scenario_page(
            sc, results, truth, true_reversals
        )
        pages.append(page)
        rows.append((label, comparison, truth))
        paper.append(paper_row)
        summary[sc["name"]] = {
            "truth": {k: truth[k] for k in ("amplitude_deg", "frequency_hz", "thd_percent")},
            "comparison": comparison.to_dict(),
        }
    pages.append(
        _Page(
            "table1_comparison.html",
            _report(
                "THD by two schemes, all five motions",
                f"The layout of {cite('feng2023')} Table 1, beside the paper's values",
                [comparison_section(rows, paper=paper)],
            ),
            "The THD by the combined scheme and by the FOG for the five motions, and the paper's.",
            [],
        )
    )
    rate_page, summary["rate_standard"] = _rate_standard(files)
    pages.append(rate_page)
    step("multi-head encoder: self-calibration and rate")
    gyro_pages, summary["gyros"] = _gyros(files)
    pages += gyro_pages
    step("gyros: scale factor, triad, multiposition")
    turntable_page, summary["turntable"] = _turntable(files)
    pages.append(turntable_page)
    step("turntable: error allocation and Monte Carlo")
    files.json("summary.json", to_jsonable(summary))
    for page in pages:
        files.outputs.append(Output(out / REPORTS / page.name, render_html(page.report)))
    intro = Section(
        title="What this is",
        paragraphs=[
            "A sinusoidal-motion calibration campaign of a low-frequency angular-acceleration rotary "
            f"table, run on rotacal's digital twin: the five motions of {cite('feng2023')} Table 1, "
            "each measured by the combined scheme (optical shaft encoder, 36 000 lines, or a laser "
            "triangulation sensor for the smallest amplitude) and by a fibre-optic gyro; then the "
            f"angular-velocity standard of {cite('kokuyama2015')}, five gyro calibrations and the "
            f"error budget of the two-axis turntable of {cite('gyrowheel')}.",
            "The twin's motion has harmonics, stagnation and creep at the reversals; its sensors have "
            "offsets, gain and phase errors, noise and quantisation. Because the twin knows the true "
            "motion, every result can be checked against the truth. The FOG has one fixed noise "
            "density, so its SNR falls with the motion's rate — as in the paper, the 0.025°/10 Hz run "
            "has too low an SNR for the FOG's THD to be trusted.",
        ],
    )
    index = Report(
        title="rotacal demo — a calibration campaign on the digital twin",
        subtitle="One report per analysis; each opens with its summary of results.",
        sections=[intro],
        inputs={"captures": "simulated by rotacal's digital twin", "output folder": str(out)},
        links=[
            Link(
                title=paragraph(page.report.title.removeprefix("rotacal demo — ")),
                href=f"{REPORTS}/{page.name}",
                description=page.description,
                results=page.headline,
            )
            for page in pages
        ],
        references=["feng2023", "kokuyama2015", "gyrowheel"],
    )
    files.outputs.append(Output(out / INDEX, render_html(index)))
    written_names = [Path(o.path).relative_to(out).as_posix() for o in files.outputs]
    assert written_names == demo_files(), "demo_files is stale"
    written = write_outputs(
        files.outputs, overwrite=overwrite, make_folders=True, hint="--overwrite"
    )
    step("report")
    return written
