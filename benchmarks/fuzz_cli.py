"""Absurd, non-finite and degenerate numeric input on every analysis command: counts by outcome.

    python benchmarks/fuzz_cli.py [--only "motion encoder"] [--limit N] [--show 20]

Starts from valid twin captures (``rotacal simulate …``, small ones) and the turntable example
(``rotacal turntable example``) and derives command lines from them: columns scaled to 1e±300,
shifted by 1e300, made constant or all zero, one sample of ±1e300 / NaN / ±inf, copies of another
column (identical heads, a == b), negative, duplicated, reversed and huge time stamps, truncated
records, absurd options (--lines 0/−1/10⁹, --radius-mm 0/1e300, --harmonics 0/10⁶, --periods 0,
--pulses-per-rev 1, --fs-hz 1e300, --latitude-deg 91, --full-scale-deg-s 0, …) and turntable TOML
numbers near 1e300 or 0. Every command line runs in this process through the CLI's own entry
(click's CliRunner), so the outcome is what a user sees.

Outcomes (a case passes when it ends in the first two):
  ok          exit 0 with finite results (and, where the variant keeps the twin's truth, the
              same key results as the unmutated twin)
  refused     exit 2 with ONE line "rotacal: error: …" that names the column/option/key at fault
              (and the capture file, for faults in a capture)
  silent      exit 0 on input that makes the method degenerate (a "perfect" or meaningless number)
  wrong       exit 0 on a truth-keeping variant with results that differ from the twin's
  unnamed     exit 2, but the line names neither the column/option/key nor (for data) the file
  internal    exit 1 ("internal error") or any other exit code, or an exception escaping the CLI
  timeout     the case ran longer than --timeout seconds

The test suite (tests/cli/test_absurd_inputs.py) runs a seeded, representative subset of these
cases with the same classifier.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import random
import re
import resource
import signal
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

#: What the twins are made of: small captures so that hundreds of command lines run in minutes.
TWINS = {
    "enc": "simulate encoder --lines 3600 --fs-hz 4000 --duration-s 3.2",
    "lts": "simulate lts --fs-hz 2000 --duration-s 3.2",
    "fog": "simulate fog --fs-hz 2000 --duration-s 3.2",
    "pulses": "simulate pulses --heads 4 --pulses-per-rev 360 --revolutions 3",
    "rates": "simulate gyro-rates --samples-per-point 50",
    "triad": "simulate gyro-triad --samples-per-point 50",
    "rot": "simulate gyro-rotations",
    "noise": "simulate gyro-noise --duration-s 600 --fs-hz 100",
    "mp": "simulate multiposition",
}

PASSING = ("ok", "refused")
OUTCOMES = ("ok", "refused", "silent", "wrong", "unnamed", "internal", "timeout")


@dataclass(frozen=True)
class Command:
    """One analysis command: its twin, its fixed arguments and the results that must be finite."""

    name: str
    twin: str
    args: tuple[str, ...]
    columns: tuple[str, ...]  # the columns the command reads (others are carried along unused)
    keys: tuple[str, ...]  # JSON keys whose values must be finite numbers on exit 0
    options: tuple[tuple[str, str, str], ...] = ()  # (option, value, expect)


_MOTION_OPTIONS = (
    ("--harmonics", "0", "refuse"),
    ("--harmonics", "-1", "refuse"),
    ("--harmonics", "1", "either"),
    ("--harmonics", "1000000", "refuse"),
    ("--periods", "0", "refuse"),
    ("--periods", "-1", "refuse"),
    ("--periods", "1", "either"),
    ("--periods", "1000000", "either"),
    ("--set-amplitude-deg", "0", "refuse"),
    ("--set-amplitude-deg", "-1", "refuse"),
    ("--set-amplitude-deg", "1e300", "refuse"),
    ("--set-amplitude-deg", "1e-300", "refuse"),
    ("--set-amplitude-deg", "nan", "refuse"),
    ("--set-amplitude-deg", "inf", "refuse"),
    ("--set-frequency-hz", "0", "refuse"),
    ("--set-frequency-hz", "1e300", "refuse"),
    ("--set-frequency-hz", "1e-300", "refuse"),
    ("--set-frequency-hz", "nan", "refuse"),
    ("--set-frequency-hz", "-inf", "refuse"),
)
_MOTION_KEYS = (
    "amplitude_deg",
    "frequency_hz",
    "thd_percent",
    "angular_acceleration_amplitude_deg_s2",
)

COMMANDS = (
    Command(
        "motion encoder",
        "enc",
        ("--lines", "3600"),
        ("time_s", "a", "b"),
        _MOTION_KEYS,
        (
            ("--lines", "0", "refuse"),
            ("--lines", "-1", "refuse"),
            ("--lines", "1", "either"),
            ("--lines", "1000000000", "either"),
            ("--lines", "1e9", "refuse"),
            *_MOTION_OPTIONS,
        ),
    ),
    Command(
        "motion lts",
        "lts",
        ("--radius-mm", "100"),
        ("time_s", "displacement_mm"),
        _MOTION_KEYS,
        (
            ("--radius-mm", "0", "refuse"),
            ("--radius-mm", "-100", "refuse"),
            ("--radius-mm", "1e300", "refuse"),
            ("--radius-mm", "1e-300", "refuse"),
            ("--radius-mm", "nan", "refuse"),
            ("--radius-mm", "inf", "refuse"),
            ("--radius-mm", "0.001", "either"),
            *_MOTION_OPTIONS,
        ),
    ),
    Command("motion fog", "fog", (), ("time_s", "rate_deg_s"), _MOTION_KEYS, _MOTION_OPTIONS),
    Command(
        "selfcal",
        "pulses",
        ("--pulses-per-rev", "360"),
        ("head_0", "head_1", "head_2", "head_3"),
        ("deviation_pp_arcsec",),
        (
            ("--pulses-per-rev", "0", "refuse"),
            ("--pulses-per-rev", "1", "refuse"),
            ("--pulses-per-rev", "-360", "refuse"),
            ("--pulses-per-rev", "2", "refuse"),
            ("--pulses-per-rev", "359", "either"),
            ("--pulses-per-rev", "1000000000", "refuse"),
        ),
    ),
    Command(
        "rate",
        "pulses",
        ("--pulses-per-rev", "360"),
        ("head_0", "head_1", "head_2", "head_3"),
        ("mean_rate_deg_s", "rate_deviation_rms_percent"),
        (
            ("--pulses-per-rev", "0", "refuse"),
            ("--pulses-per-rev", "1", "refuse"),
            ("--pulses-per-rev", "1000000000", "refuse"),
            ("--average", "0", "refuse"),
            ("--average", "-1", "refuse"),
            ("--average", "1000000000", "refuse"),
            ("--set-rate-deg-s", "0", "refuse"),
            ("--set-rate-deg-s", "1e300", "refuse"),
            ("--set-rate-deg-s", "nan", "refuse"),
            ("--set-rate-deg-s", "inf", "refuse"),
            ("--head", "7", "refuse"),
            ("--head", "-1", "refuse"),
            ("--head", "all", "either"),
        ),
    ),
    Command(
        "gyro scale-factor",
        "rates",
        (),
        ("rate_deg_s", "output"),
        ("scale_factor", "bias", "nonlinearity_percent_fs"),
        (
            ("--full-scale-deg-s", "0", "refuse"),
            ("--full-scale-deg-s", "-100", "refuse"),
            ("--full-scale-deg-s", "1e300", "refuse"),
            ("--full-scale-deg-s", "1e-300", "refuse"),
            ("--full-scale-deg-s", "nan", "refuse"),
            ("--full-scale-deg-s", "inf", "refuse"),
            ("--requirement", "fmvss126", "either"),
            ("--requirement", "nonsense", "refuse"),
        ),
    ),
    Command(
        "gyro triad",
        "triad",
        (),
        ("wx_deg_s", "wy_deg_s", "wz_deg_s", "ux", "uy", "uz"),
        ("scale_misalignment", "bias"),
        (
            ("--reject-k", "0", "refuse"),
            ("--reject-k", "-3", "refuse"),
            ("--reject-k", "1e300", "either"),
            ("--reject-k", "1e-300", "refuse"),
            ("--reject-k", "nan", "refuse"),
            ("--reject-k", "inf", "either"),  # documented: no rejection
        ),
    ),
    Command(
        "gyro rotations",
        "rot",
        ("--sections", "{twin_truth}"),
        ("time_s", "ux", "uy", "uz"),
        ("scale_misalignment", "bias"),
        (
            ("--fs-hz", "0", "refuse"),
            ("--fs-hz", "-100", "refuse"),
            ("--fs-hz", "1e300", "refuse"),
            ("--fs-hz", "1e-300", "refuse"),
            ("--fs-hz", "nan", "refuse"),
            ("--angle-deg", "0", "refuse"),
            ("--angle-deg", "-360", "either"),
            ("--angle-deg", "1e300", "refuse"),
            ("--angle-deg", "1e-300", "refuse"),
            ("--angle-deg", "nan", "refuse"),
        ),
    ),
    Command(
        "gyro multiposition",
        "mp",
        ("--axis", "x", "--latitude-deg", "45.75"),
        ("phi1_deg", "phi2_deg", "output_deg_h"),
        ("drift_coefficients",),
        (
            ("--latitude-deg", "91", "refuse"),
            ("--latitude-deg", "-91", "refuse"),
            ("--latitude-deg", "90", "either"),
            ("--latitude-deg", "1e300", "refuse"),
            ("--latitude-deg", "nan", "refuse"),
            ("--latitude-deg", "inf", "refuse"),
        ),
    ),
    Command(
        "allan",
        "noise",
        (),
        ("time_s", "rate_deg_s"),
        ("tau_s", "adev_deg_s", "arw_deg_rt_h"),
        (
            ("--fs-hz", "0", "refuse"),
            ("--fs-hz", "-1", "refuse"),
            ("--fs-hz", "1e300", "refuse"),
            ("--fs-hz", "1e-300", "refuse"),
            ("--fs-hz", "nan", "refuse"),
            ("--fs-hz", "inf", "refuse"),
            ("--fs-hz", "50", "refuse"),  # contradicts the time_s column (100 Hz)
        ),
    ),
)

#: Faults of one column: name → (function of the column, expect). ``expect`` says what a correct
#: program must do: "refuse" (the column can give no trustworthy result), "same" (the variant keeps
#: the twin's truth: exit 0 with the twin's key results), "either" (exit 0 with finite results, or a
#: named refusal).
Mutation = Callable[[np.ndarray], np.ndarray]


def _set(i: Callable[[int], int], value: float) -> Mutation:
    def mutate(x: np.ndarray) -> np.ndarray:
        y = x.astype(np.float64, copy=True)
        if y.size:
            y[i(y.size)] = value
        return y

    return mutate


_MID = lambda n: n // 2  # noqa: E731
_FIRST = lambda n: 0  # noqa: E731
_LAST = lambda n: n - 1  # noqa: E731

VALUE_FAULTS: dict[str, tuple[Mutation, str]] = {
    "one sample NaN": (_set(_MID, math.nan), "refuse"),
    "first sample NaN": (_set(_FIRST, math.nan), "refuse"),
    "one sample +inf": (_set(_MID, math.inf), "refuse"),
    "last sample -inf": (_set(_LAST, -math.inf), "refuse"),
    "all NaN": (lambda x: np.full(x.shape, math.nan), "refuse"),
    "one sample 1e300": (_set(_MID, 1e300), "refuse"),
    "one sample -1e300": (_set(_MID, -1e300), "refuse"),
    "last sample 1e300": (_set(_LAST, 1e300), "refuse"),
    "one sample 1.7e308": (_set(_MID, 1.7e308), "refuse"),
    "scaled by 1e300": (lambda x: x * 1e300, "refuse"),
    "scaled by 1e-300": (lambda x: x * 1e-300, "refuse"),
    "scaled by 1e-320 (subnormal)": (lambda x: x * 1e-320, "refuse"),
    "shifted by 1e300": (lambda x: x + 1e300, "refuse"),
    "constant 0.5": (lambda x: np.full(x.shape, 0.5), "refuse"),
    "all zero": (lambda x: np.zeros(x.shape), "refuse"),
    "constant 1e300": (lambda x: np.full(x.shape, 1e300), "refuse"),
    "constant -1e-300": (lambda x: np.full(x.shape, -1e-300), "refuse"),
}

TIME_FAULTS: dict[str, tuple[Mutation, str]] = {
    "negative time stamps (shifted by -1000 s)": (lambda t: t - 1000.0, "same"),
    "reversed": (lambda t: t[::-1].copy(), "refuse"),
    "one duplicated time stamp": (
        lambda t: np.concatenate(
            [t[: t.size // 2], t[t.size // 2 - 1 : t.size // 2], t[t.size // 2 + 1 :]]
        ),
        "refuse",
    ),
    "all time stamps equal": (lambda t: np.zeros(t.shape), "refuse"),
    "time shifted by 1e300": (lambda t: t + 1e300, "refuse"),
    "time shifted by 1e12": (lambda t: t + 1e12, "refuse"),
    "time scaled by 1e300": (lambda t: t * 1e300, "refuse"),
    "time scaled by 1e-300": (lambda t: t * 1e-300, "refuse"),
    "one time stamp 1e300": (_set(_MID, 1e300), "refuse"),
    "last time stamp 1e300": (_set(_LAST, 1e300), "refuse"),
    "one time stamp NaN": (_set(_MID, math.nan), "refuse"),
    "one time stamp -inf": (_set(_FIRST, -math.inf), "refuse"),
}

LENGTH_FAULTS: dict[str, tuple[int, str]] = {
    "empty": (0, "refuse"),
    "one sample": (1, "refuse"),
    "two samples": (2, "refuse"),
    "five samples": (5, "refuse"),
}


@dataclass
class Case:
    """One command line and what a correct program does with it."""

    command: str
    fault: str
    expect: str  # "refuse" | "same" | "either"
    args: list[str]
    names: tuple[str, ...]  # the error line must name one of these (case-insensitive)
    file_name: str | None = None  # a capture fault: the line must name this file too
    write: Callable[[], None] | None = None  # writes the mutated input (lazily)
    keys: tuple[str, ...] = ()
    truth: dict[str, Any] | None = None  # key results of the unmutated twin ("same")


@dataclass
class Outcome:
    kind: str
    exit_code: int | None
    line: str
    seconds: float
    case: Case = field(repr=False)


# ------------------------------------------------------------------------------------ the twins
def make_twins(folder: Path) -> dict[str, Path]:
    """Write the small twin captures and the turntable example into ``folder``."""
    from click.testing import CliRunner

    from rotacal.cli import cli

    runner = CliRunner()
    paths: dict[str, Path] = {}
    for key, line in TWINS.items():
        path = folder / f"{key}.npz"
        result = runner.invoke(cli, [*line.split(), "--out", str(path), "--overwrite"])
        if result.exit_code != 0:
            raise RuntimeError(f"could not make the {key} twin: {result.output}")
        paths[key] = path
    selfcal = folder / "selfcal.json"
    result = runner.invoke(
        cli, ["selfcal", str(paths["pulses"]), "--pulses-per-rev", "360", "--json", str(selfcal)]
    )
    if result.exit_code != 0:
        raise RuntimeError(f"could not self-calibrate the pulses twin: {result.output}")
    paths["selfcal"] = selfcal
    toml = folder / "turntable.toml"
    result = runner.invoke(cli, ["turntable", "example", "--out", str(toml), "--overwrite"])
    if result.exit_code != 0:
        raise RuntimeError(f"could not write the turntable example: {result.output}")
    paths["turntable"] = toml
    return paths


def _load(path: Path) -> dict[str, np.ndarray]:
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


def _writer(path: Path, columns: dict[str, np.ndarray]) -> Callable[[], None]:
    def write() -> None:
        np.savez(path, **columns)

    return write


def _text_writer(path: Path, text: str) -> Callable[[], None]:
    def write() -> None:
        path.write_text(text, encoding="utf-8")

    return write


# ------------------------------------------------------------------------------------ the cases
def _base_args(cmd: Command, capture: Path, twins: dict[str, Path]) -> list[str]:
    truth = str(twins[cmd.twin]) + ".truth.json"
    return [
        *cmd.name.split(),
        str(capture),
        *(a.replace("{twin_truth}", truth) for a in cmd.args),
        "--json",
        "-",
    ]


#: Options that need a partner: option → (partner, a valid value of it).
_PAIRED = {
    "--set-amplitude-deg": ("--set-frequency-hz", "2"),
    "--set-frequency-hz": ("--set-amplitude-deg", "0.5"),
}


def _option_names(option: str) -> tuple[str, ...]:
    bare = option.lstrip("-")
    return (option, bare, bare.replace("-", "_"))


def build_cases(folder: Path, twins: dict[str, Path]) -> list[Case]:
    """Every command line of the fuzz run (deterministic; the inputs are written on demand)."""
    cases: list[Case] = []
    counter = iter(range(10**9))

    def new_path(suffix: str = ".npz") -> Path:
        return folder / f"case{next(counter):04d}{suffix}"

    for cmd in COMMANDS:
        base = _load(twins[cmd.twin])
        # the unmutated twin: its key results are the truth of the truth-keeping variants
        cases.append(
            Case(
                cmd.name,
                "valid twin",
                "same",
                _base_args(cmd, twins[cmd.twin], twins),
                (),
                keys=cmd.keys,
            )
        )
        for option, value, expect in cmd.options:
            args = _base_args(cmd, twins[cmd.twin], twins)
            if option in _PAIRED:  # the set values come as a pair: the other one valid
                other, valid = _PAIRED[option]
                args += [other, valid]
            if option in args:
                args[args.index(option) + 1] = value
            else:
                args += [option, value]
            cases.append(
                Case(
                    cmd.name,
                    f"{option} {value}",
                    expect,
                    args,
                    _option_names(option),
                    keys=cmd.keys,
                )
            )
        if cmd.name == "motion encoder":
            cases += _chunked_cases(cmd, base, twins, new_path)
        for column in base:
            used = column in cmd.columns
            faults = dict(VALUE_FAULTS)
            if column == "time_s" or column.startswith("head_"):
                faults.update(TIME_FAULTS)
            for fault, (mutate, expect) in faults.items():
                cols = dict(base)
                cols[column] = mutate(base[column])
                if column.startswith("head_") and expect == "same":
                    expect = "refuse"  # one head shifted in time no longer overlaps the others
                path = new_path()
                cases.append(
                    Case(
                        cmd.name,
                        f"column {column}: {fault}",
                        expect if used else "same",
                        _base_args(cmd, path, twins),
                        (column,),
                        path.name,
                        _writer(path, cols),
                        cmd.keys,
                    )
                )
        if cmd.twin == "pulses":  # every head shifted alike keeps the twin's truth
            path = new_path()
            cols = {k: v - 1000.0 for k, v in base.items()}
            cases.append(
                Case(
                    cmd.name,
                    "every head's time stamps shifted by -1000 s",
                    "same",
                    _base_args(cmd, path, twins),
                    cmd.columns,
                    path.name,
                    _writer(path, cols),
                    cmd.keys,
                )
            )
        cases += _copy_cases(cmd, base, twins, new_path)
        for fault, (n, expect) in LENGTH_FAULTS.items():
            cols = {k: v[:n] for k, v in base.items()}
            path = new_path()
            # a fault of the whole capture: naming the file is enough; for rotations a capture
            # shorter than the --sections is named by the section that does not fit
            sections = cmd.name == "gyro rotations" and n > 1
            cases.append(
                Case(
                    cmd.name,
                    f"truncated: {fault}",
                    expect,
                    _base_args(cmd, path, twins),
                    ("section",) if sections else (),
                    None if sections else path.name,
                    _writer(path, cols),
                    cmd.keys,
                )
            )
        cases += _csv_cases(cmd, base, twins, new_path)
    cases += _turntable_cases(twins, new_path)
    cases += _input_file_cases(twins, new_path)
    return cases


def _input_file_cases(twins: dict[str, Path], new_path: Callable[..., Path]) -> list[Case]:
    """Absurd numbers in the other files a command reads: --selfcal JSON, --correction-from."""
    out: list[Case] = []
    selfcal = json.loads(twins["selfcal"].read_text(encoding="utf-8"))
    edits: list[tuple[str, Callable[[dict[str, Any]], None], str]] = [
        ("deviation 1e300", lambda d: d["deviation_arcsec"].__setitem__(5, 1e300), "refuse"),
        ("deviation NaN", lambda d: d["deviation_arcsec"].__setitem__(5, math.nan), "refuse"),
        (
            "deviation -Infinity",
            lambda d: d["deviation_arcsec"].__setitem__(0, -math.inf),
            "refuse",
        ),
        (
            "deviation of 10 values",
            lambda d: d.__setitem__("deviation_arcsec", d["deviation_arcsec"][:10]),
            "refuse",
        ),
        ("deviation all zero", lambda d: d.__setitem__("deviation_arcsec", [0.0] * 360), "either"),
        ("pulses_per_rev 1e300", lambda d: d.__setitem__("pulses_per_rev", 1e300), "refuse"),
        ("pulses_per_rev NaN", lambda d: d.__setitem__("pulses_per_rev", math.nan), "refuse"),
        (
            "first_pulse_time_s inf",
            lambda d: d.__setitem__("first_pulse_time_s", math.inf),
            "refuse",
        ),
    ]
    for fault, edit, expect in edits:
        data = json.loads(json.dumps(selfcal))
        edit(data)
        path = new_path(".json")
        args = [
            "rate",
            str(twins["pulses"]),
            "--pulses-per-rev",
            "360",
            "--selfcal",
            str(path),
            "--json",
            "-",
        ]
        out.append(
            Case(
                "rate",
                f"--selfcal with {fault}",
                expect,
                args,
                ("self-calibration", "deviation"),
                None,
                _text_writer(path, json.dumps(data)),
                ("mean_rate_deg_s",),
            )
        )
    enc = _load(twins["enc"])
    for fault, (mutate, column) in {
        "a constant": (lambda c: {**c, "a": np.full(c["a"].shape, 0.5)}, "a"),
        "b with one sample 1e300": (lambda c: {**c, "b": _set(_MID, 1e300)(c["b"])}, "b"),
        "b a copy of a": (lambda c: {**c, "b": c["a"].copy()}, "b"),
        "a scaled by 1e-300": (lambda c: {**c, "a": c["a"] * 1e-300}, "a"),
    }.items():
        path = new_path()
        args = [
            "motion",
            "encoder",
            str(twins["enc"]),
            "--lines",
            "3600",
            "--correction-from",
            str(path),
            "--json",
            "-",
        ]
        out.append(
            Case(
                "motion encoder",
                f"--correction-from with {fault}",
                "refuse",
                args,
                (column,),
                path.name,
                _writer(path, mutate(enc)),
                _MOTION_KEYS,
            )
        )
    return out


def _chunked_cases(
    cmd: Command, base: dict[str, np.ndarray], twins: dict[str, Path], new_path: Callable[..., Path]
) -> list[Case]:
    """The encoder's chunked path (``--chunked``) on the faults its own first pass checks."""
    out = []
    faults = {
        "b": ("one sample 1e300", "scaled by 1e-300", "constant 0.5", "one sample NaN"),
        "time_s": ("time shifted by 1e12", "time scaled by 1e300", "one duplicated time stamp"),
    }
    for column, names in faults.items():
        for fault in names:
            mutate, expect = {**VALUE_FAULTS, **TIME_FAULTS}[fault]
            cols = {**base, column: mutate(base[column])}
            path = new_path()
            out.append(
                Case(
                    cmd.name,
                    f"--chunked, column {column}: {fault}",
                    expect,
                    [*_base_args(cmd, path, twins), "--chunked"],
                    (column,),
                    path.name,
                    _writer(path, cols),
                    cmd.keys,
                )
            )
    return out


