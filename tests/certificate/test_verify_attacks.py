"""``rotacal verify`` attacked as a customer's incoming inspection would be: XML signature
wrapping (a second copy of the results where a naive reader looks), a comment that cuts a value,
a signature that covers part of the document, a consistent change of the XML and results.json, a
certificate re-signed with a self-made key (with and without --trust), a DOCTYPE with entities
(XXE, billion laughs), truncated and non-XML files, a folder without results.json, and
--recompute with a capture missing. Every attack must end in exit 1 or 2 with one line naming it;
the untampered certificate verifies (exit 0), so each test can fail for its own reason only."""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest
import tomli_w
import tomllib
from click.testing import CliRunner
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.hazmat.primitives.serialization import Encoding
from lxml import etree

from rotacal.batch.testing import write_twin_plans
from rotacal.certificate.dcc import quantity_id
from rotacal.certificate.sign import DS_NAMESPACE, load_signer, sign_dcc
from rotacal.cli import cli

from .test_signing import make_cert, write_pair

DCC, SI = "https://ptb.de/dcc", "https://ptb.de/si"
NS = {"dcc": DCC, "si": SI}
DS = {"ds": DS_NAMESPACE}
ROOT = "digitalCalibrationCertificate"
FAKE = "9.99"  # what an attacker wants a reader to see


