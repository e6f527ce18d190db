"""Signing the Digital Calibration Certificate: an enveloped XML Signature in XAdES-BES form.

:func:`load_signer` reads the laboratory's private key and its X.509 certificate (PEM) and refuses
what cannot give a trustworthy signature — a key file that cannot be read, an encrypted key without
its passphrase, a key that is not the certificate's, a certificate that is not valid on the date of
issue or now. :func:`sign_dcc` signs ``certificate.xml`` with it.

Where the signature goes: the DCC v3.1.2 schema has no ``ds:Signature`` element of its own; the
one place at the root that takes elements of another namespace is ``dcc:comment`` (after
``dcc:measurementResults``, ``xs:any namespace="##any"``, strict). The signature is put there, so
the signed DCC stays valid against PTB's schema together with the W3C XML Signature schema it then
needs for ``ds:Signature`` (:func:`validate_signed_dcc`). The reference is to the whole document
(``URI=""``) with the enveloped-signature transform, so every element — the results, the persons,
the ``plan_sha256`` — is covered. The responsible person whom the signing certificate names (its
CN) gets ``cryptElectronicSignature`` = true before signing.

The XML Signature, the XAdES qualifying properties (``SigningTime``, ``SigningCertificateV2`` —
the SHA-256 of the signer's certificate, which binds it to the signature — and
``DataObjectFormat``), the canonicalisation and the cryptography are signxml's; nothing of them is
written here.

References
----------
W3C, XML Signature Syntax and Processing Version 1.1 (2013), §6.6.4 (enveloped signature
transform); ETSI EN 319 132-1 V1.1.1 (2016), XAdES baseline signatures, §5.2 (signed
properties), §6.3 (XAdES-B-B, formerly XAdES-BES); PTB, DCC schema v3.1.2 (``dcc:comment``,
``dcc:respPersonType/cryptElectronicSignature``).
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import hashlib
import os
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

from lxml import etree

from rotacal.errors import ConfigError

from .dcc import DCC_NAMESPACE

__all__ = [
    "DS_NAMESPACE",
    "PASSPHRASE_ENV",
    "SignatureInfo",
    "Signer",
    "load_signer",
    "sign_dcc",
    "signer_name",
    "validate_signed_dcc",
]

DS_NAMESPACE = "http://www.w3.org/2000/09/xmldsig#"
#: The environment variable that holds the passphrase of an encrypted key (never an option, so
#: that it does not stay in a shell's history or a process list).
PASSPHRASE_ENV = "ROTACAL_SIGN_PASSPHRASE"
_DCC = f"{{{DCC_NAMESPACE}}}"


@dataclasses.dataclass(frozen=True)
class Signer:
    """A private key and the X.509 certificate of its public key (checked to belong together)."""

    key: Any
    certificate: Any
    key_path: Path
    cert_path: Path

    @property
    def name(self) -> str:
        """The certificate subject's common name (CN), or the whole subject when it has none."""
        return signer_name(self.certificate)

    @property
    def fingerprint_sha256(self) -> str:
        """The SHA-256 of the certificate (DER), in hexadecimal."""
        from cryptography.hazmat.primitives import hashes

        return self.certificate.fingerprint(hashes.SHA256()).hex()

    def __reduce__(self) -> tuple[Any, tuple[bytes, bytes, str, str]]:
        """Pickled as the DER of its key and certificate, so that ``rotacal batch --sign-key``
        reads and checks the key once, in its own process, and its Dask workers sign with it
        (cryptography's key objects cannot be pickled; the passphrase is not sent). The key
        travels unencrypted over Dask's connection: on this machine's local cluster that is
        local; to workers on other machines use a scheduler with TLS (``tls://``)."""
        from cryptography.hazmat.primitives.serialization import (
            Encoding,
            NoEncryption,
            PrivateFormat,
        )

        key = self.key.private_bytes(Encoding.DER, PrivateFormat.PKCS8, NoEncryption())
        cert = self.certificate.public_bytes(Encoding.DER)
        return (_signer_from_der, (key, cert, str(self.key_path), str(self.cert_path)))

    def check_valid_on(self, day: dt.date, now: dt.datetime | None = None) -> None:
        """Refuse a certificate that is not valid on the date of issue ``day`` (at any time of
        that day, UTC) or at ``now`` [default: the clock], when the signature is made.

        Raises
        ------
        ConfigError
            Naming the certificate file, the date and the certificate's validity period.
        """
        now = now or dt.datetime.now(dt.timezone.utc)
        start, end = self.certificate.not_valid_before_utc, self.certificate.not_valid_after_utc
        day_start = dt.datetime.combine(day, dt.time(0), dt.timezone.utc)
        # valid on a day: the validity period overlaps it (the hour of issue is not recorded)
        checks = [
            (
                day_start + dt.timedelta(days=1) <= start,
                day_start >= end,
                f"the date of issue {day}",
            ),
            (now < start, now > end, f"the time of signing ({now:%Y-%m-%d %H:%M} UTC)"),
        ]
        for early, late, said in checks:
            if early or late:
                raise ConfigError(
                    f"{self.cert_path}: the signing certificate is "
                    f"{'expired' if late else 'not yet valid'} on {said}: it is valid from "
                    f"{start:%Y-%m-%d %H:%M} to {end:%Y-%m-%d %H:%M} UTC; nothing was issued"
                )


