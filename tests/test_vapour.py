"""A volatile liquid's vapour in a perfect carrier gas (quasi1d/vapour.py), checked against
CoolProp's humid-air model (Hyland & Wexler, real-gas air and the enhancement factor),
which the mixture does not use, and against its own closed forms differenced."""

from __future__ import annotations

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.quasi1d.perfect_gas import PerfectGas
from rotorflow.quasi1d.vapour import HumidGas, Vapour

CP_AIR = PerfectGas()


@pytest.fixture(scope="module")
def humid():
    return HumidGas(CP_AIR, Vapour.of("Water", 293.15))


def test_the_vapour_pressure_is_coolprops(humid):
    """The table in ln p against 1 / T: within 1e-6 of CoolProp's saturation pressure
    between the nodes (the table's interpolation, not the equation of state)."""
    import CoolProp.CoolProp as CP

    T = np.linspace(280.0, 600.0, 97) + 0.123
    ref = np.array([CP.PropsSI("P", "T", t, "Q", 1.0, "Water") for t in T])
    assert np.max(np.abs(humid.vapour.p_sat(T) / ref - 1.0)) < 1e-6


@pytest.mark.parametrize("T", [293.15, 323.15, 353.15])
@pytest.mark.parametrize("p", [1e5, 8e5])
def test_saturated_air_agrees_with_coolprops_humid_air(humid, T, p):
    """Saturated humid air: vapour mass fraction within 3 % and density within 0.4 % of
    CoolProp's HAPropsSI.  Why not closer: HAPropsSI multiplies the vapour's partial
    pressure by the enhancement factor f (1.004 at 1 bar, ~1.03 at 8 bar, what the
    dissolved air does to water's vapour pressure) and takes air as a real gas (Z of
    air at 8 bar and 293 K is 0.998); the ideal mixture here has neither (measured:
    0.4 / 2.5 % in w, 0.05 / 0.3 % in density)."""
    import CoolProp.CoolProp as CP

    W = CP.HAPropsSI("W", "T", T, "P", p, "R", 1.0)  # kg vapour per kg dry air
    rho_ref = (1.0 + W) / CP.HAPropsSI("Vda", "T", T, "P", p, "R", 1.0)
    w = float(humid.saturated_fraction(p, T))
    assert w == pytest.approx(W / (1.0 + W), rel=0.03)
    assert humid.state_pT(p, T, w)[0] == pytest.approx(rho_ref, rel=4e-3)


def test_the_latent_heat_follows_kirchhoff(humid):
    """h_v(T) - c_l (T - T0) is the latent heat at T (Kirchhoff's law with constant heat
    capacities): within 1 % of CoolProp's between 0 and 100 C for water (c_l 4180)."""
    import CoolProp.CoolProp as CP

    for T in (283.15, 313.15, 373.15):
        ref = (CP.PropsSI("H", "T", T, "Q", 1.0, "Water")
               - CP.PropsSI("H", "T", T, "Q", 0.0, "Water"))
        model = float(humid.vapour.h(T)) - 4180.0 * (T - 293.15)
        assert model == pytest.approx(ref, rel=1e-2)


def test_the_state_functions_invert_each_other(humid):
    """(p, T, w) -> (rho, u) -> props gives back p and T; u_from_rho_p and T_ph too."""
    p, T, w = 3.2e5, 341.0, 0.037
    rho, u, h = humid.state_pT(p, T, w)
    p2, T2, kappa = humid.props(rho, u, w)
    assert (p2, T2) == pytest.approx((p, T), rel=1e-13)
    assert humid.u_from_rho_p(rho, p, w) == pytest.approx(u, rel=1e-13)
    assert humid.T_ph(p, h, w) == pytest.approx(T, rel=1e-13)
    assert 1.0 < kappa < CP_AIR.gamma


def test_the_pressure_derivatives_are_the_differences(humid):
    """dp(rho, u, w) against central differences of props (rel 1e-6)."""
    rho, u, w = 4.1, 3.1e5, 0.05
    analytic = humid.dp(rho, u, w)
    for i, (a, step) in enumerate(zip(analytic, (1e-4 * rho, 1e-4 * u, 1e-5), strict=True)):
        args_p = [rho, u, w]
        args_m = [rho, u, w]
        args_p[i] += step
        args_m[i] -= step
        fd = (humid.props(*args_p)[0] - humid.props(*args_m)[0]) / (2 * step)
        assert a == pytest.approx(fd, rel=1e-6)


def test_filling_reaches_the_pressure_and_keeps_the_books(humid):
    """fill: gas of enthalpy h_in and fraction w_in added at constant V until p2; the
    result is at p2 (props, not fill's algebra), the added mass carries h_in and w_in."""
    V, m, w = 2e-3, 4e-3, 0.01
    rho, u, _ = humid.state_pT(2e5, 330.0, w)
    m = rho * V
    U, mv = m * u, m * w
    h_in, w_in = humid.state_pT(6e5, 360.0, 0.02)[2], 0.02
    m2, U2, mv2 = humid.fill(m, U, mv, V, h_in, w_in, 6e5)
    x = m2 - m
    assert x > 0
    assert humid.props(m2 / V, U2 / m2, mv2 / m2)[0] == pytest.approx(6e5, rel=1e-12)
    assert (U2 - U, mv2 - mv) == pytest.approx((h_in * x, w_in * x), rel=1e-12)


def test_frozen_isentropic_expansion(humid):
    """isentropic: p / rho^kappa is kept at frozen composition (kappa of the mixture)."""
    rho, u, _ = humid.state_pT(9e5, 400.0, 0.03)
    p1, _, kappa = humid.props(rho, u, 0.03)
    rho2, u2 = humid.isentropic(rho, u, 2e5, 0.03)
    assert humid.props(rho2, u2, 0.03)[0] == pytest.approx(2e5, rel=1e-12)
    assert 2e5 / rho2 ** kappa == pytest.approx(p1 / rho ** kappa, rel=1e-12)


def test_evaporation_drives_towards_saturation(humid):
    """J > 0 below saturation at the liquid's temperature, < 0 above, 0 without liquid,
    and proportional to the liquid's mass (its surface, through h A = m c / tau)."""
    T_l = 320.0
    rho_sat = float(humid.vapour.rho_sat(T_l))
    rho = 1.2
    Ho = 1.0 * 4180.0 * (T_l - 293.15)
    for w, sign in ((0.5 * rho_sat / rho, 1.0), (1.5 * rho_sat / rho, -1.0)):
        J, T = humid.evaporation(np.array([1.0, 2.0, 0.0]), np.array([Ho, 2 * Ho, 0.0]),
                                 4180.0, 1e-3, rho, w, humid.cp(w))
        assert T[0] == pytest.approx(T_l)
        assert np.sign(J[0]) == sign and J[1] == pytest.approx(2 * J[0]) and J[2] == 0.0


def test_an_unknown_liquid_is_named():
    with pytest.raises(CaseError, match="does not know the volatile liquid 'Watr'"):
        Vapour.of("Watr", 293.15)
