"""Rotor gas loads, mechanical loss and shaft power of the quasi-1D model.

The physics checked: the kinematic identity of the table (sum of omega_r T_r per unit
pressure is dV/dt), zero net load at uniform pressure, the power balance of the
converged cycle (the shafts' mean power is the p dV work), the scaling of the
friction model with speed, and bad [mechanical] input.
"""

import math
from dataclasses import replace

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry import table as table_io
from rotorflow.geometry.films import FaceFilm, TipFilm
from rotorflow.geometry.summary import chamber_table
from rotorflow.quasi1d import Leakage, Mechanical, Operating, simulate
from rotorflow.quasi1d.loads import GasLoads, RotorLoads, fold, gas_loads, slots
from rotorflow.quasi1d.mechanical import mechanical_loss
from rotorflow.quasi1d.shaft import sign_changes
from rotorflow.workflow.case import load_case

from .conftest import CASES

#: The model's indicated power is accurate to about the integrator's rtol (1e-4, see
#: quasi1d.settings.Numerics); the loads' power is a trapezoid rule on the replayed
#: period (measured 4.5e-5 off on the default case, 2.9e-4 on the unrefined trace).
#: Twice the rtol: a rotor's torque 1 % off, or the discharge tail after death left
#: out (~1e-3), fails it.
POWER_BALANCE_RTOL = 2.0e-4
#: The table's torques and dV/dangle come from one section table by different
#: quadratures (convolution of a linear interpolant vs splines along z); measured 1.8e-7
#: of the largest dV/dangle on the default case.
KINEMATIC_RTOL = 1.0e-5
#: Chambers a whole period apart sit at the same fraction of a cell of the period-aligned
#: grid, so a uniform pressure cancels to round-off of sums of ~10 terms.
UNIFORM_RTOL = 1.0e-9


@pytest.fixture(scope="module")
def default():
    case = load_case(CASES / "default.toml")
    tab = chamber_table(case)
    raw, where = case.raw, str(case.path)
    op = Operating.from_section(raw["operating"], where)
    res = simulate(tab, op, Leakage.from_section(raw["leakage"], where))
    return tab, op, res


def test_table_torques_sum_to_the_volume_rate(default):
    # A chamber whose volume grows by dV does p dV of work on the rotors and nothing on
    # the end plates: sum over rotors of speed ratio x fluid torque = dV/dangle.
    tab = default[0]
    power = sum(s * tab.columns[f"torque_{n}_m3"]
                for n, s in zip(tab.rotor_names, tab.speed_ratios, strict=True))
    scale = np.max(np.abs(tab.dVdangle_m3_rad))
    assert np.max(np.abs(power - tab.dVdangle_m3_rad)) < KINEMATIC_RTOL * scale


def _uniform(tab, ks, theta):
    return fold(tab, theta, tab.period_rad, ks, np.ones((theta.size, ks.size)), 0.0)


def test_uniform_pressure_loads_no_rotor(default):
    tab = default[0]
    theta = np.linspace(0.0, tab.period_rad, 97)
    ks = slots(0.0, tab.period_rad, 1, 0.0, float(tab.angle_rad[-1]))
    loads = _uniform(tab, ks, theta)
    for r in loads:
        scale = np.max(np.abs(tab.columns[f"torque_{r.name}_m3"]))
        fscale = np.max(np.hypot(tab.columns[f"force_{r.name}_x_m2"],
                                 tab.columns[f"force_{r.name}_y_m2"]))
        assert np.max(np.abs(r.torque)) < UNIFORM_RTOL * scale, r.name
        assert np.max(r.radial) < UNIFORM_RTOL * fscale, r.name
    # The youngest chamber left out: the sum no longer cancels, and the check sees it.
    short = _uniform(tab, ks[1:], theta)
    assert np.max(np.abs(short[0].torque)) > 1e3 * UNIFORM_RTOL * scale


