"""``rotacal turntable`` and ``rotacal specs``: configuration-driven budgets."""

from __future__ import annotations

from pathlib import Path

import click

from ._app import cli
from ._common import (
    INPUT_FILE,
    _check_outputs,
    _check_toml_output,
    _emit_warnings,
    _names_capture,
    _sample_progress,
    _summary_wanted,
    _write_json,
    _write_report,
    _wrote,
)
from ._help import example


@cli.group(
    "turntable",
    epilog=example(
        "rotacal turntable example --out table.toml",
        "rotacal turntable budget table.toml --report budget.html",
    ),
)
def turntable() -> None:
    """Turntable geometric errors: budget, identification.

    The error model of a serial turntable by homogeneous transforms, its sensitivities, the
    allocation of tolerances to the error sources and a Monte Carlo check (GyroWheel study,
    Int. J. Aerospace Eng.).
    """


def _report_subtitle() -> str:
    from rotacal.references import cite

    return f"Error analysis and allocation of a test turntable after {cite('gyrowheel')}"


@turntable.command(
    "budget",
    epilog=example(
        "rotacal turntable budget table.toml --json budget.json --report budget.html",
        "rotacal turntable budget table.toml --runs 20000 --constraint-angles 45",
    ),
)
@click.argument("config", type=INPUT_FILE)
@click.option(
    "--runs", type=int, default=None, help="Monte Carlo draws (default: config, else 10⁶)."
)
@click.option(
    "--seed", type=int, default=None, help="Seed of the draws (default: config, else 2026)."
)
@click.option(
    "--json", "json_path", metavar="PATH", help="Write the results as JSON ('-' = stdout)."
)
@click.option(
    "--requirement-derivation",
    type=click.Choice(["calibration-check", "earth-rate-only"]),
    default=None,
    help="How [requirement] calibration_deg_h becomes the orientation requirement: "
    "'calibration-check' (tables built to the allocation keep the calibration within it) or "
    "'earth-rate-only' (the GyroWheel study's eq. (16), the Earth-rate reading alone). Default: the config's "
    "[requirement] derivation, else calibration-check.",
)
@click.option(
    "--constraint-angles",
    metavar="every|DEG",
    default=None,
    help="Where the allocation's constraint holds: 'every' angle, or only at multiples of DEG "
    "(dividing 360; 45 = the paper's grid φ2 ∈ {0°, 45°, 90°}). Default: the config's "
    "[allocation] constraint_angles, else every.",
)
@click.option("--report", "report_path", metavar="PATH.html", help="Write an HTML report.")
@click.option("--overwrite", is_flag=True, help="Replace existing --json/--report files.")
@_names_capture
def turntable_budget_cmd(
    config: str,
    runs: int | None,
    seed: int | None,
    json_path: str | None,
    requirement_derivation: str | None,
    constraint_angles: str | None,
    report_path: str | None,
    overwrite: bool,
) -> None:
    """Allocate a turntable's accuracy to its error sources.

    CONFIG.toml describes the table (see 'rotacal turntable example'): the sensitivities, the
    tolerance of each error source, the worst case and a Monte Carlo check of it.
    """
    from rotacal.turntable import load_turntable, turntable_budget

    _check_outputs(json_path, report_path, overwrite)
    table = load_turntable(Path(config))
    runs_total = (
        runs
        if runs is not None
        else int(table.settings.get("monte_carlo", {}).get("runs", 1_000_000))
    )
    with _sample_progress(runs_total, "Monte Carlo") as advance:
        result = turntable_budget(
            table,
            runs=runs,
            seed=seed,
            progress=lambda done, _t: advance(done),
            requirement_derivation=requirement_derivation,
            constraint_angles=constraint_angles,
        )
    _emit_warnings(result)
    _write_json(result.to_dict(), json_path)
    if report_path:
        from rotacal.report.turntable import table_name, turntable_section

        _write_report(
            f"Turntable error budget: {table_name(result)}",
            _report_subtitle(),
            [turntable_section(result)],
            config,
            report_path,
            warnings=result.warnings,
        )
    if _summary_wanted():
        req = result.requirement_arcmin
        click.echo(
            "requirement (arcmin)  "
            + "  ".join(f"{c} {req[c]:.4g}" for c in ("psi", "theta", "gamma"))
            + f"  ({result.requirement_source})"
        )
        click.echo(f"{'error':<10} {'lower':>9} {'upper':>9}  (arcmin)  set by")
        for name, ub in result.upper_bounds_arcmin.items():
            lb = result.lower_bounds_arcmin.get(name)
            if ub is None:
                click.echo(f"{name:<10} {'':>9} {'—':>9}  no effect on orientation")
                continue
            click.echo(
                f"{name:<10} {lb:>9.4f} {ub:>9.4f}            {result.binding.get(name, '')}"
            )
        mc = result.monte_carlo
        mx = mc["max_abs_arcmin"]
        click.echo(
            f"Monte Carlo {mc['runs']} draws: max |Δ| (arcmin) "
            + "  ".join(f"{c} {mx[c]:.4g}" for c in ("psi", "theta", "gamma"))
            + ("  — all within" if mc["all_within"] else f"  — {mc['outside']} OUTSIDE")
        )
        cal = result.calibration
        if cal is not None:
            worst = cal["worst_table_rate_error_deg_h"]
            frac = cal["fraction_above_required"]
            click.echo(
                f"calibration to {cal['required_deg_h']:g} °/h ({cal['plan']}): worst table "
                f"Δωx {max(worst['linear_deg_h']['x'], worst['full_deg_h']['x']):.4g}, "
                f"Δωy {max(worst['linear_deg_h']['y'], worst['full_deg_h']['y']):.4g} °/h; "
                f"of {cal['runs']} tables drawn {frac['x'] * 100:.1f} % (x), "
                f"{frac['y'] * 100:.1f} % (y) above"
                + ("" if worst["worst_deg_h"] <= cal["required_deg_h"] else " — NOT MET")
            )


