"""Absurd, non-finite and degenerate numeric input: a named refusal or an honest result, never a
crash and never a "perfect" number from a degenerate method (issue 12).

Two parts:
- a seeded, representative subset of the command lines of ``benchmarks/fuzz_cli.py`` (the full run
  prints counts by outcome), through the CLI in this process, classified by the same rules: exit 0
  with finite results (the twin's own results where the variant keeps its truth), or exit 2 with
  one line that names the column/option/key and the capture file;
- for each class of fault, a test against its truth: the refusal names the right column and
  sample, the API raises the same typed error, and the valid twin still gives the twin's truth.
"""

from __future__ import annotations

import importlib.util
import math
import random
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

from rotacal.cli import cli
from rotacal.encoder.selfcal import self_calibrate
from rotacal.errors import CaptureError, ConfigError
from rotacal.gyro import calibrate_multiposition, calibrate_scale_factor
from rotacal.gyro.noise import gyro_noise
from rotacal.signal import overlapping_adev
from rotacal.signal._values import (
    LARGEST,
    SMALLEST,
    check_magnitudes,
    check_not_copies,
    check_setting,
    check_time_span,
)
from rotacal.sim import (
    SineMotion,
    simulate_encoder,
    simulate_gyro_noise,
    simulate_gyro_rates,
    simulate_multiposition,
    simulate_pulses,
)
from rotacal.table import calibrate_encoder_motion, calibrate_encoder_motion_chunked
from rotacal.turntable import load_turntable

FUZZ = Path(__file__).resolve().parents[2] / "benchmarks" / "fuzz_cli.py"
#: Cases per command drawn for the suite (the benchmark runs all of them).
PER_COMMAND = 14
SEED = 12


def _fuzz_module() -> Any:
    spec = importlib.util.spec_from_file_location("rotacal_bench_fuzz_cli", FUZZ)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def fuzz(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, list[Any]]:
    module = _fuzz_module()
    folder = tmp_path_factory.mktemp("fuzz_cli")
    twins = module.make_twins(folder)
    return module, module.build_cases(folder, twins)


#: Faults the issue names: always in the subset.
_ALWAYS = (
    "column rate_deg_s: one sample 1e300",  # Allan: every deviation null
    "every head an identical copy of head_0",  # selfcal: 0.0″ peak-to-peak
    "column b an identical copy of a",  # quadrature: a == b
    "column time_s: time scaled by 1e300",  # LinAlgError in the fits
)
_COMMANDS = (
    "motion encoder",
    "motion lts",
    "motion fog",
    "selfcal",
    "rate",
    "gyro scale-factor",
    "gyro triad",
    "gyro rotations",
    "gyro multiposition",
    "allan",
    "turntable budget",
)


@pytest.mark.parametrize("command", _COMMANDS)
def test_fuzz_subset_ends_in_an_honest_result_or_one_named_line(
    fuzz: tuple[Any, list[Any]], command: str
) -> None:
    module, cases = fuzz
    mine = [c for c in cases if c.command == command]
    if command == "turntable budget":
        # a full budget takes ~10 s: the suite keeps the TOML and option faults refused at loading
        mine = [c for c in mine if c.expect == "refuse"]
    chosen = [c for c in mine if c.fault == "valid twin" or c.fault in _ALWAYS]
    rest = [c for c in mine if c not in chosen]
    chosen += random.Random(f"{SEED}:{command}").sample(rest, min(PER_COMMAND, len(rest)))
    module.attach_truth(chosen)
    failures = []
    for case in chosen:
        outcome = module.run_case(case)
        if outcome.kind not in module.PASSING:
            failures.append(f"{outcome.kind}: {case.fault}: {outcome.line}")
    assert not failures, "\n".join(failures)
    assert any(c.expect == "refuse" for c in chosen)  # the subset exercises refusals


# ------------------------------------------------------------------ the shared checks, by class
def test_magnitudes_name_the_column_the_sample_and_the_fault() -> None:
    x = np.linspace(-1.0, 1.0, 101)
    check_magnitudes("a", x)  # an ordinary signal passes
    check_magnitudes("a", np.zeros(5))  # zeros pass (constancy is checked apart)
    check_magnitudes("a", np.array([LARGEST, -LARGEST, SMALLEST]))  # the bounds themselves pass
    y = x.copy()
    y[37] = 1e300
    with pytest.raises(
        CaptureError, match=r"column 'b' holds 1e\+300 at sample 37: values near 1e300"
    ):
        check_magnitudes("b", y)
    with pytest.raises(CaptureError, match="at sample 1037"):  # a chunk's offset is counted
        check_magnitudes("b", y, offset=1000)
    y[37] = math.nan
    with pytest.raises(CaptureError, match="column 'b' has a NaN at sample 37"):
        check_magnitudes("b", y)
    with pytest.raises(CaptureError, match=r"below 1e-100 in magnitude.*largest is 1e-300"):
        check_magnitudes("b", x * 1e-300)
    with pytest.raises(CaptureError, match="below 1e-100"):  # subnormal numbers
        check_magnitudes("b", x * 1e-320)


