"""Bad input for a real fluid (issue 14): exit status 2, one line on stderr naming the
problem, nothing written.  The cases are examples/refrigeration_r134a.toml (R134a,
3 bar: saturation temperature 273.82 K) with one key changed.
"""

from __future__ import annotations

import math

import CoolProp.CoolProp as CP
import pytest

from rotorflow.errors import CaseError
from rotorflow.quasi1d.coolprop_fluid import SATURATION_T_TOLERANCE_K, tabulated

from .conftest import CASES, run_cli

R134A_CASE = CASES / "refrigeration_r134a.toml"
TSAT_3BAR = CP.PropsSI("T", "P", 3e5, "Q", 1.0, "R134a")  # 273.82 K


def _cli(*args):
    return run_cli(*args)


def _refused(tmp_path, text):
    """Run `rotorflow simulate` on ``text``; the one line of stderr when it exits 2 having
    written nothing."""
    case = tmp_path / "case.toml"
    case.write_text(text)
    traces = tmp_path / "traces"
    out = _cli("simulate", case, "--json", "--traces", traces)
    assert out.returncode == 2 and out.stdout == "", out.stderr
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1, out.stderr
    assert not traces.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]
    return lines[0]


def _case(old, new, base=R134A_CASE):
    text = base.read_text()
    assert old in text
    return text.replace(old, new)


@pytest.mark.parametrize("T, state", [(270.0, "subcooled liquid"), (273.82, "saturated"),
                                      (273.9, "saturated")])
def test_dry_suction_inside_the_dome_or_liquid_is_refused(tmp_path, T, state):
    # No suction_quality: the suction must be superheated vapour.  At 3 bar R134a
    # saturates at 273.82 K: 270 K is liquid, 273.82 K on the line (CoolProp's (p, T)
    # flash is singular there), 273.9 K within SATURATION_T_TOLERANCE_K of it.  The line
    # names the saturation temperature, so the user sees how far off the input is.
    line = _refused(tmp_path, _case("T_suction_K = 285", f"T_suction_K = {T}"))
    assert "T_suction_K" in line and state in line and f"{TSAT_3BAR:.2f} K" in line, line


def test_dry_suction_just_above_saturation_is_accepted():
    # The other side of the check: 2 tolerances above the saturation temperature is a
    # (barely) superheated vapour, and its table is built.
    T = round(TSAT_3BAR + 2 * SATURATION_T_TOLERANCE_K, 2)
    rho, u = (CP.PropsSI(k, "P", 3e5, "T", T, "R134a") for k in ("Dmass", "Umass"))
    assert tabulated("R134a", 3e5, 9e5, T, T, T, 2.7).in_range([rho], [u])
    with pytest.raises(CaseError, match="saturated"):
        tabulated("R134a", 3e5, 9e5, TSAT_3BAR, TSAT_3BAR, TSAT_3BAR, 2.7)


def test_supercritical_suction_has_no_dome_to_refuse():
    # Above the critical pressure there is no saturation temperature: CO2 at 80 bar and
    # 300 K (below its critical 304.1 K: a dense supercritical fluid) is not refused as
    # "liquid"; the check applies below the critical pressure only.
    assert tabulated("CO2", 80e5, 120e5, 300.0, 300.0, 300.0, 1.3).name == "CO2"


@pytest.mark.parametrize("q", ["0", "-0.2", "1.5"])
def test_suction_quality_outside_zero_one_is_refused(tmp_path, q):
    line = _refused(tmp_path, _case("T_suction_K = 285",
                                    f"T_suction_K = 273.82\nsuction_quality = {q}"))
    # (one message for all three: the range, not "must be positive" for the first two)
    assert "suction_quality" in line and q in line and "(0, 1]" in line, line


def test_unknown_coolprop_mixture_name_is_refused(tmp_path):
    # (An unknown pure fluid, R9999, is tests/test_quasi1d_real_fluid.py's.)
    line = _refused(tmp_path, _case('fluid = "CoolProp::R134a"', 'fluid = "CoolProp::R410X"'))
    assert "CoolProp::R410X" in line, line


def test_wet_suction_of_a_pseudo_pure_blend_is_refused(tmp_path):
    # CoolProp's R410A is a pseudo-pure fluid whose (rho, u) flash fails inside the dome:
    # a wet suction has no table cells.  Refused in one line (it was a traceback from
    # the chamber's first state).
    text = _case('fluid = "CoolProp::R134a"', 'fluid = "CoolProp::R410A"')
    text = text.replace("p_suction_bar = 3.0", "p_suction_bar = 8.0").replace(
        "p_discharge_bar = 9.0", "p_discharge_bar = 24.0")
    Tsat = CP.PropsSI("T", "P", 8e5, "Q", 0.97, "R410A")
    line = _refused(tmp_path, text.replace(
        "T_suction_K = 285", f"T_suction_K = {Tsat:.2f}\nsuction_quality = 0.97"))
    assert "R410A" in line and "superheated" in line, line