@pytest.fixture(scope="module")
def issued(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """One certificate of a rotation-test twin (the cheapest measurement to run), signed by the
    laboratory's self-signed ECDSA key (its certificate is the trust anchor); a key of Mallory's
    with the same CN; the first reported quantity's id and value as the XML states it."""
    folder = tmp_path_factory.mktemp("attacks")
    [plan] = write_twin_plans(folder, 1, commands=("gyro rotations",))
    data = tomllib.loads(plan.read_text(encoding="utf-8"))
    data["certificate"]["number"] = "RC-2026-0042"  # given: issued without a records store
    data["measurement"][0]["limits"] = {"bias[0]": {"max": -5.0}}  # a unit that fails (≈ 0.5)
    plan.write_text(tomli_w.dumps(data), encoding="utf-8")
    lab_key, mallory_key = (ec.generate_private_key(ec.SECP256R1()) for _ in range(2))
    lab = write_pair(folder, "lab", lab_key, make_cert(lab_key))
    mallory = write_pair(folder, "mallory", mallory_key, make_cert(mallory_key))
    args = ["certify", str(plan), "--no-record", "--sign-key", str(lab[0])]
    result = CliRunner().invoke(cli, [*args, "--sign-cert", str(lab[1])], catch_exceptions=False)
    assert result.exit_code == 0, result.output
    certificate = folder / "RC-2026-0042"
    reported = json.loads((certificate / "results.json").read_text())["measurements"][0]
    ids = [quantity_id(1, q["quantity"]) for q in reported["reported"][:2]]
    xml = (certificate / "certificate.xml").read_text(encoding="utf-8")
    root = etree.fromstring(xml.encode())
    value = root.xpath(f"//dcc:quantity[@id='{ids[0]}']/si:real/si:value/text()", namespaces=NS)[0]
    assert xml.count(f"<si:value>{value}</si:value>") == 1 and FAKE not in xml
    assert reported["conformity"] == {"bias[0]": "fail"}
    return {
        "certificate": certificate,
        "plan": plan,
        "lab": lab,
        "mallory": mallory,
        "id": ids[0],
        "other_id": ids[1],
        "value": value,
    }


@pytest.fixture
def copy(issued: dict[str, Any], tmp_path: Path) -> Path:
    """A copy of the certificate folder with its plan and captures, without its PDF (a receiver
    may get the DCC alone: the PDF's hash must not be what catches an attack)."""
    source, plan = issued["certificate"], issued["plan"]
    shutil.copy(plan, tmp_path / plan.name)
    shutil.copytree(plan.parent / "captures-0000", tmp_path / "captures-0000")
    folder = Path(shutil.copytree(source, tmp_path / source.name))
    (folder / "certificate.pdf").unlink()
    return folder


def _verify(path: Path, *args: str) -> tuple[int, str, dict[str, Any]]:
    """Exit code, the one line printed, and the JSON of ``rotacal verify``."""
    runner = CliRunner()
    shown = runner.invoke(cli, ["verify", str(path), *args])
    found = runner.invoke(cli, ["verify", str(path), *args, "--json", "-"])
    assert shown.exit_code == found.exit_code and shown.exit_code in (0, 1), shown.output
    assert shown.stdout.count("\n") == 1, shown.stdout
    return shown.exit_code, shown.stdout, json.loads(found.stdout)


def _refused(path: Path, *args: str) -> str:
    """The one line of an input ``rotacal verify`` cannot use (exit 2)."""
    result = CliRunner().invoke(cli, ["verify", str(path), *args])
    assert result.exit_code == 2 and result.output.count("\n") == 1, result.output
    assert "Traceback" not in result.output
    return result.output


def _edit(folder: Path, old: str, new: str, forged: str | None = None) -> None:
    """Replace ``old`` by ``new`` once in certificate.xml; with ``forged``, state it as the first
    reported value in results.json too (what an attacker who changes both does)."""
    xml = (folder / "certificate.xml").read_text(encoding="utf-8")
    assert old in xml
    (folder / "certificate.xml").write_text(xml.replace(old, new, 1), encoding="utf-8")
    if forged is not None:
        _forge_json(folder, forged)


def _forge_json(folder: Path, value: str) -> None:
    doc = json.loads((folder / "results.json").read_text())
    doc["measurements"][0]["reported"][0]["value"] = float(value)
    (folder / "results.json").write_text(json.dumps(doc))


def _quantity(folder: Path, qid: str, value: str) -> str:
    """The XML of the dcc:quantity ``qid``, its value replaced by ``value``."""
    root = etree.parse(str(folder / "certificate.xml")).getroot()
    [quantity] = root.xpath(f"//dcc:quantity[@id='{qid}']", namespaces=NS)
    quantity.find("si:real/si:value", NS).text = value
    return etree.tostring(quantity, encoding="unicode")


def test_the_untampered_certificate_verifies_and_is_trusted_through_its_anchor(
    issued: dict[str, Any], copy: Path
) -> None:
    code, line, doc = _verify(copy, "--trust", str(issued["lab"][1]))
    assert code == 0 and "VERIFIED —" in line and "UNTRUSTED" not in line, line
    assert doc["trusted"] is True and doc["signer"]["trusted"] is True and doc["inputs_checked"]


# --- what the digest does not cover ------------------------------------------------------------


def _cut(value: str) -> tuple[str, str]:
    """The element of ``value`` and the same with a comment after its first two characters: the
    canonicalisation drops the comment, so the signature still holds, while a reader of the
    element's first text node sees the two characters alone."""
    return f"<si:value>{value}</si:value>", f"<si:value>{value[:2]}<!---->{value[2:]}</si:value>"


@pytest.mark.parametrize("forge_json", [True, False], ids=["and-results-json", "xml-alone"])
def test_a_comment_that_cuts_a_value_is_caught(
    issued: dict[str, Any], copy: Path, forge_json: bool
) -> None:
    value, qid = issued["value"], issued["id"]
    _edit(copy, *_cut(value), value[:2] if forge_json else None)
    code, line, doc = _verify(copy)
    assert code == 1 and doc["signature_valid"] is True
    assert "holds a comment on line" in line and "signature does not cover" in line
    if forge_json:  # compared with what was signed, not with the text before the comment
        said = f"{qid} si:value: {value} in certificate.xml, {float(value[:2])} in results.json"
        assert said in line


@pytest.mark.parametrize("forge_json", [True, False], ids=["and-results-json", "xml-alone"])
def test_a_copy_of_the_results_inside_the_signature_is_caught(
    issued: dict[str, Any], copy: Path, forge_json: bool
) -> None:
    # XML signature wrapping: the enveloped transform removes ds:Signature with all it holds
    fake = _quantity(copy, issued["id"], FAKE)
    wrapped = (
        f'<ds:Object><dcc:result xmlns:dcc="{DCC}" xmlns:si="{SI}"><dcc:data>{fake}</dcc:data>'
        "</dcc:result></ds:Object></ds:Signature>"
    )
    _edit(copy, "</ds:Signature>", wrapped, FAKE if forge_json else None)
    code, line, doc = _verify(copy)
    assert code == 1 and doc["signature_valid"] is True
    assert "holds result (line" in line and "inside ds:Signature" in line and "wrapping" in line
    if forge_json:
        assert f"{issued['value']} in certificate.xml, {FAKE} in results.json" in line


def test_a_copy_of_the_results_outside_the_signature_breaks_its_digest(
    issued: dict[str, Any], copy: Path
) -> None:
    fake = _quantity(copy, issued["id"], FAKE)
    _edit(copy, "<dcc:comment>", f"<dcc:comment>{fake}", FAKE)
    code, line, doc = _verify(copy)
    assert code == 1 and doc["signature_valid"] is False
    assert "changed after signing" in line


def test_the_xml_and_results_json_changed_together_fail_on_the_signature(
    issued: dict[str, Any], copy: Path
) -> None:
    _edit(copy, f"<si:value>{issued['value']}</si:value>", f"<si:value>{FAKE}</si:value>", FAKE)
    code, line, doc = _verify(copy)
    assert code == 1 and doc["signature_valid"] is False and doc["consistent"] is True
    assert "the signed content of certificate.xml was changed after signing" in line


def test_a_failed_unit_passed_in_results_json_is_caught(copy: Path) -> None:
    doc = json.loads((copy / "results.json").read_text())
    doc["measurements"][0]["conformity"]["bias[0]"] = "pass"
    (copy / "results.json").write_text(json.dumps(doc))
    code, line, found = _verify(copy)
    assert code == 1 and found["signature_valid"] is True and found["consistent"] is False
    qid = quantity_id(1, "bias[0]")
    assert f"{qid} conformity: fail in certificate.xml, pass in results.json" in line


def test_another_units_serial_in_results_json_is_caught(copy: Path) -> None:
    doc = json.loads((copy / "results.json").read_text())
    doc["item"]["serial"] = "SN-9999"
    (copy / "results.json").write_text(json.dumps(doc))
    code, line, found = _verify(copy)
    assert code == 1 and found["signature_valid"] is True and found["consistent"] is False
    said = "the item's serial number 'SN-0000' in certificate.xml, item.serial 'SN-9999'"
    assert said in line


def test_the_signed_content_is_the_document_without_its_signature(
    issued: dict[str, Any], copy: Path
) -> None:
    """Why verify reads the numbers from signxml's ``signed_xml``: for the reference ``URI=""``
    with the enveloped transform it is the parsed document without ``ds:Signature``,
    canonically; and where a comment cuts a value, the parsed element's text is not the signed
    value while ``signed_xml`` holds the signed one."""
    from signxml.xades import XAdESVerifier

    def signed_and_parsed(data: bytes) -> tuple[etree._Element, etree._Element]:
        cert = etree.fromstring(data).findtext(".//ds:X509Certificate", namespaces=DS) or ""
        pem = f"-----BEGIN CERTIFICATE-----\n{cert.strip()}\n-----END CERTIFICATE-----\n"
        results = XAdESVerifier().verify(data, x509_cert=pem)
        [signed] = [r.signed_xml for r in results if r.signed_xml.tag == f"{{{DCC}}}" + ROOT]
        parsed = etree.fromstring(data)
        signature = parsed.find(".//ds:Signature", DS)
        signature.getparent().remove(signature)
        return signed, parsed

    def c14n(element: etree._Element) -> bytes:
        return etree.tostring(element, method="c14n", with_comments=False)

    signed, parsed = signed_and_parsed((copy / "certificate.xml").read_bytes())
    assert c14n(signed) == c14n(parsed)
    value, qid = issued["value"], issued["id"]
    _edit(copy, *_cut(value))
    signed, parsed = signed_and_parsed((copy / "certificate.xml").read_bytes())
    assert c14n(signed) == c14n(parsed)
    where = f"//dcc:quantity[@id='{qid}']/si:real/si:value"
    assert parsed.xpath(where, namespaces=NS)[0].text == value[:2]
    assert signed.xpath(where, namespaces=NS)[0].text == value


# --- signatures by someone else ----------------------------------------------------------------


def _unsigned(folder: Path, issued: dict[str, Any]) -> etree._Element:
    """certificate.xml without its signature, its first reported value changed to FAKE (in
    results.json too)."""
    root = etree.fromstring((folder / "certificate.xml").read_bytes())
    signature = root.find(".//ds:Signature", DS)
    signature.getparent().remove(signature)
    where = f"//dcc:quantity[@id='{issued['id']}']/si:real/si:value"
    root.xpath(where, namespaces=NS)[0].text = FAKE
    _forge_json(folder, FAKE)
    return root


def test_a_certificate_re_signed_with_a_self_made_key(issued: dict[str, Any], copy: Path) -> None:
    xml, _ = sign_dcc(etree.tostring(_unsigned(copy, issued)), load_signer(*issued["mallory"]))
    (copy / "certificate.xml").write_bytes(xml)
    code, line, doc = _verify(copy, "--trust", str(issued["lab"][1]))
    assert code == 1 and doc["signature_valid"] is False and doc["trusted"] is False
    assert "does not chain to --trust" in line and doc["signer"]["trusted"] is False
    # without a trust anchor the signature holds, and the line says that nobody vouches for it
    code, line, doc = _verify(copy)
    assert code == 0 and "VERIFIED, SIGNER UNTRUSTED" in line and "give --trust" in line
    assert doc["trusted"] is False and doc["signer"]["trusted"] is False


def test_a_signature_over_part_of_the_document_is_refused(
    issued: dict[str, Any], copy: Path
) -> None:
    from signxml import DigestAlgorithm, SignatureConstructionMethod, SignatureMethod
    from signxml.xades import XAdESSigner

    root = _unsigned(copy, issued)  # the first value changed; another quantity alone signed
    comment = root.find(f"{{{DCC}}}comment")
    etree.SubElement(comment, f"{{{DS_NAMESPACE}}}Signature", Id="placeholder")
    mallory = load_signer(*issued["mallory"])
    signed = XAdESSigner(
        method=SignatureConstructionMethod.enveloped,
        signature_algorithm=SignatureMethod.ECDSA_SHA256,
        digest_algorithm=DigestAlgorithm.SHA256,
    ).sign(
        root,
        key=mallory.key,
        cert=[mallory.certificate.public_bytes(Encoding.PEM).decode()],
        reference_uri=f"#{issued['other_id']}",
    )
    (copy / "certificate.xml").write_bytes(etree.tostring(signed))
    code, line, doc = _verify(copy)
    assert code == 1 and doc["signature_valid"] is False
    assert "does not cover the whole certificate" in line and 'URI=""' in line


# --- input that cannot be used -----------------------------------------------------------------

LAUGHS = "".join(
    f'<!ENTITY l{i} "{f"&l{i - 1};" * 10}">' if i else '<!ENTITY l0 "lol">' for i in range(10)
)


@pytest.mark.parametrize(
    ("doctype", "use"),
    [
        pytest.param(f"<!DOCTYPE d [{LAUGHS}]>", "&l9;", id="billion-laughs"),
        pytest.param('<!DOCTYPE d [<!ENTITY x SYSTEM "file:///etc/hostname">]>', "&x;", id="xxe"),
    ],
)
def test_a_doctype_is_refused_unread(
    issued: dict[str, Any], copy: Path, doctype: str, use: str
) -> None:
    xml = (copy / "certificate.xml").read_text(encoding="utf-8")
    xml = xml.replace("?>\n", f"?>\n{doctype}\n", 1)
    xml = xml.replace(f">{issued['value']}<", f">{use}<", 1)
    (copy / "certificate.xml").write_text(xml, encoding="utf-8")
    line = _refused(copy)
    assert "declares a DOCTYPE" in line and "refused unread" in line
    assert Path("/etc/hostname").read_text().strip() not in line.split("certificate.xml:")[1]


@pytest.mark.parametrize("damage", ["truncated", "binary"])
def test_a_truncated_or_non_xml_file_is_exit_2(copy: Path, damage: str) -> None:
    path = copy / "certificate.xml"
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2] if damage == "truncated" else bytes(range(256)))
    assert "not well-formed XML" in _refused(path)


def test_a_folder_without_results_json_is_named(copy: Path) -> None:
    (copy / "results.json").unlink()
    code, line, doc = _verify(copy)
    assert code == 1 and doc["consistent"] is False
    assert "results.json: missing" in line


def test_recompute_names_a_missing_capture(copy: Path) -> None:
    capture = next((copy.parent / "captures-0000").glob("*.npz"))
    capture.unlink()
    line = _refused(copy, "--recompute")
    assert capture.name in line and "no such file" in line