def _copy_cases(
    cmd: Command, base: dict[str, np.ndarray], twins: dict[str, Path], new_path: Callable[..., Path]
) -> list[Case]:
    """Columns that are copies of others: identical heads, a == b, output == rate, ux == uy."""
    used = [c for c in cmd.columns if c in base]
    variants: list[tuple[str, dict[str, np.ndarray], tuple[str, ...]]] = []
    if cmd.twin == "pulses":
        h0 = base["head_0"]
        variants.append(
            ("every head an identical copy of head_0", {h: h0.copy() for h in used}, tuple(used))
        )
        variants.append(
            (
                "head_1 an identical copy of head_0",
                {**base, "head_1": h0.copy()},
                ("head_1", "head_0"),
            )
        )
        variants.append(
            (
                "heads that are copies of head_0 shifted by a quarter turn's time",
                {h: h0 + k * (h0[-1] - h0[0]) / 12 for k, h in enumerate(used)},
                tuple(used),
            )
        )
    else:
        data = [c for c in used if c != "time_s"]
        for i, a in enumerate(data):
            for b in data[i + 1 : i + 3]:
                variants.append(
                    (f"column {b} an identical copy of {a}", {**base, b: base[a].copy()}, (a, b))
                )
                variants.append((f"column {b} = -{a}", {**base, b: -base[a]}, (a, b)))
    out = []
    for fault, cols, names in variants:
        # measured columns differ by noise at least: an exact copy (or negative) of another
        # column is data written twice, and a method fed with it reports a perfect or
        # meaningless result (identical heads: 0.0″; output = set rate: NL 0)
        expect = "refuse"
        path = new_path()
        out.append(
            Case(
                cmd.name,
                fault,
                expect,
                _base_args(cmd, path, twins),
                names,
                path.name,
                _writer(path, cols),
                cmd.keys,
            )
        )
    return out


