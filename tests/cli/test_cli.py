"""The command line: the contract of INTERFACE.md, and one clear line with exit code 2 on bad input."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.cli import cli

MOTION_KEYS = {
    "amplitude_deg",
    "frequency_hz",
    "angular_acceleration_amplitude_deg_s2",
    "thd_percent",
    "harmonic_amplitudes_deg",
    "reversal_times_s",
    "periods_used",
}
SET_KEYS = {
    "amplitude_error_percent",
    "frequency_error_percent",
    "angular_acceleration_error_percent",
    "position_error_max_deg",
    "position_error_rms_deg",
}


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


def assert_one_line_error(result, *needles: str):
    assert result.exit_code == 2, result.output
    err = result.stderr.strip()
    assert err.count("\n") == 0, err
    assert "Traceback" not in result.output
    for n in needles:
        assert n.lower() in err.lower(), err


@pytest.fixture(scope="module")
def encoder_capture(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("cli") / "run.npz"
    r = run(
        "simulate",
        "encoder",
        "--amplitude-deg",
        "0.5",
        "--frequency-hz",
        "2",
        "--harmonic",
        "2:0.03",
        "--out",
        str(path),
    )
    assert r.exit_code == 0, r.output
    return path


def test_simulate_writes_capture_and_truth(encoder_capture):
    truth = json.loads(Path(str(encoder_capture) + ".truth.json").read_text())
    assert truth["thd_percent"] == pytest.approx(3.0, rel=1e-6)
    with np.load(encoder_capture) as z:
        assert {"time_s", "a", "b"} <= set(z.files)


def test_motion_encoder_json_has_the_interface_keys_and_matches_truth(
    encoder_capture, tmp_path, unrendered_figures
):
    # one-pixel figures: this test never looks at them (tests/report draws and looks at them)
    out = tmp_path / "r.json"
    rep = tmp_path / "r.html"
    r = run(
        "motion",
        "encoder",
        str(encoder_capture),
        "--lines",
        "36000",
        "--set-amplitude-deg",
        "0.5",
        "--set-frequency-hz",
        "2",
        "--json",
        str(out),
        "--report",
        str(rep),
    )
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    assert MOTION_KEYS | SET_KEYS <= set(d)
    assert "snr_db" not in d
    truth = json.loads(Path(str(encoder_capture) + ".truth.json").read_text())
    assert d["thd_percent"] == pytest.approx(truth["thd_percent"], abs=0.02)
    assert len(d["harmonic_amplitudes_deg"]) == 10
    html = rep.read_text()
    assert html.count("data:image/png;base64,") >= 5 and "<script src" not in html
    assert "Diagnostics, not results" in html and "Feng et al. (2023)" in html


def test_motion_json_to_stdout(encoder_capture):
    r = run(
        "motion",
        "encoder",
        str(encoder_capture),
        "--lines",
        "36000",
        "--json",
        "-",
        "--harmonics",
        "4",
    )
    assert r.exit_code == 0, r.stderr
    assert len(json.loads(r.stdout)["harmonic_amplitudes_deg"]) == 4


def test_fog_and_lts_through_the_cli(tmp_path):
    fog, lts = tmp_path / "fog.csv", tmp_path / "lts.h5"
    assert run("simulate", "fog", "--snr-db", "15", "--out", str(fog)).exit_code == 0
    assert (
        run(
            "simulate", "lts", "--amplitude-deg", "0.025", "--frequency-hz", "10", "--out", str(lts)
        ).exit_code
        == 0
    )
    r = run("motion", "fog", str(fog), "--json", "-")
    assert r.exit_code == 0, r.stderr
    assert "snr_db" in json.loads(r.stdout)
    r = run("motion", "lts", str(lts), "--radius-mm", "100", "--json", "-")
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["amplitude_deg"] == pytest.approx(0.025, rel=1e-3)


def test_column_mapping(tmp_path):
    path = tmp_path / "daq.csv"
    t = np.arange(0, 3.0, 1e-3)
    rate = 2 * np.pi * 2 * 0.5 * np.cos(2 * np.pi * 2 * t)
    np.savetxt(path, np.column_stack([t, rate]), delimiter=",", header="t,gyro_z", comments="")
    r = run(
        "motion",
        "fog",
        str(path),
        "--column",
        "t=time_s",
        "--column",
        "gyro_z=rate_deg_s",
        "--json",
        "-",
    )
    assert r.exit_code == 0, r.stderr
    assert json.loads(r.stdout)["amplitude_deg"] == pytest.approx(0.5, rel=1e-6)


# ---------------------------------------------------------------------------- bad input, one line, exit 2
def _csv(path: Path, header: str, rows: np.ndarray) -> Path:
    np.savetxt(path, rows, delimiter=",", header=header, comments="")
    return path


def _good_rows(n_periods: float = 4.0) -> np.ndarray:
    t = np.arange(0, n_periods / 2.0, 2e-5)
    phi = 2 * np.pi * 36000 * 0.5 * np.sin(2 * np.pi * 2.0 * t) / 360
    return np.column_stack([t, np.cos(phi), np.sin(phi)])


def test_missing_column_is_named(tmp_path):
    p = _csv(tmp_path / "c.csv", "time_s,a,bb", _good_rows()[:5000])
    assert_one_line_error(run("motion", "encoder", str(p), "--lines", "36000"), "'b'", "--column")


def test_nan_is_named(tmp_path):
    rows = _good_rows()
    rows[1234, 1] = np.nan
    p = tmp_path / "c.npz"
    np.savez(p, time_s=rows[:, 0], a=rows[:, 1], b=rows[:, 2])
    assert_one_line_error(run("motion", "encoder", str(p), "--lines", "36000"), "a")


def test_time_not_increasing(tmp_path):
    rows = _good_rows()
    rows[500:510, 0] = rows[500, 0]
    p = tmp_path / "c.npz"
    np.savez(p, time_s=rows[:, 0], a=rows[:, 1], b=rows[:, 2])
    assert_one_line_error(run("motion", "encoder", str(p), "--lines", "36000"), "time_s")


def test_less_than_one_period(tmp_path):
    rows = _good_rows(0.7)
    p = tmp_path / "c.npz"
    np.savez(p, time_s=rows[:, 0], a=rows[:, 1], b=rows[:, 2])
    assert_one_line_error(run("motion", "encoder", str(p), "--lines", "36000"), "period")


def test_clipped_signals(tmp_path):
    rows = _good_rows()
    rows[:, 1:] = np.clip(1.3 * rows[:, 1:], -1.0, 1.0)
    p = tmp_path / "c.npz"
    np.savez(p, time_s=rows[:, 0], a=rows[:, 1], b=rows[:, 2])
    assert_one_line_error(run("motion", "encoder", str(p), "--lines", "36000"), "clip")


def test_non_quadrature_signals(tmp_path):
    rows = _good_rows()
    rows[:, 2] = rows[:, 1] * 0.9 + 0.001 * np.sin(np.arange(rows.shape[0]))
    p = tmp_path / "c.npz"
    np.savez(p, time_s=rows[:, 0], a=rows[:, 1], b=rows[:, 2])
    assert_one_line_error(run("motion", "encoder", str(p), "--lines", "36000"), "quadrature")


def test_file_that_is_not_what_its_extension_says(tmp_path):
    p = _csv(tmp_path / "c.npz", "time_s,a,b", _good_rows()[:100])
    assert_one_line_error(run("motion", "encoder", str(p), "--lines", "36000"), "c.npz")


def test_missing_file(tmp_path):
    assert_one_line_error(run("motion", "fog", str(tmp_path / "nope.csv")), "nope.csv")


def test_bad_option_value(encoder_capture):
    assert_one_line_error(run("motion", "encoder", str(encoder_capture), "--lines", "0"), "--lines")


def test_simulate_refuses_to_overwrite(encoder_capture):
    before = encoder_capture.read_bytes()
    r = run("simulate", "encoder", "--out", str(encoder_capture))
    assert_one_line_error(r, "exist")
    assert encoder_capture.read_bytes() == before


def test_report_refuses_to_overwrite_the_input(encoder_capture):
    before = encoder_capture.read_bytes()
    r = run(
        "motion",
        "encoder",
        str(encoder_capture),
        "--lines",
        "36000",
        "--report",
        str(encoder_capture),
    )
    assert_one_line_error(r, "overwrite")
    assert encoder_capture.read_bytes() == before


def test_console_script_runs_as_a_process(encoder_capture):
    """The installed entry point, end to end, in a real process (no traceback on a bad option)."""
    exe = Path(sys.executable).with_name("rotacal")
    cmd = [str(exe)] if exe.exists() else [sys.executable, "-m", "rotacal"]
    p = subprocess.run(
        [*cmd, "motion", "encoder", str(encoder_capture)], capture_output=True, text=True
    )
    assert p.returncode == 2
    assert "--lines" in p.stderr and "Traceback" not in p.stderr


def test_existing_outputs_are_not_replaced_without_overwrite(encoder_capture, tmp_path):
    out = tmp_path / "r.json"
    out.write_text("keep me")
    args = ["motion", "encoder", str(encoder_capture), "--lines", "36000", "--json", str(out)]
    assert_one_line_error(run(*args), "exists", "--overwrite")
    assert out.read_text() == "keep me"
    assert run(*args, "--overwrite").exit_code == 0
    assert "thd_percent" in out.read_text()


def test_json_and_report_cannot_share_a_file(encoder_capture, tmp_path):
    same = tmp_path / "x.html"
    r = run(
        "motion",
        "encoder",
        str(encoder_capture),
        "--lines",
        "36000",
        "--json",
        str(same),
        "--report",
        str(same),
    )
    assert_one_line_error(r, "same file")
    assert_one_line_error(
        run("motion", "encoder", str(encoder_capture), "--lines", "36000", "--report", "-"),
        "--report",
    )


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["lts", "--snr-db", "10"], "--snr-db"),
        (["fog", "--snr-db", "10", "--noise", "0.1"], "not both"),
        (["fog", "--harmonic", "3:0.1", "--harmonic", "3:0.2"], "twice"),
        (["lts", "--bias-deg-s", "1"], "no such option '--bias-deg-s'"),
        (["fog", "--adc-bits", "12"], "rotacal simulate fog --help"),
        (["pulses", "--amplitude-deg", "1"], "no such option"),
        (["fog", "--harmonic", "3000:0.1"], "nyquist"),
    ],
)
def test_simulate_refuses_options_it_would_ignore(tmp_path, args, needle):
    r = run("simulate", args[0], "--out", str(tmp_path / "x.npz"), *args[1:])
    assert_one_line_error(r, needle)


def test_warnings_reach_the_user_as_one_line(tmp_path):
    """A capture whose phase skips subintervals: a one-line warning, and a correct result."""
    t = np.arange(0, 3.0, 1 / 6000)
    phi = 2 * np.pi * 36000 * 0.5 * np.sin(2 * np.pi * 2.0 * t) / 360
    p = tmp_path / "slow.npz"
    np.savez(p, time_s=t, a=np.cos(phi), b=np.sin(phi))
    r = run("motion", "encoder", str(p), "--lines", "36000", "--json", "-")
    assert r.exit_code == 0, r.stderr
    warn = [ln for ln in r.stderr.splitlines() if ln]
    assert warn and all(ln.startswith("rotacal: warning:") for ln in warn)
    assert json.loads(r.stdout)["amplitude_deg"] == pytest.approx(0.5, rel=2e-4)


def test_chunked_path_gives_the_in_memory_answer(encoder_capture):
    args = ["motion", "encoder", str(encoder_capture), "--lines", "36000", "--json", "-"]
    whole = json.loads(run(*args, "--in-memory").stdout)
    streamed = run(*args, "--chunked")
    assert streamed.exit_code == 0, streamed.stderr
    chunked = json.loads(streamed.stdout)
    assert chunked["reversal_times_s"] == whole["reversal_times_s"]
    assert chunked["thd_percent"] == pytest.approx(whole["thd_percent"], rel=1e-9)


def test_correction_from_another_capture_serves_a_motion_shorter_than_a_signal_period(tmp_path):
    """0.002° with 36 000 lines is 144° of the signal period: too short an arc for Heydemann."""
    small, big = tmp_path / "small.npz", tmp_path / "big.npz"
    errors = ["--offset-a", "0.03", "--gain-ratio", "0.97", "--phase-error-deg", "1.5"]
    assert (
        run(
            "simulate",
            "encoder",
            "--amplitude-deg",
            "0.002",
            "--frequency-hz",
            "5",
            "--harmonic",
            "3:0.02",
            *errors,
            "--out",
            str(small),
        ).exit_code
        == 0
    )
    assert (
        run(
            "simulate",
            "encoder",
            "--amplitude-deg",
            "0.05",
            "--frequency-hz",
            "1",
            *errors,
            "--out",
            str(big),
        ).exit_code
        == 0
    )
    truth = json.loads(Path(str(small) + ".truth.json").read_text())
    alone = run("motion", "encoder", str(small), "--lines", "36000", "--json", "-")
    assert alone.exit_code == 0 and "partial period" in alone.stderr
    assert alone.stderr.startswith("rotacal: warning:") and alone.stderr.count("\n") == 1
    for mode in ("--in-memory", "--chunked"):
        r = run(
            "motion",
            "encoder",
            str(small),
            "--lines",
            "36000",
            "--correction-from",
            str(big),
            "--json",
            "-",
            mode,
        )
        assert r.exit_code == 0, r.stderr
        d = json.loads(r.stdout)
        assert d["amplitude_deg"] == pytest.approx(truth["amplitude_deg"], rel=2e-4)
        assert d["thd_percent"] == pytest.approx(truth["thd_percent"], abs=0.02)
    # the reference must itself cover whole signal periods
    assert_one_line_error(
        run("motion", "encoder", str(big), "--lines", "36000", "--correction-from", str(small)),
        "--correction-from",
    )
