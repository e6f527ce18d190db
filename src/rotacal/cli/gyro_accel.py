"""``rotacal gyro accelerometer``: the accelerometer triad of a Ferraris session (six static
positions against gravity, Ferraris et al. 1995)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import click

from ._common import (
    INPUT_FILE,
    _analysis_options,
    _check_outputs,
    _clipping_option,
    _names_capture,
    _publish,
    _status,
    _summary_wanted,
)
from ._ferraris import (
    echo_matrix,
    echo_vector,
    gravity_options,
    read_sections,
    read_triads,
    sections_option,
)
from ._help import example
from .gyro import gyro


@gyro.command(
    "accelerometer",
    epilog=example(
        "rotacal gyro accelerometer session.csv --sections session_list.json "
        "--column acc_x=ax --column acc_y=ay --column acc_z=az --latitude-deg 49.6",
    ),
)
@click.argument("capture", type=INPUT_FILE)
@sections_option
@gravity_options
@click.option(
    "--output-unit",
    default="",
    help="Unit of the outputs ax, ay, az (e.g. m/s^2, g, LSB), for the results and the report.",
)
@_clipping_option
@_analysis_options
@_names_capture
def gyro_accelerometer(
    capture: str,
    sections_path: str,
    latitude_deg: float | None,
    gravity_m_s2: float | None,
    position_u_deg: float,
    output_unit: str,
    columns: Sequence[str],
    group: str | None,
    **kw: Any,
) -> None:
    """Accelerometer triad from six static positions.

    Columns ax, ay, az and the positions x_p, x_a, y_p, y_a, z_p, z_a (each axis up, then down)
    in --sections: K_a, R_a (misalignment) and b_a in u = K_a·R_a·a + b_a, with uncertainties.
    """
    from rotacal.gyro.accel_triad import calibrate_accel_triad

    json_path, report_path = kw.pop("json_path"), kw.pop("report_path")
    _check_outputs(json_path, report_path, kw.pop("overwrite"))
    kw.pop("specs")  # no instrument specification applies to the static means
    sections, _ = read_sections(sections_path)
    _, _, acc = read_triads(capture, columns, group, gyro=False)
    static = sections.get("static", sections) if isinstance(sections, dict) else sections
    with _status("averaging the positions"):
        result = calibrate_accel_triad(
            acc,
            {k: v for k, v in static.items() if not k.endswith("_rot")},
            gravity_m_s2=gravity_m_s2,
            latitude_deg=latitude_deg,
            position_u_deg=position_u_deg,
            output_unit=output_unit,
            allow_clipped=kw.pop("allow_clipped"),
        )
    data = _publish(
        result,
        json_path,
        report_path,
        capture,
        "Accelerometer triad from six static positions",
        "Ferraris et al. (1995), eqs. (19)–(23): u = K_a·R_a·a + b_a against gravity",
        ("accel", "accel_section"),
    )
    if _summary_wanted():
        unit = output_unit or "output unit"
        echo_matrix(data, "scale_misalignment", "K_a·R_a", f"{unit}/(m/s²)")
        echo_vector(data, "scale_factors", "K_a", f"{unit}/(m/s²)")
        echo_vector(data, "bias", "b_a", unit)
        click.echo(f"g                 {result.gravity_m_s2:.6f} m/s²")