def _csv_cases(
    cmd: Command, base: dict[str, np.ndarray], twins: dict[str, Path], new_path: Callable[..., Path]
) -> list[Case]:
    """Text cells a CSV may hold: 'nan', 'inf', '1e999' (overflows to inf), '1e-999' (zero)."""
    if cmd.twin == "pulses":
        return []
    names = list(base)
    target = next(c for c in cmd.columns if c != "time_s")
    table = np.column_stack([base[c] for c in names])
    rows = [",".join(repr(float(v)) for v in row) for row in table]
    out = []
    for cell, expect in (
        ("nan", "refuse"),
        ("inf", "refuse"),
        ("-Infinity", "refuse"),
        ("1e999", "refuse"),
        ("1e300", "refuse"),
    ):
        k = names.index(target)
        mutated = list(rows)
        fields = mutated[len(rows) // 2].split(",")
        fields[k] = cell
        mutated[len(rows) // 2] = ",".join(fields)
        path = new_path(".csv")
        text = ",".join(names) + "\n" + "\n".join(mutated) + "\n"
        out.append(
            Case(
                cmd.name,
                f"CSV cell {cell!r} in column {target}",
                expect,
                _base_args(cmd, path, twins),
                (target,),
                path.name,
                _text_writer(path, text),
                cmd.keys,
            )
        )
    return out


#: Turntable TOML faults: (key, new value, expect). ``key`` is a top-level key of a table
#: (``psi``) or ``error.lower`` / ``error.weight`` of an ``[errors]`` entry; faults whose key the
#: example does not hold are left out (the example changes with the project).
_TOML_FAULTS: tuple[tuple[str, str, str], ...] = (
    *(("psi", v, "refuse") for v in ("1e300", "1e-300", "0", "nan", "inf", "-1.62")),
    ("theta", "1.7976931348623157e308", "refuse"),
    *(("calibration_deg_h", v, "refuse") for v in ("1e300", "1e-300", "0", "nan", "-0.01")),
    *(("phi_y1.lower", v, "refuse") for v in ("1e300", "nan", "-0.05")),
    ("phi_y1.lower", "1e-300", "either"),
    *(("phi_y1.weight", v, "refuse") for v in ("1e300", "1e-300", "0", "inf")),
    ("eta.lower", "1e300", "refuse"),
    *(("step_deg", v, "refuse") for v in ("0", "1e300", "1e-300", "nan", "-45", "0.001")),
    *(("runs", v, "refuse") for v in ("0", "-1", "1e300", "1_000_000_000_000_000")),
    *(("seed", v, "refuse") for v in ("-1", "1e300")),
    ("seed", "100_000_000_000_000_000_000_000", "either"),
    *(("required_deg_h", v, "refuse") for v in ("0", "1e300", "1e-300", "nan")),
    *(("latitude_deg", v, "refuse") for v in ("91", "1e300", "nan")),
    ("latitude_deg", "90", "either"),
    *(("outer_steps", v, "refuse") for v in ("0", "1", "1_000_000_000_000")),
    *(("inner_steps", v, "refuse") for v in ("1e300", "1_000_000_000_000")),
)


def _toml_edit(text: str, key: str, value: str) -> str | None:
    """``text`` with ``key`` set to ``value`` (the raw TOML), or None if the key is not there."""
    if "." in key:
        entry, field_ = key.split(".")
        line = re.search(rf"(?m)^{entry}\s*=\s*\{{\s*lower\s*=\s*[^,}}]+", text)
        if line is None:
            return None
        head = line.group(0)
        if field_ == "lower":
            edited = re.sub(r"lower\s*=\s*[^,}]+$", f"lower = {value}", head)
        else:
            edited = f"{head}, {field_} = {value}"
        return text[: line.start()] + edited + text[line.end() :]
    line = re.search(rf"(?m)^{key}\s*=\s*[^\n#]+", text)
    if line is None:
        return None
    return text[: line.start()] + f"{key} = {value}" + text[line.end() :]


def _turntable_cases(twins: dict[str, Path], new_path: Callable[..., Path]) -> list[Case]:
    text = twins["turntable"].read_text(encoding="utf-8")
    keys = ("upper_bounds_arcmin",)
    out = []
    for key, value, expect in _TOML_FAULTS:
        edited = _toml_edit(text, key, value)
        if edited is None:
            continue
        path = new_path(".toml")
        args = ["turntable", "budget", str(path), "--runs", "2000", "--json", "-"]
        names = tuple(key.split("."))
        out.append(
            Case(
                "turntable budget",
                f"TOML {key} = {value}",
                expect,
                args,
                names,
                path.name,
                _text_writer(path, edited),
                keys,
            )
        )
    base = ["turntable", "budget", str(twins["turntable"]), "--json", "-"]
    for option, value in (
        ("--runs", "0"),
        ("--runs", "-1"),
        ("--runs", "1e9"),
        ("--seed", "-1"),
        ("--seed", "1e300"),
    ):
        out.append(
            Case(
                "turntable budget",
                f"{option} {value}",
                "refuse",
                [*base, option, value],
                _option_names(option),
                keys=keys,
            )
        )
    return out


# ------------------------------------------------------------------------------------ running
class CaseTimeout(BaseException):
    """Raised by the alarm: a BaseException, so neither the CLI nor CliRunner swallows it."""


@contextlib.contextmanager
def _deadline(seconds: float) -> Iterator[None]:
    def alarm(signum: int, frame: Any) -> None:
        raise CaseTimeout

    old = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def _finite_leaves(value: Any, nullable: bool = False) -> bool:
    if isinstance(value, bool):
        return True
    if isinstance(value, (int, float)):
        return math.isfinite(value)
    if isinstance(value, dict):
        return all(_finite_leaves(v, nullable) for v in value.values())
    if isinstance(value, list):
        return all(_finite_leaves(v, nullable) for v in value)
    return value is None and nullable  # null where a number belongs, unless the key allows it


#: Keys whose entries may be null on a valid result (an error with no effect on orientation).
NULLABLE = ("upper_bounds_arcmin",)


def _close(a: Any, b: Any, rtol: float = 1e-6, atol: float = 1e-9) -> bool:
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k], rtol, atol) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_close(x, y, rtol, atol) for x, y in zip(a, b, strict=True))
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return abs(a - b) <= atol + rtol * abs(b)
    return bool(a == b)


