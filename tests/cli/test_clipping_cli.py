"""--allow-clipped on the command line: a clipped capture ends with one line naming the file, the
column and the share (exit 2); with the flag the analysis runs and says so on stderr, in the JSON
and in the report; an unclipped capture says nothing."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from rotacal import sim
from rotacal.cli import cli


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


def _share(text: str) -> float:
    m = re.search(r"clipped \(a saturated sensor or ADC\): ([0-9.]+) %", text)
    assert m is not None, text
    return float(m.group(1)) / 100


def _write(cap, path: Path) -> Path:
    cap.write(path)
    return path


def _refused(result, path: Path, column: str) -> float:
    assert result.exit_code == 2, result.output
    err = result.stderr.strip()
    assert err.count("\n") == 0 and "Traceback" not in result.output
    assert err.startswith(f"rotacal: error: {path.name}: column '{column}' is clipped"), err
    assert "--allow-clipped" in err
    return _share(err)


def _allowed(result, column: str, json_path: Path, report: Path) -> None:
    assert result.exit_code == 0, result.output
    warn = [ln for ln in result.stderr.splitlines() if ln.startswith("rotacal: warning:")]
    assert any(f"column '{column}' is clipped" in ln for ln in warn), result.stderr
    d = json.loads(json_path.read_text())
    assert any(f"column '{column}' is clipped" in w for w in d["warnings"])
    assert f"column &#39;{column}&#39; is clipped" in report.read_text() or (
        f"column '{column}' is clipped" in report.read_text()
    )


def test_lts_and_fog_clipped_by_the_twin(tmp_path, unrendered_figures):
    # one-pixel figures: this test never looks at them (tests/report draws and looks at them)
    amp = 0.5
    d_amp = 100.0 * math.tan(math.radians(amp))
    lts = tmp_path / "lts.csv"
    r = run("simulate", "lts", "--out", str(lts), "--range-mm", str(0.7 * d_amp))
    assert r.exit_code == 0, r.output
    truth = json.loads(Path(str(lts) + ".truth.json").read_text())
    share = truth["sensor"]["clipped_samples"] / truth["samples"]
    got = _refused(run("motion", "lts", str(lts), "--radius-mm", "100"), lts, "displacement_mm")
    assert got == pytest.approx(share, abs=0.001)
    out, rep = tmp_path / "lts.json", tmp_path / "lts.html"
    r = run(
        "motion", "lts", str(lts), "--radius-mm", "100", "--allow-clipped",
        "--json", str(out), "--report", str(rep),
    )  # fmt: skip
    _allowed(r, "displacement_mm", out, rep)
    fog = tmp_path / "fog.npz"
    r = run("simulate", "fog", "--out", str(fog), "--snr-db", "10", "--range-deg-s", "1.633")
    assert r.exit_code == 0, r.output
    _refused(run("motion", "fog", str(fog)), fog, "rate_deg_s")


@pytest.mark.parametrize("chunked", ["--in-memory", "--chunked"])
def test_encoder_at_the_rails_in_memory_and_chunked(tmp_path, chunked):
    cap = sim.simulate("encoder", adc_bits=16, amplitude_b=1.3, noise_rms=0.002, seed=2)
    path = _write(cap, tmp_path / "enc.npz")
    _refused(run("motion", "encoder", str(path), "--lines", "36000", chunked), path, "b")
    r = run("motion", "encoder", str(path), "--lines", "36000", chunked, "--allow-clipped")
    assert r.exit_code == 0, r.output
    assert "column 'b' is clipped" in r.stderr


def test_a_clipped_reference_for_the_correction_is_named(tmp_path):
    ref = _write(sim.simulate("encoder", adc_bits=16, amplitude_a=1.3, seed=3), tmp_path / "r.npz")
    cap = _write(sim.simulate("encoder", adc_bits=16, seed=4), tmp_path / "c.npz")
    r = run("motion", "encoder", str(cap), "--lines", "36000", "--correction-from", str(ref))
    assert r.exit_code == 2, r.output
    assert f"--correction-from {ref}: column 'a' is clipped" in r.stderr


def _gyro_cases(tmp_path: Path):
    rates = _write(sim.simulate_gyro_rates(saturation=(1.3, 3.7), seed=1), tmp_path / "r.csv")
    triad = _write(sim.simulate_gyro_triad(output_limit=91.0, seed=1), tmp_path / "t.npz")
    rot = _write(sim.simulate_gyro_rotations(output_limit=150.0, seed=1), tmp_path / "o.npz")
    multi = _write(sim.simulate_multiposition(output_limit_deg_h=120.0), tmp_path / "m.csv")
    noise = sim.simulate_gyro_noise(duration_s=300.0, range_deg_s=0.125, seed=1)
    allan = _write(noise, tmp_path / "n.npz")
    return [
        (("gyro", "scale-factor", str(rates)), rates, "output"),
        (("gyro", "triad", str(triad)), triad, "ux"),
        (("gyro", "rotations", str(rot), "--sections", f"{rot}.truth.json"), rot, "ux"),
        (
            ("gyro", "multiposition", str(multi), "--axis", "x", "--latitude-deg", "45.75"),
            multi,
            "output_deg_h",
        ),
        (("allan", str(allan)), allan, "rate_deg_s"),
    ]


def test_every_gyro_command_refuses_and_allows(tmp_path, unrendered_figures):
    # one-pixel figures: this test never looks at them (tests/report draws and looks at them)
    for args, path, column in _gyro_cases(tmp_path):
        _refused(run(*args), path, column)
        out, rep = tmp_path / f"{path.stem}.json", tmp_path / f"{path.stem}.html"
        r = run(*args, "--allow-clipped", "--json", str(out), "--report", str(rep))
        _allowed(r, column, out, rep)


def test_unclipped_captures_say_nothing(tmp_path):
    lts = tmp_path / "ok.csv"
    assert run("simulate", "lts", "--out", str(lts)).exit_code == 0
    r = run("motion", "lts", str(lts), "--radius-mm", "100", "--json", "-")
    assert r.exit_code == 0 and "warning" not in r.stderr
    assert json.loads(r.stdout)["warnings"] == []
    rates = _write(sim.simulate_gyro_rates(quantum=1e-2, seed=2), tmp_path / "q.csv")
    r = run("gyro", "scale-factor", str(rates), "--json", "-")
    assert r.exit_code == 0 and "warning" not in r.stderr, r.stderr


@pytest.mark.parametrize(
    "command",
    [
        ("motion", "encoder"),
        ("motion", "lts"),
        ("motion", "fog"),
        ("gyro", "scale-factor"),
        ("gyro", "triad"),
        ("gyro", "rotations"),
        ("gyro", "multiposition"),
        ("allan",),
    ],
)
def test_every_motion_gyro_and_allan_command_has_the_flag(command):
    r = run(*command, "--help")
    assert r.exit_code == 0 and "--allow-clipped" in r.output