@pytest.mark.parametrize("name, words", [
    ("CoolProp::", ["unknown fluid"]),  # (CoolProp lists an empty alias: it passed)
    ("CoolProp::R32&R125", ["mixture", "CoolProp::R410A"]),
    ("CoolProp::R407C.mix", ["mixture", "pseudo-pure"]),
    ("CoolProp::R134", ["unknown fluid", "did you mean CoolProp::R134a"]),
    # a CoolProp name without its prefix: the hint named none (only "CoolProp::Air")
    ("CO2", ["unknown fluid", "did you mean CoolProp::CO2"]),
])
def test_fluid_names_that_are_no_fluid_are_refused_with_a_remedy(tmp_path, name, words):
    line = _refused(tmp_path, _case('fluid = "CoolProp::R134a"', f'fluid = "{name}"'))
    assert all(w in line for w in words), line


def test_a_suction_beyond_the_equation_of_state_is_refused(tmp_path):
    # CoolProp's R134a equation holds to 455 K; above it CoolProp extrapolates silently
    tmax = CP.AbstractState("HEOS", "R134a").Tmax()
    line = _refused(tmp_path, _case("T_suction_K = 285", f"T_suction_K = {tmax + 15:g}"))
    assert "T_suction_K" in line and f"{tmax:.2f} K" in line, line


def test_a_blends_suction_inside_its_glide_is_named_so(tmp_path):
    # R407C at 4.6 bar: bubble point 266.9 K, dew point 273.2 K; 271 K lies in the glide,
    # which the message called subcooled liquid
    text = _case('fluid = "CoolProp::R134a"', 'fluid = "CoolProp::R407C"').replace(
        "p_suction_bar = 3.0", "p_suction_bar = 4.6")
    line = _refused(tmp_path, text.replace("T_suction_K = 285", "T_suction_K = 271"))
    assert "glide" in line and "subcooled" not in line, line


def test_a_wet_suction_whose_liquid_cannot_fit_is_refused_as_a_hydraulic_lock(tmp_path):
    # Quality 0.01 at 3 bar: the liquid is 53 % of the suction volume (CoolProp's
    # saturated densities), the chamber keeps 1 / 2.7 = 37 % when the discharge opens.
    # (It was a 31-line traceback from the chambers' starting guess.)
    rho_l, rho_v = (CP.PropsSI("Dmass", "P", 3e5, "Q", q, "R134a") for q in (0.0, 1.0))
    share = 0.99 / rho_l / (0.99 / rho_l + 0.01 / rho_v)
    line = _refused(tmp_path, _case("T_suction_K = 285",
                                    f"T_suction_K = {TSAT_3BAR:.2f}\nsuction_quality = 0.01"))
    assert "hydraulic lock" in line and f"{share:.1%}" in line, line


def test_a_dense_suction_squeezed_past_the_equation_of_state_is_named():
    # CO2 at 80 bar / 300 K is liquid-like (753 kg/m3): a volume ratio of 2.1 takes its
    # isentrope to 1.8e4 bar (CoolProp's flash at 2.1 times the density), past the
    # equation's 8000 bar; the message was CoolProp's melting line at 1.79e9 Pa.  At a
    # volume ratio of 1.2 it runs (test_supercritical_suction_has_no_dome_to_refuse).
    with pytest.raises(CaseError, match=r"volume_ratio 2.1 squeezes the suction of CO2"):
        tabulated("CO2", 80e5, 130e5, 300.0, 300.0, 300.0, 2.1)
    assert tabulated("CO2", 80e5, 130e5, 300.0, 300.0, 300.0, 1.2).name == "CO2"


def test_a_state_off_the_property_table_says_which_way_it_left():
    # (the message said only that the state left the table; an ammonia or steam twin
    # screw whose leakage runs the gas away hot gave that after a period)
    f = tabulated("R134a", 3e5, 9e5, 285.0, 285.0, 285.0, 2.7)
    rho_hi, u_hi = math.exp(f.x0 + f.dx * (f.nx - 1)), f.u0 + f.du * (f.nu - 1)
    rho_mid, u_mid = math.exp(f.x0 + 0.5 * f.dx * (f.nx - 1)), f.u0 + 0.5 * f.du * (f.nu - 1)
    assert "hotter" in f.out_of_range([rho_mid], [u_hi + f.du])
    assert "colder" in f.out_of_range([rho_mid], [f.u0 - f.du])
    assert "denser" in f.out_of_range([rho_hi * 1.5], [u_mid])
    assert "thinner" in f.out_of_range([math.exp(f.x0) / 1.5], [u_mid])


def test_a_suction_below_the_triple_point_is_named_a_celsius_slip(tmp_path):
    # 60 passes the 50 K plausibility floor; below R134a's triple point (169.85 K) the
    # dew-point check called it "subcooled liquid"
    line = _refused(tmp_path, _case("T_suction_K = 285", "T_suction_K = 60"))
    assert "169.85 K" in line and "Celsius" in line and "liquid" not in line, line


def test_pressures_in_kpa_name_the_dense_suction(tmp_path):
    # 300 and 650 "bar" (kPa meant): a liquid at 1351 kg/m3 whose range CoolProp cannot
    # bracket; the line gave CoolProp's Brent message alone
    text = _case("p_suction_bar = 3.0", "p_suction_bar = 300").replace(
        "p_discharge_bar = 9.0", "p_discharge_bar = 650")
    line = _refused(tmp_path, text)
    rho = CP.PropsSI("D", "P", 300e5, "T", 285.0, "R134a")
    assert f"{rho:.4g} kg/m3" in line and "critical density" in line, line
