"""The chamber's wall heat transfer (quasi1d/heat.py): the Dittus-Boelter correlation
against its closed form evaluated with handbook properties, its scaling laws and its
limits, and the model using it conserving energy with heat flowing the right way."""

from __future__ import annotations

import math

import pytest

from rotorflow.errors import CaseError
from rotorflow.quasi1d import Leakage, Operating, simulate
from rotorflow.quasi1d.heat import WallHeat, dittus_boelter, hydraulic_diameter
from rotorflow.quasi1d.perfect_gas import PerfectGas
from rotorflow.quasi1d.synthetic import sin2_table

AIR = PerfectGas(cp_J_kgK=1006.43)


def test_dittus_boelter_is_its_closed_form_with_handbook_air():
    """Air at 1 bar and 300 K in a 50 mm duct at 20 m/s (Re ~ 6.3e4), with the properties
    of Incropera & DeWitt's Table A.4 (mu 184.6e-7 Pa s, k 26.3e-3 W/(m K), Pr 0.707):
    h = k / D 0.023 Re^0.8 Pr^0.4 (gas heated by walls at 400 K).  2 %: the model's
    Sutherland mu and constant Pr = 0.71 against the table (mu 0.3 %, k 1.5 %)."""
    rho, T, u, D = 1e5 / (287.05 * 300.0), 300.0, 20.0, 0.05
    mu, k, pr = 184.6e-7, 26.3e-3, 0.707
    re = rho * u * D / mu
    expected = k / D * 0.023 * re**0.8 * pr**0.4
    assert float(dittus_boelter(rho, T, 400.0, u, D, AIR)) == pytest.approx(expected, rel=0.02)
    # cooled gas (walls at 250 K): Pr^0.3 instead of Pr^0.4
    assert float(dittus_boelter(rho, T, 250.0, u, D, AIR)) == pytest.approx(
        expected * pr**-0.1, rel=0.02)


def test_dittus_boelter_scales_as_density_to_the_power_0_8():
    """h ~ (rho u)^0.8 D^-0.2 at fixed T: what makes a rarefied chamber nearly adiabatic."""
    h = lambda rho, u, D: float(dittus_boelter(rho, 350.0, 300.0, u, D, AIR))  # noqa: E731
    assert h(0.02, 20.0, 0.05) / h(0.01, 20.0, 0.05) == pytest.approx(2**0.8, rel=1e-12)
    assert h(0.01, 40.0, 0.05) / h(0.01, 20.0, 0.05) == pytest.approx(2**0.8, rel=1e-12)
    assert h(0.01, 20.0, 0.10) / h(0.01, 20.0, 0.05) == pytest.approx(2**-0.2, rel=1e-12)


def test_no_heat_without_flow_or_temperature_difference():
    law = WallHeat(0.0, "dittus-boelter", 350.0, speed=20.0, gas=AIR)
    V, rho = 1e-3, 0.5
    assert float(law.rate(V, None, rho, 350.0)) == 0.0  # gas at the wall temperature
    still = WallHeat(0.0, "dittus-boelter", 350.0, speed=0.0, gas=AIR)
    assert float(still.rate(V, None, rho, 500.0)) == 0.0  # no velocity, no Re
    # and a hotter gas loses heat, a colder one gains it
    assert float(law.rate(V, None, rho, 500.0)) < 0.0 < float(law.rate(V, None, rho, 300.0))


def test_hydraulic_diameter_is_four_volume_over_the_wall_area():
    """D_h = 4 V / (6 V^(2/3)): two thirds of the cube's edge, as for a cube duct's 4A/P."""
    assert float(hydraulic_diameter(0.001)) == pytest.approx(2.0 / 3.0 * 0.1, rel=1e-12)


def _op(**kw):
    d = {"p_suction_bar": 1.0, "p_discharge_bar": 8.0, "T_suction_K": 300.0,
         "speed_rpm": 3000.0, "volume_ratio": 4.6}
    d.update(kw)
    return Operating.from_section(d, "test")


def test_the_model_with_the_correlation_conserves_energy_and_heat_flows_downhill():
    table = sin2_table(rows=721)
    leak = Leakage(gap_m=5e-6, model="nozzle", coefficient=0.5)
    corr = {"heat_transfer_correlation": "dittus-boelter"}
    cold = simulate(table, _op(T_wall_K=300.0, **corr), leak).figures
    hot = simulate(table, _op(T_wall_K=700.0, **corr), leak).figures
    assert cold["heat_to_gas_W"] < 0.0 < hot["heat_to_gas_W"]
    assert hot["energy_balance_error"] < 1e-6 and cold["energy_balance_error"] < 1e-6
    assert all(math.isfinite(f["indicated_power_W"]) for f in (cold, hot))


@pytest.mark.parametrize("extra, words", [
    ({"heat_transfer_W_m2K": 100.0}, "not both"),
    ({"fluid": "CoolProp::R134a"}, "fluid \"air\" only"),
    ({"heat_transfer_correlation": "nusselt"}, "must be one of"),
])
def test_bad_heat_transfer_keys_are_refused(extra, words):
    keys = {"heat_transfer_correlation": "dittus-boelter", **extra}
    with pytest.raises(CaseError, match=words):
        _op(**keys)
