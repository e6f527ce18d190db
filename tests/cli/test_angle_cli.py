"""`motion angle`, `rate` on readings and `simulate angle` end to end (in process), and refusals."""

from __future__ import annotations

import json

import numpy as np
from tests.cli.test_gyro_cli import one_line_error, run, simulated


def test_motion_angle_on_a_wrapping_counter(tmp_path):
    path, truth = simulated(tmp_path, "angle", "--harmonic", "3:0.01", "--noise-deg", "0.002")
    r = run(
        "motion", "angle", str(path), "--counts-per-rev", "144000", "--set-amplitude-deg", "0.5",
        "--set-frequency-hz", "2", "--json", "-",
    )  # fmt: skip
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert truth["sensor"]["wraps"] > 0 and d["warnings"] == []
    assert abs(d["amplitude_deg"] - truth["amplitude_deg"]) <= d["amplitude_deg_U"]
    lo, hi = d["thd_percent_interval"]
    assert lo <= truth["thd_percent"] <= hi
    assert d["provenance"]["command"] == "motion angle"


def test_motion_angle_on_an_angle_readout_and_rate_on_counts(tmp_path):
    path, truth = simulated(tmp_path, "angle", "--reading", "angle", "--resolution-deg", "0.001")
    r = run("motion", "angle", str(path), "--json", "-")
    assert r.exit_code == 0, r.output
    assert abs(json.loads(r.stdout)["amplitude_deg"] - truth["amplitude_deg"]) < 1e-3
    (tmp_path / "spin").mkdir()
    spin, _ = simulated(
        tmp_path / "spin", "angle", "--rate-deg-s", "100", "--duration-s", "4", "--counter-bits", "8",
        "--counts-per-rev", "3600", "--fs-hz", "1000", "--drop-rows", "2",
    )  # fmt: skip
    r = run("rate", str(spin), "--pulses-per-rev", "360", "--counts-per-rev", "3600", "--json", "-")
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert abs(d["mean_rate_deg_s"] - 100) < 2 * 0.1 / 4 and "2 gap(s)" in d["warnings"][0]
    assert set(d) >= {"rate_deviation_rms_percent", "allan_angle_deg", "allan_relative"}


def test_refusals_are_one_line(tmp_path):
    path, _ = simulated(tmp_path, "angle")
    one_line_error(run("motion", "angle", str(path)), "--counts-per-rev")
    one_line_error(run("rate", str(path), "--pulses-per-rev", "360"), "--counts-per-rev")
    one_line_error(
        run(
            "rate", str(path), "--pulses-per-rev", "3600", "--counts-per-rev", "1", "--workers", "2"
        ),
        "--workers is not available",
    )
    one_line_error(
        run("motion", "angle", str(path), "--counts-per-rev", "144000", "--resolution-deg", "1"),
        "--resolution-deg",
    )
    one_line_error(
        run("rate", str(path), "--pulses-per-rev", "3600", "--counts-per-rev", "144000"),
        "turns back",
    )
    t = np.arange(200) * 0.01
    bad = tmp_path / "jump.npz"
    np.savez(bad, time_s=t, count=np.where(t > 1, 120, 0) + np.arange(200) % 2)
    one_line_error(
        run("motion", "angle", str(bad), "--counts-per-rev", "360", "--counter-bits", "8"),
        "jump.npz", "sample 101", "ambiguous",
    )  # fmt: skip
    none = tmp_path / "none.npz"
    np.savez(none, time_s=t, theta=t)
    one_line_error(
        run("motion", "angle", str(none)), "none.npz", "no column 'angle_deg' or 'count'"
    )


def test_window_deg_reaches_the_windows_of_the_crossing_times(tmp_path, monkeypatch):
    """`rate --window-deg` (the rate command's option where it has it) runs the angle-window
    analysis on the marks' crossing times: the wiring, with that analysis stood in for."""
    import sys
    import types

    import rotacal.cli.pulses as pulses
    from rotacal.cli import _rate_angle

    seen, finished = {}, {}
    windows = types.ModuleType("rotacal.table.rate_windows")
    windows.rate_windows_stream = lambda chunks, **kw: (
        seen.update(times=list(chunks()), **kw) or "W"
    )
    joined = types.ModuleType("rotacal.table.rate_windows_result")
    joined.with_windows = lambda result, w: (result, w)
    monkeypatch.setitem(sys.modules, "rotacal.table.rate_windows", windows)
    monkeypatch.setitem(sys.modules, "rotacal.table.rate_windows_result", joined)
    monkeypatch.setattr(pulses, "_finish_rate", lambda result, *a: finished.update(r=result))
    t = np.arange(20_000) / 1_000
    path = tmp_path / "spin.npz"
    np.savez(path, time_s=t, angle_deg=30.0 * t)
    kw = {"capture": str(path), "columns": (), "group": None, "json_path": None}
    kw |= {"report_path": None, "overwrite": False, "pulses_per_rev": 360, "average": 10}
    kw |= {"set_rate_deg_s": 30.0, "specs": None, "head": "0", "window_deg": [1.0, 10.0]}
    own = {"counts_per_rev": None, "counter_bits": None, "signed": None, "allow_gaps": False}
    _rate_angle._rate_of_readings("angle_deg", own, kw)
    result, w = finished["r"]
    assert w == "W" and seen["windows_deg"] == [1.0, 10.0] and seen["pulses_per_rev"] == 360
    np.testing.assert_allclose(seen["times"][0], np.arange(1, 600) / 30.0, atol=1e-12)
    assert seen["timing_jitter_s"] == result.timing_jitter_s and seen["check"] is False
