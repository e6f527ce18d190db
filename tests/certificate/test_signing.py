"""Signed certificates and ``rotacal verify``: a certificate signed with keys made here (RSA and
ECDSA, a CA and its signer, an expired one) verifies; the signed DCC stays valid against PTB's
schema; every tamper — a digit of a value, a byte of a capture, the plan, the embedded
certificate swapped, the signature removed — is caught and named; bad keys are refused before
anything is issued."""

from __future__ import annotations

import datetime as dt
import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner
from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec, ed25519, rsa
from cryptography.x509.oid import NameOID
from lxml import etree

from rotacal.certificate.sign import load_signer, sign_dcc
from rotacal.cli import cli
from rotacal.errors import ConfigError

from .conftest import plan_dict, write_plan

NS = {
    "dcc": "https://ptb.de/dcc",
    "si": "https://ptb.de/si",
    "ds": "http://www.w3.org/2000/09/xmldsig#",
}
ISSUE = dt.datetime(2026, 11, 25, tzinfo=dt.timezone.utc)
SIGNER = "B. Manager"  # the plan's approver (plan_dict)


def _name(cn: str) -> x509.Name:
    return x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, cn)])


def make_cert(
    key: Any,
    cn: str = SIGNER,
    *,
    days: tuple[int, int] = (-365, 3650),
    issuer: tuple[Any, x509.Certificate] | None = None,
    ca: bool = False,
) -> x509.Certificate:
    """A certificate of ``key``'s public key, valid ``days`` around the issue date, self-signed
    or signed by ``issuer`` (its key and certificate)."""
    signing_key, issuer_name = (
        (key, _name(cn)) if issuer is None else (issuer[0], issuer[1].subject)
    )
    usage = x509.KeyUsage(
        digital_signature=not ca,
        content_commitment=False,
        key_encipherment=False,
        data_encipherment=False,
        key_agreement=False,
        key_cert_sign=ca,
        crl_sign=ca,
        encipher_only=False,
        decipher_only=False,
    )
    builder = (
        x509.CertificateBuilder()
        .subject_name(_name(cn))
        .issuer_name(issuer_name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(ISSUE + dt.timedelta(days=days[0]))
        .not_valid_after(ISSUE + dt.timedelta(days=days[1]))
        .add_extension(usage, critical=True)
        .add_extension(x509.BasicConstraints(ca=ca, path_length=None), critical=True)
        .add_extension(x509.SubjectKeyIdentifier.from_public_key(key.public_key()), critical=False)
    )
    if issuer is not None:
        builder = builder.add_extension(
            x509.AuthorityKeyIdentifier.from_issuer_public_key(issuer[0].public_key()),
            critical=False,
        )
    algorithm = None if isinstance(signing_key, ed25519.Ed25519PrivateKey) else hashes.SHA256()
    return builder.sign(signing_key, algorithm)


def write_pair(
    folder: Path, name: str, key: Any, cert: x509.Certificate, passphrase: bytes | None = None
) -> tuple[Path, Path]:
    encryption = (
        serialization.BestAvailableEncryption(passphrase)
        if passphrase
        else serialization.NoEncryption()
    )
    key_path, cert_path = folder / f"{name}.key", folder / f"{name}.pem"
    key_path.write_bytes(
        key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, encryption)
    )
    cert_path.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    return key_path, cert_path


def _run(*args: str) -> Any:
    return CliRunner().invoke(cli, list(args), catch_exceptions=False)


