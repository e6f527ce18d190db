"""``rotacal verify``: check a certificate's signature, schema and data, as its receiver would."""

from __future__ import annotations

import sys

import click

from ._app import cli
from ._common import _check_outputs, _write_json
from ._help import example


@cli.command(
    "verify",
    epilog=example(
        "rotacal verify RC-2026-0042                      # the folder certify wrote",
        "rotacal verify certificate.xml --trust lab-ca.pem",
        "rotacal verify RC-2026-0042 --recompute --json verdict.json",
    ),
)
@click.argument("path", metavar="PATH")
@click.option(
    "--trust",
    metavar="CERT.pem",
    default=None,
    help="Trust anchors (PEM): the signer's certificate must be one of them or chain to one, "
    "at the signing time. Without it the signature is checked with the certificate it embeds.",
)
@click.option(
    "--recompute",
    is_flag=True,
    help="Run the plan's measurements again from its captures and compare every number and "
    "plan_sha256.",
)
@click.option(
    "--plan",
    "plan",
    metavar="PLAN.toml",
    default=None,
    help="The plan file [default: the plan results.json names, beside the certificate folder].",
)
@click.option(
    "--json", "json_path", metavar="PATH", help="Write the findings as JSON ('-' = stdout)."
)
@click.option("--overwrite", is_flag=True, help="Replace an existing --json file.")
def verify_command(
    path: str,
    trust: str | None,
    recompute: bool,
    plan: str | None,
    json_path: str | None,
    overwrite: bool,
) -> None:
    """Verify a certificate folder or its certificate.xml.

    Checks the XML Signature (XAdES-BES) and the signer's certificate (against --trust when
    given, at the signing time), the DCC schema, that results.json states what the signed XML
    states, the SHA-256 of the plan and of every capture that can be reached, and with
    --recompute every number again. Exit 0 and one line when all holds; exit 1 and a line naming
    what fails; exit 2 when PATH cannot be used.
    """
    from rotacal.certificate.verify import verify_certificate

    _declare_inputs(path, trust, plan)
    _check_outputs(json_path, None, overwrite)
    found = verify_certificate(path, trust=trust, recompute=recompute, plan=plan)
    _write_json(found.to_dict(), json_path)
    if json_path != "-":
        click.echo(found.verdict())
        for note in found.notes:
            click.echo(f"note: {note}", err=True)
    if not found.ok:
        sys.exit(1)


def _declare_inputs(path: str, trust: str | None, plan: str | None) -> None:
    """Declare the files verify reads as the command's inputs: certificate.xml, --trust and
    --plan in the provenance, and no --json may replace them or results.json."""
    from pathlib import Path

    from rotacal.io.outputs import InputFile

    from ._common import _INPUT_PATHS_KEY, _INPUTS_KEY

    ctx = click.get_current_context()
    given = Path(path)
    xml = given / "certificate.xml" if given.is_dir() else given
    named: dict[str, Path | None] = {
        "path": xml,
        "trust": Path(trust) if trust else None,
        "plan": Path(plan) if plan else None,
    }
    inputs = [("PATH", xml), ("PATH", xml.parent / "results.json")]
    inputs += [(f"--{n}", f) for n, f in named.items() if n != "path" and f is not None]
    for label, file in inputs:
        if file.is_file():
            ctx.meta.setdefault(_INPUTS_KEY, []).append(InputFile(str(file), f"{label} {file}"))
    for name, given_file in named.items():
        if given_file is not None and given_file.is_file():
            ctx.meta.setdefault(_INPUT_PATHS_KEY, {})[name] = [str(given_file)]
