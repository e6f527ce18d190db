"""Every public name of every package is importable as before, though most load lazily."""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys

import pytest

import rotacal

PACKAGES = sorted(m.name for m in pkgutil.iter_modules(rotacal.__path__, "rotacal.") if m.ispkg)


@pytest.mark.parametrize("package", PACKAGES)
def test_every_name_of_all_is_importable_and_listed(package):
    mod = importlib.import_module(package)
    names = getattr(mod, "__all__", [])
    for name in names:
        value = getattr(mod, name)  # a lazy name loads its module here
        assert value is not None, f"{package}.{name}"
    assert set(names) <= set(dir(mod))  # __dir__ lists the lazy names too
    namespace: dict[str, object] = {}
    exec(f"from {package} import *", namespace)  # the star import goes through __all__
    assert set(names) <= set(namespace)


def test_a_lazy_name_is_the_object_of_its_module():
    from rotacal.encoder import demodulate
    from rotacal.encoder.quadrature import demodulate as direct
    from rotacal.table import calibrate_encoder_motion
    from rotacal.table.motion import calibrate_encoder_motion as direct_table

    assert demodulate is direct and calibrate_encoder_motion is direct_table
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        rotacal.signal.no_such_name  # noqa: B018


def test_importing_the_packages_loads_no_scipy_numba_or_file_libraries():
    # start-up pays only for what a command uses: the packages' own imports pull in none of
    # the heavy libraries (SciPy ~1 s, Numba ~0.3 s, h5py, nptdms)
    code = (
        "import sys, rotacal.cli, rotacal.signal, rotacal.encoder, rotacal.table, rotacal.io, "
        "rotacal.uncertainty, rotacal.numbers\n"
        "heavy = [m for m in ('scipy', 'numba', 'h5py', 'nptdms') if m in sys.modules]\n"
        "print(','.join(heavy))"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert out == ""
