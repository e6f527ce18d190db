"""A rate table's acceptance certificate: rate accuracy and stability per angle window, position
accuracy (ISO 230-2) and the identified geometric errors, judged against a plan's limits.

Truth comes from the twins: the table's true rate stability from the pulse twin's true angle
(``rotacal.sim.pulses.table_angle_deg``, the twin's model, not the analysis), so a table whose
true stability is inside the limit must pass and one outside must fail."""

from __future__ import annotations

import io
import json
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.certificate.content import CertificateContent
from rotacal.certificate.dcc import dcc_xml
from rotacal.certificate.issue import build_content
from rotacal.certificate.stated import stated_budgets
from rotacal.certificate.units import dsi_unit, printed_unit
from rotacal.cli import cli
from rotacal.errors import ConfigError
from rotacal.plan.read import read_plan
from rotacal.plan.run import run_plan
from rotacal.sim.pulses import table_angle_deg

from .conftest import plan_dict, write_plan

#: The datasheet's rate stability over 1° (%), and the twins' true rate fluctuation (%, rms): one
#: well inside it, one well outside.
LIMIT_1DEG = 0.01
STEADY, UNSTEADY = 0.002, 0.05
#: A small scale error, so that over 1° the table's own rate is what the windows see.
PULSES = "pulses --heads 2 --pulses-per-rev 3600 --revolutions 4 --harmonic 1:0.02 "
PULSES += "--graduation-noise-arcsec 0.001 --rate-fluctuation-percent"
#: The allocation's bound of every geometric error (arcsec): the twin's errors lie on both sides.
ALLOCATED_ARCSEC = 6.0
RATE_OPTIONS = {"pulses-per-rev": 3600, "set-rate-deg-s": 300, "window-deg": "1,10,360"}


def _simulate(folder: Path, line: str, out: str) -> None:
    result = CliRunner().invoke(cli, ["simulate", *line.split(), "--out", str(folder / out)])
    assert result.exit_code == 0, result.output


def _rate(name: str, capture: str, limits: dict[str, Any]) -> dict[str, Any]:
    return {
        "name": name,
        "command": "rate",
        "capture": capture,
        "options": {**RATE_OPTIONS, "no-compensation": True},
        "limits": limits,
    }


def _plan(folder: Path, measurements: list[dict[str, Any]], name: str = "plan.toml") -> Path:
    data = plan_dict([])
    data["item"] = {"kind": "rate-table", "manufacturer": "T", "model": "RT-2", "serial": "S-20"}
    data["measurement"] = measurements
    return write_plan(folder, data, name)


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("acceptance")
    _simulate(folder, f"{PULSES} {STEADY}", "steady.npz")
    _simulate(folder, f"{PULSES} {UNSTEADY}", "unsteady.npz")
    _simulate(folder, "position", "position.csv")
    _simulate(folder, "orientation", "orientation.csv")
    bounds = {
        name: ALLOCATED_ARCSEC / 60.0
        for name in json.loads((folder / "orientation.csv.truth.json").read_text())["errors_arcsec"]
    }
    (folder / "budget.json").write_text(json.dumps({"upper_bounds_arcmin": bounds}))
    return folder


@pytest.fixture(scope="module")
def content(folder: Path) -> CertificateContent:
    """The acceptance plan: two tables' rates, a position test, an identification."""
    one = {"rate_stability_percent.1": {"max": LIMIT_1DEG}}
    plan = read_plan(
        _plan(
            folder,
            [
                _rate("Steady table", "steady.npz", one),
                _rate(
                    "Unsteady table",
                    "unsteady.npz",
                    {"rate_stability_percent": {"1": {"max": LIMIT_1DEG}}},
                ),
                {
                    "name": "Position accuracy",
                    "command": "position",
                    "capture": "position.csv",
                    "limits": {"positioning_accuracy_bidirectional_arcsec": {"max": 60.0}},
                },
                {
                    "name": "Geometric errors against the allocation",
                    "command": "turntable identify",
                    "capture": "orientation.csv",
                    "options": {"budget": "budget.json"},
                    "limits": {"errors_arcsec": "allocation"},
                },
            ],
        )
    )
    with tempfile.TemporaryDirectory() as scratch:
        runs = run_plan(plan, Path(scratch))
    return build_content(plan, runs, plan.number, "0.1.0")


