"""Verifying a certificate as its receiver would: ``rotacal verify``.

:func:`verify_certificate` takes a certificate folder (or its ``certificate.xml``) and checks, in
this order, everything a customer's incoming inspection can check without calling the laboratory:

1. the XML Signature (XAdES-BES) over the whole DCC, with the certificate it embeds: every
   reference's digest, the signature value, that the embedded certificate is the one the signed
   properties name (``xades:SigningCertificateV2``), that it was valid at the signed
   ``xades:SigningTime`` — and, with a trust anchor, that it chains to it (signxml's verifier,
   with cryptography's path validation at the signing time);
2. the DCC against the DCC v3.1.2 schema with the XML Signature schema;
3. that ``results.json`` states what the signed XML states — read from the content the
   signature covers (signxml's ``signed_xml``), never from the file as parsed, which may hold a
   second copy inside ``ds:Signature`` or a comment inside a value that no digest covers (both
   named as problems): the certificate number, the ``plan_sha256``, the item's serial and
   model, the dates, every reported value, unit, U, k and coverage probability (or interval)
   and every verdict of conformity;
4. where the plan and its captures can be reached (beside the certificate folder, or ``plan``):
   the SHA-256 of each against the certificate's, and the signed ``plan_sha256`` recomputed from
   the plan's bytes and the capture hashes;
5. with ``recompute``: the plan's measurements run again from its captures, and every number of
   every result and ``plan_sha256`` compared with the certificate's.

Each failure is a line in ``problems`` that names what failed (the element and its two values,
the capture whose hash differs); what could not be checked (captures not reachable, no trust
anchor given) is a line in ``notes`` and no failure.

References
----------
W3C, XML Signature Syntax and Processing 1.1 (2013), §3.2 (core validation); ETSI EN 319 102-1
V1.1.1 (2016), §5 (validation of a basic signature: format, identification of the signing
certificate, X.509 validation at the signing time, cryptographic verification); ETSI EN 319 132-1
§5.2.2 (SigningCertificateV2); PTB, DCC schema v3.1.2.
"""

from __future__ import annotations

import base64
import dataclasses
import datetime as dt
import hashlib
import json
import math
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

from lxml import etree

from rotacal.errors import ConfigError

from .dcc import DCC_NAMESPACE, SCHEMA_VERSION, SI_NAMESPACE, quantity_id
from .sign import DS_NAMESPACE, signer_name, validate_signed_dcc

__all__ = ["Verification", "verify_certificate"]

_NS = {"dcc": DCC_NAMESPACE, "si": SI_NAMESPACE, "ds": DS_NAMESPACE}
_XADES = "{http://uri.etsi.org/01903/v1.3.2#}"
#: The relative tolerance of the comparison of recomputed results with the certificate's: the
#: NumPy and Numba paths agree to 1e-12, so anything beyond 1e-9 is a different result.
RECOMPUTE_RTOL = 1e-9