def _signer_from_der(key: bytes, cert: bytes, key_path: str, cert_path: str) -> Signer:
    """A :class:`Signer` unpickled (see :meth:`Signer.__reduce__`)."""
    from cryptography import x509
    from cryptography.hazmat.primitives.serialization import load_der_private_key

    return Signer(
        load_der_private_key(key, password=None),
        x509.load_der_x509_certificate(cert),
        Path(key_path),
        Path(cert_path),
    )


@dataclasses.dataclass(frozen=True)
class SignatureInfo:
    """What the PDF and the verdict say of a signature: the signer and the signed file's hash."""

    signer: str
    fingerprint_sha256: str
    signing_time: str
    xml_sha256: str

    def to_dict(self) -> dict[str, str]:
        return dataclasses.asdict(self)


def signer_name(certificate: Any) -> str:
    """A certificate subject's common name (CN), or its whole subject (RFC 4514) without one."""
    from cryptography.x509.oid import NameOID

    cn = certificate.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    return str(cn[0].value) if cn else certificate.subject.rfc4514_string()


def _read(path: Path, what: str) -> bytes:
    try:
        return path.read_bytes()
    except OSError as e:
        raise ConfigError(
            f"{path}: the {what} cannot be read ({e.strerror}); nothing was issued"
        ) from None


def load_signer(
    key_path: str | Path, cert_path: str | Path, passphrase: str | None = None
) -> Signer:
    """The signer of ``key_path`` (PEM private key, RSA or ECDSA) and ``cert_path`` (PEM X.509).

    Parameters
    ----------
    key_path, cert_path : str or Path
        The private key and its certificate.
    passphrase : str, optional
        The encrypted key's passphrase [default: the environment variable
        ``ROTACAL_SIGN_PASSPHRASE``].

    Raises
    ------
    ConfigError
        One line naming the file: unreadable, not a PEM key or certificate, encrypted without a
        passphrase or with a wrong one, a key type XAdES signing here does not take, or a key that
        is not the certificate's.
    """
    from cryptography import x509
    from cryptography.hazmat.primitives.asymmetric import ec, rsa
    from cryptography.hazmat.primitives.serialization import (
        Encoding,
        PublicFormat,
        load_pem_private_key,
    )

    key_path, cert_path = Path(key_path), Path(cert_path)
    key_pem, cert_pem = _read(key_path, "signing key"), _read(cert_path, "signing certificate")
    if passphrase is None:
        passphrase = os.environ.get(PASSPHRASE_ENV) or None
    try:
        key = load_pem_private_key(key_pem, password=passphrase.encode() if passphrase else None)
    except TypeError:  # encrypted without a passphrase, or a passphrase for a plain key
        need = (
            "is encrypted: set its passphrase in" if not passphrase else "is not encrypted: unset"
        )
        raise ConfigError(f"{key_path}: the signing key {need} {PASSPHRASE_ENV}") from None
    except ValueError as e:
        wrong = "bad decrypt" in str(e).lower() or "incorrect password" in str(e).lower()
        why = f"the passphrase in {PASSPHRASE_ENV} is wrong" if wrong else "not a PEM private key"
        raise ConfigError(f"{key_path}: the signing key cannot be read ({why})") from None
    if not isinstance(key, (rsa.RSAPrivateKey, ec.EllipticCurvePrivateKey)):
        raise ConfigError(
            f"{key_path}: a {type(key).__name__} cannot sign a DCC here; use an RSA or ECDSA key"
        )
    try:
        certificate = x509.load_pem_x509_certificate(cert_pem)
    except ValueError:
        raise ConfigError(
            f"{cert_path}: not a PEM X.509 certificate (-----BEGIN CERTIFICATE-----)"
        ) from None

    def spki(public: Any) -> bytes:
        return bytes(public.public_bytes(Encoding.DER, PublicFormat.SubjectPublicKeyInfo))

    if spki(key.public_key()) != spki(certificate.public_key()):
        raise ConfigError(
            f"{key_path}: the signing key does not match the certificate {cert_path} "
            f"(subject {signer_name(certificate)}); nothing was issued"
        )
    return Signer(key, certificate, key_path, cert_path)


def _mark_signer(root: etree._Element, name: str) -> None:
    """Set ``cryptElectronicSignature`` of the responsible person the certificate names (its CN
    equal to the person's name), after ``mainSigner`` / ``cryptElectronicSeal`` (the schema's
    order); a laboratory seal whose CN names no person marks no one."""
    for person in root.iterfind(f"{_DCC}administrativeData/{_DCC}respPersons/{_DCC}respPerson"):
        if person.findtext(f"{_DCC}person/{_DCC}name/{_DCC}content") != name:
            continue
        if person.find(f"{_DCC}cryptElectronicSignature") is not None:
            return
        flag = etree.Element(f"{_DCC}cryptElectronicSignature")
        flag.text = "true"
        flag.tail, person[-1].tail = person[-1].tail, person[-2].tail  # keep the indentation
        stamp = person.find(f"{_DCC}cryptElectronicTimeStamp")
        if stamp is not None:
            stamp.addprevious(flag)
        else:
            person.append(flag)
        return