def _true_stability_percent(truth_file: Path, window_deg: float) -> float:
    """100·s/mean of the table's true mean rates over consecutive windows of ``window_deg``,
    from the twin's true angle (windows of equal time: the rate varies by 10⁻⁴ at most, so a
    window of W/Ω holds W to within that)."""
    truth = json.loads(truth_file.read_text())
    omega = truth["mean_rate_deg_s"]
    t0, t1 = truth["first_pulse_time_head0_s"], min(truth["record_stop_s"])
    edges = np.arange(t0, t1, window_deg / omega)
    rates = np.diff(table_angle_deg(truth, edges)) / np.diff(edges)
    return float(100.0 * rates.std(ddof=1) / rates.mean())


def test_a_table_inside_its_stability_limit_passes_one_outside_fails(
    folder: Path, content: CertificateContent
) -> None:
    steady, unsteady = content.measurements[:2]
    for m, twin in ((steady, "steady.npz"), (unsteady, "unsteady.npz")):
        truth = _true_stability_percent(folder / f"{twin}.truth.json", 1.0)
        (q,) = (q for q in m.quantities if q.key == "rate_stability_percent.1")
        assert q.unit == "%" and q.name == "rate stability over 1°"
        assert abs(float(q.value) - truth) <= float(q.U), (q.value, q.U, truth)
        (c,) = m.conformity
        assert c.key == "rate_stability_percent.1" and c.limit_max == "0.01"
        assert c.verdict == ("pass" if truth < LIMIT_1DEG else "fail"), (truth, c.statement)
    assert steady.conformity[0].verdict == "pass" and unsteady.conformity[0].verdict == "fail"


def test_the_acceptance_results_have_units_and_u_and_the_dcc_validates(
    content: CertificateContent, dcc_schema: Any
) -> None:
    keys = {m.command: {q.key: q for q in m.quantities} for m in content.measurements}
    for window in ("1", "10", "360"):
        for group in ("rate_accuracy_percent", "rate_stability_percent"):
            q = keys["rate"][f"{group}.{window}"]
            assert q.unit == "%" and q.dsi_unit == r"\percent" and float(q.U) > 0
    accuracy = keys["position"]["positioning_accuracy_bidirectional_arcsec"]
    # five runs, no reference u: two deciding positions' scatter, each ν = 4, so by
    # Welch–Satterthwaite 4 ≤ ν_eff ≤ 8 and t₉₅(8) = 2.306 ≤ k ≤ t₉₅(4) = 2.776
    assert accuracy.unit == "arcsec" and 2.306 <= float(accuracy.k) <= 2.777
    identified = keys["turntable identify"]
    assert "errors_arcsec.alpha_x2" in identified  # separable alone
    assert "errors_arcsec.eta" not in identified  # η: no value, not a result
    assert "errors_arcsec.phi_y1+eps_y" in identified  # its separable sum is
    assert identified["errors_arcsec.phi_y1+eps_y"].name == "geometric error φ_y1 + ε_y"
    assert [c.verdict for c in content.measurements[2].conformity] == ["pass"]
    errors = [str(e) for e in dcc_schema.iter_errors(io.BytesIO(dcc_xml(content)))]
    assert errors == []


def test_stated_results_take_k_as_the_command_states_it() -> None:
    """U = k·u: Student's t of N − 1 windows, the JSON's own k, a rectangular 1.65."""
    windows = {
        "rate_stability_percent": {"10": 0.01},
        "rate_stability_percent_u": {"10": 0.001},
        "window_count": {"10": 5},
    }
    (b,) = stated_budgets("rate", windows).values()
    assert b["k"] == pytest.approx(2.776, abs=1e-3) and b["U"] == pytest.approx(2.776e-3, abs=1e-6)
    identify = {
        "errors_arcsec": {"eta": None, "alpha_x2": 1.0},
        "errors_u_arcsec": {"alpha_x2": 0.1},
    }
    assert list(stated_budgets("turntable identify", {**identify, "k": 2.5})) == [
        "errors_arcsec.alpha_x2"
    ]
    assert stated_budgets("turntable identify", {**identify, "k": 2.5})["errors_arcsec.alpha_x2"][
        "U"
    ] == pytest.approx(0.25)
    res = stated_budgets("gyro resolution", {"threshold_deg_s": 0.01, "threshold_deg_s_u": 0.002})
    assert res["threshold_deg_s"]["U"] == pytest.approx(1.65 * 0.002)