@dataclasses.dataclass(frozen=True)
class Verification:
    """What :func:`verify_certificate` found (INTERFACE.md, ``rotacal verify``)."""

    path: Path
    number: str
    signed: bool
    signature_valid: bool
    signer: dict[str, Any] | None
    schema_valid: bool
    consistent: bool
    recomputed: bool | None
    problems: tuple[str, ...]
    notes: tuple[str, ...]
    inputs_checked: int
    pdf_matches: bool | None = None

    @property
    def ok(self) -> bool:
        """Every check made holds."""
        return not self.problems

    def to_dict(self) -> dict[str, Any]:
        return {
            "certificate": str(self.path),
            "certificate_number": self.number,
            "signed": self.signed,
            "signature_valid": self.signature_valid,
            "signer": self.signer,
            "trusted": bool(self.signer and self.signer["trusted"]),
            "schema_valid": self.schema_valid,
            "consistent": self.consistent,
            "recomputed": self.recomputed,
            "inputs_checked": self.inputs_checked,
            "pdf_matches": self.pdf_matches,
            "problems": list(self.problems),
            "notes": list(self.notes),
        }

    def verdict(self) -> str:
        """The one line ``rotacal verify`` prints."""
        head = f"{self.path} (certificate {self.number or '?'})"
        if self.problems:
            return f"{head}: NOT VERIFIED — " + "; ".join(self.problems)
        assert self.signer is not None
        # without a trust anchor anyone's key verifies: the line must not read as trusted
        trusted = self.signer["trusted"]
        trust = (
            "trusted through --trust"
            if trusted
            else "UNTRUSTED: not checked against a trust anchor, give --trust"
        )
        parts = [
            f"signed by {self.signer['name']} (certificate SHA-256 "
            f"{self.signer['fingerprint_sha256'][:16]}…, {trust})",
            "signature valid",
            f"valid DCC {SCHEMA_VERSION}",
            "results.json agrees",
        ]
        if self.pdf_matches:
            parts.append("certificate.pdf names this certificate.xml")
        if self.inputs_checked:
            parts.append(f"plan and captures match ({self.inputs_checked} files)")
        if self.recomputed:
            parts.append("recomputed: every number and plan_sha256 the same")
        verdict = "VERIFIED" if trusted else "VERIFIED, SIGNER UNTRUSTED"
        return f"{head}: {verdict} — " + ", ".join(parts)


# --- input ------------------------------------------------------------------------------------


def _locate(path: Path) -> tuple[Path, Path]:
    """(the certificate's folder, its certificate.xml) of a folder or an XML path."""
    if path.is_dir():
        xml = path / "certificate.xml"
        if not xml.is_file():
            raise ConfigError(
                f"{path}: no certificate.xml in this folder; give a certificate folder"
            )
        return path, xml
    if not path.exists():
        raise ConfigError(f"{path}: no such file or folder")
    return path.parent, path


def _read_xml(xml_path: Path) -> tuple[bytes, etree._Element]:
    try:
        data = xml_path.read_bytes()
    except OSError as e:
        raise ConfigError(f"{xml_path}: cannot be read ({e.strerror})") from None
    # a DCC declares no DTD: one that does is refused before any parser expands or fetches its
    # entities (entity expansion, "billion laughs"; external entities, XXE)
    refused = (
        f"{xml_path}: declares a DOCTYPE (a DTD with entities: entity expansion or an external "
        "entity); a DCC has none, so it is refused unread"
    )
    if b"<!DOCTYPE" in data:
        raise ConfigError(refused)
    try:
        root = etree.fromstring(data, etree.XMLParser(resolve_entities=False, no_network=True))
    except etree.XMLSyntaxError as e:
        raise ConfigError(f"{xml_path}: not well-formed XML ({e})") from None
    docinfo = root.getroottree().docinfo
    if docinfo.internalDTD is not None or docinfo.externalDTD is not None or docinfo.doctype:
        raise ConfigError(refused)  # a DOCTYPE in another encoding than the bytes searched
    if root.tag != f"{{{DCC_NAMESPACE}}}digitalCalibrationCertificate":
        raise ConfigError(f"{xml_path}: not a Digital Calibration Certificate (root {root.tag})")
    return data, root


# --- 1. the signature -------------------------------------------------------------------------


def _load_trust(trust: Path) -> list[Any]:
    from cryptography import x509

    try:
        certs = x509.load_pem_x509_certificates(trust.read_bytes())
    except OSError as e:
        raise ConfigError(f"--trust {trust}: cannot be read ({e.strerror})") from None
    except ValueError:
        raise ConfigError(f"--trust {trust}: not a PEM X.509 certificate") from None
    return list(certs)


def _embedded(signature: etree._Element) -> Any:
    from cryptography import x509

    text = signature.findtext("ds:KeyInfo/ds:X509Data/ds:X509Certificate", namespaces=_NS)
    if not text:
        return None
    try:
        return x509.load_der_x509_certificate(base64.b64decode("".join(text.split())))
    except ValueError:
        return None


