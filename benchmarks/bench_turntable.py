"""Speed of the turntable Monte Carlo check (rotacal.turntable.allocation), one core; allocation vs Table 4.

On the seed's two-axis table (seed 001) with rotacal's allocation for eq. (16)'s printed requirement
(0.027° on each component, stated — the packaged table derives its own from 0.01 °/h, see
``bench_turntable_requirement.py``; the stated one keeps these figures comparable between runs):

1. ``monte_carlo_check`` with ``--runs`` draws (default 10⁶): random generator, full model, maxima,
   histograms and largest values — draws/s of the Philox stream's fused compiled pass (one thread,
   two threads), of its NumPy twin (``ROTACAL_NUMBA=0``; the same numbers), and of the OLD path
   measured in this run (``stream="pcg64"``: NumPy's PCG64 generator, then the compiled kernel and
   tallies, as before), with the ratio new/old; and the PCG64 generator alone (the old floor);
2. the same draws (same generator and seed) evaluated five ways, all measured in this run:
   a. ``table.fast_orientation_error``, compiled kernel (turntable/fast.py),
   b. the same, NumPy path (``ROTACAL_NUMBA=0``: the code of c, through the method),
   c. BASELINE: the NumPy kernel as it was before the compiled one (``matrices._fast_kernel`` on
      chunks of 16 384 draws, its constant checks per entry),
   d. the generic batched chain: ``table.transform`` (4×4 homogeneous transforms, eq. (22)) and
      ``table.ideal_transform``, ΔR = R_dᵀ·R_t by ``np.matmul`` (eq. (23)), in chunks,
   e. a per-draw Python loop building the 4×4 matrices of eqs. (17)–(22) with NumPy (on 10⁴
      draws, time scaled to ``--runs``),
   with draws/s, the speed-up over (c) and the largest difference from (a);
3. seconds, draws/s (wall clock and per CPU-second) and peak RSS of ``monte_carlo_check``
   (compiled, one thread) at 10⁶, 10⁷ and 10⁸ draws, new stream and old path back to back, each
   in a fresh process (``--sizes``; peak RSS: that process's VmHWM), after importing Numba and
   loading (or compiling) the kernels, whose time is printed apart; the ratios new/old;
4. rotacal's upper bounds next to Table 4 (arcmin) and the worst cases (linear and full model).

Best of ``--repeat`` (default 3) with ``time.perf_counter`` (and ``time.process_time`` for the CPU
time: on a machine others load, the wall clock counts their time too); no asserts. ``--quick``:
2·10⁵ draws, one repeat, sizes 10⁶ only.

Run: ``python benchmarks/bench_turntable.py [--runs N] [--repeat R] [--sizes 1e6,1e7,1e8] [--quick]``
"""

from __future__ import annotations

import argparse
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import json  # noqa: E402
import math  # noqa: E402
import resource  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from functools import partial  # noqa: E402
from typing import Any  # noqa: E402

import numpy as np  # noqa: E402

from rotacal.turntable.allocation import allocate, monte_carlo_check, worst_case  # noqa: E402
from rotacal.turntable.matrices import _fast_kernel  # noqa: E402
from rotacal.turntable.model import Turntable, seed_table  # noqa: E402
from rotacal.turntable.seed001 import EQ16_DEG  # noqa: E402
from rotacal.turntable.seed001 import TABLE4_ARCMIN as TABLE4  # noqa: E402

ARCMIN = math.pi / 10_800.0
CHUNK = 262_144
LOOP_DRAWS = 10_000


