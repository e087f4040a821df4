"""Case-file sections of the quasi-1D model: values in SI, one clear line for bad input."""

from __future__ import annotations

import math

import pytest

from rotorflow.errors import CaseError
from rotorflow.quasi1d import Leakage, Numerics, Operating, Ports, simulate
from rotorflow.quasi1d.synthetic import sin2_table

GOOD = {"p_suction_bar": 1.0, "p_discharge_bar": 8.0, "T_suction_K": 300.0,
        "speed_rpm": 3000.0, "fluid": "air", "volume_ratio": 4.6, "driven": "inner"}


def _op(**kw):
    d = dict(GOOD)
    d.update(kw)
    return d


def test_operating_reads_si_values():
    op = Operating.from_section(_op(suction_close_deg=200, discharge_open_deg=560), "case.toml")
    assert op.p_suction_Pa == 1e5 and op.p_discharge_Pa == 8e5
    assert op.suction_close_rad == pytest.approx(math.radians(200))
    assert op.wall_temperature_K == 300.0  # defaults to the suction temperature
    assert op.R_J_kgK == pytest.approx(287.0, rel=1e-3)


def test_leakage_ports_numerics_read_si_values():
    lk = Leakage.from_section({"gap_um": 5, "model": "fanno", "coefficient": 0.7}, "c.toml")
    assert lk.gap_m == pytest.approx(5e-6) and lk.model == "fanno" and lk.coefficient == 0.7
    assert Ports.from_section({"model": "nozzle", "coefficient": 0.6}, "c.toml").coefficient == 0.6
    assert Numerics.from_section({"integrator": "bs3", "rtol": 1e-5}, "c.toml").rtol == 1e-5
    assert Leakage.from_section({"model": "none"}, "c.toml").gap_m == 0.0


@pytest.mark.parametrize(
    "cls, section, d, words",
    [
        (Operating, "operating", _op(p_sucton_bar=1.0), ["unknown key 'p_sucton_bar'",
                                                         "[operating]", "case.toml"]),
        (Operating, "operating", _op(p_suction_bar=-1.0), ["p_suction_bar", "positive"]),
        (Operating, "operating", _op(p_discharge_bar=0.5), ["p_discharge_bar", "compressor"]),
        (Operating, "operating", _op(fluid="unobtainium"), ["unknown fluid", "unobtainium"]),
        (Operating, "operating", _op(fluid="CoolProp::Unobtainium"), ["unknown fluid"]),
        (Operating, "operating", _op(T_suction_K="hot"), ["T_suction_K", "number"]),
        (Operating, "operating", _op(heat_capacity="variable"), ["heat_capacity", "constant"]),
        (Operating, "operating", _op(heat_capacity="temperature", cp_J_kgK=1005.0),
         ["cp_J_kgK", "constant-cp"]),
        (Operating, "operating", _op(fluid="CoolProp::Air", cp_J_kgK=1005.0),
         ["cp_J_kgK", "CoolProp::Air"]),
        (Operating, "operating", _op(speed_rpm=0), ["speed_rpm", "positive"]),
        (Operating, "operating", _op(volume_ratio=0.5), ["volume_ratio", "at least 1"]),
        (Operating, "operating", {k: v for k, v in GOOD.items() if k != "T_suction_K"},
         ["missing key 'T_suction_K'"]),
        (Operating, "operating", _op(suction_close_deg=300, discharge_open_deg=200),
         ["discharge_open_deg", "later"]),
        (Leakage, "leakage", {"gap_um": 5, "model": "labyrinth"}, ["model", "nozzle"]),
        (Leakage, "leakage", {"model": "nozzle"}, ["missing key 'gap_um'"]),
        (Leakage, "leakage", {"gap_um": 0, "model": "nozzle"}, ["gap_um", "positive"]),
        (Leakage, "leakage", {"gap_um": 5, "wall_motion": "yes"}, ["wall_motion", "true"]),
        (Leakage, "leakage", {"gap_um": 5, "gap_mm": 1}, ["unknown key 'gap_mm'", "[leakage]"]),
        (Ports, "ports", {"model": "valve"}, ["model", "ideal"]),
        (Ports, "ports", {"coefficient": -1}, ["coefficient", "positive"]),
        (Numerics, "numerics", {"integrator": "euler"}, ["integrator"]),
        (Numerics, "numerics", {"max_cycles": 2.5}, ["max_cycles", "integer"]),
    ],
)
def test_bad_input_is_one_clear_line(cls, section, d, words):
    with pytest.raises(CaseError) as e:
        cls.from_section(d, "case.toml")
    msg = str(e.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg


def test_missing_table_and_impossible_ports():
    op = Operating.from_section(GOOD, "case.toml")
    with pytest.raises(CaseError, match="chamber table"):
        simulate(None, op)
    table = sin2_table(rows=301)
    with pytest.raises(CaseError, match="volume_ratio"):  # discharge volume below vanishing
        simulate(table, Operating.from_section(_op(volume_ratio=5000.0), "case.toml"))
    with pytest.raises(CaseError, match="suction port closing"):
        simulate(table, Operating.from_section(_op(suction_close_deg=2000.0), "case.toml"))
    with pytest.raises(CaseError, match="volume_ratio or discharge_open_deg"):
        simulate(table, Operating.from_section(
            {k: v for k, v in GOOD.items() if k != "volume_ratio"}, "case.toml"))


def test_air_is_dry_air_with_cp_of_t_unless_a_constant_cp_is_given():
    from rotorflow.quasi1d.fluids import PerfectGas, ThermallyPerfectGas, make_fluid

    op = Operating.from_section(_op(), "case.toml")
    assert op.heat_capacity == "temperature"
    assert isinstance(make_fluid(op, 4.6), ThermallyPerfectGas)
    for extra in ({"cp_J_kgK": 1005.0}, {"molar_mass_g_mol": 28.0},
                  {"heat_capacity": "constant"}):
        op = Operating.from_section(_op(**extra), "case.toml")
        assert op.heat_capacity == "constant"
        gas = make_fluid(op, 4.6)
        assert isinstance(gas, PerfectGas) and gas.cp_J_kgK == op.cp_J_kgK


def test_ideal_gas_needs_cp_above_R():
    op = Operating.from_section(_op(cp_J_kgK=200.0), "case.toml")
    with pytest.raises(CaseError, match="cp_J_kgK"):
        simulate(sin2_table(rows=301), op)


def test_coolprop_names_are_accepted():
    op = Operating.from_section(_op(fluid="CoolProp::Air"), "case.toml")
    assert op.fluid == "CoolProp::Air"
    op = Operating.from_section(_op(fluid="CoolProp::R134a"), "case.toml")
    assert op.fluid == "CoolProp::R134a"