def test_copies_and_negated_copies_are_named_distinct_columns_pass() -> None:
    rng = np.random.default_rng(1)
    a, b = rng.standard_normal(1000), rng.standard_normal(1000)
    check_not_copies({"a": a, "b": b}, "why")
    with pytest.raises(CaptureError, match="column 'b' is an identical copy of column 'a': why"):
        check_not_copies({"a": a, "b": a.copy()}, "why")
    with pytest.raises(CaptureError, match="column 'b' is the negative of column 'a'"):
        check_not_copies({"a": a, "b": -a}, "why")
    late = a.copy()
    late[-1] += 1e-12  # equal in the first 64 samples only: not a copy
    check_not_copies({"a": a, "b": late}, "why")


def test_time_span_refuses_coarse_float64_time_and_keeps_unix_time() -> None:
    # Unix time at 10 kHz: float64 resolves 1.7e9 s to 2.4e-7 s, 0.24 % of a step: accepted
    check_time_span("time_s", 1.7e9, 1.7e9 + 10.0, 1e-4)
    with pytest.raises(CaptureError, match=r"resolved only to 0.000122 s .* 24.4 % of the"):
        check_time_span("time_s", 1e12, 1e12 + 1.0, 5e-4)
    with pytest.raises(CaptureError, match="time_s' runs from 0 s to 3e\\+300 s"):
        check_time_span("time_s", 0.0, 3e300, 1e296)


def test_settings_name_the_option() -> None:
    assert check_setting("--radius-mm", 100) == 100.0
    for value, message in (
        (0.0, "must be > 0"),
        (math.nan, "finite"),
        (math.inf, "finite"),
        (1e300, "beyond what float64"),
        (1e-300, "beyond what float64"),
    ):
        with pytest.raises(ConfigError, match=f"--radius-mm.*{message}"):
            check_setting("--radius-mm", value)


# ------------------------------------------------------------------ the two cases
def test_allan_refuses_one_sample_of_1e300_and_the_twin_keeps_its_truth() -> None:
    cap = simulate_gyro_noise(duration_s=600.0, fs_hz=100.0, bias_instability_deg_h=0.0, seed=3)
    rate = cap.columns["rate_deg_s"].copy()
    clean = gyro_noise(rate, fs_hz=100.0)
    # truth: the twin's ARW 0.3 °/√h, within the result's own 95 % interval
    low, high = clean.noise_terms["arw_deg_rt_h_interval"]
    assert low <= cap.truth["arw_deg_rt_h"] <= high
    rate[12345] = 1e300
    with pytest.raises(CaptureError, match=r"column 'rate_deg_s' holds 1e\+300 at sample 12345"):
        gyro_noise(rate, fs_hz=100.0)
    with pytest.raises(CaptureError, match=r"column 'data' holds 1e\+300 at sample 12345"):
        overlapping_adev(rate, fs=100.0)


def _heads(cap: Any) -> list[np.ndarray]:
    return [cap.columns[f"head_{i}"] for i in range(cap.truth["heads"])]


def test_selfcal_refuses_heads_that_are_copies_and_the_twin_keeps_its_truth() -> None:
    cap = simulate_pulses(heads=4, pulses_per_rev=720, revolutions=2.5, seed=4)
    heads = _heads(cap)
    r = self_calibrate(heads, pulses_per_rev=720)
    truth = np.asarray(cap.truth["deviation_detectable_arcsec"])
    assert np.sqrt(np.mean((r.deviation_arcsec - truth) ** 2)) < 0.05
    assert r.deviation_pp_arcsec > 1.0  # the twin's scale is not perfect
    same = [heads[0], heads[0].copy(), heads[0].copy(), heads[0].copy()]
    with pytest.raises(CaptureError, match=r"'head_1' is a copy of head_0 .* no information"):
        self_calibrate(same, pulses_per_rev=720)
    shifted = [heads[0], heads[1], heads[0] + 0.123, heads[3]]  # one head a time-shifted copy
    with pytest.raises(CaptureError, match=r"'head_2' is a copy of head_0 .* shifted by 0.123 s"):
        self_calibrate(shifted, pulses_per_rev=720)


