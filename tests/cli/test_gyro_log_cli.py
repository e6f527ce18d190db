"""`rotacal gyro scale-factor` on a continuous log: the twin end to end, the report, refusals."""

from __future__ import annotations

import json

import numpy as np
from tests.cli.test_gyro_cli import one_line_error, run, simulated


def test_twin_log_end_to_end(tmp_path):
    path, truth = simulated(tmp_path, "gyro-log", "--lag-s", "0.2")
    report = tmp_path / "sf.html"
    r = run("gyro", "scale-factor", str(path), "--json", "-", "--report", str(report))
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert len(d["plateaus"]) == len(truth["plateaus"]) and d["warnings"] == []
    for p, q in zip(d["plateaus"], truth["plateaus"], strict=True):
        assert set(p) >= {"start_s", "end_s", "rate_deg_s", "samples"}
        assert abs(p["end_s"] - q["end_s"]) <= 0.02
    assert abs(d["scale_factor"] - truth["ls_scale_factor"]) <= 3 * d["scale_factor_u"]
    assert d["provenance"]["options"]["settle-s"] is None and d["settle_source"] == "output"
    html = report.read_text()
    assert "Plateaus of the continuous log" in html and html.count("data:image/png") == 2


def test_given_settling_and_the_rate_table_path(tmp_path):
    path, _ = simulated(tmp_path, "gyro-log")
    r = run("gyro", "scale-factor", str(path), "--settle-s", "3", "--json", "-")
    d = json.loads(r.stdout)
    assert d["settle_s"] == 3.0 and d["settle_source"] == "given"
    # a rate-table capture (no time_s) has no plateaus, and refuses the log options
    rates, _ = simulated(tmp_path, "gyro-rates")
    r = run("gyro", "scale-factor", str(rates), "--json", "-")
    assert "plateaus" not in json.loads(r.stdout)
    one_line_error(run("gyro", "scale-factor", str(rates), "--settle-s", "2"), "--settle-s")


def test_bad_logs_are_one_line(tmp_path):
    t = np.arange(3000) * 0.01
    cases = {
        "flat": (t, np.full(t.size, 5.0), "one plateau rate"),
        "sine": (t, 30 * np.sin(t), "never settles"),
        "back": (t[::-1], np.repeat([1.0, 9.0], 1500), "time_s does not increase"),
    }
    for name, (time, rate, needle) in cases.items():
        path = tmp_path / f"{name}.npz"
        np.savez(path, time_s=time, rate_deg_s=rate, output=0.01 * rate + 2.0)
        one_line_error(run("gyro", "scale-factor", str(path)), needle)