def _signer(cert: Any, signing_time: dt.datetime | None, trusted: bool) -> dict[str, Any]:
    from cryptography.hazmat.primitives import hashes

    return {
        "name": signer_name(cert),
        "subject": cert.subject.rfc4514_string(),
        "issuer": cert.issuer.rfc4514_string(),
        "serial_number": format(cert.serial_number, "x"),
        "fingerprint_sha256": cert.fingerprint(hashes.SHA256()).hex(),
        "not_valid_before": cert.not_valid_before_utc.isoformat(),
        "not_valid_after": cert.not_valid_after_utc.isoformat(),
        "signing_time": signing_time.isoformat() if signing_time else None,
        "trusted": trusted,
    }


def _signing_time(signature: etree._Element) -> dt.datetime | None:
    text = signature.findtext(f".//{_XADES}SigningTime")
    try:
        when = dt.datetime.fromisoformat((text or "").strip().replace("Z", "+00:00"))
    except ValueError:
        return None
    return when if when.tzinfo else when.replace(tzinfo=dt.timezone.utc)


def _names_embedded(signature: etree._Element, cert: Any) -> bool:
    """Whether the signed properties' SigningCertificateV2 digest is the embedded certificate's."""
    from cryptography.hazmat.primitives import hashes

    algorithms = {
        "http://www.w3.org/2001/04/xmlenc#sha256": hashes.SHA256(),
        "http://www.w3.org/2001/04/xmldsig-more#sha384": hashes.SHA384(),
        "http://www.w3.org/2001/04/xmlenc#sha512": hashes.SHA512(),
    }
    digest = signature.find(f".//{_XADES}SigningCertificateV2/{_XADES}Cert/{_XADES}CertDigest")
    if digest is None:
        return False
    method = digest.find("ds:DigestMethod", namespaces=_NS)
    algorithm = algorithms.get(method.get("Algorithm", "") if method is not None else "")
    value = digest.findtext("ds:DigestValue", namespaces=_NS) or ""
    return algorithm is not None and base64.b64decode(value) == cert.fingerprint(algorithm)


def _check_signature(
    data: bytes, root: etree._Element, trust: Path | None, problems: list[str], notes: list[str]
) -> tuple[bool, dict[str, Any] | None, etree._Element | None]:
    """(signed, signer, the signed DCC) of the DCC; failures appended to ``problems``.

    The signed DCC is the content the signature's digest covers, as signxml returns it
    (``VerifyResult.signed_xml``: parsed again from the canonical bytes that were digested, so it
    holds neither the ``ds:Signature`` nor comments); None unless the signature is valid.
    """
    from cryptography.hazmat.primitives.serialization import Encoding
    from signxml.exceptions import InvalidCertificate, InvalidDigest, SignXMLException
    from signxml.xades import XAdESSignatureConfiguration, XAdESVerifier

    anchors = _load_trust(trust) if trust is not None else []
    signatures = root.findall(".//ds:Signature", namespaces=_NS)
    if not signatures:
        problems.append("certificate.xml carries no signature (no ds:Signature): it is unsigned")
        return False, None, None
    if len(signatures) > 1:
        problems.append(f"certificate.xml carries {len(signatures)} signatures; one is expected")
        return True, None, None
    signature = signatures[0]
    cert = _embedded(signature)
    if cert is None:
        problems.append("the signature embeds no readable signer certificate (ds:X509Certificate)")
        return True, None, None
    when = _signing_time(signature)
    pinned = any(a.public_bytes(Encoding.DER) == cert.public_bytes(Encoding.DER) for a in anchors)
    info = _signer(cert, when, trusted=False)  # trusted once the chain to --trust is checked
    who = (
        f"the embedded certificate (CN={info['name']}, SHA-256 {info['fingerprint_sha256'][:16]}…)"
    )
    if when is None:
        problems.append("the signature has no readable xades:SigningTime")
        return True, info, None
    if not _names_embedded(signature, cert):
        problems.append(
            f"{who} is not the certificate the signed properties name "
            "(xades:SigningCertificateV2): the embedded certificate was replaced"
        )
        return True, info, None
    if not cert.not_valid_before_utc <= when <= cert.not_valid_after_utc:
        problems.append(
            f"{who} was not valid at the signing time {when.isoformat()} (valid "
            f"{info['not_valid_before']} to {info['not_valid_after']})"
        )
        return True, info, None
    config = XAdESSignatureConfiguration(verification_time=when)
    try:
        if anchors and not pinned:
            with tempfile.NamedTemporaryFile(suffix=".pem") as store:
                store.write(b"".join(a.public_bytes(Encoding.PEM) for a in anchors))
                store.flush()
                results = XAdESVerifier().verify(data, ca_pem_file=store.name, expect_config=config)
        else:
            results = XAdESVerifier().verify(data, x509_cert=cert, expect_config=config)
    except InvalidDigest as e:
        problems.append(_digest_problem(str(e)))
        return True, info, None
    except InvalidCertificate as e:
        why = " ".join(str(e).split()).split(". Use SignatureConfiguration")[0]
        problems.append(f"{who} does not chain to --trust {trust}: {why}")
        return True, info, None
    except SignXMLException as e:
        problems.append(f"the signature does not verify with {who}: {' '.join(str(e).split())}")
        return True, info, None
    signed = _whole_document(signature, results, root)
    if signed is None:
        problems.append(
            "the signature does not cover the whole certificate: no reference is the document "
            '(URI="" with the enveloped-signature transform), so what it covers is not what is read'
        )
        return True, info, None
    info["trusted"] = bool(anchors)
    if not anchors:
        notes.append("the signer's certificate was not checked against a trust anchor (--trust)")
    return True, info, signed