# ------------------------------------------------------------------ encoder: in memory and chunked
@pytest.fixture(scope="module")
def encoder_twin() -> Any:
    motion = SineMotion(amplitude_deg=0.5, frequency_hz=2.0)
    return simulate_encoder(motion, lines=3600, fs_hz=4000.0, duration_s=3.2, noise_rms=1e-3)


def _chunks(t: np.ndarray, a: np.ndarray, b: np.ndarray, size: int = 3000) -> Any:
    def source() -> Any:
        for s in range(0, t.size, size):
            yield {"time_s": t[s : s + size], "a": a[s : s + size], "b": b[s : s + size]}

    return source


def test_encoder_faults_are_named_alike_in_memory_and_chunked(encoder_twin: Any) -> None:
    c = encoder_twin.columns
    t, a, b = c["time_s"], c["a"], c["b"]
    bad_b = b.copy()
    bad_b[7777] = 1e300
    constant_a = np.full_like(a, 0.5)
    faults = (
        ((t, a, bad_b), r"column 'b' holds 1e\+300 at sample 7777"),
        ((t, a, b * 1e-300), "column 'b' holds only values below 1e-100"),
        ((t * 1e300, a, b), "column 'time_s' runs from 0 s to"),
        ((t + 1e12, a, b), "column 'time_s': time stamps near 1e\\+12 s are resolved only"),
    )
    for (tt, aa, bb), message in faults:
        with pytest.raises(CaptureError, match=message):
            calibrate_encoder_motion(tt, aa, bb, lines=3600)
        with pytest.raises(CaptureError, match=message):
            calibrate_encoder_motion_chunked(_chunks(tt, aa, bb), lines=3600)
    # constant and copied channels (on the fit's points; the chunked path fits the same points)
    with pytest.raises(CaptureError, match=r"column 'a' is constant \(all 0.5\)"):
        calibrate_encoder_motion(t, constant_a, b, lines=3600)
    with pytest.raises(CaptureError, match="column 'b' is an identical copy of column 'a'"):
        calibrate_encoder_motion(t, a, a.copy(), lines=3600)
    with pytest.raises(CaptureError, match="column 'b' is the negative of column 'a'"):
        calibrate_encoder_motion_chunked(_chunks(t, a, -a), lines=3600)


def test_encoder_truth_keeping_variants_give_the_twins_results(encoder_twin: Any) -> None:
    c = encoder_twin.columns
    t, a, b = c["time_s"], c["a"], c["b"]
    base = calibrate_encoder_motion(t, a, b, lines=3600)
    assert base.amplitude_deg == pytest.approx(encoder_twin.truth["amplitude_deg"], rel=2e-4)
    # negative time stamps (a record that starts before 0) and signals in another unit (×1e6)
    for tt, aa, bb in ((t - 1000.0, a, b), (t, a * 1e6, b * 1e6)):
        r = calibrate_encoder_motion(tt, aa, bb, lines=3600)
        assert r.amplitude_deg == pytest.approx(base.amplitude_deg, rel=1e-9)
        assert r.frequency_hz == pytest.approx(base.frequency_hz, rel=1e-9)


# ------------------------------------------------------------------ gyro calibrations
def test_scale_factor_refuses_an_output_that_copies_the_set_rate() -> None:
    cap = simulate_gyro_rates(samples_per_point=50, seed=1)
    rate, out = cap.columns["rate_deg_s"], cap.columns["output"]
    r = calibrate_scale_factor(rate, out)
    assert r.scale_factor == pytest.approx(cap.truth["ls_scale_factor"], rel=1e-4)
    with pytest.raises(CaptureError, match="'output' is an identical copy of column 'rate_deg_s'"):
        calibrate_scale_factor(rate, rate.copy())
    with pytest.raises(CaptureError, match=r"'output' holds 1e\+300 at sample 3"):
        calibrate_scale_factor(rate, np.where(np.arange(rate.size) == 3, 1e300, out))
    with pytest.raises(ConfigError, match="--full-scale-deg-s = 1e\\+300"):
        calibrate_scale_factor(rate, out, full_scale_deg_s=1e300)