@turntable.command(
    "example",
    epilog=example("rotacal turntable example --out table.toml"),
)
@click.option("--out", required=True, metavar="FILE.toml", help="Where to write the example.")
@click.option("--overwrite", is_flag=True, help="Replace an existing file.")
def turntable_example(out: str, overwrite: bool) -> None:
    """Write the paper's two-axis table as commented TOML.

    A configuration to start from for `rotacal turntable budget` (the GyroWheel study's table).
    """
    from rotacal.io.outputs import write_output
    from rotacal.turntable import seed_table_toml

    _check_toml_output(out)
    write_output(out, seed_table_toml(), label=f"--out {out}", overwrite=overwrite)
    _wrote(out)


# ----------------------------------------------------------------------------------------------- specs
@cli.group(
    "specs",
    epilog=example(
        "rotacal specs example --out lab.toml",
        "rotacal motion encoder run.npz --lines 36000 --specs lab.toml",
    ),
)
def specs_group() -> None:
    """Instrument specifications for --specs (Type B).

    What a capture cannot tell — the encoder's graduation accuracy, the laser triangulation
    sensor's radius, the DAQ timebase, the table's set-rate accuracy, the latitude — each with
    its distribution, as the Type B inputs of the uncertainty budgets.
    """


@specs_group.command(
    "example",
    epilog=example("rotacal specs example --out lab.toml"),
)
@click.option("--out", required=True, metavar="FILE.toml", help="Where to write the example.")
@click.option("--overwrite", is_flag=True, help="Replace an existing file.")
def specs_example(out: str, overwrite: bool) -> None:
    """Write a commented specifications file.

    Every entry rotacal's uncertainty budgets use, to edit to your instruments.
    """
    from rotacal.io.outputs import write_output
    from rotacal.uncertainty.specs import example_specs_toml

    _check_toml_output(out)
    write_output(out, example_specs_toml(), label=f"--out {out}", overwrite=overwrite)
    _wrote(out)


from . import turntable_identify  # noqa: E402,F401  (registers `turntable identify`)