def _whole_document(
    signature: etree._Element, results: list[Any], root: etree._Element
) -> etree._Element | None:
    """The signed DCC of a verified signature: the content of its reference with ``URI=""`` and
    the enveloped-signature transform (W3C XML Signature 1.1 §4.4.3.2, §6.6.4), when that content
    is the DCC's root; None when no reference is the whole document.

    The numbers are read from this content and not from the parsed file: the file may also hold
    what the digest does not cover — a copy of the results inside ``ds:Signature`` (which the
    enveloped transform removes), or a comment that cuts a value's text in two (which the
    canonicalisation of a same-document reference drops, so ``0.01<!---->25`` is signed as
    ``0.0125`` while a reader of the element's first text node sees ``0.01``).
    """
    references = signature.findall("ds:SignedInfo/ds:Reference", namespaces=_NS)
    enveloped = "http://www.w3.org/2000/09/xmldsig#enveloped-signature"
    for reference, result in zip(references, results, strict=False):
        algorithms = [
            t.get("Algorithm") for t in reference.findall("ds:Transforms/ds:Transform", _NS)
        ]
        content = result.signed_xml
        if (
            reference.get("URI") == ""
            and enveloped in algorithms
            and content is not None
            and content.tag == root.tag
        ):
            return content
    return None


_SIGNATURE_NAMESPACES = (DS_NAMESPACE, _XADES[1:-1], "http://www.w3.org/2009/xmldsig11#")


def _uncovered(root: etree._Element) -> list[str]:
    """What the file holds that no signature covers and a reader might take for the DCC's: a
    comment (dropped by the canonicalisation, it can cut a value's text in two) or an element of
    another namespace inside ``ds:Signature`` (removed by the enveloped transform: a copy of the
    results placed there is the XML signature wrapping attack). rotacal writes neither."""
    out = [
        f"certificate.xml holds a comment on line {c.sourceline}, which the signature does not "
        "cover (a comment inside a value makes a reader of its text see another number)"
        for c in root.iter(etree.Comment)
    ][:1]
    for signature in root.iterfind(".//ds:Signature", namespaces=_NS):
        foreign = [
            e
            for e in signature.iter()
            if isinstance(e.tag, str) and etree.QName(e).namespace not in _SIGNATURE_NAMESPACES
        ]
        if foreign:
            out.append(
                f"certificate.xml holds {etree.QName(foreign[0]).localname} (line "
                f"{foreign[0].sourceline}) inside ds:Signature, where the signature does not cover "
                "it: an XML signature wrapping attempt"
            )
    return out


