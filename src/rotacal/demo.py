"""``rotacal demo``: a calibration campaign on the digital twin, analysed end to end.

It runs the five scenarios of Feng et al. (2023) Table 1 — 0.025°/10 Hz by LTS, 0.1°/5 Hz,
0.25°/3 Hz, 0.5°/2 Hz and 5°/0.5 Hz by the optical shaft encoder, each also by the FOG — and the
angular-velocity standard of Kokuyama et al. (seed 004): a 12-head, 18 000-pulse self-calibratable
encoder on a table turning at 300 °/s, self-calibrated over 10 revolutions, and the rate's
stability and s(φ); gyro calibrations (scale factor, triad, rotations, multiposition drift, noise);
and the error budget of seed 001's two-axis turntable (allocation and a 10⁶-draw Monte Carlo
check). It writes ``DIR/report.html`` (each result beside the twin's truth and the
papers' numbers) plus one JSON per analysis (each with ``warnings`` and ``provenance``).

Every file is made in memory first and written at the end, all together or none
(:func:`rotacal.io.outputs.write_outputs`): a demo that fails leaves no file, and a file of an
earlier demo (or one the user edited) is replaced only with ``overwrite``.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from rotacal import sim
from rotacal.io.outputs import Output, write_outputs
from rotacal.provenance import provenance_record
from rotacal.results import to_jsonable
from rotacal.table import (
    MotionResult,
    calibrate_encoder_motion,
    calibrate_fog_motion,
    calibrate_lts_motion,
    compare_schemes,
)

__all__ = ["demo_files", "demo_steps", "run_demo"]

_NAMES = {"encoder": "OSE", "lts": "LTS", "fog": "FOG"}


#: The files of the demo's folder besides one JSON per scenario and scheme (``_motion_file``).
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
    "report.html",
)


def _motion_file(scenario: dict[str, Any], kind: str) -> str:
    return f"motion_{scenario['name']}_{kind}.json"


def demo_files() -> list[str]:
    """The names of every file `run_demo` writes into its folder (known before it runs)."""
    motion = [
        _motion_file(sc, kind)
        for sc in sim.table1_scenarios()
        for kind in (sc["paper_sensors"][0], "fog")
    ]
    return motion + list(_FIXED_FILES)


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


def demo_steps() -> int:
    """How many progress steps `run_demo` reports (for a progress bar)."""
    return 2 * len(sim.table1_scenarios()) + 4


def _rate_standard(files: _Files) -> tuple[list[Any], dict[str, Any]]:
    """The seed-004 facility on the twin: self-calibration, rate stability, s(φ)."""
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
    table = Table(
        ["quantity", "rotacal", "twin's truth", "seed 004"],
        [
            [
                "deviation peak-to-peak",
                f"{selfcal.deviation_pp_arcsec:.3f} arcsec",
                f"{truth['deviation_detectable_pp_arcsec']:.3f} arcsec (detectable part)",
                "~6 arcsec (Figure 4)",
            ],
            ["deviation, rms error against the truth", f"{err_rms:.2g} arcsec", "0", "—"],
            [
                "repeatability, rms",
                f"{selfcal.repeatability_rms_arcsec:.2g} arcsec",
                "1 ns timing jitter",
                "~0.1 arcsec (Figure 5)",
            ],
            [
                "mean rate",
                f"{rate.mean_rate_deg_s:.6f} °/s",
                f"{truth['mean_rate_whole_revs_deg_s']:.6f} °/s",
                "300 °/s set",
            ],
            [
                "bias against the set rate",
                f"{rate.rate_bias_percent:+.4f} %",
                f"{true_bias:+.4f} %",
                "about 0.01 % (Figure 9)",
            ],
            [
                "rate fluctuation, rms (10-pulse average)",
                f"{rate.rate_deviation_rms_percent:.4f} %",
                f"{truth['rate_fluctuation_rms_percent']:.4f} % (continuous rate)",
                "below 0.01 %",
            ],
        ],
        caption="Against the twin's truth and the seed's figures",
    )
    intro = Section(
        title="Angular-velocity standard (Kokuyama et al., seed 004)",
        paragraphs=[
            "A 12-head self-calibratable encoder with 18 000 pulses per revolution (as NMIJ's SelfA) "
            "on a table turning at 300 °/s for 10 revolutions. The twin's scale has eccentricity, "
            "low-order harmonics (also orders 12 and 24, which no 12-head arrangement can see) and "
            "random graduation errors; its heads are misplaced by a few arcsec, start and stop at "
            "different times, and every pulse time has 1 ns of jitter. The table runs 0.01 % fast "
            "with 0.01 % rate fluctuation.",
        ],
        tables=[table],
    )
    summary = {
        "deviation_error_rms_arcsec": err_rms,
        "selfcal": {k: v for k, v in selfcal.to_dict().items() if k != "deviation_arcsec"},
        "rate": {
            k: rate.to_dict()[k]
            for k in ("mean_rate_deg_s", "rate_bias_percent", "rate_deviation_rms_percent")
        },
    }
    return [intro, selfcal_section(selfcal), rate_section(rate)], summary


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


def _truth_table(
    results: list[MotionResult], truth: dict[str, Any], true_reversals: list[int]
) -> Any:
    from rotacal.report.html import Table

    rows = [
        ["amplitude (°)", f"{truth['amplitude_deg']:.7g}"]
        + [f"{r.amplitude_deg:.7g}" for r in results],
        ["frequency (Hz)", f"{truth['frequency_hz']:.9g}"]
        + [f"{r.frequency_hz:.9g}" for r in results],
        ["THD (%)", f"{truth['thd_percent']:.4f}"] + [f"{r.thd_percent:.4f}" for r in results],
        ["reversing moments found / true (whole capture)", ""]
        + [
            f"{r.reversal_times_s.size} / {n}" for r, n in zip(results, true_reversals, strict=True)
        ],
    ]
    cols = ["quantity", "twin truth"] + [_NAMES[r.scheme] for r in results]
    return Table(cols, rows, caption="rotacal against the twin's truth (over the analysed periods)")


def _gyros(files: _Files) -> tuple[list[Any], dict[str, Any]]:
    """Gyro calibrations on the twin: scale factor vs FMVSS 126, a 3-axis triad, drift coefficients."""
    from rotacal.gyro import (
        calibrate_multiposition,
        calibrate_scale_factor,
        calibrate_triad_columns,
        calibrate_triad_rotations,
        gyro_noise,
    )
    from rotacal.report.gyro_scale import scale_factor_section
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
    intro = Section(
        title="Gyroscope calibrations",
        paragraphs=[
            "Three gyro tests on the twin. A single-axis analog yaw-rate sensor at 11 rates over "
            "±100 °/s (seed 004 §4), checked against FMVSS 126. A MEMS triad turned about each "
            "axis at 6…90 °/s in both directions (seed 003), with 2 % gross outliers injected: "
            f"K is {k_err:.1e} and b {b_err:.1e} °/s from the truth. The drift coefficients "
            "of a gyro's x axis from 64 turntable positions with the seed 001 Table 1 values "
            "as truth. And 8 hours of a gyro at rest (angle random walk 0.1 °/√h, bias "
            f"instability 2 °/h): rotacal reads {noise.arw_deg_rt_h:.3f} °/√h and "
            f"{noise.bias_instability_deg_h:.2f} °/h off its Allan deviation.",
        ],
    )
    sections = [
        intro,
        scale_factor_section(sf, "Scale factor and nonlinearity", truth=rates.truth),
        triad_section(triad, "3-axis calibration (2 % outliers)"),
        rotations_section(
            rot,
            "3-axis calibration from rotations through 360° (Ferraris)",
            reference={
                "label": "twin's truth",
                "scale_misalignment": rot_cap.truth["scale_misalignment"],
                "bias": rot_cap.truth["bias"],
            },
        ),
        multiposition_section(
            multi,
            "Multiposition drift coefficients (x axis)",
            truth=multi_cap.truth["drift_coefficients"],
        ),
        noise_section(noise, "Noise terms of a gyro at rest (IEEE Std 952)"),
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
    return sections, summary


def _turntable(files: _Files) -> tuple[list[Any], dict[str, Any]]:
    """Seed 001's two-axis turntable: sensitivities, allocation, 10⁶-draw Monte Carlo check."""
    from rotacal.report.turntable import turntable_section
    from rotacal.turntable import seed_table, turntable_budget

    budget = turntable_budget(seed_table(), runs=1_000_000)
    files.json("turntable_budget.json", budget.to_dict())
    summary = {
        "upper_bounds_arcmin": budget.upper_bounds_arcmin,
        "monte_carlo": budget.monte_carlo,
        "calibration": budget.calibration,
    }
    return [turntable_section(budget)], summary