def sign_dcc(xml: bytes, signer: Signer) -> tuple[bytes, SignatureInfo]:
    """``certificate.xml`` signed: an enveloped XAdES-BES signature in ``dcc:comment``.

    Parameters
    ----------
    xml : bytes
        A DCC, valid against the DCC schema (as :func:`rotacal.certificate.dcc.dcc_xml` makes it).
    signer : Signer
        The key and certificate (:func:`load_signer`); the certificate is embedded.

    Returns
    -------
    (bytes, SignatureInfo)
        The signed DCC (valid against the DCC and XML Signature schemas: checked) and what the
        PDF prints of its signature.

    References
    ----------
    W3C XML Signature 1.1 §6.6.4; ETSI EN 319 132-1 V1.1.1 §6.3 (XAdES-BES / B-B).
    """
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.hazmat.primitives.serialization import Encoding
    from signxml import DigestAlgorithm, SignatureConstructionMethod, SignatureMethod
    from signxml.xades import XAdESDataObjectFormat, XAdESSigner

    root = etree.fromstring(xml)
    _mark_signer(root, signer.name)
    comment = root.find(f"{_DCC}comment")
    if comment is None:  # the schema's sequence: comment after measurementResults, before document
        comment = etree.Element(f"{_DCC}comment")
        root.find(f"{_DCC}measurementResults").addnext(comment)
    etree.SubElement(
        comment, f"{{{DS_NAMESPACE}}}Signature", Id="placeholder", nsmap={"ds": DS_NAMESPACE}
    )
    is_ec = isinstance(signer.key, ec.EllipticCurvePrivateKey)
    xades = XAdESSigner(
        method=SignatureConstructionMethod.enveloped,  # at the placeholder in dcc:comment
        signature_algorithm=SignatureMethod.ECDSA_SHA256 if is_ec else SignatureMethod.RSA_SHA256,
        digest_algorithm=DigestAlgorithm.SHA256,
        data_object_format=XAdESDataObjectFormat(
            Description="PTB Digital Calibration Certificate v3.1.2", MimeType="text/xml"
        ),
    )
    signed = xades.sign(
        root, key=signer.key, cert=[signer.certificate.public_bytes(Encoding.PEM).decode()]
    )
    out = b'<?xml version="1.0" encoding="UTF-8"?>\n' + etree.tostring(signed, encoding="UTF-8")
    fault = validate_signed_dcc(out)
    if fault is not None:  # a signed DCC that the schemas refuse is not issued
        raise ConfigError(f"the signed certificate.xml is not valid: {fault}; nothing was issued")
    signing_time = signed.findtext(".//{http://uri.etsi.org/01903/v1.3.2#}SigningTime") or ""
    info = SignatureInfo(
        signer=signer.name,
        fingerprint_sha256=signer.fingerprint_sha256,
        signing_time=signing_time,
        xml_sha256=hashlib.sha256(out).hexdigest(),
    )
    return out, info


_WRAPPER = """<?xml version="1.0" encoding="UTF-8"?>
<xs:schema xmlns:xs="http://www.w3.org/2001/XMLSchema" targetNamespace="urn:rotacal:signed-dcc">
  <xs:import namespace="https://ptb.de/dcc" schemaLocation="{dcc}"/>
  <xs:import namespace="http://www.w3.org/2000/09/xmldsig#" schemaLocation="{ds}"/>
</xs:schema>
"""


@lru_cache(maxsize=1)
def _signed_schema() -> etree.XMLSchema:
    """The DCC schema rotacal carries together with W3C's XML Signature schema (signxml's copy)."""
    import signxml

    ds = Path(signxml.__file__).parent / "schemas" / "xmldsig-core-schema.xsd"
    folder = resources.files("rotacal.certificate") / "schema"
    with resources.as_file(folder) as path:
        text = _WRAPPER.format(dcc=(path / "dcc.xsd").as_uri(), ds=ds.as_uri())
        return etree.XMLSchema(etree.fromstring(text.encode(), base_url=str(path) + "/"))


def validate_signed_dcc(xml: bytes) -> str | None:
    """Check a signed (or unsigned) DCC against the DCC v3.1.2 schema with the XML Signature
    schema for its ``ds:Signature``; the first fault as one line, or None when it is valid.

    Raises
    ------
    ConfigError
        When ``xml`` is not well-formed.
    """
    try:
        document = etree.fromstring(xml)
    except etree.XMLSyntaxError as e:
        raise ConfigError(f"certificate.xml is not well-formed XML ({e})") from None
    schema = _signed_schema()
    if schema.validate(document):
        return None
    error = schema.error_log.filter_from_errors()[0]
    return f"line {error.line}: {error.message.rstrip('.')}"