def _digest_problem(message: str) -> str:
    if "reference 0" in message or "reference" not in message:
        return (
            "the signed content of certificate.xml was changed after signing (the digest of "
            "the document differs from the signed one)"
        )
    return f"the signed properties or key information were changed after signing ({message})"


def _check_pdf(folder: Path, data: bytes, problems: list[str], notes: list[str]) -> bool | None:
    """Whether certificate.pdf names the SHA-256 of this certificate.xml (a signed certificate's
    PDF carries it on its last page and in its XMP metadata, which PDF/A keeps uncompressed)."""
    pdf = folder / "certificate.pdf"
    if not pdf.is_file():
        notes.append("no certificate.pdf beside certificate.xml: the PDF was not checked")
        return None
    digest = hashlib.sha256(data).hexdigest()
    if digest.encode("ascii") in pdf.read_bytes():
        return True
    problems.append(
        f"certificate.pdf does not name the SHA-256 of this certificate.xml ({digest[:16]}…): "
        "the PDF belongs to another certificate.xml, or one of them was changed"
    )
    return False


# --- 3. results.json against the XML ----------------------------------------------------------


def _numbers_equal(xml_text: str | None, value: Any) -> bool:
    if xml_text is None or value is None:
        return xml_text is None and value is None
    try:
        return float(xml_text) == float(value)
    except (TypeError, ValueError):
        return False


def _agreement(root: etree._Element, doc: Mapping[str, Any]) -> list[str]:
    """Every disagreement of results.json with the XML, one line each (naming the element)."""
    out = []
    number = root.findtext(
        "dcc:administrativeData/dcc:coreData/dcc:uniqueIdentifier", namespaces=_NS
    )
    if number != doc.get("certificate_number"):
        out.append(
            f"dcc:uniqueIdentifier {number!r} in certificate.xml, certificate_number "
            f"{doc.get('certificate_number')!r} in results.json"
        )
    ids = root.xpath(
        "dcc:administrativeData/dcc:coreData/dcc:identifications/dcc:identification/dcc:value/text()",
        namespaces=_NS,
    )
    if doc.get("plan_sha256") not in ids:
        out.append(
            f"plan_sha256 {doc.get('plan_sha256')} of results.json is not the one certificate.xml "
            "states"
        )
    core, item = (
        "dcc:administrativeData/dcc:coreData/",
        "dcc:administrativeData/dcc:items/dcc:item/",
    )
    serial = "dcc:identifications/dcc:identification[dcc:issuer='manufacturer']/dcc:value"
    for path, stated, name in (  # what says which unit, and when it was calibrated
        (item + serial, doc.get("item", {}).get("serial"), "item.serial"),
        (item + "dcc:model", doc.get("item", {}).get("model"), "item.model"),
        (
            core + "dcc:beginPerformanceDate",
            doc.get("calibration_start_date"),
            "calibration_start_date",
        ),
        (core + "dcc:endPerformanceDate", doc.get("calibration_end_date"), "calibration_end_date"),
    ):
        xml = root.findtext(path, namespaces=_NS)
        if xml != stated:
            element = path.rsplit("/", 1)[-1] if "[" not in path else "the item's serial number"
            out.append(f"{element} {xml!r} in certificate.xml, {name} {stated!r} in results.json")
    reals = {
        q.get("id"): q.find("si:real", namespaces=_NS)
        for q in root.iterfind(
            "dcc:measurementResults/dcc:measurementResult/dcc:results/dcc:result/dcc:data/"
            "dcc:quantity",
            namespaces=_NS,
        )
    }
    seen = set()
    for index, m in enumerate(doc.get("measurements", []), start=1):
        for q in m.get("reported", []):
            qid = quantity_id(index, str(q.get("quantity")))
            seen.add(qid)
            real = reals.get(qid)
            if real is None:
                out.append(f"{qid}: in results.json but not in certificate.xml")
                continue
            out += _real_agreement(qid, real, q)
    out += [
        f"{qid}: in certificate.xml but not in results.json" for qid in reals if qid not in seen
    ]
    return out + _conformity_agreement(root, doc)