def run_demo(
    out: Path, progress: Callable[[str], None] | None = None, *, overwrite: bool = False
) -> list[Path]:
    """Simulate, analyse and report the Table 1 campaign into the folder ``out``.

    Every file (:func:`demo_files`) is written at the end, all or none; an existing one is
    replaced only with ``overwrite`` (ConfigError otherwise). Returns the paths written, in order.
    """
    from rotacal.report.html import Report, Section, render_html
    from rotacal.report.motion import comparison_section, motion_figures, motion_section

    step = progress or (lambda label: None)
    out = Path(out)
    files = _Files(out)
    rows = []
    paper = []
    scenario_sections = []
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
        comparison = compare_schemes(results[0], results[1])
        label = f"{sc['amplitude_deg']:g}° / {sc['frequency_hz']:g} Hz"
        rows.append((label, comparison, truth))
        p = sc["paper_thd_percent"]
        combined = p["ose"] if p["ose"] is not None else p["lts"]
        paper.append((combined, p["fog"], combined - p["fog"]))
        summary[sc["name"]] = {
            "truth": {k: truth[k] for k in ("amplitude_deg", "frequency_hz", "thd_percent")},
            "comparison": comparison.to_dict(),
        }
        primary_section = motion_section(results[0], f"{label} — by {_NAMES[primary]}")
        primary_section.tables.insert(0, _truth_table(results, truth, true_reversals))
        primary_section.paragraphs.insert(0, sc["note"] + ".")
        fog_section = motion_section(results[1], f"{label} — by FOG", figures=False)
        fog_section.figures = [
            f for f in motion_figures(results[1]) if "position" not in f.title.lower()
        ]
        scenario_sections += [primary_section, fog_section]
    rate_sections, summary["rate_standard"] = _rate_standard(files)
    step("multi-head encoder: self-calibration and rate")
    gyro_sections, summary["gyros"] = _gyros(files)
    step("gyros: scale factor, triad, multiposition")
    turntable_sections, summary["turntable"] = _turntable(files)
    step("turntable: error allocation and Monte Carlo")
    files.json("summary.json", to_jsonable(summary))
    intro = Section(
        title="What this is",
        paragraphs=[
            "A sinusoidal-motion calibration campaign of a low-frequency angular-acceleration rotary "
            "table, run on rotacal's digital twin: the five motions of Feng et al. (2023), Sensors "
            "23:4876, Table 1, each measured by the combined scheme (optical shaft encoder, 36 000 lines, "
            "or a laser triangulation sensor for the smallest amplitude) and by a fibre-optic gyro.",
            "The twin's motion has harmonics, stagnation and creep at the reversals; its sensors have "
            "offsets, gain and phase errors, noise and quantisation. Because the twin knows the true "
            "motion, every result below can be checked against the truth. The FOG has one fixed noise "
            "density, so its SNR falls with the motion's rate — as in the paper, the 0.025°/10 Hz run "
            "has too low an SNR for the FOG's THD to be trusted.",
        ],
    )
    report = Report(
        title="rotacal demo — a calibration campaign on the digital twin",
        subtitle="Sinusoidal motion (Feng et al. 2023, Table 1), the angular-velocity standard "
        "(Kokuyama et al., seed 004), gyro calibrations and a turntable's error budget (seed 001)",
        sections=[
            intro,
            comparison_section(rows, paper=paper),
            *scenario_sections,
            *rate_sections,
            *gyro_sections,
            *turntable_sections,
        ],
        inputs={"captures": "simulated (rotacal.sim.table1_scenarios)", "output folder": str(out)},
    )
    files.outputs.append(Output(out / "report.html", render_html(report)))
    assert [Path(o.path).name for o in files.outputs] == demo_files(), "demo_files is stale"
    written = write_outputs(
        files.outputs, overwrite=overwrite, make_folders=True, hint="--overwrite"
    )
    step("report")
    return written
