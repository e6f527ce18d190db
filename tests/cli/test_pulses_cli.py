"""`rotacal simulate pulses`, `rotacal selfcal`, `rotacal rate`: INTERFACE keys, files, bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from tests.encoder.test_selfcal_stream import _leaves

from rotacal.cli import cli
from rotacal.io import read_capture

SELFCAL_KEYS = {
    "deviation_arcsec",
    "heads",
    "pulses_per_rev",
    "deviation_pp_arcsec",
    "undetectable_harmonics_note",
}
RATE_KEYS = {"mean_rate_deg_s", "rate_deviation_rms_percent", "allan_angle_deg", "allan_relative"}


def run(*args: str):
    return CliRunner().invoke(cli, list(args), prog_name="rotacal")


def one_line_error(result, *needles):
    assert result.exit_code == 2, result.output
    err = result.stderr.strip()
    assert err.count("\n") == 0 and "Traceback" not in result.output, err
    for n in needles:
        assert n.lower() in err.lower(), err


@pytest.fixture(scope="module")
def pulses(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("pulses") / "heads.h5"
    r = run(
        "simulate",
        "pulses",
        "--heads",
        "6",
        "--pulses-per-rev",
        "3600",
        "--rate-deg-s",
        "60",
        "--revolutions",
        "3.3",
        "--rate-bias-percent",
        "0.01",
        "--out",
        str(path),
    )
    assert r.exit_code == 0, r.output
    return path


def test_selfcal_json_matches_the_truth(pulses, tmp_path):
    out = tmp_path / "sc.json"
    r = run(
        "selfcal",
        str(pulses),
        "--pulses-per-rev",
        "3600",
        "--json",
        str(out),
        "--report",
        str(tmp_path / "sc.html"),
    )
    assert r.exit_code == 0, r.output
    d = json.loads(out.read_text())
    assert SELFCAL_KEYS <= set(d)
    assert d["heads"] == 6 and d["pulses_per_rev"] == 3600 and len(d["deviation_arcsec"]) == 3600
    truth = json.loads(Path(str(pulses) + ".truth.json").read_text())
    err = np.asarray(d["deviation_arcsec"]) - np.asarray(truth["deviation_detectable_arcsec"])
    assert np.sqrt(np.mean(err**2)) < 0.02
    html = (tmp_path / "sc.html").read_text()
    assert html.count("<img") == 3 and "undetectable" in html


def test_rate_with_and_without_a_selfcal_json(pulses, tmp_path):
    sc = tmp_path / "sc.json"
    assert run("selfcal", str(pulses), "--pulses-per-rev", "3600", "--json", str(sc)).exit_code == 0
    r = run(
        "rate",
        str(pulses),
        "--pulses-per-rev",
        "3600",
        "--selfcal",
        str(sc),
        "--set-rate-deg-s",
        "60",
        "--json",
        "-",
        "--report",
        str(tmp_path / "rate.html"),
    )
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert RATE_KEYS <= set(d)
    truth = json.loads(Path(str(pulses) + ".truth.json").read_text())
    assert d["mean_rate_deg_s"] == pytest.approx(truth["mean_rate_whole_revs_deg_s"], rel=1e-9)
    assert d["compensated"] and d["deviation_shift_pulses"] == 0
    assert (tmp_path / "rate.html").read_text().count("<img") == 2
    # without --selfcal the capture self-calibrates itself: the same answer
    d2 = json.loads(run("rate", str(pulses), "--pulses-per-rev", "3600", "--json", "-").stdout)
    assert d2["rate_deviation_rms_percent"] == pytest.approx(d["rate_deviation_rms_percent"])
    text = run("rate", str(pulses), "--pulses-per-rev", "3600", "--head", "all")
    assert text.exit_code == 0 and "mean rate" in text.stdout


def test_csv_with_padded_columns(tmp_path):
    path = tmp_path / "heads.csv"
    assert (
        run(
            "simulate",
            "pulses",
            "--heads",
            "4",
            "--pulses-per-rev",
            "1200",
            "--rate-deg-s",
            "30",
            "--revolutions",
            "2.5",
            "--out",
            str(path),
        ).exit_code
        == 0
    )
    r = run("selfcal", str(path), "--pulses-per-rev", "1200", "--json", "-")
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout)["heads"] == 4


def test_bad_input_is_one_line(pulses, tmp_path):
    one_line_error(run("selfcal", str(pulses), "--pulses-per-rev", "7200"), "3600 pulses")
    no_heads = tmp_path / "x.npz"
    np.savez(no_heads, time_s=np.arange(10.0))
    one_line_error(run("selfcal", str(no_heads), "--pulses-per-rev", "10"), "x.npz", "head_0")
    gap = tmp_path / "gap.npz"
    cols = dict(read_capture(pulses, ragged=True).columns)
    cols["head_2"] = np.delete(cols["head_2"], np.arange(100, 110))
    np.savez(gap, **cols)
    one_line_error(run("selfcal", str(gap), "--pulses-per-rev", "3600"), "head_2", "missing")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    one_line_error(
        run("rate", str(pulses), "--pulses-per-rev", "3600", "--selfcal", str(bad)), "not JSON"
    )
    one_line_error(
        run("rate", str(pulses), "--pulses-per-rev", "3600", "--head", "9"), "head 9 does not exist"
    )


def test_selfcal_reads_a_large_capture_in_chunks_with_the_same_json(pulses, tmp_path, monkeypatch):
    import rotacal.cli.pulses as pulses_cli
    import rotacal.encoder.selfcal_stream as stream

    calls = []
    real = stream.self_calibrate_chunked
    monkeypatch.setattr(
        stream, "self_calibrate_chunked", lambda *a, **k: calls.append(1) or real(*a, **k)
    )
    monkeypatch.setattr(pulses_cli, "_SELFCAL_IN_MEMORY_MAX", 1000)  # this capture is "large"
    monkeypatch.setattr(pulses_cli, "_SELFCAL_CHUNK_ROWS", 1777)  # chunks across revolutions
    auto, mem = tmp_path / "auto.json", tmp_path / "mem.json"
    args = [str(pulses), "--pulses-per-rev", "3600", "--json"]
    r = run("selfcal", *args, str(auto), "--report", str(tmp_path / "sc.html"))
    assert r.exit_code == 0, r.output
    assert calls == [1] and (tmp_path / "sc.html").read_text().count("<img") == 3
    r = run("selfcal", *args, str(mem), "--in-memory")
    assert r.exit_code == 0, r.output
    assert calls == [1]
    # the provenance says how each was run (the options differ); the results must not
    a = dict(_leaves({**json.loads(mem.read_text()), "provenance": None}))
    b = dict(_leaves({**json.loads(auto.read_text()), "provenance": None}))
    assert a.keys() == b.keys()
    scale = max(abs(v) for k, v in a.items() if k.startswith("/deviation_arcsec["))
    for key, x in a.items():
        if isinstance(x, float):
            curve = key.startswith(("/deviation_arcsec[", "/harmonic_amplitudes_arcsec["))
            assert abs(b[key] - x) <= 1e-9 * (scale if curve else abs(x)), key
        else:
            assert b[key] == x, key
