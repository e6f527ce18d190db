"""Tests of the turntable TOML loader (rotacal.turntable.config) and the packaged seed table.

Truths: seed 001's Tables 2–3 and eq. (16) (0.027° = 1.62 arcmin), unit conversions written here,
and one expected fault per bad configuration (one line, naming what to fix).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rotacal.errors import ConfigError
from rotacal.turntable import model
from rotacal.turntable.config import load_turntable, parse_turntable, seed_table, seed_table_toml

ARCMIN = math.pi / 10_800

TABLE2 = {  # seed 001, Table 2 (symbol → definition), in the χ order of eq. (25), then η
    "phi_y1": "Position error of outer axis",
    "phi_z2": "Position error of inner axis",
    "alpha_x1": "Wobble error component of outer axis about x-axis",
    "alpha_z1": "Wobble error component of outer axis about z-axis",
    "alpha_x2": "Wobble error component of inner axis about x-axis",
    "alpha_y2": "Wobble error component of inner axis about y-axis",
    "eps_x": "Orthogonality error component about x-axis",
    "eps_y": "Orthogonality error component about y-axis",
    "eta": "Intersection error",
}

BASE = """
name = "base"
units = "arcmin"
length_units = "mm"

[requirement]
psi = 1.62
theta = 1.62
gamma = 1.62

[[chain]]
axis = "y"
angle = "phi1"
rotations = { phi_y1 = "y", alpha_z1 = "z", alpha_x1 = "x" }

[[chain]]
rotations = { eps_y = "y", eps_x = "x" }
translations = { eta = "x" }

[[chain]]
axis = "z"
angle = "phi2"
rotations = { alpha_y2 = "y", phi_z2 = "z", alpha_x2 = "x" }

[errors]
phi_y1 = { lower = 0.05 }
phi_z2 = { lower = 0.05 }
alpha_x1 = { lower = 0.05 }
alpha_z1 = { lower = 0.05 }
alpha_x2 = { lower = 0.05 }
alpha_y2 = { lower = 0.05 }
eps_x = { lower = 0.05 }
eps_y = { lower = 0.05 }
eta = { lower = 0.0 }

[monte_carlo]
runs = 1000