def test_power_balance_of_the_default_case(default):
    tab, _, res = default
    fig = res.figures
    loads = res.loads
    assert fig["converged"]
    assert loads.power_balance_error == pytest.approx(fig["loads"]["power_balance_error"])
    omega = {r.name: r.speed_ratio * loads.omega_ref for r in loads.rotors}
    power = sum(loads.mean(r.torque) * omega[r.name] for r in loads.rotors)
    assert power == pytest.approx(fig["indicated_power_W"], rel=POWER_BALANCE_RTOL)
    # A table whose inner-rotor torques are 1 % off breaks the balance.
    cols = dict(tab.columns)
    cols["torque_inner_m3"] = 1.01 * cols["torque_inner_m3"]
    bad = gas_loads(res, replace(tab, columns=cols))
    assert bad.power_balance_error > POWER_BALANCE_RTOL


def test_shaft_figures_of_the_default_case(default):
    fig = default[2].figures
    assert fig["mechanical_loss_W"] > 0.0
    assert fig["shaft_power_W"] == pytest.approx(fig["indicated_power_W"]
                                                 + fig["mechanical_loss_W"], rel=1e-12)
    assert fig["adiabatic_efficiency_shaft"] < fig["adiabatic_efficiency"]
    for name in ("outer", "inner"):
        rotor = fig["loads"]["rotors"][name]
        assert rotor["torque_Nm_min"] <= rotor["torque_Nm_mean"] <= rotor["torque_Nm_max"]
        assert rotor["radial_force_N_max"] >= rotor["radial_force_N_mean"] > 0.0
    # Compression pushes the rotors towards the suction end (-z).
    assert fig["loads"]["rotors"]["inner"]["axial_force_N_mean"] < 0.0


def test_axial_force_splits_into_end_faces_and_flanks(default):
    """Seed 004 separates the end force from the gas force on the flanks: the end face
    (the inner rotor's section, Green's theorem on its profile) carries the pressure
    difference between the plates."""
    tab, op, res = default
    case = load_case(CASES / "default.toml")
    inner = next(r for r in case.pair.rotors if r.name == "inner")
    rotor = res.figures["loads"]["rotors"]["inner"]
    dp = op.p_discharge_Pa - op.p_suction_Pa
    assert rotor["axial_end_force_N"] == pytest.approx(-dp * abs(inner.profile.area),
                                                       rel=1e-9)
    assert rotor["axial_end_force_N"] + rotor["axial_flank_force_N_mean"] == pytest.approx(
        rotor["axial_force_N_mean"], rel=1e-12)


def _one_rotor(radial_N, axial_N, omega):
    theta = np.linspace(0.0, 1.0, 5)
    ones = np.ones_like(theta)
    rotor = RotorLoads("male", 1.0, radial_N * ones, 0.0 * ones, ones,
                       None if axial_N is None else axial_N * ones)
    return GasLoads(theta, (rotor,), omega, 1.0)


def test_skf_bearing_moment_by_hand():
    # Two cylindrical roller bearings at 500 N each and one angular contact ball bearing
    # at 500 N, d = 50 mm: 2 (0.5 0.0011 500 0.05) + 0.5 0.0020 500 0.05 = 0.0525 N m;
    # seal 0.1 N m; 100 rad/s.
    mech = Mechanical(bearing_bore_m=0.05, seal_torque_Nm=0.1)
    loss = mechanical_loss(_one_rotor(1000.0, -500.0, 100.0), mech, 0.2, 100.0)
    assert loss.bearings_W["male"] == pytest.approx(5.25, rel=1e-12)
    assert loss.total_W == pytest.approx(15.25, rel=1e-12)


