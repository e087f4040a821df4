"""Dry air with cp(T) (ThermallyPerfectGas) against CoolProp and against its own calculus;
the one perfect gas against the CFD recordings.

The closed forms u(T), h(T), s0(T) are integrals of cp(T); the tests differentiate them
numerically, so a wrong integration constant-free term shows.  The chamber equations read
T, kappa and 1/cv from a table in u: checked against the Newton inverse.
"""

from __future__ import annotations

import json
from pathlib import Path

import CoolProp.CoolProp as CP
import numpy as np
import pytest

from rotorflow.quasi1d.fluids import PerfectGas, dry_air, make_fluid
from rotorflow.quasi1d.perfect_gas import R_UNIVERSAL
from rotorflow.quasi1d.settings import Operating

AIR = dry_air()


def test_cp_matches_coolprop_ideal_gas_air():
    T = np.geomspace(120.0, 2400.0, 60)
    ref = np.array([CP.PropsSI("Cp0mass", "T", t, "P", 1e5, "Air") for t in T])
    assert np.max(np.abs(AIR.cp(T) / ref - 1.0)) < 1e-4
    # cp really varies: 6 % between 300 K and 650 K (a constant cp cannot pass this test)
    assert AIR.cp(650.0) / AIR.cp(300.0) > 1.05


def test_closed_forms_are_the_integrals_of_cp():
    T = np.linspace(150.0, 2500.0, 40)
    d = 1e-3 * T
    du = (AIR.u_T(T + d) - AIR.u_T(T - d)) / (2 * d)
    ds = (AIR.s0_T(T + d) - AIR.s0_T(T - d)) / (2 * d)
    assert np.max(np.abs(du / AIR.cv(T) - 1.0)) < 1e-6
    assert np.max(np.abs(ds * T / AIR.cp(T) - 1.0)) < 1e-6
    assert np.allclose(AIR.h_T(T) - AIR.u_T(T), AIR.R * T, rtol=1e-14)


def test_enthalpy_and_entropy_differences_match_coolprop_at_low_pressure():
    # 0.05 bar: real-gas terms below 1e-4, so CoolProp's air is the ideal gas here
    p = 5e3
    for T1, T2 in ((300.0, 650.0), (250.0, 1200.0)):
        h = [CP.PropsSI("Hmass", "T", t, "P", p, "Air") for t in (T1, T2)]
        s = [CP.PropsSI("Smass", "T", t, "P", p, "Air") for t in (T1, T2)]
        assert AIR.h_T(T2) - AIR.h_T(T1) == pytest.approx(h[1] - h[0], rel=2e-4)
        assert AIR.s0_T(T2) - AIR.s0_T(T1) == pytest.approx(s[1] - s[0], rel=2e-4)


def test_table_lookup_equals_the_newton_inverse():
    T = np.geomspace(25.0, 9900.0, 997)  # off the table's nodes
    u = AIR.u_T(T)
    rho = np.full_like(T, 3.0)
    p, T_tab, kappa = AIR.props(rho, u)
    assert np.max(np.abs(T_tab / T - 1.0)) < 1e-6  # 8192 nodes: linear interpolation
    assert np.allclose(p, rho * AIR.R * T, rtol=1e-6)
    assert np.allclose(kappa, AIR.cp(T) / AIR.cv(T), rtol=1e-6)
    assert AIR.T_u(u) == pytest.approx(T, rel=1e-12)


def test_pressure_derivatives_match_finite_differences():
    rho, T = np.array([0.5, 2.0, 9.0]), np.array([280.0, 500.0, 900.0])
    u = AIR.u_T(T)
    dr, du = 1e-6 * rho, 1e-6 * u
    pr, pu = AIR.dp(rho, u)
    fr = (AIR.props(rho + dr, u)[0] - AIR.props(rho - dr, u)[0]) / (2 * dr)
    fu = (AIR.props(rho, u + du)[0] - AIR.props(rho, u - du)[0]) / (2 * du)
    # dp/drho exact; dp/du = rho R / cv, continuous in u, so it differs from the slope
    # of the piecewise-linear T(u) by up to dT cv'/cv ~ 5e-4 (1.8 K cells)
    assert np.allclose(pr, fr, rtol=1e-8) and np.allclose(pu, fu, rtol=1e-3)
    assert np.allclose(pu, rho * AIR.R / AIR.cv(T), rtol=1e-6)