def _conformity_agreement(root: etree._Element, doc: Mapping[str, Any]) -> list[str]:
    """Every statement of conformity results.json and the XML do not share: the verdicts of
    results.json against the ``dcc:conformity`` of the XML's statements (``refId`` → quantity),
    ILAC-G8's conditional pass / fail standing for an indeterminate verdict (see
    :func:`rotacal.certificate.dcc.dcc_conformity`)."""
    said = {"pass": "pass", "fail": "fail", "conditionalPass": "indeterminate"}
    said["conditionalFail"] = "indeterminate"
    xml = {
        s.get("refId"): said.get(s.findtext("dcc:conformity", namespaces=_NS) or "", "?")
        for s in root.iterfind(
            "dcc:administrativeData/dcc:statements/dcc:statement[dcc:conformity]", namespaces=_NS
        )
    }
    json_ = {
        quantity_id(index, str(key)): verdict
        for index, m in enumerate(doc.get("measurements", []), start=1)
        for key, verdict in (m.get("conformity") or {}).items()
    }
    return [
        f"{qid} conformity: {xml.get(qid, 'no statement')} in certificate.xml, "
        f"{json_.get(qid, 'no verdict')} in results.json"
        for qid in sorted(set(xml) | set(json_), key=str)
        if xml.get(qid) != json_.get(qid)
    ]


def _real_agreement(qid: str, real: etree._Element, q: Mapping[str, Any]) -> list[str]:
    def text(path: str) -> str | None:
        return real.findtext(path, namespaces=_NS)

    pairs: list[tuple[str, str | None, Any]] = [("si:value", text("si:value"), q.get("value"))]
    if q.get("interval") is None:
        pairs += [
            ("si:expandedUnc/si:uncertainty", text("si:expandedUnc/si:uncertainty"), q.get("U")),
            (
                "si:expandedUnc/si:coverageFactor",
                text("si:expandedUnc/si:coverageFactor"),
                q.get("k"),
            ),
            (
                "si:expandedUnc/si:coverageProbability",
                text("si:expandedUnc/si:coverageProbability"),
                q.get("coverage_probability"),
            ),
        ]
    else:
        low, high = q["interval"]
        pairs += [
            ("si:coverageInterval/si:intervalMin", text("si:coverageInterval/si:intervalMin"), low),
            (
                "si:coverageInterval/si:intervalMax",
                text("si:coverageInterval/si:intervalMax"),
                high,
            ),
        ]
    out = [
        f"{qid} {element}: {xml} in certificate.xml, {value} in results.json"
        for element, xml, value in pairs
        if not _numbers_equal(xml, value)
    ]
    if text("si:unit") != q.get("dsi_unit"):
        out.append(
            f"{qid} si:unit: {text('si:unit')} in certificate.xml, {q.get('dsi_unit')} in results.json"
        )
    return out


# --- 4. the plan and the captures ---------------------------------------------------------------


def _sha256_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _find_plan(doc: Mapping[str, Any], folder: Path, plan: Path | None) -> Path | None:
    if plan is not None:
        if not plan.is_file():
            raise ConfigError(f"--plan {plan}: no such file")
        return plan
    inputs = doc.get("provenance", {}).get("inputs", [])
    name = inputs[0].get("path") if inputs else None
    if not name:
        return None
    for candidate in (folder.parent / name, folder / name):
        if candidate.is_file():
            return candidate
    return None


def _captures(doc: Mapping[str, Any]) -> Iterator[tuple[int, Mapping[str, Any]]]:
    for index, m in enumerate(doc.get("measurements", []), start=1):
        for c in m.get("captures", []):
            yield index, c


