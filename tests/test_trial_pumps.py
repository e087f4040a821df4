"""Defects a trial of the 1-1 screw pumps found: the multiphase pump at a gas volume
fraction of 1 with the liquid's keys left in the case (a designer's all-gas point of a
multiphase map) is the dry pump, not a chamber whose gas volume is read from the
accumulators; a sweep or an optimisation may vary a twin-screw rotor's wrap by the key
its case gives it."""

from __future__ import annotations

import copy
import functools

import pytest

from rotorflow.geometry.summary import build_machine, chamber_table
from rotorflow.postprocess import pump_multiphase as pm
from rotorflow.workflow.case import case_from_raw, load_toml


@functools.cache
def pump():
    raw = load_toml(pm.EXAMPLE)
    case = case_from_raw(raw, pm.EXAMPLE)
    return raw, chamber_table(case, build_machine(case))


def test_a_gas_volume_fraction_of_one_with_liquid_keys_is_the_dry_pump():
    """Measured before the fix: 'step size underflow near angle 1.057410 rad' (the model
    took 1 / rho_l with no liquid block, so the liquid's mass was read from the
    accumulators' columns)."""
    raw, table = pump()
    dry = copy.deepcopy(raw)
    for key in ("gas_volume_fraction", "liquid_density_kg_m3", "liquid_cp_J_kgK"):
        dry["operating"].pop(key)
    wet = copy.deepcopy(raw)
    wet["operating"]["gas_volume_fraction"] = 1.0
    a = pm.point(dry, table, str(pm.EXAMPLE))
    b = pm.point(wet, table, str(pm.EXAMPLE))
    assert b["converged"]
    for key in ("eta_v", "indicated_kW", "power_kW", "mass_flow_kg_s"):
        assert b[key] == pytest.approx(a[key], rel=1e-9), key


# --- a pump's wrap in a sweep or an optimisation ------------------------------------------

def _copy_example(tmp_path, name):
    src = pm.EXAMPLE.parent / name
    (tmp_path / name).write_text(src.read_text())
    return tmp_path / name


def test_a_sweep_over_the_wrap_of_a_twin_screw_rotor_is_read(tmp_path):
    """The pump examples give their wrap as wrap_male_deg, which the case loader takes;
    a sweep over it was refused ("unknown key 'wrap_male_deg' in [sweep]")."""
    from rotorflow.errors import CaseError
    from rotorflow.workflow.sweep_file import load_sweep

    _copy_example(tmp_path, "screw_pump_vacuum.toml")
    path = tmp_path / "wrap.toml"
    path.write_text('[study]\nbase = "screw_pump_vacuum.toml"\nwant = ["geometry"]\n\n'
                    '[grid]\n"sweep.wrap_male_deg" = [720, 1440]\n')
    spec = load_sweep(path)
    assert [row["sweep.wrap_male_deg"] for _, row in spec.points] == [720, 1440]
    path.write_text(path.read_text().replace("wrap_male_deg", "wrap_rotor_deg"))
    with pytest.raises(CaseError, match="unknown key 'wrap_rotor_deg' in \\[sweep\\]"):
        load_sweep(path)


def test_an_optimisation_over_the_wrap_of_a_twin_screw_rotor_is_read(tmp_path):
    from rotorflow.workflow.optimise_spec import load_optimise

    case = _copy_example(tmp_path, "screw_pump_vacuum.toml")
    case.write_text(case.read_text() + '\n[optimise]\npopulation = 4\ngenerations = 1\n\n'
                    '[optimise.variables]\n"sweep.wrap_male_deg" = [720.0, 1440.0]\n\n'
                    '[optimise.objectives]\n"geometry.swept_volume_m3" = "max"\n')
    spec = load_optimise(case)
    assert [v.name for v in spec.variables] == ["sweep.wrap_male_deg"]


# --- unit slips in the liquid's keys ------------------------------------------------------

@pytest.mark.parametrize("key, value, word", [
    ("liquid_density_kg_m3", 0.998, "g/cm3"),        # water in g/cm3
    ("liquid_density_kg_m3", 998000.0, "denser"),
    ("liquid_cp_J_kgK", 4.18, "kJ/kgK"),              # water in kJ/kgK
])
def test_a_slip_in_the_liquids_keys_is_refused_in_one_line(key, value, word):
    """Both slips ran before: 0.998 kg/m3 for 60 s to an unconverged cycle, 4.18 J/kgK to
    a discharge 100 K hotter than the water-cooled 293 K, exit 0."""
    from rotorflow.errors import CaseError

    raw = copy.deepcopy(load_toml(pm.EXAMPLE))
    raw["operating"][key] = value
    with pytest.raises(CaseError) as err:
        case_from_raw(raw, pm.EXAMPLE)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith(f"{key} = {value:g} in [operating]"), msg
    assert word in msg and f'accept = ["operating.{key}"]' in msg, msg


# --- an oil-flooded machine that delivers nothing -----------------------------------------

def test_an_oil_flooded_screw_that_delivers_nothing_gets_its_figures():
    """The 4/6 oil-flooded compressor with its oil's viscosities and 1 mm clearances: the
    leakage exceeds the displacement, so there is no discharged mixture; the oil films'
    temperature took it and the command ended in a TypeError traceback."""
    import math

    from rotorflow.quasi1d import case_settings, simulate

    path = pm.EXAMPLE.parent / "twin_screw_4_6.toml"
    raw = copy.deepcopy(load_toml(path))
    raw["operating"]["speed_rpm"] = 3000
    raw["leakage"]["gap_um"] = 1000
    raw["mechanical"].update(oil_viscosity_40C_cSt=46, oil_viscosity_100C_cSt=6.8)
    case = case_from_raw(raw, path)
    table = chamber_table(case, build_machine(case))
    fig = simulate(table, *case_settings(raw, str(path))).figures
    assert fig["mass_flow_kg_s"] < 0 and "no delivery" in fig["warning"]
    assert fig["discharge_mixture_temperature_K"] is None
    mech = fig["mechanical"]
    assert mech["oil_film_temperature_K"] == pytest.approx(raw["operating"]["T_oil_K"])
    assert mech["oil_film_heating_K"] is None
    assert math.isfinite(fig["shaft_power_W"]) and sum(mech["oil_film_W"].values()) > 0