@pytest.mark.parametrize("axial", [-500.0, None])
def test_friction_is_linear_in_speed_at_given_loads(default, axial):
    # Every term is Coulomb friction (bearings, seal): at given loads the loss doubles
    # with the speed.  (No viscous term is modelled, see quasi1d.mechanical, so nothing
    # grows with its square.)
    mech = Mechanical(seal_torque_Nm=0.2)
    for loads in (_one_rotor(800.0, axial, 100.0), default[2].loads):
        slow = mechanical_loss(loads, mech, 0.1, 50.0).total_W
        fast = mechanical_loss(replace(loads, omega_ref=2.0 * loads.omega_ref), mech, 0.1,
                               100.0).total_W
        assert fast == pytest.approx(2.0 * slow, rel=1e-12)
    # ... and is linear in the load
    one = mechanical_loss(_one_rotor(800.0, axial, 100.0), mech, 0.1, 0.0).total_W
    two = mechanical_loss(_one_rotor(1600.0, None if axial is None else 2 * axial, 100.0),
                          mech, 0.1, 0.0).total_W
    assert two == pytest.approx(2.0 * one, rel=1e-12)


def test_undefined_axial_load_is_reported():
    loss = mechanical_loss(_one_rotor(800.0, None, 100.0), Mechanical(), 0.1, 100.0)
    assert len(loss.not_modelled) == 1 and "male" in loss.not_modelled[0]


def test_sign_changes_of_a_periodic_torque():
    assert sign_changes(np.array([1.0, 2.0, 3.0])) == 0
    assert sign_changes(np.array([1.0, -1.0, 2.0, -2.0])) == 4
    assert sign_changes(np.array([1.0, 0.0, 1.0, -1.0, -1.0])) == 2


@pytest.mark.parametrize("section, word", [
    ({"bearing_mu": 0.001}, "bearing_mu"),
    ({"bearing_bore_mm": -3.0}, "bearing_bore_mm"),
    ({"seal_torque_Nm": "lots"}, "seal_torque_Nm"),
    ({"oil_viscosity_40C_cSt": 46.0}, "oil_viscosity_100C_cSt"),
    ({"oil_viscosity_40C_cSt": 10.0, "oil_viscosity_100C_cSt": 12.0}, "oil_viscosity_100C_cSt"),
    ({"oil_viscosity_40C_cSt": 46.0, "oil_viscosity_100C_cSt": 6.8,
      "oil_density_kg_m3": 0.0}, "oil_density_kg_m3"),
])
def test_bad_mechanical_input(tmp_path, section, word):
    with pytest.raises(CaseError, match=word) as err:
        Mechanical.from_section(section, "pump.toml")
    assert "pump.toml" in str(err.value) and "[mechanical]" in str(err.value)
    # ... and from the case file, naming the file
    case = tmp_path / "case.toml"
    lines = "\n".join(f"{k} = {v!r}".replace("'", '"') for k, v in section.items())
    case.write_text((CASES / "default.toml").read_text() + f"\n[mechanical]\n{lines}\n")
    with pytest.raises(CaseError, match=word) as err:
        load_case(case)
    assert str(case) in str(err.value)


def test_table_keeps_the_loads_through_its_files(default, tmp_path):
    tab = default[0]
    table_io.write(tab, tmp_path / "t.csv")
    back = table_io.read(tmp_path / "t.csv")
    assert back.rotor_names == tab.rotor_names and back.speed_ratios == tab.speed_ratios
    assert back.rotor_scalars == tab.rotor_scalars
    # the CSV keeps 13 significant digits
    col = tab.columns["torque_outer_m3"]
    np.testing.assert_allclose(back.columns["torque_outer_m3"], col, rtol=1e-12,
                               atol=1e-12 * np.abs(col).max())
    # ... and the oil films, exactly (JSON keeps a float's 17 digits)
    films = (TipFilm("outer", "seal-next", 0.05, 0.8, (0.0, 1.0 / 3.0, 2e-3)),
             FaceFilm("inner", "hp-face", math.pi * 1e-6))
    table_io.write(replace(tab, oil_films=films), tmp_path / "f.csv")
    assert table_io.read(tmp_path / "f.csv").oil_films == films
