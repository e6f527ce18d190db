"""What issuing a certificate costs on top of the measurements it certifies.

Makes the twin captures of a five-measurement plan (gyro scale factor, gyro triad, Allan deviation,
encoder self-calibration, sinusoidal motion from an encoder) in a temporary folder, then times,
alternating, ``--repeat`` times each:

- the five analysis commands as a user runs them today: five ``rotacal … --json`` processes;
- ``rotacal certify plan.toml``: one process that runs the five and issues the certificate
  (figures, PDF, DCC validated against its schema, results.json).

Prints the median of each, their ratio (the issue's bar: under 2), the peak RSS of the certify
process, and the split of one in-process certification into its steps (reading the plan, the
measurements, the figures, rendering PDF and XML). No asserts.

Run: ``python benchmarks/bench_certify.py [--repeat 3]``
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import tomli_w

SIMULATE = {
    "rates.npz": "gyro-rates",
    "triad.npz": "gyro-triad",
    "noise.npz": "gyro-noise",
    "pulses.npz": "pulses",
    "encoder.npz": "encoder --harmonic 2:0.01 --harmonic 3:0.003 --noise 0.002 --adc-bits 16",
}
MEASUREMENTS = [
    (
        "gyro scale-factor",
        "rates.npz",
        {"full-scale-deg-s": 100, "output-unit": "V"},
        {"nonlinearity_percent_fs": {"max": 0.5}},
    ),
    (
        "gyro triad",
        "triad.npz",
        {"output-unit": "deg/s"},
        {"scale_misalignment[0][0]": {"min": 0.99, "max": 1.01}},
    ),
    ("allan", "noise.npz", {"column": "rate_deg_s"}, {"arw_deg_rt_h": {"max": 0.5}}),
    ("selfcal", "pulses.npz", {"pulses-per-rev": 18000}, {"deviation_pp_arcsec": {"max": 10.0}}),
    ("motion encoder", "encoder.npz", {"lines": 36000}, {"thd_percent": {"max": 2.0}}),
]


def rotacal(*args: str, cwd: Path) -> float:
    """Run ``rotacal ARGS`` in a fresh process; its wall time (s)."""
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "rotacal", *args], cwd=cwd, check=True, capture_output=True
    )
    return time.perf_counter() - start


def make_plan(folder: Path) -> Path:
    for name, kind in SIMULATE.items():
        rotacal("simulate", *kind.split(), "--out", name, cwd=folder)
    plan = {
        "certificate": {"number": "RC-BENCH-1", "date": "2026-11-25"},
        "laboratory": {"name": "Rate Lab", "country": "DE"},
        "customer": {"name": "Gyro Maker Ltd"},
        "person": [{"name": "A", "role": "performed"}, {"name": "B", "role": "approved"}],
        "item": {"kind": "gyroscope", "manufacturer": "M", "model": "GM-300", "serial": "SN-1"},
        "standard": [
            {"name": "Encoder", "id": "STD-17", "certificate": "C-1", "due": "2027-06-30"}
        ],
        "measurement": [
            {
                "name": command,
                "command": command,
                "capture": capture,
                "options": options,
                "limits": limits,
            }
            for command, capture, options, limits in MEASUREMENTS
        ],
    }
    path = folder / "plan.toml"
    path.write_text(tomli_w.dumps(plan), encoding="utf-8")
    return path


def five_commands(folder: Path) -> float:
    total = 0.0
    for i, (command, capture, options, _) in enumerate(MEASUREMENTS):
        args = [*command.split(), capture]
        for name, value in options.items():
            args += [f"--{name}", str(value)]
        total += rotacal(*args, "--json", f"m{i}.json", "--overwrite", cwd=folder)
    return total


def steps(plan: Path) -> dict[str, float]:
    """One certification in this process, step by step (s)."""
    from rotacal import __version__
    from rotacal.certificate import issue
    from rotacal.plan.read import read_plan
    from rotacal.plan.run import run_plan

    times = {}
    t = time.perf_counter()
    p = read_plan(plan)
    times["read the plan"] = time.perf_counter() - t
    with tempfile.TemporaryDirectory() as scratch:
        t = time.perf_counter()
        runs = run_plan(p, Path(scratch))
        times["five measurements"] = time.perf_counter() - t
        t = time.perf_counter()
        content = issue.build_content(p, runs, p.number, __version__)
        times["quantities and conformity"] = time.perf_counter() - t
        t = time.perf_counter()
        content = issue._draw(content, Path(scratch))
        times["figures"] = time.perf_counter() - t
        t = time.perf_counter()
        issue._render(content, Path(scratch))
        times["results.json, DCC (validated), PDF"] = time.perf_counter() - t
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        plan = make_plan(folder)
        alone, certify = [], []
        for i in range(args.repeat):
            alone.append(five_commands(folder))
            certify.append(
                rotacal("certify", str(plan), "--out", str(folder / f"cert{i}"), cwd=folder)
            )
        peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        a, c = statistics.median(alone), statistics.median(certify)
        print(f"five analysis commands (5 processes): {a:6.2f} s (median of {args.repeat})")
        print(f"rotacal certify (1 process):          {c:6.2f} s (median of {args.repeat})")
        print(f"ratio certify / commands:             {c / a:6.2f}  (bar: < 2)")
        print(f"peak RSS of a child process:          {peak_mb:6.0f} MB")
        print("one certification in-process, by step:")
        for name, seconds in steps(plan).items():
            print(f"  {name:40s} {seconds:6.2f} s")


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    main()
