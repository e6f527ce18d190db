"""Instrument specifications: the one spec → Input helper (policy A), and the file's checks."""

from __future__ import annotations

import math

import pytest

from rotacal.errors import ConfigError
from rotacal.uncertainty.distributions import Rectangular
from rotacal.uncertainty.specs import (
    TYPE_A_ONLY_NOTE,
    InstrumentSpecs,
    corrected_note,
    example_specs_toml,
    load_specs,
    spec_distribution,
    spec_input,
    type_a_note,
)


def _one_line(exc: pytest.ExceptionInfo[ConfigError], *needles: str) -> str:
    text = str(exc.value)
    assert "\n" not in text and "np.float64" not in text, text
    for needle in needles:
        assert needle in text, text
    return text


# ------------------------------------------------------------------------- the policy-A helper
def test_input_of_a_stated_mean_carries_value_u_dof_and_origin(tmp_path):
    path = tmp_path / "lab.toml"
    path.write_text(
        "[timebase]\n"
        'relative_error = { distribution = "normal", value = 1.2e-6, u = 1e-7, dof = 12 }\n'
        "[encoder]\n"
        'graduation_error_arcsec = { distribution = "rectangular", half_width = 1.5 }\n',
        encoding="utf-8",
    )
    specs = load_specs(path)
    inp = specs.input("timebase.relative_error", name="timebase error ε")
    assert inp is not None
    assert (inp.name, inp.value, inp.u, inp.dof) == ("timebase error ε", 1.2e-6, 1e-7, 12.0)
    assert inp.unit == ""  # KNOWN_SPECS says "1": a ratio shows no unit
    assert inp.distribution == "normal" and inp.description == "normal u=1e-07"
    assert inp.source == "Type B, timebase.relative_error, from lab.toml"
    # an error stated without a value is centred on 0; rectangular u = a/√3 (GUM 4.3.7)
    g = specs.input("encoder.graduation_error_arcsec", name="graduation")
    assert g is not None
    assert (g.value, g.unit, g.dof) == (0.0, "arcsec", math.inf)
    assert g.u == pytest.approx(1.5 / math.sqrt(3.0), rel=1e-15)
    assert g.description == "rectangular ±1.5"
    # a unit conversion scales value and u; the description keeps the file's unit
    rad = math.pi / 648_000.0
    gr = specs.input("encoder.graduation_error_arcsec", name="g", unit="rad", scale=rad)
    assert gr is not None and gr.unit == "rad" and gr.description == "rectangular ±1.5 arcsec"
    assert gr.u == pytest.approx(1.5 / math.sqrt(3.0) * rad, rel=1e-15)
    # not stated → None (also through the None-tolerant function); unknown name → one line
    assert specs.input("lts.resolution_um", name="q") is None
    assert spec_input(None, "lts.resolution_um", name="q") is None
    assert spec_distribution(None, "lts.resolution_um") is None
    assert (
        spec_distribution(specs, "timebase.relative_error")
        is specs.entries["timebase.relative_error"]
    )
    with pytest.raises(ConfigError) as exc:
        specs.input("timebase.relative_eror", name="x")
    _one_line(exc, "not a known specification")


def test_mean_and_the_standard_notes():
    specs = load_specs(
        {
            "timebase": {"relative_error": {"distribution": "normal", "value": 1.2e-6, "u": 1e-7}},
            "table": {"set_angle_arcsec": {"distribution": "rectangular", "half_width": 2.0}},
        }
    )
    assert specs.mean("timebase.relative_error") == 1.2e-6
    assert specs.mean("table.set_angle_arcsec") == 0.0
    assert specs.mean("lts.resolution_um") == 0.0  # not stated
    note = specs.correction_note("timebase.relative_error")
    assert note == (
        "corrected for the stated mean of timebase.relative_error = 1.2e-06 (GUM §3.2.4, from "
        "specifications); its u stays in the budget."
    )
    assert specs.correction_note("table.set_angle_arcsec") is None  # centred on zero
    assert "= -3 arcsec (GUM" in corrected_note("table.set_angle_arcsec", -3.0, "arcsec")
    assert type_a_note(None, ("timebase.relative_error",)) == TYPE_A_ONLY_NOTE
    assert TYPE_A_ONLY_NOTE == "no instrument specification stated: Type A only."
    assert type_a_note(specs, ("timebase.relative_error", "lts.resolution_um")) is None
    other = type_a_note(specs, ("lts.resolution_um",))
    assert other is not None and "lts.resolution_um in specifications" in other
    assert other.endswith("Type A only.")