def best_of(fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    best = math.inf
    out = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


CPU_SECONDS: dict[str, float] = {}  # label → best CPU time (this process, all its threads)


def best_of_cpu(label: str, fn: Callable[[], Any], repeat: int) -> tuple[float, Any]:
    """:func:`best_of`, keeping the best CPU time too: on a loaded machine the wall clock counts
    the time others hold the cores, the CPU time only the time this process ran."""
    best_cpu = math.inf

    def timed() -> Any:
        nonlocal best_cpu
        c0 = time.process_time()
        out = fn()
        best_cpu = min(best_cpu, time.process_time() - c0)
        return out

    best, out = best_of(timed, repeat)
    CPU_SECONDS[label] = best_cpu
    return best, out


def draws(table: Turntable, alloc: Any, runs: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The Monte Carlo's draws (random signs), made as monte_carlo_check makes them."""
    names = table.angular_error_names
    lb = np.array([alloc.lower_bounds_rad[n] for n in names])
    ub = np.array([alloc.upper_bounds_rad[n] for n in names])
    rng = np.random.Generator(np.random.PCG64(seed))
    u = rng.random((runs, len(names) + len(table.angle_names)))
    v = 2.0 * u[:, : len(names)] - 1.0
    chi = np.copysign(lb + (ub - lb) * np.abs(v), v)
    return 2.0 * math.pi * u[:, len(names) :], chi


def baseline_kernel(table: Turntable, angles: np.ndarray, chi: np.ndarray) -> np.ndarray:
    """(Δψ, Δθ, Δγ) as ``fast_orientation_error`` computed them before the compiled kernel."""
    out = np.empty((angles.shape[0], 3))
    needs_angle = table._fast_angles()
    for start in range(0, angles.shape[0], 16_384):
        stop = min(angles.shape[0], start + 16_384)
        a_t = angles[start:stop].T
        c_t = np.ascontiguousarray(chi[start:stop].T)
        trig = {k: (np.cos(a_t[k]), np.sin(a_t[k])) for k in needs_angle}
        out[start:stop, 0], out[start:stop, 1], out[start:stop, 2] = _fast_kernel(
            table._p.links, trig, c_t
        )
    return out


def with_numba(flag: str, fn: Callable[[], Any]) -> Callable[[], Any]:
    """``fn`` run with ``ROTACAL_NUMBA`` set to ``flag``."""

    def run() -> Any:
        before = os.environ.get("ROTACAL_NUMBA")
        os.environ["ROTACAL_NUMBA"] = flag
        try:
            return fn()
        finally:
            if before is None:
                del os.environ["ROTACAL_NUMBA"]
            else:
                os.environ["ROTACAL_NUMBA"] = before

    return run


def peak_rss_mb() -> float:
    """This process's peak resident memory (MB): VmHWM, which starts afresh with the program
    (ru_maxrss of a child keeps the parent's peak at the fork, here the parent's 10⁶ draws)."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def child(runs: int, stream: str) -> None:
    """Allocate, then time ``monte_carlo_check`` of ``runs`` draws; print seconds and peak RSS."""
    table = seed_table()
    alloc = allocate(table, math.radians(EQ16_DEG))
    t0 = time.perf_counter()
    warm = with_numba(
        "1", lambda: monte_carlo_check(table, alloc, runs=1_000, seed=1, stream=stream)
    )
    warm()  # import Numba and compile (or load) the kernels: timed apart
    load = time.perf_counter() - t0
    before = peak_rss_mb()
    t0, c0 = time.perf_counter(), time.process_time()
    monte_carlo_check(table, alloc, runs=runs, seed=2026, stream=stream)
    elapsed, cpu = time.perf_counter() - t0, time.process_time() - c0
    peak = peak_rss_mb()
    print(json.dumps({"seconds": elapsed, "cpu": cpu, "peak_mb": peak, "before_mb": before,
                      "load": load}))  # fmt: skip


def via_transform(table: Turntable, angles: np.ndarray, chi: np.ndarray) -> np.ndarray:
    """(Δψ, Δθ, Δγ) from the batched 4×4 chain of eq. (22) and ΔR = R_dᵀ·R_t (eq. (23))."""
    out = np.empty((angles.shape[0], 3))
    names = table.angular_error_names
    for s in range(0, angles.shape[0], CHUNK):
        a = [angles[s : s + CHUNK, k] for k in range(angles.shape[1])]
        errors = {n: chi[s : s + CHUNK, i] for i, n in enumerate(names)}
        rt = table.transform(a, errors)[..., :3, :3]
        rd = table.ideal_transform(a)[..., :3, :3]
        dr = np.matmul(np.swapaxes(rd, -1, -2), rt)
        out[s : s + CHUNK] = np.stack([dr[:, 0, 2], dr[:, 1, 0], dr[:, 2, 1]], axis=1)
    return out


def per_draw_loop(angles: np.ndarray, chi: np.ndarray) -> np.ndarray:
    """One draw at a time: the 4×4 matrices of eqs. (17)–(22) built and multiplied in Python."""

    def e4(ex: float, ey: float, ez: float) -> np.ndarray:
        return np.array(
            [[1.0, -ez, ey, 0.0], [ez, 1.0, -ex, 0.0], [-ey, ex, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
        )

    out = np.empty((angles.shape[0], 3))
    for k in range(angles.shape[0]):
        p1, p2 = angles[k]
        fy1, fz2, ax1, az1, ax2, ay2, ex, ey = chi[k]
        c1, s1, c2, s2 = math.cos(p1), math.sin(p1), math.cos(p2), math.sin(p2)
        ry = np.array([[c1, 0, s1, 0], [0, 1, 0, 0], [-s1, 0, c1, 0], [0, 0, 0, 1.0]])
        rz = np.array([[c2, -s2, 0, 0], [s2, c2, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
        t01 = ry @ e4(ax1, fy1, az1)  # eq. (17)
        t12 = e4(ex, ey, 0.0)  # eq. (18), η = 0
        t23 = rz @ e4(ax2, ay2, fz2)  # eq. (19)
        tt = t01 @ t12 @ t23 @ np.eye(4)  # eqs. (20), (22)
        td = ry @ rz  # eq. (21)
        dr = td[:3, :3].T @ tt[:3, :3]  # eq. (23)
        out[k] = dr[0, 2], dr[1, 0], dr[2, 1]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--sizes", default="1e6,1e7,1e8", help="draws for the seconds/peak-RSS table")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--child", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--stream", default="philox", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(int(args.child), args.stream)
        return
    if args.quick:
        args.runs, args.repeat, args.sizes = 200_000, 1, "1e6"
    runs, seed = args.runs, 2026

    table = seed_table()
    t_alloc, alloc = best_of(lambda: allocate(table, math.radians(EQ16_DEG)), 1)
    for name in ("philox", "pcg64"):  # compile (or load) first
        warm = partial(monte_carlo_check, table, alloc, runs=1_000, seed=1, stream=name)
        with_numba("1", warm)()

    def mc(stream: str = "philox", threads: int = 1) -> Callable[[], Any]:
        return lambda: monte_carlo_check(
            table, alloc, runs=runs, seed=seed, stream=stream, threads=threads
        )

    t_mc, result = best_of_cpu("new", with_numba("1", mc()), args.repeat)
    t_mc2, result2 = best_of_cpu("new2", with_numba("1", mc(threads=2)), args.repeat)
    t_mc_np, result_np = best_of_cpu("new_np", with_numba("0", mc()), args.repeat)
    t_old, result_old = best_of_cpu("old", with_numba("1", mc("pcg64")), args.repeat)
    t_old_np, _ = best_of_cpu("old_np", with_numba("0", mc("pcg64")), args.repeat)
    width = len(table.angular_error_names) + len(table.angle_names)

    def uniforms_only() -> None:
        rng, buffer = np.random.Generator(np.random.PCG64(seed)), np.empty((262_144, width))
        for start in range(0, runs, 262_144):
            rng.random(out=buffer[: min(262_144, runs - start)])

    t_rng, _ = best_of_cpu("rng", uniforms_only, args.repeat)
    same_mc = (
        {**result.to_dict(), "draws_per_second": 0}
        == {**result_np.to_dict(), "draws_per_second": 0}
        == {**result2.to_dict(), "draws_per_second": 0}
    )
    angles, chi = draws(table, alloc, runs, seed)
    fast = lambda: table.fast_orientation_error(angles, chi)  # noqa: E731
    t_fast, d_fast = best_of(with_numba("1", fast), args.repeat)
    t_np, d_np = best_of(with_numba("0", fast), args.repeat)
    t_base, d_base = best_of(lambda: baseline_kernel(table, angles, chi), args.repeat)
    t_htm, d_htm = best_of(lambda: via_transform(table, angles, chi), 1)
    n_loop = min(LOOP_DRAWS, runs)
    t_loop_part, d_loop = best_of(lambda: per_draw_loop(angles[:n_loop], chi[:n_loop]), 1)
    t_loop = t_loop_part * runs / n_loop
    same = all(
        float(np.max(np.abs(d_fast[:, j]))) == result_old.max_abs_rad[c]
        for j, c in enumerate(("psi", "theta", "gamma"))
    )

    print(f"turntable Monte Carlo, seed 001 table, {runs:,} draws, one core unless stated")
    print(f"{'monte_carlo_check (whole: RNG + model + tallies)':66s} {'time':>9s} {'draws/s':>12s} "
          f"{'× old':>7s} {'CPU s':>7s} {'draws/CPU-s':>12s} {'× old':>6s}")  # fmt: skip
    cpu_old = CPU_SECONDS["old"]
    for label, t, key in (
        ("NEW: Philox stream, fused compiled pass, 1 thread", t_mc, "new"),
        ("NEW: the same, 2 threads (threads=2)", t_mc2, "new2"),
        ("NEW: its NumPy twin (ROTACAL_NUMBA=0)", t_mc_np, "new_np"),
        ("OLD: PCG64 stream, compiled kernel and tallies (stream='pcg64')", t_old, "old"),
        ("OLD: PCG64 stream, NumPy path", t_old_np, "old_np"),
        (f"   the old floor: PCG64 alone, {width} uniforms per draw", t_rng, "rng"),
    ):
        cpu = CPU_SECONDS[key]
        print(
            f"{label:66s} {t:8.3f}s {runs / t:12,.0f} {t_old / t:7.2f} {cpu:6.3f}s "
            f"{runs / cpu:12,.0f} {cpu_old / cpu:6.2f}"
        )
    print(
        f"× old: draws/s over the old compiled path, measured in this run (wall clock, then CPU "
        f"time of this process: the draws a core gives when others do not hold it); the new "
        f"stream's result is the same on the compiled path, 1 and 2 threads, and its NumPy "
        f"twin: {same_mc}"
    )
    print()
    print("the model alone on the old stream's draws:")
    print(f"{'case':66s} {'time':>9s} {'draws/s':>12s} {'× (c)':>7s}  max |Δ − (a)| (rad)")
    rows = [
        ("a. fast_orientation_error, compiled kernel", t_fast, 0.0),
        ("b. fast_orientation_error, NumPy path (the code of c)", t_np,
         float(np.max(np.abs(d_np - d_fast)))),
        ("c. BASELINE: the NumPy kernel before (_fast_kernel per chunk)", t_base,
         float(np.max(np.abs(d_base - d_fast)))),
        ("d. batched 4×4 HTM chain: transform + matmul", t_htm,
         float(np.max(np.abs(d_htm - d_fast)))),
        (f"e. per-draw Python loop, eqs. (17)–(22) ({n_loop:,} draws, scaled)", t_loop,
         float(np.max(np.abs(d_loop - d_fast[:n_loop])))),
    ]  # fmt: skip
    for label, t, diff in rows:
        print(
            f"{label:66s} {t:8.3f}s {runs / t:12,.0f} {t_base / t:7.2f}  "
            + ("" if diff is None else f"{diff:.1e}")
        )
    print(
        f"× (c): draws/s over the baseline (c), measured in this run; the old path's maxima are "
        f"(a)'s: {same}"
    )
    print()
    print(
        f"{'monte_carlo_check draws':>24s} {'stream':>7s} {'seconds':>9s} {'draws/s':>12s} "
        f"{'× old':>6s} {'draws/CPU-s':>12s} {'× old':>6s} {'peak RSS':>10s} "
        f"{'before it (imports, allocation)':>32s} {'kernels loaded in':>18s}"
    )
    for size in (int(float(x)) for x in args.sizes.split(",") if x):
        seconds, cpu = {}, {}
        for stream in ("pcg64", "philox"):  # back to back, each in a fresh process
            out = subprocess.run(
                [sys.executable, __file__, "--child", str(size), "--stream", stream],
                check=True,
                capture_output=True,
                text=True,
            ).stdout
            got = json.loads(out.strip().splitlines()[-1])
            seconds[stream], cpu[stream] = got["seconds"], got["cpu"]
            print(
                f"{size:24,d} {stream:>7s} {got['seconds']:9.2f} {size / got['seconds']:12,.0f} "
                f"{seconds['pcg64'] / got['seconds']:6.2f} {size / got['cpu']:12,.0f} "
                f"{cpu['pcg64'] / got['cpu']:6.2f} {got['peak_mb']:7.0f} MB "
                f"{got['before_mb']:29.0f} MB {got['load']:16.2f} s"
            )
    print()
    print(f"allocation (SLSQP + exchange, full-model guard) in {t_alloc:.2f} s; arcmin:")
    print(f"{'error':10s} {'Table 4':>9s} {'rotacal':>9s} {'ratio':>7s}  binding")
    for name in table.error_names:
        ub = alloc.upper_bounds_rad[name]
        if ub is None:
            print(f"{name:10s} {'—':>9s} {'None':>9s} {'':>7s}  (no effect on the orientation)")
            continue
        paper = TABLE4[name]
        print(
            f"{name:10s} {paper:9.4f} {ub / ARCMIN:9.4f} {ub / ARCMIN / paper:7.4f}  "
            f"{alloc.binding[name]}"
        )
    wc4 = worst_case(table, {n: v * ARCMIN for n, v in TABLE4.items()}, alloc.requirement_rad)
    print(f"{'worst case (arcmin)':22s} {'linear T4':>10s} {'full T4':>10s} {'linear':>10s} "
          f"{'full':>10s} {'MC max':>10s} {'limit':>8s}")  # fmt: skip
    for c in ("psi", "theta", "gamma"):
        w = alloc.worst_case[c]
        print(
            f"{c:22s} {wc4[c]['linear_rad'] / ARCMIN:10.5f} {wc4[c]['full_rad'] / ARCMIN:10.5f} "
            f"{w['linear_rad'] / ARCMIN:10.5f} {w['full_rad'] / ARCMIN:10.5f} "
            f"{result.max_abs_arcmin[c]:10.5f} {alloc.requirement_rad[c] / ARCMIN:8.3f}"
        )
    print(
        f"Monte Carlo: all within = {result.all_within}, outside = {result.outside}; full-model guard "
        f"scales {alloc.optimiser['full_model_scale']}"
    )


if __name__ == "__main__":
    main()