@pytest.fixture(scope="module")
def keys(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """A CA (ECDSA) and its RSA signer, a self-signed ECDSA signer, another ECDSA key."""
    folder = tmp_path_factory.mktemp("keys")
    ca_key, ed_key = ec.generate_private_key(ec.SECP256R1()), ed25519.Ed25519PrivateKey.generate()
    ca = make_cert(ca_key, "Rate Lab CA", ca=True, days=(-3650, 7300))
    rsa_key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
    ec_key, other_key = (
        ec.generate_private_key(ec.SECP256R1()),
        ec.generate_private_key(ec.SECP256R1()),
    )
    out = {
        "folder": folder,
        "rsa": write_pair(folder, "rsa", rsa_key, make_cert(rsa_key, issuer=(ca_key, ca))),
        "ec": write_pair(folder, "ec", ec_key, make_cert(ec_key)),
        "other": write_pair(folder, "other", other_key, make_cert(other_key, "Mallory")),
        "expired": write_pair(folder, "expired", ec_key, make_cert(ec_key, days=(-800, -400))),
        "encrypted": write_pair(folder, "encrypted", ec_key, make_cert(ec_key), b"s3cret"),
        "edwards": write_pair(folder, "edwards", ed_key, make_cert(ed_key)),
        "ca": folder / "ca.pem",
    }
    out["ca"].write_bytes(ca.public_bytes(serialization.Encoding.PEM))
    return out


@pytest.fixture(scope="module")
def signed(tmp_path_factory: pytest.TempPathFactory, keys: dict[str, Any]) -> Path:
    """A plan of one measurement on a small twin, certified and signed with the CA's RSA signer."""
    folder = tmp_path_factory.mktemp("signed")
    # a rate-table test: 11 set rates, 200 samples each, S = 0.0125 V/(°/s), bias 0.01 V
    rates = np.repeat(np.linspace(-100.0, 100.0, 11), 200)
    noise = np.random.default_rng(21).normal(0.0, 2e-3, rates.size)
    np.savez(folder / "rates.npz", rate_deg_s=rates, output=0.0125 * rates + 0.01 + noise)
    measurement = {
        "name": "Scale factor",
        "command": "gyro scale-factor",
        "limits": {"scale_factor": {"min": 0.0124, "max": 0.0126}},
    }
    plan = write_plan(folder, plan_dict([measurement]))
    key, cert = keys["rsa"]
    result = _run(
        "certify", str(plan), "--no-record", "--sign-key", str(key), "--sign-cert", str(cert)
    )
    assert result.exit_code == 0, result.output
    return folder / "RC-2026-0042"


@pytest.fixture
def copy(signed: Path, tmp_path: Path) -> Path:
    """A copy of the signed certificate with its plan and capture, to tamper with."""
    for name in ("plan.toml", "rates.npz"):
        shutil.copy(signed.parent / name, tmp_path / name)
    return Path(shutil.copytree(signed, tmp_path / signed.name))


def _verify(path: Path, *args: str) -> tuple[int, str, dict[str, Any]]:
    result = CliRunner().invoke(cli, ["verify", str(path), *args, "--json", "-"])
    assert result.exit_code in (0, 1), result.output
    doc = json.loads(result.stdout)
    line = "; ".join(doc["problems"])
    return result.exit_code, line, doc


KEYS = (
    "signed",
    "signature_valid",
    "signer",
    "schema_valid",
    "consistent",
    "recomputed",
    "problems",
)


# --- a signed certificate --------------------------------------------------------------------


def test_the_signed_certificate_verifies_against_its_ca(signed: Path, keys) -> None:
    result = _run("verify", str(signed), "--trust", str(keys["ca"]))
    assert result.exit_code == 0, result.output
    assert result.stdout.count("\n") == 1 and "VERIFIED" in result.stdout
    code, _, doc = _verify(signed, "--trust", str(keys["ca"]))
    assert code == 0 and set(KEYS) <= set(doc)
    assert doc["signed"] and doc["signature_valid"] and doc["schema_valid"] and doc["consistent"]
    assert doc["recomputed"] is None and doc["problems"] == [] and doc["pdf_matches"] is True
    cert = x509.load_pem_x509_certificate(keys["rsa"][1].read_bytes())
    assert doc["signer"]["name"] == SIGNER and doc["signer"]["trusted"] is True
    assert doc["signer"]["fingerprint_sha256"] == cert.fingerprint(hashes.SHA256()).hex()


def test_another_trust_anchor_is_refused(signed: Path, keys) -> None:
    code, line, doc = _verify(signed, "--trust", str(keys["other"][1]))
    assert code == 1 and not doc["signature_valid"]
    assert "does not chain to --trust" in line and SIGNER in line


def test_the_signed_dcc_is_valid_against_ptbs_schema_with_xmldsig(signed: Path) -> None:
    """xmlschema (not libxml2, which certify uses) with PTB's DCC 3.1.2 from the shared standards
    folder and W3C's xmldsig schema."""
    import signxml
    import xmlschema

    dcc = Path(__file__).resolve().parents[3] / "shared" / "standards" / "dcc" / "dcc.xsd"
    xsd = Path(signxml.__file__).parent / "schemas" / "xmldsig-core-schema.xsd"
    schema = xmlschema.XMLSchema([str(dcc), str(xsd)], base_url=str(dcc.parent))
    root = etree.parse(str(signed / "certificate.xml")).getroot()
    assert root.find("dcc:comment/ds:Signature", NS) is not None
    schema.validate(str(signed / "certificate.xml"))


def test_the_pdf_names_the_signer_and_the_signed_xmls_hash(signed: Path) -> None:
    import hashlib

    import pypdf

    last = pypdf.PdfReader(str(signed / "certificate.pdf")).pages[-1].extract_text()
    text = "".join(last.split())
    assert hashlib.sha256((signed / "certificate.xml").read_bytes()).hexdigest() in text
    assert SIGNER.replace(" ", "") in text and "XAdES" in text


def test_recompute_gives_every_number_and_plan_sha256_again(signed: Path) -> None:
    code, line, doc = _verify(signed, "--recompute")
    assert code == 0, line
    assert doc["recomputed"] is True


def test_an_ecdsa_signature_verifies_with_its_own_certificate(signed: Path, keys) -> None:
    xml = (signed / "certificate.xml").read_bytes()
    root = etree.fromstring(xml)
    comment = root.find("dcc:comment", NS)
    root.remove(comment)
    out, info = sign_dcc(etree.tostring(root), load_signer(*keys["ec"]))
    assert info.signer == SIGNER
    folder = signed.parent / "ec-copy"
    shutil.copytree(signed, folder)
    (folder / "certificate.xml").write_bytes(out)
    (folder / "certificate.pdf").unlink()  # it names the RSA-signed XML's hash
    code, line, doc = _verify(folder, "--trust", str(keys["ec"][1]))
    shutil.rmtree(folder)
    assert code == 0, line
    assert doc["signer"]["trusted"] is True
    # the person the certificate names is marked as the one who signed electronically
    person = etree.fromstring(out).xpath(
        "//dcc:respPerson[dcc:cryptElectronicSignature='true']/dcc:person/dcc:name/dcc:content",
        namespaces=NS,
    )
    assert [p.text for p in person] == [SIGNER]


# --- tampering -------------------------------------------------------------------------------


def test_one_digit_of_one_value_is_caught_and_named(copy: Path) -> None:
    xml = copy / "certificate.xml"
    root = etree.parse(str(xml)).getroot()
    value = root.find(".//dcc:quantity[@id='m1_scale_factor']/si:real/si:value", NS)
    old = value.text
    digit = next(i for i in range(len(old) - 1, -1, -1) if old[i].isdigit())
    new = old[:digit] + str((int(old[digit]) + 1) % 10) + old[digit + 1 :]
    xml.write_bytes(xml.read_bytes().replace(f">{old}<".encode(), f">{new}<".encode(), 1))
    code, line, doc = _verify(copy)
    assert code == 1 and not doc["signature_valid"] and not doc["consistent"]
    assert "changed after signing" in line
    assert f"m1_scale_factor si:value: {new} in certificate.xml" in line


def test_one_byte_of_a_capture_is_caught_and_named(copy: Path) -> None:
    capture = copy.parent / "rates.npz"
    data = bytearray(capture.read_bytes())
    data[len(data) // 2] ^= 0x01
    capture.write_bytes(bytes(data))
    code, line, doc = _verify(copy)
    assert code == 1 and doc["signature_valid"]
    assert "capture rates.npz (measurement 1): its SHA-256 differs" in line


def test_a_changed_plan_is_caught_and_named(copy: Path) -> None:
    plan = copy.parent / "plan.toml"
    plan.write_text(plan.read_text().replace("0.0126", "0.0127"))
    code, line, _ = _verify(copy)
    assert code == 1
    assert "plan.toml: its SHA-256 differs" in line and "plan_sha256" in line


def test_a_swapped_embedded_certificate_is_caught_and_named(copy: Path, keys) -> None:
    xml = copy / "certificate.xml"
    root = etree.parse(str(xml)).getroot()
    embedded = root.find(".//ds:X509Certificate", NS)
    other = x509.load_pem_x509_certificate(keys["other"][1].read_bytes())
    der = other.public_bytes(serialization.Encoding.DER)
    import base64

    embedded.text = base64.b64encode(der).decode()
    xml.write_bytes(etree.tostring(root, xml_declaration=True, encoding="UTF-8"))
    code, line, doc = _verify(copy)
    assert code == 1 and not doc["signature_valid"]
    assert "CN=Mallory" in line and "embedded certificate was replaced" in line


def test_a_pdf_of_another_certificate_xml_is_caught(copy: Path) -> None:
    import hashlib

    pdf = copy / "certificate.pdf"
    digest = hashlib.sha256((copy / "certificate.xml").read_bytes()).hexdigest().encode()
    other = digest[:-1] + (b"0" if digest[-1:] != b"0" else b"1")
    pdf.write_bytes(pdf.read_bytes().replace(digest, other))
    code, line, doc = _verify(copy)
    assert code == 1 and doc["pdf_matches"] is False and doc["signature_valid"]
    assert "certificate.pdf does not name the SHA-256 of this certificate.xml" in line


def test_a_removed_signature_is_caught(copy: Path) -> None:
    xml = copy / "certificate.xml"
    root = etree.parse(str(xml)).getroot()
    root.remove(root.find("dcc:comment", NS))
    xml.write_bytes(etree.tostring(root, xml_declaration=True, encoding="UTF-8"))
    code, line, doc = _verify(copy)
    assert code == 1 and doc["signed"] is False and doc["schema_valid"] and doc["consistent"]
    assert "no signature" in line


def test_a_changed_results_json_is_named(copy: Path) -> None:
    doc = json.loads((copy / "results.json").read_text())
    doc["measurements"][0]["reported"][0]["U"] *= 2
    (copy / "results.json").write_text(json.dumps(doc))
    code, line, _ = _verify(copy)
    assert code == 1 and "si:expandedUnc/si:uncertainty" in line and "results.json" in line


def test_unusable_input_is_exit_2(tmp_path: Path) -> None:
    (tmp_path / "certificate.xml").write_text("<not-closed")
    for path in (tmp_path, tmp_path / "missing"):
        result = CliRunner().invoke(cli, ["verify", str(path)])
        assert result.exit_code == 2 and result.output.count("\n") == 1, result.output


# --- refusals: nothing issued ----------------------------------------------------------------


@pytest.mark.parametrize(
    ("key", "cert", "said"),
    [
        ("other", "ec", "does not match the certificate"),
        ("expired", "expired", "expired on the date of issue 2026-11-25"),
        ("missing", "ec", "cannot be read"),
        ("encrypted", "encrypted", "is encrypted: set its passphrase in ROTACAL_SIGN_PASSPHRASE"),
        ("ec", "other", "does not match the certificate"),
        ("edwards", "edwards", "cannot sign a DCC here; use an RSA or ECDSA key"),
    ],
)
def test_a_bad_signing_key_or_certificate_issues_nothing(
    signed: Path, keys, tmp_path: Path, monkeypatch, key, cert, said
) -> None:
    monkeypatch.delenv("ROTACAL_SIGN_PASSPHRASE", raising=False)
    folder = keys["folder"]
    for name in ("plan.toml", "rates.npz"):
        shutil.copy(signed.parent / name, tmp_path / name)
    result = CliRunner().invoke(
        cli,
        [
            "certify",
            str(tmp_path / "plan.toml"),
            "--no-record",
            "--sign-key",
            str(folder / f"{key}.key"),
            "--sign-cert",
            str(folder / f"{cert}.pem"),
        ],
    )
    assert result.exit_code == 2, result.output
    assert said in result.output and result.output.count("\n") == 1, result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.toml", "rates.npz"]


def test_an_expired_certificate_draws_no_number(signed: Path, keys, tmp_path: Path) -> None:
    """The signer is refused before the records store is asked anything."""
    from rotacal.certificate.issue import certify

    asked: list[str] = []

    class Registry:
        def __getattr__(self, name: str) -> Any:
            asked.append(name)
            raise AssertionError(f"the store was asked {name}")

    for name in ("plan.toml", "rates.npz"):
        shutil.copy(signed.parent / name, tmp_path / name)
    plan = tmp_path / "plan.toml"
    plan.write_text(plan.read_text().replace('number = "RC-2026-0042"', 'number = "auto"'))
    with pytest.raises(ConfigError, match="expired on the date of issue"):
        certify(plan, registry=Registry(), signer=load_signer(*keys["expired"]))  # type: ignore[arg-type]
    assert asked == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.toml", "rates.npz"]


def test_an_encrypted_key_is_read_with_its_passphrase(keys, monkeypatch) -> None:
    monkeypatch.setenv("ROTACAL_SIGN_PASSPHRASE", "s3cret")
    assert load_signer(*keys["encrypted"]).name == SIGNER
    monkeypatch.setenv("ROTACAL_SIGN_PASSPHRASE", "wrong")
    with pytest.raises(ConfigError, match=r"passphrase .* is wrong"):
        load_signer(*keys["encrypted"])


def test_a_certificate_not_yet_valid_on_the_issue_date_is_refused(keys) -> None:
    signer = load_signer(*keys["ec"])
    with pytest.raises(ConfigError, match="not yet valid on the date of issue 2024-01-01"):
        signer.check_valid_on(dt.date(2024, 1, 1))


def test_verify_follows_the_output_convention(signed: Path, tmp_path: Path) -> None:
    """``wrote`` line, --overwrite, provenance and warnings, the same JSON run to run, and no
    --json over the certificate's own files."""
    target = tmp_path / "verdict.json"
    first = CliRunner().invoke(cli, ["verify", str(signed), "--json", str(target)])
    assert first.exit_code == 0 and f"wrote {target}" in first.stderr
    doc = json.loads(target.read_text())
    assert doc["warnings"] == [] and doc["provenance"]["command"] == "verify"
    assert doc["provenance"]["inputs"][0]["path"].endswith("certificate.xml")
    again = CliRunner().invoke(cli, ["verify", str(signed), "--json", str(target)])
    assert again.exit_code == 2 and "--overwrite" in again.stderr
    text = target.read_bytes()
    assert (
        CliRunner()
        .invoke(cli, ["verify", str(signed), "--json", str(target), "--overwrite"])
        .exit_code
        == 0
    )
    assert target.read_bytes() == text
    over = CliRunner().invoke(cli, ["verify", str(signed), "--json", str(signed / "results.json")])
    assert over.exit_code == 2 and not over.stdout