# ---------------------------------------------------------------------------------- P2-7 checks
def test_lower_and_upper_work_and_a_swap_has_its_own_message():
    specs = load_specs(
        {
            "timebase": {
                "relative_error": {"distribution": "rectangular", "lower": -1e-6, "upper": 3e-6}
            },
            "lts": {"radius_mm": {"distribution": "triangular", "lower": 99.0, "upper": 101.0}},
        }
    )
    tb = specs.entries["timebase.relative_error"]
    assert isinstance(tb, Rectangular) and (tb.lower, tb.upper) == (-1e-6, 3e-6)
    assert specs.mean("timebase.relative_error") == pytest.approx(1e-6, rel=1e-12)
    assert specs.mean("lts.radius_mm") == pytest.approx(100.0)
    with pytest.raises(ConfigError) as exc:
        load_specs(
            '[timebase]\nrelative_error = { distribution = "rectangular", lower = 3e-6, '
            "upper = -1e-6 }\n"
        )
    _one_line(exc, "[timebase] relative_error", "'lower' (3e-06) is above 'upper' (-1e-06)")
    with pytest.raises(ConfigError) as exc:  # value and limits together: still refused
        load_specs(
            {
                "timebase": {
                    "relative_error": {
                        "distribution": "rectangular",
                        "value": 0.0,
                        "lower": -1e-6,
                        "upper": 1e-6,
                    }
                }
            }
        )
    _one_line(exc, "give either 'lower' and 'upper', or 'value'")


@pytest.mark.parametrize("dof", [1, 2, 0.5])
def test_t_with_two_or_fewer_dof_is_refused_in_the_file(dof):
    with pytest.raises(ConfigError) as exc:
        load_specs(
            f'[timebase]\nrelative_error = {{ distribution = "t", u = 1e-6, dof = {dof} }}\n'
        )
    _one_line(exc, "specifications text: [timebase] relative_error", "dof > 2")
    # ν = 3 has a finite u = scale·√3
    s = load_specs({"timebase": {"relative_error": {"distribution": "t", "u": 1e-6, "dof": 3}}})
    assert s.entries["timebase.relative_error"].std == pytest.approx(1e-6 * math.sqrt(3.0))


@pytest.mark.parametrize(
    ("entry", "needle"),
    [
        ('relative_error = { distribution = "rectangular", half_width = 1e300 }', "too large"),
        ('relative_error = { distribution = "normal", u = 1e200 }', "too large"),
        ('relative_error = { distribution = "normal", U = 1e308, k = 1e-10 }', "finite"),
    ],
)
def test_a_u_that_overflows_names_the_file_and_entry(tmp_path, entry, needle):
    path = tmp_path / "lab.toml"
    path.write_text(f"[timebase]\n{entry}\n", encoding="utf-8")
    with pytest.raises(ConfigError) as exc:
        load_specs(path)
    _one_line(exc, "lab.toml: [timebase] relative_error", needle)


@pytest.mark.parametrize(
    ("section", "name", "spec", "limit"),
    [
        ("timebase", "relative_error", {"half_width": 2.0}, "≤ 0.01"),  # 2 ≠ 2 ppm
        ("timebase", "relative_error", {"value": 0.02, "half_width": 1e-6}, "≤ 0.01"),
        ("table", "set_rate_relative", {"half_width": 0.05}, "≤ 0.01"),  # 5 % as a fraction?
        ("fog", "scale_factor_relative", {"half_width": 100.0}, "≤ 0.01"),  # ppm as a fraction
        ("encoder", "graduation_error_arcsec", {"half_width": 36000.0}, "≤ 3600 arcsec"),
        ("table", "set_angle_arcsec", {"value": -4000.0, "half_width": 1.0}, "≤ 3600 arcsec"),
        ("table", "orientation_error_arcsec", {"half_width": 5000.0}, "≤ 3600 arcsec"),
        ("encoder", "undetectable_harmonics_arcsec", {"half_width": 4000.0}, "≤ 3600 arcsec"),
        ("lts", "resolution_um", {"half_width": 5000.0}, "≤ 1000 µm"),
        ("lts", "radius_mm", {"value": -100.0, "half_width": 0.01}, "0 < R"),
        ("lts", "radius_mm", {"value": 0.15, "half_width": 0.5}, "√3·u < R"),  # metres?
        ("lts", "radius_mm", {"value": 150_000.0, "half_width": 1.0}, "≤ 10000 mm"),
        ("site", "latitude_deg", {"value": 95.0, "half_width": 0.1}, "±90°"),
        ("site", "latitude_deg", {"value": 89.99, "half_width": 0.1}, "±90°"),
    ],
)
def test_implausible_values_for_an_entry_say_check_units(section, name, spec, limit):
    body = {"distribution": "rectangular", **spec}
    with pytest.raises(ConfigError) as exc:
        load_specs({section: {name: body}})
    _one_line(
        exc,
        f"[{section}] {name}",
        f"is implausible for {section}.{name}",
        limit,
        "check units",
    )


def test_plausible_limits_and_the_example_file_pass():
    ok = load_specs(
        {
            "timebase": {"relative_error": {"distribution": "rectangular", "half_width": 0.01}},
            "site": {"latitude_deg": {"distribution": "normal", "value": -90.0 + 1e-9, "u": 0}},
            "lts": {"radius_mm": {"distribution": "normal", "value": 150.0, "u": 0.02}},
        }
    )
    assert ok.mean("site.latitude_deg") == pytest.approx(-90.0)
    load_specs(example_specs_toml())
    # a specification built in code is trusted (a twin may exaggerate an effect on purpose)
    big = InstrumentSpecs({"timebase.relative_error": Rectangular.centered(0.0, 0.1)})
    inp = big.input("timebase.relative_error", name="e")
    assert inp is not None and inp.u == pytest.approx(0.1 / math.sqrt(3.0))