@pytest.mark.parametrize(
    ("limits", "said"),
    [
        ({"rate_stability_percent.5": {"max": 0.01}}, "no window of 5°"),
        ({"rate_stability_percent": {"10.0": {"max": 0.01}}}, "write it rate_stability_percent.10"),
        ({"rate_stability_percent": {"max": 0.01}}, "name the window: rate_stability_percent.1,"),
        ({"rate_stabilty_percent.10": {"max": 0.01}}, None),  # misspelt name: after the run
    ],
)
def test_a_limit_on_a_window_not_measured_is_refused_naming_the_plan_key(
    folder: Path, limits: dict[str, Any], said: str | None
) -> None:
    path = _plan(folder, [_rate("Rate", "steady.npz", limits)], "refused.toml")
    if said is None:
        read_plan(path)  # not a window result: certify refuses it, naming the results it has
        return
    with pytest.raises(ConfigError) as e:
        read_plan(path)
    message = str(e.value)
    assert "\n" not in message and said in message
    assert message.startswith(f"{path}: measurement[1].limits.rate_stability_percent")
    assert "(line " in message


def test_certify_refuses_a_window_limit_without_window_deg_in_one_line(folder: Path) -> None:
    rate = _rate("Rate", "steady.npz", {"rate_accuracy_percent.360": {"max": 0.01}})
    del rate["options"]["window-deg"]
    path = _plan(folder, [rate], "no-windows.toml")
    result = CliRunner().invoke(cli, ["certify", str(path), "--no-record"])
    assert result.exit_code == 2
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and "options.window-deg" in lines[0], result.output
    assert "measurement[1].limits.rate_accuracy_percent.360" in lines[0]


def test_an_accelerometer_triads_units_can_be_stated() -> None:
    """gyro accelerometer: K per m/s² of the output unit, the bias in the output unit."""
    assert dsi_unit("m/s^2/(m/s²)", "m/s^2") == r"\one"  # outputs in m/s²: a pure number
    assert dsi_unit("LSB/(m/s²)", "LSB") == r"\second\tothe{2}\per\metre"
    assert dsi_unit("V/(m/s²)", "V") == r"\volt\second\tothe{2}\per\metre"
    assert printed_unit("m/s^2", "m/s^2") == "m/s²"
    assert dsi_unit("m/s^2", "m/s^2") == r"\metre\per\second\tothe{2}"


def test_identified_errors_are_judged_against_the_allocation(
    folder: Path, content: CertificateContent
) -> None:
    """errors_arcsec = "allocation": each separable sum Σaᵢχᵢ within ± Σ|aᵢ|·UBᵢ; the verdicts
    follow from the twin's true errors (none within 1 arcsec of its bound)."""
    truth = json.loads((folder / "orientation.csv.truth.json").read_text())["errors_arcsec"]
    identify = content.measurements[3]
    judged = {c.key: c for c in identify.conformity}
    combinations = identify.results["combinations"]
    assert len(judged) == len(combinations) == 5
    for combo in combinations:
        true = sum(a * truth[n] for n, a in combo["coefficients"].items())
        bound = sum(abs(a) * ALLOCATED_ARCSEC for a in combo["coefficients"].values())
        assert abs(abs(true) - bound) > 1.0
        key = "errors_arcsec." + "+".join(combo["coefficients"])
        assert judged[key].limit_max == f"{bound:g}" and judged[key].limit_min == f"{-bound:g}"
        assert judged[key].verdict == ("pass" if abs(true) < bound else "fail"), judged[key]
    assert {c.verdict for c in judged.values()} == {"pass", "fail"}


def test_an_allocation_limit_needs_the_allocation(folder: Path) -> None:
    identify = {"name": "G", "command": "turntable identify", "capture": "orientation.csv"}
    path = _plan(folder, [{**identify, "limits": {"errors_arcsec": "allocation"}}], "alloc.toml")
    with pytest.raises(
        ConfigError,
        match=r"measurement\[1\]\.limits\.errors_arcsec \(line \d+\): .*options\.config",
    ):
        read_plan(path)
    rate = _rate("Rate", "steady.npz", {"rate_stability_percent": "allocation"})
    with pytest.raises(ConfigError, match="only a turntable identify measurement"):
        read_plan(_plan(folder, [rate], "alloc-rate.toml"))


def test_motion_angle_is_a_measurement(folder: Path) -> None:
    """The contract's `motion angle` is a measurement a plan may name, with its method."""
    from rotacal.certificate.methods import method_of

    entry = {"name": "Angle", "command": "motion angle", "capture": "position.csv"}
    assert read_plan(_plan(folder, [entry], "angle.toml")).measurements[0].command == "motion angle"
    assert "IEEE Std 1057" in method_of("motion angle")[0]