@pytest.mark.parametrize("gas", [AIR, PerfectGas.from_gas_constant(287.0, 1004.5)],
                         ids=["cp(T)", "perfect"])
def test_isentropic_blowdown_and_constant_volume_fill(gas):
    rho, p1, p2, V = 8.0, 9e5, 6e5, 2e-5
    u = gas.state_pT(p1, p1 / (rho * gas.R))[1]
    r2, u2 = gas.isentropic(np.array([rho]), np.array([u]), p2)
    T2 = p2 / (r2[0] * gas.R)
    assert gas.props(r2, u2)[0][0] == pytest.approx(p2, rel=1e-6)
    # isentropic: no work lost, so the enthalpy drop is the isentropic work p1 -> p2
    T1 = p1 / (rho * gas.R)
    assert gas.state_pT(p2, T2)[2] - gas.state_pT(p1, T1)[2] == pytest.approx(
        gas.work_isentropic(p1, T1, p2), rel=1e-9)
    # fill at constant volume with hot gas: pressure reached, energy booked as m h_in
    m, U = np.array([rho * V]), np.array([rho * V * u])
    h_in = gas.state_pT(12e5, 700.0)[2]
    m2, U2 = (np.ravel(v) for v in gas.fill(m, U, V, h_in, 12e5))
    assert gas.props(m2 / V, U2 / m2)[0][0] == pytest.approx(12e5, rel=1e-6)
    assert U2[0] - U[0] == pytest.approx((m2[0] - m[0]) * h_in, rel=1e-12)
    assert m2[0] > m[0]


# --- the one perfect gas ------------------------------------------------------------------

DATA = Path(__file__).resolve().parent / "data" / "cfd"


def test_perfect_gas_reproduces_the_recorded_cfd_gases_exactly():
    # The chamber case recorded its gas (fields), R and gamma; the channel study recorded
    # R and gamma of the gap cases' constant-viscosity air.  One R_UNIVERSAL gives the
    # same doubles (rtol 0: the CFD dictionaries must not change by a bit).
    desc = json.loads((DATA / "chamber" / "leaking" / "case.json").read_text())
    gas = PerfectGas(**desc["gas"])
    assert (gas.R, gas.gamma) == (desc["R_J_kgK"], desc["gamma"])
    channel = json.loads((DATA / "channel_study.json").read_text())
    gas = PerfectGas(transport="const")
    assert (gas.R, gas.gamma, gas.mu(300.0)) == (channel["R_J_kgK"], channel["gamma"],
                                                 channel["mu_Pa_s"])
    # R = R_UNIVERSAL / M with M in kg/mol, and R gives back its gas.
    assert gas.R == pytest.approx(R_UNIVERSAL / (1e-3 * gas.molar_mass_kg_kmol), rel=1e-15)
    assert PerfectGas.from_gas_constant(gas.R, gas.cp_J_kgK).R == pytest.approx(gas.R,
                                                                               rel=1e-15)


def test_the_constant_cp_fluid_is_the_cfd_chamber_gas():
    # heat_capacity "constant": the quasi-1D model's fluid and the chamber CFD case's gas
    # are one object, built from [operating] in one place.
    op = Operating.from_section({"p_suction_bar": 1.0, "p_discharge_bar": 3.0,
                                 "T_suction_K": 300.0, "speed_rpm": 3000.0,
                                 "heat_capacity": "constant"}, "case.toml")
    fluid = make_fluid(op, 3.0)
    assert isinstance(fluid, PerfectGas) and fluid == op.constant_cp_gas
    assert fluid.R == op.R_J_kgK
    # Sutherland's law: air at 300 K, 1.846e-5 Pa s in the tables (4 digits: rel 1e-3).
    assert fluid.mu(300.0) == pytest.approx(1.846e-5, rel=1e-3)
