"""``rotacal turntable`` and ``rotacal specs``: configuration-driven budgets."""

from __future__ import annotations

from pathlib import Path

import click

from rotacal.errors import ConfigError

from ._app import cli
from ._common import (
    _check_outputs,
    _emit_warnings,
    _names_capture,
    _sample_progress,
    _write_json,
    _write_report,
)


@cli.group("turntable")
def turntable() -> None:
    """Turntable geometric errors: model, sensitivities, allocation, Monte Carlo (seed 001)."""


_SEED001 = "GyroWheel calibration tests: turntable error analysis and allocation (seed 001)"


@turntable.command("budget")
@click.argument("config", type=click.Path(dir_okay=False))
@click.option(
    "--runs", type=int, default=None, help="Monte Carlo draws (default: config, else 10⁶)."
)
@click.option(
    "--seed", type=int, default=None, help="Seed of the draws (default: config, else 2026)."
)
@click.option(
    "--json", "json_path", metavar="PATH", help="Write the results as JSON ('-' = stdout)."
)
@click.option("--report", "report_path", metavar="PATH.html", help="Write an HTML report.")
@click.option("--overwrite", is_flag=True, help="Replace existing --json/--report files.")
@_names_capture
def turntable_budget_cmd(
    config: str,
    runs: int | None,
    seed: int | None,
    json_path: str | None,
    report_path: str | None,
    overwrite: bool,
) -> None:
    """Allocate accuracy to a turntable's error sources and check it (CONFIG.toml: see
    'rotacal turntable example')."""
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
            table, runs=runs, seed=seed, progress=lambda done, _t: advance(done)
        )
    _emit_warnings(result)
    _write_json(result.to_dict(), json_path, (Path(config),))
    if report_path:
        from rotacal.report.turntable import turntable_section

        _write_report(
            f"Turntable error budget: {result.table}",
            _SEED001 + " — eqs. (7)–(34)",
            [turntable_section(result)],
            config,
            report_path,
            warnings=result.warnings,
        )
    if json_path is None and report_path is None:
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


@turntable.command("example")
@click.option("--out", required=True, metavar="FILE.toml", help="Where to write the example.")
@click.option("--overwrite", is_flag=True, help="Replace an existing file.")
def turntable_example(out: str, overwrite: bool) -> None:
    """Write the seed's two-axis table as a commented TOML to start a configuration from."""
    from rotacal.turntable import seed_table_toml

    path = Path(out)
    if path.exists() and not overwrite:
        raise ConfigError(f"{out} exists; choose another name or pass --overwrite")
    path.write_text(seed_table_toml(), encoding="utf-8")
    click.echo(f"wrote {out}")


# ----------------------------------------------------------------------------------------------- specs
@cli.group("specs")
def specs_group() -> None:
    """Instrument specifications: the Type B inputs of the uncertainty budgets (--specs)."""


@specs_group.command("example")
@click.option("--out", required=True, metavar="FILE.toml", help="Where to write the example.")
@click.option("--overwrite", is_flag=True, help="Replace an existing file.")
def specs_example(out: str, overwrite: bool) -> None:
    """Write a commented specifications file with every entry rotacal's budgets use."""
    from rotacal.uncertainty.specs import example_specs_toml

    path = Path(out)
    if path.exists() and not overwrite:
        raise ConfigError(f"{out} exists; choose another name or pass --overwrite")
    path.write_text(example_specs_toml(), encoding="utf-8")
    click.echo(f"wrote {out}")
