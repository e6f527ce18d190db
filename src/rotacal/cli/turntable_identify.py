"""``rotacal turntable identify``: a turntable's geometric errors from measured orientation errors.

Registered on the ``turntable`` group by one import at the end of :mod:`rotacal.cli.turntable`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import click

from rotacal.columns import TURNTABLE_IDENTIFY
from rotacal.errors import ConfigError

from ._common import (
    INPUT_FILE,
    _analysis_options,
    _check_outputs,
    _names_capture,
    _naming_file,
    _publish,
    _read,
    _status,
    _summary_wanted,
)
from ._help import example
from .turntable import turntable


def _budget_bounds(path: str) -> dict[str, float | None]:
    """``upper_bounds_arcmin`` of a ``rotacal turntable budget --json`` file, in arcsec."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ConfigError(f"--budget {path}: not a readable JSON file ({e}).") from None
    bounds = data.get("upper_bounds_arcmin") if isinstance(data, dict) else None
    if not isinstance(bounds, dict) or not bounds:
        raise ConfigError(
            f"--budget {path}: no upper_bounds_arcmin; give the JSON that 'rotacal turntable "
            "budget CONFIG.toml --json' writes."
        )
    out: dict[str, float | None] = {}
    for name, value in bounds.items():
        if value is None:
            out[name] = None
        elif isinstance(value, (int, float)) and math.isfinite(value) and value >= 0:
            out[name] = float(value) * 60.0
        else:
            raise ConfigError(
                f"--budget {path}: upper_bounds_arcmin.{name} must be a number ≥ 0, got {value!r}."
            )
    return out


@turntable.command(
    "identify",
    epilog=example(
        "rotacal turntable identify errors.csv --config table.toml --report identify.html",
        "rotacal turntable identify errors.csv --budget budget.json --json identify.json",
    ),
)
@click.argument("capture", type=INPUT_FILE)
@click.option(
    "--config",
    "config_path",
    type=INPUT_FILE,
    metavar="CONFIG.toml",
    default=None,
    help="The table (its chain) and its allocation (as 'turntable budget' makes it) to compare "
    "with [default: the GyroWheel study's table, no comparison].",
)
@click.option(
    "--budget",
    "budget_path",
    type=INPUT_FILE,
    metavar="BUDGET.json",
    default=None,
    help="Compare with the upper_bounds_arcmin of a 'turntable budget --json' result instead "
    "of allocating again.",
)
@click.option(
    "--model",
    type=click.Choice(["seed", "exact"]),
    default="seed",
    show_default=True,
    help="Forward model: the paper's small-angle matrices, or proper rotations (Table 3 order).",
)
@click.option(
    "--rcond",
    type=click.FloatRange(1e-9, 1.0, max_open=True),
    default=1e-3,
    show_default=True,
    help="Directions with singular value below rcond·σmax are reported as inseparable.",
)
@click.option(
    "--next",
    "next_positions",
    type=click.IntRange(0, 100),
    default=6,
    show_default=True,
    help="How many positions to recommend measuring next (D-optimal).",
)
@click.option(
    "--design-step-deg",
    type=float,
    default=30.0,
    show_default=True,
    help="Grid step (deg) of the candidate positions for the recommendation.",
)
@_analysis_options
@_names_capture
def turntable_identify_cmd(
    capture: str,
    config_path: str | None,
    budget_path: str | None,
    model: str,
    rcond: float,
    next_positions: int,
    design_step_deg: float,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Identify a turntable's geometric errors.

    Columns phi1_deg, phi2_deg (the position) and dpsi_arcsec, dtheta_arcsec, dgamma_arcsec
    (the orientation error measured there): the nine errors of the GyroWheel study's model
    (eqs. 17–25) by nonlinear least squares, with u; the sums the positions cannot separate,
    what would separate them, the positions to measure next, and the allocation's bounds.
    """
    from rotacal.turntable import load_turntable, seed_table
    from rotacal.turntable.budget import budget_allocation
    from rotacal.turntable.identify import ARCSEC, identify_turntable
    from rotacal.turntable.identify_design import candidate_grid

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    if kw.pop("specs") is not None:
        raise ConfigError("--specs: turntable identify takes no Type B inputs; drop the option.")
    try:
        candidate_grid(design_step_deg)
    except ConfigError as e:
        raise ConfigError(f"--design-step-deg: {e}") from None
    table = seed_table() if config_path is None else load_turntable(Path(config_path))
    bounds: dict[str, float | None] | None = None
    source = ""
    if budget_path is not None:
        bounds, source = _budget_bounds(budget_path), f"--budget {budget_path}"
    elif config_path is not None:
        with _status("allocating"), _naming_file(config_path, "--config"):
            alloc = budget_allocation(table)
        bounds = {n: (None if v is None else v / ARCSEC) for n, v in alloc.upper_bounds_rad.items()}
        source = f"the allocation of --config {config_path}"
    cap = _read(capture, list(TURNTABLE_IDENTIFY.required), columns, group)
    with _status("fitting"):
        result = identify_turntable(
            *(cap[name] for name in TURNTABLE_IDENTIFY.required),
            table=table,
            model=model,
            rcond=rcond,
            bounds_arcsec=bounds,
            bounds_source=source,
            next_positions=next_positions,
            design_step_deg=design_step_deg,
        )
    _publish(
        result,
        json_path,
        report_path,
        capture,
        "Turntable identification",
        "The geometric errors of the GyroWheel study's model (eqs. 17–25) from orientation "
        "errors at many positions",
        ("turntable_identify", "identify_section"),
    )
    if _summary_wanted():
        _print_summary(result)


def _print_summary(result: Any) -> None:
    click.echo(
        f"{result.positions} positions, {result.rank} separable combinations, ν = {result.dof}, "
        f"s = {result.s_arcsec:.3g} arcsec"
    )
    coverage = f"(k = {result.k:.3g}, p = {result.coverage_probability * 100:.0f} %)"
    decisions = {}
    if result.allocation is not None:
        decisions = {e["name"]: e for e in result.allocation["combinations"]}
    for combo in result.combinations:
        line = (
            f"{combo['name']:<28} {combo['value_arcsec']:>10.3f} ± {combo['U_arcsec']:.3f} arcsec "
            + coverage
        )
        entry = decisions.get(combo["name"])
        if entry is not None and entry["bound_arcsec"] is not None:
            line += f"   bound {entry['bound_arcsec']:.3g}: {entry['decision']}"
        click.echo(line)
    if result.unidentifiable:
        click.echo(f"not separable alone: {', '.join(result.unidentifiable)}")
    if result.next_positions_deg:
        click.echo(
            "measure next (φ1, φ2 deg): "
            + ", ".join(f"({a:g}, {b:g})" for a, b in result.next_positions_deg)
        )
    if result.allocation is not None:
        click.echo(f"against {result.allocation['source']}: {result.allocation['verdict']}")
