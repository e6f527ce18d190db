"""A log of rotation runs (rotacal.gyro.triad_log, seed 003): runs split, whole revolutions
averaged, K and b from the run means against the twin's truth; the remainder's bias against its
closed form; the refusal of a run under one revolution; `gyro triad --runs`."""

from __future__ import annotations

import functools
import json

import numpy as np
import pytest
from tests.cli.test_gyro_cli import one_line_error, run, simulated

from rotacal.errors import CaptureError
from rotacal.gyro.triad_log import calibrate_triad_log, split_runs
from rotacal.sim import simulate_gyro_triad_log

_W = ("wx_deg_s", "wy_deg_s", "wz_deg_s")
_U = ("ux", "uy", "uz")
_FS = 20.0


@functools.cache
def _twin(run_s=75.0):
    # 75 s runs: 1¼ revolutions at 6 °/s, 3¾ at 18 °/s, … — every run leaves a remainder
    cap = simulate_gyro_triad_log(run_s=run_s, fs_hz=_FS, seed=11)
    c = cap.columns
    return (
        c["time_s"],
        np.column_stack([c[k] for k in _W]),
        np.column_stack([c[k] for k in _U]),
        cap.truth,
    )


def test_whole_revolutions_recover_the_truth():
    t, w, u, truth = _twin()
    r = calibrate_triad_log(t, w, u)
    k, b = np.array(truth["scale_misalignment"]), np.array(truth["bias"])
    assert np.all(np.abs(r.scale_misalignment - k) <= 4 * r.scale_misalignment_u)
    assert np.all(np.abs(r.bias - b) <= 4 * r.bias_u)
    assert len(r.runs) == len(truth["runs"]) == 30 and r.outliers_rejected == 0
    for got, true in zip(r.runs, truth["runs"], strict=True):
        assert got["start_s"] == true["start"] / _FS and got["rate_deg_s"] == true["rate_deg_s"]
        revs = int(true["angle_deg"] // 360)
        assert got["revolutions"] == revs
        assert got["samples_used"] == round(revs * 360 / max(map(abs, true["rate_deg_s"])) * _FS)


def test_the_remainder_biases_a_partial_average_as_its_closed_form_says():
    """Run mean − (K·ω + b) from the truth: over whole revolutions noise only; over the whole
    run G·ḡ, ḡ the mean of gravity turning through Θ from φ: ([sin(φ+Θ) − sin φ]/Θ,
    [cos φ − cos(φ+Θ)]/Θ) across the rotation axis (the twin's g_s = cos θ·e₁ + sin θ·e₂)."""
    t, w, u, truth = _twin()
    k, b, g = (np.array(truth[x]) for x in ("scale_misalignment", "bias", "g_sensitivity"))
    noise = truth["sensor"]["noise_std"]
    largest = 0.0
    for whole in (True, False):
        r = calibrate_triad_log(t, w, u, whole_revolutions=whole)
        for got, true in zip(r.runs, truth["runs"], strict=True):
            rate = np.array(true["rate_deg_s"])
            left = np.array(got["output_mean"]) - (k @ rate + b)
            se = noise / np.sqrt(got["samples_used"] if whole else got["samples"])
            if whole:
                assert np.all(np.abs(left) <= 5 * se), got
                continue
            axis = int(np.flatnonzero(rate)[0])
            phi, big = np.deg2rad(true["phase_deg"]), np.deg2rad(true["angle_deg"])
            gbar = np.zeros(3)
            gbar[(axis + 1) % 3] = (np.sin(phi + big) - np.sin(phi)) / big
            gbar[(axis + 2) % 3] = (np.cos(phi) - np.cos(phi + big)) / big
            expected = g @ gbar
            largest = max(largest, float(np.max(np.abs(expected)) / se))
            # the closed form is the integral; the samples step 4.5° at 90 °/s: 5 % of the term
            assert np.all(np.abs(left - expected) <= 5 * se + 0.05 * np.abs(expected)), got
    assert largest > 10  # the bias is there to be seen: the test above can fail


def test_a_run_under_one_revolution_is_refused():
    t, w, _, _ = _twin(run_s=50.0)  # 6 °/s for 50 s: 300°
    with pytest.raises(CaptureError, match=r"turns 300° .* less than one revolution"):
        split_runs(t, w)
    with pytest.raises(CaptureError, match="less than one revolution"):
        calibrate_triad_log(*_twin()[:3], settle_s=20.0)  # 75 s less 20: 330° at 6 °/s


def test_cli_runs(tmp_path):
    path, truth = simulated(tmp_path, "gyro-triad-log", "--fs-hz", "20", "--run-s", "61")
    r = run("gyro", "triad", str(path), "--runs", "--json", "-")
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout)
    assert len(d["runs"]) == 30 and d["averaging"] == "whole revolutions"
    k = np.array(truth["scale_misalignment"])
    assert np.all(
        np.abs(np.array(d["scale_misalignment"]) - k) <= 4 * np.array(d["scale_misalignment_u"])
    )
    one_line_error(run("gyro", "triad", str(path), "--settle-s", "1"), "--runs")
    one_line_error(
        run("gyro", "triad", str(path), "--runs", "--settle-s", "2"), "less than one revolution"
    )