def classify(
    case: Case, exit_code: int | None, stdout: str, stderr: str, crashed: bool
) -> tuple[str, str]:
    """The outcome of one run (see the module docstring) and the line that shows it."""
    errors = [
        ln for ln in stderr.splitlines() if ln.strip() and not ln.startswith("rotacal: warning:")
    ]
    first = errors[0] if errors else ""
    if crashed or exit_code not in (0, 2):
        return "internal", first or f"exit {exit_code}"
    if exit_code == 2:
        if len(errors) != 1 or not first.startswith("rotacal: error:"):
            return "internal", " | ".join(errors) or "exit 2 without a line"
        text = first.lower()
        named = not case.names or any(n.lower() in text for n in case.names)
        filed = case.file_name is None or case.file_name.lower() in text
        if case.expect == "same":
            return "wrong", first
        return ("refused" if named and filed else "unnamed"), first
    try:
        data = json.loads(stdout)
    except json.JSONDecodeError:
        return "internal", "exit 0 without JSON on stdout"
    values = {k: data.get(k) for k in case.keys}
    if case.expect == "refuse":
        return "silent", f"exit 0: {json.dumps(values)[:200]}"
    if not all(_finite_leaves(v, k in NULLABLE) for k, v in values.items()):
        return "silent", f"exit 0 with null/non-finite results: {json.dumps(values)[:200]}"
    if case.command == "selfcal" and data.get("deviation_pp_arcsec") == 0.0:
        return "silent", "exit 0 with a perfect scale (0.0 arcsec peak-to-peak)"
    if case.expect == "same" and case.truth is not None and not _close(values, case.truth):
        return (
            "wrong",
            f"exit 0 but {json.dumps(values)[:160]} != twin {json.dumps(case.truth)[:160]}",
        )
    return "ok", ""


