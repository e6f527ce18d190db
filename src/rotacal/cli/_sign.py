"""The signing options of ``rotacal certify`` (``--sign-key``, ``--sign-cert``), kept apart so
that the command's module only names them."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

import click

if TYPE_CHECKING:
    from rotacal.certificate.sign import Signer

F = TypeVar("F", bound=Callable[..., Any])


def sign_options(func: F) -> F:
    """``--sign-key KEY.pem`` and ``--sign-cert CERT.pem`` (both or neither)."""
    func = click.option(
        "--sign-cert",
        metavar="CERT.pem",
        default=None,
        help="The signer's X.509 certificate (PEM), embedded in the signature.",
    )(func)
    return click.option(
        "--sign-key",
        metavar="KEY.pem",
        default=None,
        help="Sign certificate.xml (XML Signature, XAdES-BES) with this private key (PEM, RSA "
        "or ECDSA; an encrypted key's passphrase in ROTACAL_SIGN_PASSPHRASE).",
    )(func)


def load_sign_options(key: str | None, cert: str | None) -> Signer | None:
    """The signer of the two options, checked before anything runs; None without them."""
    if key is None and cert is None:
        return None
    if key is None or cert is None:
        given, missing = (
            ("--sign-key", "--sign-cert") if cert is None else ("--sign-cert", "--sign-key")
        )
        raise click.UsageError(f"{given} needs {missing} too (the key and its certificate)")
    from rotacal.certificate.sign import load_signer

    return load_signer(key, cert)
