"""The whole `rotacal motion encoder` command against reading the file and a bare unwrap, one run.

    python benchmarks/bench_encoder_command.py [--samples 2e7] [--periods 10,1000] [--quick] [--cpu]

For each number of motion periods a twin capture is written as NPZ (``rotacal simulate
encoder``), then timed as separate processes, best of ``--repeat``, from start to exit:

- baseline: ``python -c`` that imports NumPy, ``np.load``\\ s the NPZ's ``a`` and ``b`` and runs a
  bare ``np.unwrap(np.arctan2(b, a))`` (the issue's bar for the command: ≤ 1.3×);
- ``rotacal motion encoder FILE --lines 36000 --json OUT`` (reading, validation, demodulation, fit,
  budgets, JSON), with Numba chosen by size and with ``ROTACAL_NUMBA=0``;
- the same command on the same columns written by ``np.savez`` (whose members' data are not
  aligned in the file, unlike rotacal's: NumPy's slower unaligned paths then run).

Prints seconds, the ratio to the baseline and the peak RSS of each process (from
``resource.getrusage`` of the children). Machines here are shared: the ratios are the figures;
``--cpu`` times CPU seconds (user + system of the process) instead of wall time, which other
processes on the machine disturb less; it counts the command's SHA-256 of the file (for the
JSON's provenance), which runs on a second thread and costs no wall time where a core is free.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

FS = 200_000.0


def best(
    cmd: list[str], env: dict[str, str], repeats: int, cpu: bool = False
) -> tuple[float, float]:
    """Wall time (s), or CPU time (user + system, s) with ``cpu``, and peak RSS (MB) of the
    command, best of ``repeats``; each run inside a fresh wrapper process, whose RUSAGE_CHILDREN
    figures are that command's alone."""
    wrapper = [
        sys.executable,
        "-c",
        "import resource, subprocess, sys, time\n"
        "t0 = time.perf_counter(); subprocess.run(sys.argv[2:], check=True, "
        "stdout=subprocess.DEVNULL)\n"
        "wall = time.perf_counter() - t0\n"
        "ru = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
        "print(ru.ru_utime + ru.ru_stime if sys.argv[1] == 'cpu' else wall, ru.ru_maxrss / 1024)",
        "cpu" if cpu else "wall",
        *cmd,
    ]
    out = []
    for _ in range(repeats):
        res = subprocess.run(wrapper, check=True, env=env, capture_output=True, text=True)
        sec, mb = (float(x) for x in res.stdout.split())
        out.append((sec, mb))
    return min(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--samples", type=float, default=2e7)
    ap.add_argument("--periods", default="10,1000")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="10⁶ samples, 1 repeat")
    ap.add_argument("--cpu", action="store_true", help="CPU seconds instead of wall seconds")
    args = ap.parse_args()
    n = int(1e6 if args.quick else args.samples)
    repeats = 1 if args.quick else args.repeat
    env = dict(os.environ)
    env.setdefault("OPENBLAS_NUM_THREADS", "1")
    # each process may cache the bytecode it compiles (as a pip install or a developer's
    # checkout has it): where the environment forbids it, every run of the command would
    # compile rotacal's modules again (~0.1-0.2 s) while the baseline's NumPy has its cache
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    duration = n / FS
    clock = "CPU s" if args.cpu else "s"
    print(f"samples {n:,}; best of {repeats}; separate processes, start to exit")
    print(f"{'periods':>7s}  {'what':<40s} {clock:>7s} {'ratio':>6s} {'peak MB':>8s}")
    with tempfile.TemporaryDirectory() as tmp:
        for periods in (float(p) for p in args.periods.split(",")):
            f = periods / duration
            path = Path(tmp) / f"enc_{periods:g}.npz"
            subprocess.run(
                ["rotacal", "simulate", "encoder", "--out", str(path), "--fs-hz", f"{FS:g}",
                 "--duration-s", f"{duration:g}", "--frequency-hz", f"{f:g}",
                 "--amplitude-deg", f"{0.5 * min(1.0, 20.0 / f):g}", "--harmonic", "2:0.01",
                 "--offset-a", "0.02", "--gain-ratio", "0.98", "--phase-error-deg", "0.5",
                 "--noise", "0.003", "--overwrite"],
                check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            )  # fmt: skip
            base_cmd = [
                sys.executable,
                "-c",
                "import sys, numpy as np; d = np.load(sys.argv[1]); a, b = d['a'], d['b']; "
                "np.unwrap(np.arctan2(b, a))",
                str(path),
            ]
            # the same columns as np.savez writes them: members not aligned in the file, as in
            # most captures a user brings (rotacal's writer aligns them)
            plain = Path(tmp) / f"savez_{periods:g}.npz"
            subprocess.run(
                [sys.executable, "-c", "import sys, numpy as np; d = dict(np.load(sys.argv[1])); "
                 "np.savez(sys.argv[2], **d)", str(path), str(plain)],
                check=True, env=env,
            )  # fmt: skip

            def cli(capture: Path) -> list[str]:
                out = str(Path(tmp) / "out.json")
                return ["rotacal", "motion", "encoder", str(capture), "--lines", "36000",
                        "--overwrite", "--json", out]  # fmt: skip

            def timed(cmd: list[str], extra: dict[str, str] | None = None) -> tuple[float, float]:
                return best(cmd, env | (extra or {}), repeats, args.cpu)

            rows = [
                ("np.load + np.unwrap(np.arctan2)  [baseline]", timed(base_cmd)),
                ("rotacal motion encoder (Numba by size)", timed(cli(path))),
                ("rotacal motion encoder (ROTACAL_NUMBA=0)", timed(cli(path), {"ROTACAL_NUMBA": "0"})),
                ("the same on the np.savez file", timed(cli(plain))),
            ]  # fmt: skip
            t_base = rows[0][1][0]
            for name, (sec, mb) in rows:
                print(f"{periods:7.0f}  {name:<40s} {sec:7.2f} {sec / t_base:6.2f} {mb:8.0f}")
            plain.unlink()
            path.unlink()


if __name__ == "__main__":
    main()