def run_case(case: Case, timeout_s: float = 120.0) -> Outcome:
    """Run one case through the CLI in this process and classify it."""
    from click.testing import CliRunner

    from rotacal.cli import cli

    if case.write is not None:
        case.write()
    runner = CliRunner()
    t0 = time.perf_counter()
    try:
        with _deadline(timeout_s):
            result = runner.invoke(cli, case.args, catch_exceptions=True)
    except CaseTimeout:
        return Outcome(
            "timeout", None, f"longer than {timeout_s:g} s", time.perf_counter() - t0, case
        )
    seconds = time.perf_counter() - t0
    crashed = result.exception is not None and not isinstance(result.exception, SystemExit)
    kind, line = classify(case, result.exit_code, result.stdout, result.stderr, crashed)
    if crashed and not line:
        line = f"{type(result.exception).__name__}: {result.exception}"
    return Outcome(kind, result.exit_code, line, seconds, case)


def attach_truth(cases: list[Case]) -> None:
    """Run each command's valid twin and give its key results to the truth-keeping variants."""
    truths: dict[str, dict[str, Any]] = {}
    for case in cases:
        if case.fault == "valid twin":
            outcome = run_case(case)
            if outcome.kind != "ok":
                raise RuntimeError(f"{case.command} fails on its valid twin: {outcome.line}")
            runner_json = _json_of(case)
            truths[case.command] = {k: runner_json.get(k) for k in case.keys}
    for case in cases:
        if case.expect == "same":
            case.truth = truths.get(case.command)