def _check_inputs(
    doc: Mapping[str, Any],
    xml_plan_sha256: set[str],
    plan: Path | None,
    problems: list[str],
    notes: list[str],
) -> int:
    """Hash the plan and the captures that can be reached; the number of files checked."""
    from .issue import plan_sha256

    if plan is None:
        notes.append("the plan is not beside the certificate folder (--plan): inputs not checked")
        return 0
    inputs = doc.get("provenance", {}).get("inputs", [])
    stated = inputs[0].get("sha256") if inputs else None
    plan_bytes = plan.read_bytes()
    checked = 1
    if hashlib.sha256(plan_bytes).hexdigest() != stated:
        problems.append(
            f"plan {plan}: its SHA-256 differs from the certificate's: the plan changed"
        )
    digests, missing = [], []
    for index, c in _captures(doc):
        path = plan.parent / str(c.get("path"))
        digests.append(str(c.get("sha256")))
        if not path.is_file():
            missing.append(str(c.get("path")))
            continue
        checked += 1
        if _sha256_file(path) != c.get("sha256"):
            problems.append(
                f"capture {c.get('path')} (measurement {index}): its SHA-256 differs from the "
                "certificate's: the capture changed"
            )
    if missing:
        notes.append(f"captures not reachable beside the plan, not checked: {', '.join(missing)}")
    if plan_sha256(plan_bytes, digests) not in xml_plan_sha256:
        problems.append(
            "plan_sha256: the plan's bytes and the capture hashes of results.json do not give "
            "the signed plan_sha256 of certificate.xml"
        )
    return checked


# --- 5. recompute -------------------------------------------------------------------------------


def _differences(now: Any, then: Any, where: str) -> Iterator[str]:
    """Where two JSON values differ (numbers within :data:`RECOMPUTE_RTOL`)."""
    if isinstance(now, Mapping) and isinstance(then, Mapping):
        for key in sorted(set(now) | set(then)):
            if key == "rotacal_version":  # the version that verifies may be a later one
                continue
            if key not in now or key not in then:
                yield f"{where}.{key}: only in the {'recomputation' if key in now else 'certificate'}"
                continue
            yield from _differences(now[key], then[key], f"{where}.{key}")
    elif isinstance(now, list) and isinstance(then, list):
        if len(now) != len(then):
            yield f"{where}: {len(now)} values now, {len(then)} in the certificate"
            return
        for i, (a, b) in enumerate(zip(now, then, strict=True)):
            yield from _differences(a, b, f"{where}[{i}]")
    elif (
        isinstance(now, (int, float))
        and isinstance(then, (int, float))
        and not (isinstance(now, bool) or isinstance(then, bool))
    ):
        if not math.isclose(now, then, rel_tol=RECOMPUTE_RTOL, abs_tol=0.0) and not (
            now != now and then != then
        ):
            yield f"{where}: {now!r} now, {then!r} in the certificate"
    elif now != then:
        yield f"{where}: {now!r} now, {then!r} in the certificate"


def _recompute(doc: Mapping[str, Any], plan: Path | None, problems: list[str]) -> bool:
    from rotacal import __version__
    from rotacal.plan.read import read_plan
    from rotacal.plan.run import run_plan

    from .issue import build_content, results_document

    if plan is None:
        raise ConfigError(
            "--recompute needs the plan and its captures: the plan is not beside the certificate "
            "folder; give it with --plan"
        )
    parsed = read_plan(plan)
    with tempfile.TemporaryDirectory(prefix="rotacal-verify-") as scratch:
        runs = run_plan(parsed, Path(scratch))
    content = build_content(parsed, runs, str(doc.get("certificate_number")), __version__)
    found = []
    if content.plan_sha256 != doc.get("plan_sha256"):
        found.append(
            f"plan_sha256 {content.plan_sha256} recomputed, {doc.get('plan_sha256')} in the "
            "certificate"
        )
    now = results_document(content)["measurements"]
    then = doc.get("measurements", [])
    keep = ("name", "command", "reported", "conformity", "results")
    for i, (a, b) in enumerate(zip(now, then, strict=False), start=1):
        for key in keep:
            found += list(_differences(a.get(key), b.get(key), f"measurement {i} {key}"))
    if len(now) != len(then):
        found.append(f"{len(now)} measurements recomputed, {len(then)} in the certificate")
    if found:
        more = f" (and {len(found) - 3} more)" if len(found) > 3 else ""
        problems.append("recomputed from the plan: " + "; ".join(found[:3]) + more)
    return not found


