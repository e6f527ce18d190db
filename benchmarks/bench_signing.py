"""What signing a certificate costs, and how long verifying one takes (issue 21's bars).

Makes the five-measurement plan of ``bench_certify.py`` (gyro scale factor, triad, Allan,
self-calibration, sinusoidal motion) on its twin captures, an RSA-2048 key and its certificate,
then measures in this one run:

- signing, in-process: the render step (results.json, DCC validated, PDF) of the same content
  without and with the signer, alternating, best of ``--repeat`` (CPU time); the difference is
  what signing adds (bar: under 200 ms), quoted also as a ratio; and what importing signxml
  adds to a fresh process (the certify command imports it only when it signs);
- signing, whole command: ``rotacal certify`` unsigned and signed in fresh processes,
  alternating; the children's CPU time, best of ``--repeat`` (imports of signxml included);
- verifying the signed five-measurement certificate without ``--recompute``: in-process
  (best of ``--repeat``) and as ``rotacal verify`` in a fresh process (bar: under 1 s);
- the peak RSS of the child processes.

No asserts. Run: ``python benchmarks/bench_signing.py [--repeat 5]``
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from bench_certify import make_plan


def make_key(folder: Path) -> tuple[Path, Path]:
    """An RSA-2048 key and a self-signed certificate valid around the plan's date."""
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import rsa
    from cryptography.x509.oid import NameOID

    key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "B")])
    now = dt.datetime.now(dt.timezone.utc)
    cert = (
        x509.CertificateBuilder()
        .subject_name(name)
        .issuer_name(name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - dt.timedelta(days=3650))
        .not_valid_after(now + dt.timedelta(days=3650))
        .sign(key, hashes.SHA256())
    )
    key_path, cert_path = folder / "lab.key", folder / "lab.pem"
    key_path.write_bytes(
        key.private_bytes(
            serialization.Encoding.PEM,
            serialization.PrivateFormat.PKCS8,
            serialization.NoEncryption(),
        )
    )
    cert_path.write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    return key_path, cert_path


def child_cpu(*args: str, cwd: Path) -> tuple[float, float]:
    """Run ``rotacal ARGS`` in a fresh process: (its CPU time, its wall time) in s."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "rotacal", *args], cwd=cwd, check=True, capture_output=True
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall


def import_cpu(modules: str, repeat: int) -> float:
    """Best CPU time (s) of a fresh process that imports ``modules``."""
    best = float("inf")
    for _ in range(repeat):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([sys.executable, "-c", f"import {modules}"], check=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        best = min(best, cpu)
    return best


def render_step(plan: Path, key: Path, cert: Path, repeat: int) -> tuple[float, float]:
    """Best CPU time (s) of the render step without and with signing, on one content."""
    from rotacal.certificate import issue
    from rotacal.certificate.sign import load_signer
    from rotacal.plan.read import read_plan

    signer = load_signer(key, cert)
    plain, signed = [], []
    with tempfile.TemporaryDirectory() as scratch:
        content = issue.measure_into(read_plan(plan), Path(scratch))
        issue._render(content, Path(scratch), signer)  # warm: imports, schemas
        for _ in range(repeat):
            for with_signer, times in ((None, plain), (signer, signed)):
                t = time.process_time()
                issue._render(content, Path(scratch), with_signer)
                times.append(time.process_time() - t)
    return min(plain), min(signed)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    from rotacal.certificate.verify import verify_certificate

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        plan = make_plan(folder)
        key, cert = make_key(folder)
        plain, signed = render_step(plan, key, cert, args.repeat)
        print("render step (results.json, DCC validated, PDF), in-process, best CPU time:")
        print(f"  unsigned {plain * 1e3:7.1f} ms   signed {signed * 1e3:7.1f} ms")
        print(
            f"  signing adds {(signed - plain) * 1e3:6.1f} ms (bar: < 200 ms); "
            f"ratio signed/unsigned {signed / plain:5.2f}"
        )
        base = "rotacal.certificate.dcc, rotacal.certificate.pdf, typst"
        without = import_cpu(base, 2 * args.repeat)
        with_signxml = import_cpu(base + ", signxml.xades", 2 * args.repeat)
        print(
            f"  importing signxml in a fresh process adds {(with_signxml - without) * 1e3:5.0f} ms "
            f"CPU (best of {2 * args.repeat}); render + import: "
            f"{(signed - plain + with_signxml - without) * 1e3:5.0f} ms"
        )
        cpu: dict[str, list[float]] = {"unsigned": [], "signed": []}
        for i in range(args.repeat):
            for kind, extra in (
                ("unsigned", []),
                ("signed", ["--sign-key", str(key), "--sign-cert", str(cert)]),
            ):
                out = folder / f"{kind}-{i}"
                cpu[kind].append(
                    child_cpu(
                        "certify", str(plan), "--no-record", "--out", str(out), *extra, cwd=folder
                    )[0]
                )
        a, b = min(cpu["unsigned"]), min(cpu["signed"])
        print("rotacal certify, fresh process, best CPU time of the child:")
        print(
            f"  unsigned {a:6.2f} s   signed {b:6.2f} s   adds {(b - a) * 1e3:6.0f} ms; ratio {b / a:5.3f}"
        )
        certificate = folder / "signed-0"
        inproc, inproc_cpu = [], []
        for _ in range(args.repeat):
            t, c = time.perf_counter(), time.process_time()
            found = verify_certificate(certificate)
            inproc.append(time.perf_counter() - t)
            inproc_cpu.append(time.process_time() - c)
        assert found.ok, found.problems
        runs = [child_cpu("verify", str(certificate), cwd=folder) for _ in range(args.repeat)]
        start = [child_cpu("--version", cwd=folder) for _ in range(args.repeat)]
        print("verify the signed five-measurement certificate (no --recompute):")
        print(
            f"  in-process best wall {min(inproc) * 1e3:6.1f} ms, best CPU "
            f"{min(inproc_cpu) * 1e3:6.1f} ms (first call {inproc[0] * 1e3:6.1f} ms)"
        )
        best_cpu, best_start = min(c for c, _ in runs), min(c for c, _ in start)
        print(
            f"  rotacal verify, fresh process: best CPU {best_cpu:5.2f} s, best wall "
            f"{min(w for _, w in runs):5.2f} s (bar: < 1 s; wall waits for CPU on a shared machine)"
        )
        print(
            f"  rotacal --version (start-up), same run: best CPU {best_start:5.2f} s; "
            f"verify / start-up {best_cpu / best_start:4.2f}"
        )
        peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        print(f"peak RSS of a child process: {peak_mb:6.0f} MB")
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    main()
