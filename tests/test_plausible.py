"""Plausible ranges of case-file numbers: unit slips refused with the slip named, numbers
too large for a float refused in one line, every shipped case inside the ranges."""

import math
import subprocess
import sys
import tomllib

import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.internal_gear.pair import PinGerotor, sigma_limit
from rotorflow.workflow.case import case_from_raw
from rotorflow.workflow.plausible import check_plausible, range_of

from .conftest import CASES

DEFAULT = tomllib.loads((CASES / "default.toml").read_text())


def _with(section: str, key: str, value) -> dict:
    raw = tomllib.loads((CASES / "default.toml").read_text())
    raw.setdefault(section, {})[key] = value
    return raw


# The slips of a fuzzing run of the command line (each produced numbers before), with
# the word the message must contain to tell the user what went wrong.
SLIPS = [
    ("operating", "p_discharge_bar", 2.6e5, "Pa"),
    ("operating", "T_suction_K", 20, "Celsius"),
    ("operating", "T_wall_K", 1e-3, "Celsius"),
    ("operating", "T_wall_K", 80, "Celsius"),  # 80 C: inside 50-1500 K, half the suction's
    ("operating", "T_oil_K", 60, "Celsius"),
    ("leakage", "gap_um", 2e-5, "metres"),
    ("machine", "diameter_mm", 0.1, "metres"),
    ("machine", "length_mm", 0.1, "metres"),
    ("operating", "speed_rpm", 1e300, "rpm"),
    ("operating", "speed_rpm", 1e-6, "rpm"),
    ("operating", "volume_ratio", 100, "built-in ratio"),
    ("leakage", "coefficient", 10, "isentropic nozzle"),
    ("numerics", "rtol", 1, "rtol"),
    ("numerics", "max_steps", 1, "max_steps"),
    ("machine", "lobes_outer", 100, "lobes"),
    ("machine", "lambda", 1e300, "lambda"),
    ("sweep", "wrap_outer_deg", 10000, "turns"),
    ("operating", "heat_transfer_W_m2K", 1e12, "boiling"),
    ("operating", "oil_mass_ratio", 1e6, "liquid"),
]


@pytest.mark.parametrize("section,key,value,word", SLIPS)
def test_a_slip_is_refused_in_one_line_naming_key_value_and_cause(section, key, value, word):
    with pytest.raises(CaseError) as err:
        case_from_raw(_with(section, key, value), CASES / "x.toml")
    msg = str(err.value)
    assert "\n" not in msg
    assert msg.startswith(f"{key} = {value:g} in [{section}]"), msg
    assert word in msg, msg
    assert f'accept = ["{section}.{key}"]' in msg  # how to mean it


@pytest.mark.parametrize("section,key", [("machine", "lobes_outer"), ("machine", "lambda"),
                                         ("operating", "speed_rpm"), ("leakage", "gap_um")])
def test_an_integer_too_large_for_a_float_is_one_line(section, key):
    with pytest.raises(CaseError, match=f"{key} in \\[{section}\\] .* too large"):
        case_from_raw(_with(section, key, 10**400), CASES / "x.toml")


def test_a_deliberate_extreme_is_accepted_by_naming_its_key():
    raw = _with("operating", "T_suction_K", 20.0)  # a helium cold compressor
    raw["plausibility"] = {"accept": ["operating.T_suction_K"]}
    check_plausible(raw, "x.toml")
    raw["operating"]["T_suction_K"] = math.inf  # accepted keys are still numbers
    with pytest.raises(CaseError, match="finite"):
        check_plausible(raw, "x.toml")
    with pytest.raises(CaseError, match="accept"):
        check_plausible({**DEFAULT, "plausibility": {"allow": []}}, "x.toml")


def test_every_shipped_case_is_plausible():
    """The ranges admit what this field's machines use: every example and reference
    case (air and refrigerants, compressors and vacuum pumps, 50 to 110 mm rotors)."""
    files = sorted(CASES.glob("*.toml"))
    assert len(files) > 20
    for f in files:
        check_plausible(tomllib.loads(f.read_text()), f)


def test_ranges_follow_the_unit_in_the_key_name():
    assert range_of("leakage", "gap_um").unit == "um"
    assert range_of("leakage", "land_mm").low < range_of("machine", "diameter_mm").low
    assert range_of("sweep", "wrap_male_deg").high == range_of("sweep", "wrap_outer_deg").high
    assert range_of("cfd", "something_new").high == 1e9  # any other number: its magnitude


def test_the_command_line_refuses_a_slip_with_exit_2_and_writes_nothing(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text((CASES / "default.toml").read_text().replace(
        "T_suction_K = 293.15", "T_suction_K = 20"))
    out = subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", "simulate", case],
                         capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 2
    assert out.stderr.strip().splitlines() == [out.stderr.strip()]
    assert "Celsius" in out.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]


def test_sigma_bar_rounded_above_one_is_the_limit_itself():
    raw = _with("machine", "sigma_bar", 1.0000001)
    case = case_from_raw(raw, CASES / "x.toml")
    assert case.pair.sigma == sigma_limit(case.pair.lobes_outer, case.pair.lam)
    with pytest.raises(CaseError, match="sigma_bar"):
        case_from_raw(_with("machine", "sigma_bar", 1.001), CASES / "x.toml")


@pytest.mark.parametrize("n1,lam,sigma_bar", [(4, 1.25, 0.8), (5, 1.3, 1.0), (3, 2.0, 0.5)])
def test_the_default_arc_fillet_is_the_smallest_that_clears_the_conjugate_one(n1, lam,
                                                                             sigma_bar):
    sigma = sigma_bar * sigma_limit(n1, lam)
    arc = PinGerotor(n1, lam, sigma, 0.1, "arc")  # no apex given: accepted
    apex = arc.apex_diameter
    assert apex >= 0.1
    if apex > 0.1 * (1 + 1e-6):  # not the rotor diameter: one 0.1 % shallower cuts in
        with pytest.raises(CaseError, match="infringes"):
            PinGerotor(n1, lam, sigma, 0.1, "arc", apex * 0.999)

