"""Issuing a certificate from a plan: run the measurements, state the results, render the PDF and
the DCC, and publish the folder whole — or leave nothing behind.

Everything is made in a hidden staging folder beside the target and renamed into place at the
end (one ``rename`` on the same file system), so a reader never sees half a certificate: a plan
that fails at any step leaves no folder, consumes no number and changes nothing the user had. An
existing certificate folder is replaced only with ``overwrite``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import datetime as dt
import hashlib
import json
import os
import shutil
import tempfile
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from rotacal.errors import ConfigError, RotacalError
from rotacal.plan.model import Measurement, Plan
from rotacal.plan.read import read_plan
from rotacal.plan.run import run_plan

from .conformity import judge
from .content import CaptureRef, CertificateContent, Figure, MeasurementResult
from .methods import method_of
from .quantities import reported_quantities
from .stated import allocation_limits

if TYPE_CHECKING:
    from .sign import Signer

__all__ = [
    "IssuedCertificate",
    "build_content",
    "certify",
    "measure_into",
    "new_staging",
    "plan_measurement_count",
    "plan_sha256",
    "publish",
    "render_into",
    "results_document",
]

#: The files of a certificate folder (and the figures, ``figure-*.svg``).
PDF_NAME, XML_NAME, JSON_NAME = "certificate.pdf", "certificate.xml", "results.json"


@dataclasses.dataclass(frozen=True)
class IssuedCertificate:
    """A certificate made: its number, its folder and what it states."""

    number: str
    folder: Path
    content: CertificateContent

    @property
    def files(self) -> list[str]:
        """The files of the certificate folder: the PDF, the DCC, results.json, the figures."""
        figures = [f.file for m in self.content.measurements for f in m.figures]
        return [PDF_NAME, XML_NAME, JSON_NAME, *figures]


def plan_sha256(plan_bytes: bytes, input_digests: Sequence[str]) -> str:
    """The SHA-256 that ties a certificate to its plan and its data: of the plan file's bytes,
    followed by the hexadecimal SHA-256 of each file the measurements read (captures and option
    files, in the plan's order), each on a line of its own.

    The same plan and the same captures give the same hash wherever they lie; a changed byte in
    any of them gives another.
    """
    h = hashlib.sha256(plan_bytes)
    for digest in input_digests:
        h.update(b"\n" + digest.encode("ascii"))
    return h.hexdigest()


def _limit_error(plan: Plan, m: Measurement, key: str, known: Sequence[str]) -> ConfigError:
    return ConfigError(
        f"{plan.path}: {m.key}.limits.{key}: '{m.command}' reports no such result; its results "
        f"with an uncertainty: {', '.join(known)}"
    )


def _measurement_result(
    plan: Plan, m: Measurement, results: Mapping[str, Any]
) -> MeasurementResult:
    """What the certificate states of one measurement: its quantities and conformity."""
    output_unit = str(results.get("output_unit") or m.option_map().get("output-unit") or "")
    try:
        quantities = reported_quantities(m.command, results, output_unit=output_unit)
    except RotacalError as e:
        raise type(e)(f"{plan.path}: {m.key}: {e}") from None
    by_key = {q.key: q for q in quantities}
    conformity = []
    try:  # errors_arcsec = "allocation": a limit for each error or sum the allocation bounds
        limits = [
            x for lim in m.limits for x in (allocation_limits(results) if lim.allocation else [lim])
        ]
    except RotacalError as e:
        raise type(e)(f"{plan.path}: {m.key}.limits.errors_arcsec: {e}") from None
    for limit in limits:
        if limit.key not in by_key:
            raise _limit_error(plan, m, limit.key, list(by_key))
        conformity.append(judge(by_key[limit.key], limit, m.decision_rule))
    method, references = method_of(m.command)
    inputs = results.get("provenance", {}).get("inputs", [])
    return MeasurementResult(
        index=m.index,
        name=m.name,
        command=m.command,
        method=method,
        references=references,
        captures=tuple(CaptureRef(i["path"], i["sha256"], int(i["bytes"])) for i in inputs),
        options=dict(m.options),  # as the plan gives them; every option is in the provenance
        results=results,
        quantities=quantities,
        conformity=tuple(conformity),
        decision_rule=m.decision_rule,
        warnings=tuple(str(w) for w in results.get("warnings", ())),
    )


def build_content(
    plan: Plan, runs: Sequence[Mapping[str, Any]], number: str, software_version: str
) -> CertificateContent:
    """The certificate's content from the plan and its measurements' JSON (``runs``, in order)."""
    measurements = tuple(
        _measurement_result(plan, m, results)
        for m, results in zip(plan.measurements, runs, strict=True)
    )
    digests = [c.sha256 for m in measurements for c in m.captures]
    return CertificateContent(
        number=number,
        plan=plan,
        plan_sha256=plan_sha256(plan.text, digests),
        software_version=software_version,
        measurements=measurements,
    )


def _contact(c: Any) -> dict[str, Any]:
    return {k: v for k, v in dataclasses.asdict(c).items() if v != ""}


def _number(text: str) -> float | int:
    """A printed decimal as a JSON number (the same value; JSON keeps no trailing zeros)."""
    value = float(text)
    return int(value) if value.is_integer() and "." not in text else value


def results_document(content: CertificateContent) -> dict[str, Any]:
    """``results.json`` (INTERFACE.md): the certificate's data for software, with each command's
    own JSON under ``results``, each reported quantity as printed (``reported``) and the
    conformity (quantity → pass | fail | indeterminate, with the ``decision_rule``)."""
    plan = content.plan
    measurements = []
    for m in content.measurements:
        measurements.append(
            {
                "name": m.name,
                "command": m.command,
                "method": m.method,
                "captures": [dataclasses.asdict(c) for c in m.captures],
                "decision_rule": m.decision_rule,
                "reported": [
                    {
                        "quantity": q.key,
                        "name": q.name,
                        "value": _number(q.value),
                        "U": _number(q.U),
                        "k": _number(q.k),
                        "coverage_probability": _number(q.p),
                        "unit": q.unit,
                        "dsi_unit": q.dsi_unit,
                        "interval": [_number(x) for x in q.interval] if q.interval else None,
                        "note": q.note,
                    }
                    for q in m.quantities
                ],
                "conformity": {c.key: c.verdict for c in m.conformity},
                "conformity_statements": [
                    {
                        "quantity": c.key,
                        "verdict": c.verdict,
                        "limit_min": _number(c.limit_min) if c.limit_min else None,
                        "limit_max": _number(c.limit_max) if c.limit_max else None,
                        "statement": c.statement,
                    }
                    for c in m.conformity
                ],
                "figures": [dataclasses.asdict(f) for f in m.figures],
                "results": m.results,
                "warnings": list(m.warnings),
                "provenance": m.results.get("provenance", {}),
            }
        )
    inputs = [
        {
            "path": plan.path.name,
            "sha256": hashlib.sha256(plan.text).hexdigest(),
            "bytes": len(plan.text),
        }
    ]
    inputs += [dataclasses.asdict(c) for m in content.measurements for c in m.captures]
    return {
        "certificate_number": content.number,
        "plan_sha256": content.plan_sha256,
        "title": plan.title,
        "supersedes": plan.supersedes,
        "calibration_start_date": plan.start_date.isoformat(),
        "calibration_end_date": plan.end_date.isoformat(),
        "issue_date": plan.issue_date.isoformat(),
        "laboratory": _contact(plan.laboratory),
        "customer": _contact(plan.customer),
        "persons": [_contact(p) for p in plan.persons],
        "item": _contact(plan.item),
        "standards": [{**_contact(s), "due": s.due.isoformat()} for s in plan.standards],
        "conditions": {
            **{
                k: v
                for k, v in dataclasses.asdict(plan.conditions).items()
                if k != "others" and v is not None
            },
            **dict(plan.conditions.others),
        },
        "measurements": measurements,
        "warnings": [f"{m.name}: {w}" for m in content.measurements for w in m.warnings],
        "provenance": {
            "rotacal_version": content.software_version,
            "command": "certify",
            "options": {},
            "inputs": inputs,
        },
    }


def _draw(content: CertificateContent, folder: Path) -> CertificateContent:
    """Draw each measurement's figures into ``folder`` and note them in the content."""
    from .figures import draw_figures

    measurements = []
    for m in content.measurements:
        figures = []
        for name, caption, svg in draw_figures(m):
            (folder / name).write_bytes(svg)
            figures.append(Figure(name, caption))
        measurements.append(dataclasses.replace(m, figures=tuple(figures)))
    return dataclasses.replace(content, measurements=tuple(measurements))


def _render(content: CertificateContent, folder: Path, signer: Signer | None = None) -> None:
    """Write results.json, certificate.xml (checked against the DCC schema; signed with
    ``signer``, whose signature the PDF's last page names) and certificate.pdf."""
    from .dcc import dcc_xml, validate_dcc
    from .pdf import render_pdf

    text = json.dumps(results_document(content), indent=2, ensure_ascii=False, allow_nan=False)
    (folder / JSON_NAME).write_text(text + "\n", encoding="utf-8")
    xml = dcc_xml(content)
    validate_dcc(xml)  # a certificate that is not a valid DCC is not issued
    signature = None
    if signer is not None:
        from .sign import sign_dcc

        xml, signature = sign_dcc(xml, signer)
    (folder / XML_NAME).write_bytes(xml)
    (folder / PDF_NAME).write_bytes(render_pdf(content, folder, signature=signature))


def _check_free(folder: Path, overwrite: bool) -> None:
    if folder.exists() and not overwrite:
        raise ConfigError(
            f"{folder} exists: a certificate folder is never replaced unless --overwrite is given"
        )
    if folder.exists() and not folder.is_dir():
        raise ConfigError(f"{folder} exists and is not a folder; choose another --out")


def _swap_in(staging: Path, folder: Path, overwrite: bool) -> Path | None:
    """Rename the finished ``staging`` folder to ``folder``. An existing one (``overwrite``) is
    moved aside first; its place is returned, to be removed by :func:`_discard` once the new
    certificate is kept, or put back by :func:`_swap_back`."""
    _check_free(folder, overwrite)
    old = None
    if folder.exists():
        old = Path(tempfile.mkdtemp(prefix=f".{folder.name}.old-", dir=folder.parent))
        os.rename(folder, old / "certificate")
    try:
        os.rename(staging, folder)
    except OSError:
        if old is not None:  # put the old certificate back
            os.rename(old / "certificate", folder)
        raise
    return old


def _swap_back(staging: Path, folder: Path, old: Path | None) -> None:
    """Undo :func:`_swap_in`: the new folder back to ``staging``, the old one back in place."""
    os.rename(folder, staging)
    if old is not None:
        os.rename(old / "certificate", folder)
        shutil.rmtree(old, ignore_errors=True)


def _discard(old: Path | None) -> None:
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


class Registry(Protocol):
    """Where issued certificates are kept and numbers drawn (the records store,
    :class:`rotacal.records.Store`); :func:`certify` asks it at each step."""

    def check_plan(self, plan: Plan) -> None:
        """Refuse a plan whose number is taken or whose ``supersedes`` is not usable."""

    def check_unissued(self, plan: Plan, plan_sha256: str) -> None:
        """Refuse a plan and captures that were certified already."""

    def draw_number(self, issue_date: dt.date, *, plan: Plan | None = None) -> str:
        """The next number of the series (drawn for ``plan``: its draft in the audit trail)."""
        ...

    def void_number(self, number: str, reason: str) -> None:
        """Keep a drawn, unused number out of the series, with the reason."""

    def keep(
        self, content: CertificateContent, files: Mapping[str, bytes]
    ) -> contextlib.AbstractContextManager[None]:
        """One transaction that keeps the certificate; committed when the block succeeds."""
        ...


def plan_measurement_count(plan_path: str | Path) -> int:
    """How many measurements a plan names (for a progress bar; 0 when it cannot be read — the
    certification that follows then says why)."""
    try:
        return len(read_plan(plan_path).measurements)
    except RotacalError:
        return 0


def _folder_files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


def certify(
    plan_path: str | Path,
    *,
    out: str | Path | None = None,
    overwrite: bool = False,
    advance: Callable[[str], None] | None = None,
    registry: Registry | None = None,
    into: str | Path | None = None,
    staging_in: str | Path | None = None,
    signer: Signer | None = None,
) -> IssuedCertificate:
    """Run a plan's measurements and issue its certificate (INTERFACE.md, ``rotacal certify``).

    Parameters
    ----------
    plan_path : str or Path
        The plan file (TOML).
    out : str or Path, optional
        The certificate's folder [default: a folder named after the certificate number, beside
        the plan].
    overwrite : bool
        Replace an existing certificate folder.
    advance : callable, optional
        Called with each measurement's name when it is done (a progress bar).
    registry : Registry, optional
        The records store that draws ``number = "auto"`` and keeps the certificate, in the same
        step that publishes its folder (:func:`rotacal.records.open_store`). Without one the
        certificate is not recorded, and the plan must give its number.
    into : str or Path, optional
        Without ``out``: the folder to make the certificate's folder in, named after its number
        [default: the plan's folder] (``rotacal batch --out``).
    staging_in : str or Path, optional
        Where the hidden staging folder is made [default: the certificate folder's parent]; it
        must be on the same file system as the certificate folder.
    signer : Signer, optional
        Sign certificate.xml (XAdES-BES, :func:`rotacal.certificate.sign.load_signer`); its
        certificate must be valid on the date of issue [default: unsigned].

    Returns
    -------
    IssuedCertificate

    Raises
    ------
    ConfigError, CaptureError, StoreError
        One line naming the plan file, the key, the capture or the store at fault; nothing is
        written and nothing recorded.
    """
    plan = read_plan(plan_path)
    if signer is not None:  # refused before anything is measured or a number drawn
        signer.check_valid_on(plan.issue_date)
    if registry is not None:
        registry.check_plan(plan)
    elif plan.number == "auto":
        raise ConfigError(
            f'{plan.path}: certificate.number: "auto" draws the next number from the records '
            "store; give the number, or let the certificate be recorded (without --no-record)"
        )
    home = Path(into).resolve() if into is not None else plan.path.parent
    target = Path(out).resolve() if out is not None else None
    if target is None and plan.number != "auto":
        target = home / plan.number
    if target is not None:
        _check_free(target, overwrite)
    parent = target.parent if target is not None else home
    if not parent.is_dir():
        raise ConfigError(f"{parent}: no such folder for the certificate")
    staging = new_staging(Path(staging_in) if staging_in is not None else parent)
    try:
        content = measure_into(plan, staging, advance)
        if registry is not None:
            registry.check_unissued(plan, content.plan_sha256)
        number = plan.number
        if number == "auto":
            assert registry is not None
            number = registry.draw_number(plan.issue_date, plan=plan)
        try:
            folder = target if target is not None else home / number
            _check_free(folder, overwrite)
            content = render_into(content, number, staging, signer)
            publish(content, staging, folder, registry, overwrite=overwrite)
        except BaseException as e:
            if plan.number == "auto" and registry is not None:
                with contextlib.suppress(RotacalError):  # the store may be what failed
                    registry.void_number(number, f"not issued: {type(e).__name__}: {e}")
            raise
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return IssuedCertificate(number, folder, content)


# -- the steps of an issue, for certify() and for batches that run them on other machines ---------
#: The name every staging folder starts with (hidden; a batch removes those its killed workers left).
STAGING_PREFIX = ".rotacal-certify-"


def new_staging(parent: Path) -> Path:
    """A new, empty, hidden staging folder in ``parent`` (on the certificate folder's file
    system, so that publishing it is one ``rename``)."""
    return Path(tempfile.mkdtemp(prefix=STAGING_PREFIX, dir=parent))


def measure_into(
    plan: Plan, staging: Path, advance: Callable[[str], None] | None = None
) -> CertificateContent:
    """Run ``plan``'s measurements and draw their figures into ``staging``: the certificate's
    content under the plan's number (``"auto"`` until one is drawn); ``plan_sha256`` is known."""
    from rotacal import __version__

    scratch = staging / ".runs"
    scratch.mkdir()
    runs = run_plan(plan, scratch, advance)
    shutil.rmtree(scratch)
    return _draw(build_content(plan, runs, plan.number, __version__), staging)


def render_into(
    content: CertificateContent, number: str, staging: Path, signer: Signer | None = None
) -> CertificateContent:
    """Give the measured ``content`` its ``number`` and write results.json, certificate.xml
    (signed with ``signer``) and certificate.pdf into ``staging`` (beside the figures
    :func:`measure_into` drew)."""
    content = dataclasses.replace(content, number=number)
    _render(content, staging, signer)
    return content


def publish(
    content: CertificateContent,
    staging: Path,
    folder: Path,
    registry: Registry | None,
    *,
    overwrite: bool = False,
) -> None:
    """Put the rendered ``staging`` folder in place as ``folder`` and, with a ``registry``, keep
    the certificate in the records in the same step (the folder is taken back if the record's
    transaction does not commit)."""
    if registry is None:
        _discard(_swap_in(staging, folder, overwrite))
    else:
        _keep(registry, content, staging, folder, overwrite)


def _keep(
    registry: Registry, content: CertificateContent, staging: Path, folder: Path, overwrite: bool
) -> None:
    """Record the certificate and publish its folder as one step: the folder is put in place
    inside the store's transaction and taken back if the transaction does not commit."""
    files = _folder_files(staging)
    old: Path | None = None
    published = False
    try:
        with registry.keep(content, files):
            old = _swap_in(staging, folder, overwrite)
            published = True
    except BaseException:
        if published:
            _swap_back(staging, folder, old)
        raise
    _discard(old)
