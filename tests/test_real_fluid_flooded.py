"""A refrigerant flooded with oil, or drawing in a liquid, that the oil or liquid cools
to its condensing temperature or below (an oil-injected refrigeration screw's ordinary
case: oil cooled to about the condensing temperature).

The machine is examples/refrigeration_r134a.toml's (R134a, 3 bar / 285 K -> 9 bar,
condensing at 308.7 K).  The references are CoolProp's saturation states, independent
of the model's property table.
"""

from __future__ import annotations

import CoolProp.CoolProp as CP
import pytest

from rotorflow.quasi1d import Leakage, Operating, simulate
from rotorflow.quasi1d.fluids import make_fluid
from rotorflow.quasi1d.plenums import plenums

from .conftest import CASES

CASE = CASES / "refrigeration_r134a.toml"
P_D = 9e5
T_DEW = CP.PropsSI("T", "P", P_D, "Q", 1.0, "R134a")  # 308.7 K
RHO_DEW = CP.PropsSI("Dmass", "P", P_D, "Q", 1.0, "R134a")  # 44 kg/m3 (liquid: 1150)

#: Oil at and below the condensing temperature; a liquid drawn in at suction.
FLOODED = {
    "oil at the condensing temperature": {"oil_mass_ratio": 4, "T_oil_K": round(T_DEW, 2)},
    "oil 9 K below it": {"oil_mass_ratio": 2, "T_oil_K": 300.0},
    "liquid drawn in": {"gas_volume_fraction": 0.95, "liquid_density_kg_m3": 900,
                        "liquid_cp_J_kgK": 1900},
}


@pytest.fixture(scope="module")
def machine():
    from rotorflow.geometry.summary import chamber_table
    from rotorflow.workflow.case import load_case

    case = load_case(CASE)
    return (chamber_table(case), dict(case.raw["operating"]),
            Leakage.from_section(case.raw["leakage"], str(CASE)))


@pytest.mark.parametrize("extra", FLOODED.values(), ids=FLOODED.keys())
def test_the_gas_that_flows_back_is_vapour(machine, extra):
    # (p, T) below the dew point names subcooled liquid, which flowed back into the
    # chambers as the discharge plenum's "gas" (1150-1250 kg/m3) and stalled the cycle
    table, raw, _ = machine
    op = Operating.from_section({**raw, **extra}, "test")
    fluid = make_fluid(op, float(raw["volume_ratio"]))
    dis = plenums(fluid, op)[1]
    assert dis.T >= T_DEW - 1e-9
    assert dis.rho <= RHO_DEW * (1 + 1e-9)


@pytest.mark.parametrize("extra", FLOODED.values(), ids=FLOODED.keys())
def test_a_flooded_refrigerant_converges_and_conserves(machine, extra):
    # (each failed before: the time budget, a step-size underflow or a state off the
    # property table after 30-80 s; the liquid's, once past that, in the ideal discharge
    # port's filling, which took the chamber's gas volume for one number)
    table, raw, leak = machine
    res = simulate(table, Operating.from_section({**raw, **extra}, "test"), leak)
    fig = res.figures
    assert fig["converged"], fig.get("message")
    assert fig["mass_balance_error"] < 1e-6 and fig["energy_balance_error"] < 1e-6
    # the oil or liquid keeps the delivered refrigerant at its condensing temperature or
    # above it: it cannot leave colder than the dew point at the discharge pressure
    assert fig["discharge_temperature_K"] >= T_DEW - 1e-6
    assert 0.5 < fig["volumetric_efficiency"] < 1.0