def test_multiposition_refuses_constant_and_copied_columns() -> None:
    cap = simulate_multiposition(axis="x", seed=2)
    p1, p2, y = (cap.columns[k] for k in ("phi1_deg", "phi2_deg", "output_deg_h"))
    r = calibrate_multiposition(p1, p2, y, axis="x", latitude_deg=45.75)
    for name, value in cap.truth["drift_coefficients"].items():
        assert abs(r.drift_coefficients[name] - value) < 0.01
    with pytest.raises(CaptureError, match=r"'output_deg_h' is constant \(all 0\)"):
        calibrate_multiposition(p1, p2, np.zeros_like(y), axis="x", latitude_deg=45.75)
    with pytest.raises(
        CaptureError, match="'output_deg_h' is an identical copy of column 'phi2_deg'"
    ):
        calibrate_multiposition(p1, p2, p2.copy(), axis="x", latitude_deg=45.75)
    far = p1.copy()
    far[5] = 1e300
    with pytest.raises(CaptureError, match=r"'phi1_deg' holds 1e\+300 at sample 5: .* table angle"):
        calibrate_multiposition(far, p2, y, axis="x", latitude_deg=45.75)


# ------------------------------------------------------------------ turntable configuration
#: A two-axis table in the form of seed 001, Tables 2–3 (independent of the packaged example).
_TABLE = """
name = "Two-axis turntable"
units = "arcmin"
length_units = "mm"
[requirement]
psi = 1.62
theta = 1.62
gamma = 1.62
[[chain]]
axis = "y"
angle = "phi1"
rotations = { phi_y1 = "y", alpha_z1 = "z", alpha_x1 = "x" }
[[chain]]
rotations = { eps_y = "y", eps_x = "x" }
translations = { eta = "x" }
[[chain]]
axis = "z"
angle = "phi2"
rotations = { alpha_y2 = "y", phi_z2 = "z", alpha_x2 = "x" }
[errors]
phi_y1 = { lower = 0.05 }
phi_z2 = { lower = 0.05 }
alpha_x1 = { lower = 0.05 }
alpha_z1 = { lower = 0.05 }
alpha_x2 = { lower = 0.05 }
alpha_y2 = { lower = 0.05 }
eps_x = { lower = 0.05 }
eps_y = { lower = 0.05 }
eta = { lower = 0.0 }
[monte_carlo]
runs = 1_000_000
[calibration]
latitude_deg = 45.75
outer_steps = 8
inner_steps = 8
required_deg_h = 0.01
[sensitivity]
step_deg = 45
endpoint = true
"""


def test_turntable_numbers_beyond_float64s_range_are_refused_by_key() -> None:
    table = load_turntable(text=_TABLE)
    assert table.requirement is not None
    assert table.requirement["psi"] == pytest.approx(math.radians(1.62 / 60))  # 1.62′ in rad
    for old, new, key in (
        ("psi = 1.62", "psi = 1e300", r"\[requirement\] psi = 1e\+300"),
        ("phi_y1 = { lower = 0.05", "phi_y1 = { lower = 1e-300", "phi_y1 lower = 1e-300"),
        ("phi_y1 = { lower = 0.05", "phi_y1 = { lower = 0.05, weight = 1e300", "weight = 1e\\+300"),
        ("required_deg_h = 0.01", "required_deg_h = 1e-300", "required_deg_h = 1e-300"),
        ("runs = 1_000_000", "runs = 1_000_000_000_000", "runs must be an integer ≤"),
        ("step_deg = 45", "step_deg = 0.001", "grid of 1.3e\\+11 points"),
        ("outer_steps = 8", "outer_steps = 1", "outer_steps must be an integer ≥ 2"),
    ):
        assert old in _TABLE
        with pytest.raises(ConfigError, match=key):
            load_turntable(text=_TABLE.replace(old, new, 1))


# ------------------------------------------------------------------ the CLI names the file
def test_cli_prefixes_the_capture_file_to_an_array_error(tmp_path: Path) -> None:
    cap = simulate_gyro_noise(duration_s=60.0, fs_hz=100.0, seed=1)
    rate = cap.columns["rate_deg_s"].copy()
    rate[99] = -1e300
    path = tmp_path / "static.npz"
    np.savez(path, time_s=cap.columns["time_s"], rate_deg_s=rate)
    result = CliRunner().invoke(cli, ["allan", str(path)])
    assert result.exit_code == 2
    lines = result.stderr.strip().splitlines()
    assert lines == [
        "rotacal: error: static.npz: column 'rate_deg_s' holds -1e+300 at sample 99: values near "
        "1e300 are not a rate signal (their squares overflow float64 arithmetic); check the file "
        "and the column's unit."
    ]