def _json_of(case: Case) -> dict[str, Any]:
    from click.testing import CliRunner

    from rotacal.cli import cli

    result = CliRunner().invoke(cli, case.args)
    return dict(json.loads(result.stdout))


def limit_memory(gib: float) -> None:
    """Cap this process's address space so that a runaway allocation fails instead of swapping."""
    limit = int(gib * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", default=None, help="Run one command's cases (e.g. 'motion fog').")
    ap.add_argument("--limit", type=int, default=None, help="Run a seeded sample of N cases.")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--all", action="store_true", help="Print every case's outcome line.")
    ap.add_argument("--timeout", type=float, default=120.0, help="Seconds per case.")
    ap.add_argument("--memory-gib", type=float, default=6.0, help="Address-space cap.")
    ns = ap.parse_args()
    limit_memory(ns.memory_gib)
    with tempfile.TemporaryDirectory(prefix="rotacal-fuzz-cli-") as tmp:
        folder = Path(tmp)
        twins = make_twins(folder)
        cases = build_cases(folder, twins)
        if ns.only:
            cases = [c for c in cases if c.command == ns.only]
        if ns.limit is not None and ns.limit < len(cases):
            cases = random.Random(ns.seed).sample(cases, ns.limit)
        attach_truth(cases)
        t0 = time.perf_counter()
        outcomes = []
        for case in cases:
            outcome = run_case(case, ns.timeout)
            outcomes.append(outcome)
            if ns.all or outcome.kind not in PASSING:
                print(
                    f"  {outcome.kind:<8} {case.command}: {case.fault}: {outcome.line[:300]}",
                    flush=True,
                )
        total = time.perf_counter() - t0
    by_kind = Counter(o.kind for o in outcomes)
    print(f"\n{len(outcomes)} command lines in {total:.0f} s")
    print("outcome   " + "  ".join(f"{k} {by_kind.get(k, 0)}" for k in OUTCOMES))
    by_command: dict[str, Counter[str]] = {}
    for o in outcomes:
        by_command.setdefault(o.case.command, Counter())[o.kind] += 1
    for name, counts in by_command.items():
        print(f"  {name:<20} " + "  ".join(f"{k} {counts[k]}" for k in OUTCOMES if counts[k]))
    failures = len(outcomes) - sum(by_kind[k] for k in PASSING)
    print(f"failures  {failures}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