[calibration]
latitude_deg = 45.75
"""


def variant(old: str, new: str) -> str:
    assert old in BASE, old  # the edit must apply, or the test would test nothing
    return BASE.replace(old, new, 1)


# --------------------------------------------------------------------------- the seed table
def test_seed_table_is_tables_2_and_3() -> None:
    t = seed_table()
    assert t.error_names == tuple(TABLE2)
    assert t.angular_error_names == tuple(TABLE2)[:8]
    assert t.offset_names == ("eta",)
    assert t.angle_names == ("phi1", "phi2")
    assert {e.name: e.label for e in t.errors} == TABLE2
    assert [e.kind for e in t.errors] == [
        "position", "position", "wobble", "wobble", "wobble", "wobble",
        "squareness", "squareness", "offset",
    ]  # fmt: skip
    assert [e.iso for e in t.errors] == [
        "EBB", "ECC", "EAB", "ECB", "EAC", "EBC", "EA0C", "EB0C", "EX0C",
    ]  # fmt: skip
    # Table 3: the chain and the order of the error rotations in each link
    assert [(lk.axis, lk.angle) for lk in t.links] == [("y", "phi1"), (None, None), ("z", "phi2")]
    assert t.links[0].rotations == (("phi_y1", "y"), ("alpha_z1", "z"), ("alpha_x1", "x"))
    assert t.links[1].rotations == (("eps_y", "y"), ("eps_x", "x"))
    assert t.links[1].translations == (("eta", "x"),)
    assert t.links[2].rotations == (("alpha_y2", "y"), ("phi_z2", "z"), ("alpha_x2", "x"))
    # §2.3: a calibration accuracy of 0.01 °/h, from which the requirement is derived so that the
    # tables the allocation admits pass the calibration check (eq. (16)'s reading is the option)
    assert t.requirement is None
    assert t.calibration_requirement_deg_h == 0.01
    # lower bounds: rotacal's stated choice (the paper has none)
    for e in t.errors[:8]:
        assert e.lower == pytest.approx(0.05 * ARCMIN, rel=1e-15)
    assert t.errors[8].lower == 0.0
    assert t.units == "arcmin" and t.length_units == "mm"
    assert t.settings == {
        "monte_carlo": {"runs": 1_000_000, "seed": 2026, "signs": "random"},
        "calibration": {"latitude_deg": 45.75, "outer_steps": 8, "inner_steps": 8},
        "sensitivity": {"step_deg": 45.0, "endpoint": True},
        "requirement": {"derivation": "calibration-check"},
        "allocation": {"constraint_angles": "every"},
    }
    # the paper's averaging of Figure 8, chosen by the packaged file
    assert t.sensitivity_grid == (45.0, True)
    assert t.source == "packaged seed001.toml"
    # the model module's entry point gives the same table; each call a fresh object
    assert model.seed_table() == t and model.seed_table() is not t


def test_the_packaged_file_says_the_lower_bounds_are_rotacals_choice() -> None:
    text = (Path(model.__file__).parent / "tables" / "seed001.toml").read_text(encoding="utf-8")
    assert "rotacal's stated choice" in text and "the paper prints none" in text
    # ... and that its sensitivity averaging is the paper's, biased, and how to drop it
    flat = " ".join(line.lstrip("# ") for line in text.splitlines())
    assert (
        "the paper's averaging (reproduces Figure 8's 0.6476/0.5365; it counts 0° and 360° twice)"
        in flat
    )
    assert "delete this table for the unbiased mean over a turn (2/π = 0.6366" in flat


# ----------------------------------------------------------------------------- loading forms
def test_path_text_and_string_forms_agree(tmp_path: Path) -> None:
    f = tmp_path / "my_table.toml"
    f.write_text(BASE.replace('name = "base"\n', ""), encoding="utf-8")
    from_path = load_turntable(f)
    from_str_path = load_turntable(str(f))
    from_text = load_turntable(text=BASE)
    from_detect = load_turntable(BASE)
    assert from_path.name == "my_table" and from_str_path == from_path
    assert from_text.name == from_detect.name == "base"
    assert from_text.error_names == from_path.error_names
    assert from_text.errors == from_path.errors
    assert model.load_turntable(text=BASE) == from_text
    with pytest.raises(ConfigError, match="does not exist"):
        load_turntable(tmp_path / "missing.toml")
    with pytest.raises(ConfigError, match="not both"):
        load_turntable(f, text=BASE)


def test_units_are_converted() -> None:
    t = load_turntable(
        variant('units = "arcmin"\nlength_units = "mm"', 'units = "arcsec"\nlength_units = "um"')
        .replace("phi_y1 = { lower = 0.05 }", "phi_y1 = { lower = 3.0 }")
        .replace("eta = { lower = 0.0 }", "eta = { lower = 5 }")
        .replace("psi = 1.62", "psi = 97.2")
    )
    assert t.error("phi_y1").lower == pytest.approx(math.radians(3.0 / 3600), rel=1e-15)
    assert t.error("eta").lower == pytest.approx(5e-6, rel=1e-15)
    assert t.requirement is not None
    assert t.requirement["psi"] == pytest.approx(math.radians(0.027), rel=1e-15)
    assert t.requirement["theta"] == pytest.approx(1.62 * math.pi / 648_000, rel=1e-15)
    for unit, rad in (("rad", 1.0), ("mrad", 1e-3), ("urad", 1e-6), ("deg", math.pi / 180)):
        t = load_turntable(
            variant('units = "arcmin"', f'units = "{unit}"').replace("= 1.62", "= 0.08")
        )
        assert t.error("alpha_x2").lower == pytest.approx(0.05 * rad, rel=1e-15)
        assert t.requirement is not None
        assert t.requirement["gamma"] == pytest.approx(0.08 * rad, rel=1e-15)


def test_calibration_requirement_form() -> None:
    t = load_turntable(
        variant("psi = 1.62\ntheta = 1.62\ngamma = 1.62", "calibration_deg_h = 0.01")
    )
    assert t.requirement is None and t.calibration_requirement_deg_h == 0.01
    t = load_turntable(variant("[requirement]\npsi = 1.62\ntheta = 1.62\ngamma = 1.62\n", ""))
    assert t.requirement is None and t.calibration_requirement_deg_h is None


def test_optional_keys() -> None:
    t = load_turntable(
        variant(
            "alpha_x2 = { lower = 0.05 }",
            'alpha_x2 = { lower = 0.05, iso = "XWOB", label = "inner wobble", weight = 2.5 }',
        )
    )
    e = t.error("XWOB")
    assert (e.name, e.iso, e.label, e.weight) == ("alpha_x2", "XWOB", "inner wobble", 2.5)
    assert t.resolve("EAC") == "alpha_x2"  # the generated symbol stays accepted
    assert t.error("phi_z2").weight is None


# ---------------------------------------------------------------------------------- aliases
def test_generated_iso_aliases_resolve() -> None:
    t = load_turntable(BASE)  # no iso given anywhere
    expected = {
        "EBB": "phi_y1", "ECC": "phi_z2", "EAB": "alpha_x1", "ECB": "alpha_z1",
        "EAC": "alpha_x2", "EBC": "alpha_y2", "EA0C": "eps_x", "EB0C": "eps_y", "EX0C": "eta",
    }  # fmt: skip
    for sym, name in expected.items():
        assert t.resolve(sym) == name
        assert t.resolve(sym.lower()) == name
        assert t.error(name).iso == sym
    assert t.aliases == expected
    a = t.orientation_error([0.2, 0.9], {"EAB": 1e-4, "eb0c": -2e-4})
    b = t.orientation_error([0.2, 0.9], {"alpha_x1": 1e-4, "eps_y": -2e-4})
    np.testing.assert_array_equal(a, b)


def test_errors_table_accepts_a_generated_symbol_as_key() -> None:
    t = load_turntable(variant("phi_y1 = { lower = 0.05 }", "EBB = { lower = 0.07 }"))
    assert t.error_names[0] == "phi_y1"
    assert t.error("phi_y1").lower == pytest.approx(0.07 * ARCMIN)


def test_ambiguous_generated_alias_is_not_generated() -> None:
    # two axes about z: both position errors would be ECC
    text = """
    [[chain]]
    axis = "z"
    angle = "a"
    rotations = { pa = "z", wa = "x" }
    [[chain]]
    axis = "z"
    angle = "b"
    rotations = { pb = "z" }
    [errors]
    pa = {}
    wa = {}
    pb = {}
    """
    t = load_turntable(text)
    with pytest.raises(ConfigError, match="unknown error name 'ECC'"):
        t.resolve("ECC")
    assert t.error("pa").iso is None and t.error("pb").iso is None
    with pytest.raises(ConfigError, match="which is no error of the chain"):
        load_turntable(text.replace("pa = {}", "ECC = {}"))


# ------------------------------------------------------------------------------------ faults
FAULTS = [
    # (old, new, expected text in the message)
    (
        "phi_y1 = { lower = 0.05 }",
        "phi_y3 = { lower = 0.05 }",
        r"\[errors\] names 'phi_y3'.*valid names: phi_y1",
    ),
    ("eta = { lower = 0.0 }", "", r"chain error 'eta' is missing from \[errors\]"),
    (
        "eta = { lower = 0.0 }",
        "eta = { lower = 0.0 }\nzeta = {}",
        r"'zeta', which is no error of the chain",
    ),
    ("eps_x = { lower = 0.05 }", "EA0C = { lower = 0.05 }\neps_x = {}", r"lists 'eps_x' twice"),
    (
        'rotations = { eps_y = "y", eps_x = "x" }',
        'rotations = { eps_y = "y", alpha_x2 = "x" }',
        r"'alpha_x2' appears twice in the chain",
    ),
    (
        'rotations = { eps_y = "y", eps_x = "x" }',
        'rotations = { eps_y = "y", phi2 = "x" }',
        r"has the name of an angle",
    ),
    (
        "phi_z2 = { lower = 0.05 }",
        "phi_z2 = { lower = -0.05 }",
        r"\[errors\] phi_z2: lower = -0.05 arcmin is negative",
    ),
    (
        "phi_z2 = { lower = 0.05 }",
        "phi_z2 = { lowr = 0.05 }",
        r"\[errors\] phi_z2 has an unknown key 'lowr' \(did you mean 'lower'\?\)",
    ),
    (
        "phi_z2 = { lower = 0.05 }",
        "phi_z2 = { lower = 0.05, weight = 0 }",
        r"weight = 0 must be > 0",
    ),
    ("phi_z2 = { lower = 0.05 }", 'phi_z2 = { lower = "small" }', r"lower must be a number"),
    ("phi_z2 = { lower = 0.05 }", "phi_z2 = 0.05", r"\[errors\] phi_z2 must be a table"),
    ("theta = 1.62", "theta = 0", r"\[requirement\] theta = 0 arcmin must be > 0"),
    ("theta = 1.62", "theta = -1.0", r"\[requirement\] theta = -1 arcmin must be > 0"),
    ("theta = 1.62", "thta = 1.62", r"unknown component 'thta' \(did you mean 'theta'\?\)"),
    ("theta = 1.62", "", r"\[requirement\] lacks 'theta'"),
    (
        "gamma = 1.62",
        "gamma = 1.62\ncalibration_deg_h = 0.01",
        r"both the orientation limits and calibration_deg_h",
    ),
    ('units = "arcmin"', 'units = "grad"', r"units = 'grad' is unknown: use one of rad, mrad"),
    ('length_units = "mm"', 'length_units = "inch"', r"length_units = 'inch' is unknown"),
    ('axis = "z"', 'axis = "w"', r"\[\[chain\]\] link 3: axis = 'w' is not an axis letter"),
    (
        'rotations = { eps_y = "y", eps_x = "x" }',
        'rotations = { eps_y = "y", eps_x = "q" }',
        r"link 2: rotations eps_x = 'q' is not an axis letter",
    ),
    (
        'translations = { eta = "x" }',
        'translations = { eta = "X" }',
        r"translations eta = 'X' is not an axis letter",
    ),
    ('angle = "phi2"\n', "", r"link 3: the rotary axis about z has no angle"),
    ('angle = "phi2"', 'angle = "phi1"', r"same angle name 'phi1'"),
    (
        'translations = { eta = "x" }',
        'translations = { eta = "x" }\nangle = "psi0"',
        r"fixed link \(no axis\) cannot have an angle",
    ),
    (
        'angle = "phi1"',
        'angle = "phi1"\nrotation = { a = "x" }',
        r"link 1 has an unknown key 'rotation' \(did you mean 'rotations'\?\)",
    ),
    ("[monte_carlo]", '[monte_carlo]\nsigns = "both"', r"signs = 'both' is unknown"),
    ("[monte_carlo]", '[monte_carlo]\nstream = "mt"', r"stream = 'mt' is unknown; use 'philox'"),
    ("runs = 1000", "runs = 0", r"\[monte_carlo\] runs must be an integer ≥ 1"),
    ("runs = 1000", "runs = true", r"\[monte_carlo\] runs must be an integer ≥ 1, got True"),
    ("runs = 1000", "runs = 1.5", r"\[monte_carlo\] runs must be an integer ≥ 1, got 1.5"),
    ("runs = 1000", "seed = -1", r"\[monte_carlo\] seed must be an integer ≥ 0, got -1"),
    ("runs = 1000", "seed = 1.5", r"\[monte_carlo\] seed must be an integer ≥ 0, got 1.5"),
    ("runs = 1000", "seed = true", r"\[monte_carlo\] seed must be an integer ≥ 0, got True"),
    (
        "theta = 1.62",
        "theta = 1200",
        r"\[requirement\] theta = 1200 arcmin is 20°: the small-angle error model needs errors ≪ 1 "
        r"rad; check units",
    ),
    (
        "phi_z2 = { lower = 0.05 }",
        "phi_z2 = { lower = 600 }",
        r"\[errors\] phi_z2: lower = 600 arcmin is 10°: the small-angle error model",
    ),
    (
        "[calibration]",
        "[sensitivity]\nstep_deg = 7\n[calibration]",
        r"\[sensitivity\] step_deg = 7 must be a number of degrees > 0 that divides 360°",
    ),
    (
        "[calibration]",
        '[sensitivity]\nendpoint = "yes"\n[calibration]',
        r"\[sensitivity\] endpoint = 'yes' must be true or false",
    ),
    (
        "[calibration]",
        "[sensitivity]\nstep = 5\n[calibration]",
        r"\[sensitivity\] has an unknown key 'step' \(did you mean 'step_deg'\?\)",
    ),
    (
        "runs = 1000",
        "rums = 1000",
        r"\[monte_carlo\] has an unknown key 'rums' \(did you mean 'runs'\?\)",
    ),
    ("latitude_deg = 45.75", "latitude_deg = 95", r"latitude_deg = 95 must be within ±90°"),
    (
        'name = "base"',
        'name = "base"\nunit = "deg"',
        r"the top level has an unknown key 'unit' \(did you mean 'units'\?\)",
    ),
    ("[calibration]", "[calibraton]", r"unknown key 'calibraton' \(did you mean 'calibration'\?\)"),
    (
        'rotations = { eps_y = "y", eps_x = "x" }',
        'rotations = { eps_y = "y", eps_x = "x" ',
        r"TOML syntax error: .*line 17",
    ),
    ("theta = 1.62", "theta = 1.62.3", r"TOML syntax error: .*line 8"),
    (
        "alpha_x2 = { lower = 0.05 }",
        'alpha_x2 = { lower = 0.05, iso = "phi_z2" }',
        r"ISO symbol 'phi_z2' of 'alpha_x2' is already the name or symbol of 'phi_z2'",
    ),
]


@pytest.mark.parametrize(("old", "new", "message"), FAULTS)
def test_faults_are_one_config_error_line(old: str, new: str, message: str) -> None:
    with pytest.raises(ConfigError, match=message) as info:
        load_turntable(variant(old, new))
    text = str(info.value)
    assert "\n" not in text and text.startswith("turntable TOML text: ")


def test_an_explicit_symbol_wins_over_a_generated_one() -> None:
    # a table with its own lettering: the explicit symbol names alpha_x2, the generated EBB is dropped
    t = load_turntable(
        variant("alpha_x2 = { lower = 0.05 }", 'alpha_x2 = { lower = 0.05, iso = "EBB" }')
    )
    assert t.resolve("EBB") == "alpha_x2" and t.error("phi_y1").iso is None
    assert t.resolve("EAC") == "alpha_x2"


def test_iso_duplicates_between_explicit_symbols() -> None:
    text = variant("phi_y1 = { lower = 0.05 }", 'phi_y1 = { lower = 0.05, iso = "X1" }')
    text = text.replace("phi_z2 = { lower = 0.05 }", 'phi_z2 = { lower = 0.05, iso = "x1" }')
    with pytest.raises(ConfigError, match="ISO symbol 'x1' of 'phi_z2'"):
        load_turntable(text)


def test_faults_in_a_file_name_the_file(tmp_path: Path) -> None:
    f = tmp_path / "bad.toml"
    f.write_text(variant("theta = 1.62", "theta = 1.62 1.7"), encoding="utf-8")
    with pytest.raises(ConfigError, match=r"bad\.toml: TOML syntax error: .*line 8") as info:
        load_turntable(f)
    assert "\n" not in str(info.value)


def test_sensitivity_table_chooses_the_averaging() -> None:
    t = load_turntable(
        variant("[calibration]", "[sensitivity]\nstep_deg = 45\nendpoint = true\n[calibration]")
    )
    assert t.sensitivity_grid == (45.0, True)
    # mean |cos|, |sin| over 0:45:360 with both ends (Figure 8), typed out here
    assert t.sensitivities()[0, 0] == pytest.approx((3 + 4 * 2**-0.5) / 9, rel=1e-12)
    assert t.sensitivities()[0, 2] == pytest.approx((4 * 2**-0.5 + 2) / 9, rel=1e-12)
    only_step = load_turntable(
        variant("[calibration]", "[sensitivity]\nstep_deg = 5\n[calibration]")
    )
    assert only_step.sensitivity_grid == (5.0, False)
    assert load_turntable(BASE).sensitivity_grid == (1.0, False)  # no table: the default


def test_a_table_without_errors_is_refused_and_one_with_only_translations_loads() -> None:
    with pytest.raises(ConfigError, match=r"^turntable TOML text: the chain has no errors") as info:
        load_turntable('[[chain]]\naxis = "z"\nangle = "phi"\n[errors]\n')
    assert "\n" not in str(info.value)
    t = load_turntable(
        '[[chain]]\naxis = "z"\nangle = "phi"\ntranslations = { d = "x" }\n[errors]\nd = {}\n'
    )
    assert t.angular_error_names == () and t.offset_names == ("d",)


def test_the_source_is_the_file(tmp_path: Path) -> None:
    f = tmp_path / "table.toml"
    f.write_text(BASE, encoding="utf-8")
    assert load_turntable(f).source == str(f)
    assert load_turntable(BASE).source == "turntable TOML text"


def test_no_chain_and_wrong_types() -> None:
    with pytest.raises(ConfigError, match=r"there is no \[\[chain\]\]"):
        load_turntable('name = "x"\n[errors]\n')
    with pytest.raises(ConfigError, match=r"\[\[chain\]\] link 1 must be a table"):
        parse_turntable({"chain": [1]})
    with pytest.raises(ConfigError, match="name must be a non-empty string"):
        load_turntable(variant('name = "base"', "name = 3"))


# ------------------------------------------------- the budget's two choices (issue 12, seed 001)
def test_the_packaged_file_names_the_papers_reading_as_the_options() -> None:
    flat = " ".join(line.lstrip("# ") for line in seed_table_toml().splitlines())
    assert '"earth-rate-only": the paper\'s reading of eq. (16)' in flat
    assert "45 is the paper's φ2 ∈ {0°, 45°, 90°}" in flat
    assert "psi = 1.62, theta = 1.62, gamma = 1.62" in flat  # how to state eq. (16) as printed


@pytest.mark.parametrize(
    ("derivation", "angles", "step"),
    [
        ("earth-rate-only", "45", 45.0),
        ("calibration-check", '"every"', "every"),
        ("calibration-check", "7.5", 7.5),
    ],
)
def test_derivation_and_constraint_angles_are_read(derivation, angles, step) -> None:
    t = load_turntable(
        variant(
            "psi = 1.62\ntheta = 1.62\ngamma = 1.62",
            f'calibration_deg_h = 0.01\nderivation = "{derivation}"',
        ).replace("[calibration]", f"[allocation]\nconstraint_angles = {angles}\n[calibration]")
    )
    assert t.settings["requirement"] == {"derivation": derivation}
    assert t.settings["allocation"] == {"constraint_angles": step}


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            "gamma = 1.62",
            'gamma = 1.62\nderivation = "earth-rate-only"',
            r"\[requirement\] derivation applies to calibration_deg_h only",
        ),
        (
            "psi = 1.62\ntheta = 1.62\ngamma = 1.62",
            'calibration_deg_h = 0.01\nderivation = "paper"',
            r"\[requirement\] derivation = 'paper' is unknown: use 'calibration-check' .* or "
            "'earth-rate-only'",
        ),
        (
            "[calibration]",
            "[allocation]\nconstraint_angles = 7\n[calibration]",
            r"\[allocation\] constraint_angles = 7 must be 'every' .* divides 360°",
        ),
        (
            "[calibration]",
            "[allocation]\nconstraint_angles = true\n[calibration]",
            r"\[allocation\] constraint_angles = true must be 'every'",
        ),
        (
            "[calibration]",
            '[allocation]\nconstraint_angles = "all"\n[calibration]',
            r"\[allocation\] constraint_angles = 'all' must be 'every'",
        ),
        (
            "[calibration]",
            "[allocation]\nconstrain_angles = 45\n[calibration]",
            r"\[allocation\] has an unknown key 'constrain_angles' \(did you mean "
            r"'constraint_angles'\?\)",
        ),
    ],
)
def test_bad_choices_are_one_line(old: str, new: str, message: str) -> None:
    with pytest.raises(ConfigError, match=r"^turntable TOML text: " + message) as info:
        load_turntable(variant(old, new))
    assert "\n" not in str(info.value)