# --- the whole check ----------------------------------------------------------------------------


def verify_certificate(
    path: str | Path,
    *,
    trust: str | Path | None = None,
    recompute: bool = False,
    plan: str | Path | None = None,
) -> Verification:
    """Verify a certificate folder or its ``certificate.xml`` (see the module's text).

    Parameters
    ----------
    path : str or Path
        The certificate folder, or its certificate.xml (results.json is read beside it).
    trust : str or Path, optional
        PEM file of the certificates to trust: the signer's certificate must be one of them or
        chain to one of them, at the signing time.
    recompute : bool
        Run the plan's measurements again from its captures and compare every number.
    plan : str or Path, optional
        The plan file [default: the plan named by results.json, beside the certificate folder or
        in it].

    Returns
    -------
    Verification

    Raises
    ------
    ConfigError
        When the input cannot be used at all: no such path, not a DCC, not well-formed, an
        unreadable --trust, --recompute without a reachable plan.
    """
    folder, xml_path = _locate(Path(path))
    data, root = _read_xml(xml_path)
    problems: list[str] = []
    notes: list[str] = []
    signed, signer, signed_root = _check_signature(
        data, root, Path(trust) if trust is not None else None, problems, notes
    )
    problems += _uncovered(root)
    # what is compared is what the signature covers; an unsigned or broken one: the file as read
    content = root if signed_root is None else signed_root
    pdf_matches = _check_pdf(folder, data, problems, notes) if signed else None
    fault = validate_signed_dcc(data)
    if fault is not None:
        problems.append(
            f"certificate.xml is not valid against the DCC {SCHEMA_VERSION} schema: {fault}"
        )
    number = (
        content.findtext("dcc:administrativeData/dcc:coreData/dcc:uniqueIdentifier", namespaces=_NS)
        or ""
    )
    results = folder / "results.json"
    consistent, recomputed, checked = False, None, 0
    try:
        doc = json.loads(results.read_text(encoding="utf-8"))
    except FileNotFoundError:
        problems.append(f"{results}: missing, so results.json and certificate.xml cannot agree")
    except (OSError, ValueError) as e:
        problems.append(f"{results}: cannot be read as JSON ({' '.join(str(e).split())})")
    else:
        disagreements = _agreement(content, doc)
        consistent = not disagreements
        if disagreements:
            more = f" (and {len(disagreements) - 3} more)" if len(disagreements) > 3 else ""
            problems.append(
                "results.json and certificate.xml disagree: " + "; ".join(disagreements[:3]) + more
            )
        stated = set(
            content.xpath(
                "dcc:administrativeData/dcc:coreData/dcc:identifications/dcc:identification/"
                "dcc:value/text()",
                namespaces=_NS,
            )
        )
        found = _find_plan(doc, folder, Path(plan) if plan is not None else None)
        checked = _check_inputs(doc, stated, found, problems, notes)
        if recompute:
            recomputed = _recompute(doc, found, problems)
        else:  # what the DCC does not state cannot be checked against the signature
            notes.append(
                "the analyses' full results in results.json (measurements[].results) are not in "
                "the signed XML: --recompute checks them"
            )
    return Verification(
        path=xml_path,
        number=number,
        signed=signed,
        signature_valid=signed_root is not None,
        signer=signer,
        schema_valid=fault is None,
        consistent=consistent,
        recomputed=recomputed,
        problems=tuple(problems),
        notes=tuple(notes),
        inputs_checked=checked,
        pdf_matches=pdf_matches,
    )
