"""A liquid that fills chamber volume (quasi1d/liquid.py): the omega method's limits, the
sealed pump's work against the ideal cycle with the liquid's volume, conservation, and
the bad input of the liquid keys."""

from __future__ import annotations

import copy
import functools
import math
import re
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.optimize import brentq

from rotorflow.errors import CaseError
from rotorflow.geometry.summary import build_machine, chamber_table
from rotorflow.postprocess import pump_multiphase as pm
from rotorflow.quasi1d import Leakage, Operating, Ports, flows, liquid, simulate
from rotorflow.quasi1d.settings import AIR_MOLAR_MASS_G_MOL
from rotorflow.quasi1d.synthetic import sin2_table
from rotorflow.workflow.case import case_from_raw, load_toml

from .conftest import run_cli

# --- the omega method --------------------------------------------------------------------

def test_omega_zero_is_the_incompressible_orifice():
    eta = np.linspace(0.01, 0.999, 50)
    np.testing.assert_allclose(liquid.omega_flux(eta, 0.0), np.sqrt(2 * (1 - eta)), rtol=1e-12)


def test_omega_one_is_the_isothermal_gas_nozzle():
    """omega = 1: v = v1 p1 / p, the isothermal ideal gas; G* = sqrt(-2 eta^2 ln eta),
    choked at eta = exp(-1/2) with G* = exp(-1/2)."""
    e = math.exp(-0.5)
    assert liquid.critical_ratio(1.0) == pytest.approx(e, rel=1e-6)
    eta = np.linspace(0.65, 0.999, 20)
    np.testing.assert_allclose(liquid.omega_flux(eta, 1.0),
                               np.sqrt(-2 * eta**2 * np.log(eta)), rtol=1e-12)
    assert liquid.omega_flux(0.1, 1.0) == pytest.approx(e, rel=1e-6)


@pytest.mark.parametrize("omega", [0.02, 0.3, 0.714, 3.0, 30.0])
def test_the_critical_ratio_is_where_the_unchoked_flux_peaks(omega):
    """Leung's critical-ratio equation against an independent construction: the maximum
    of the unchoked G*(eta) over a fine grid; above it the flux is the unchoked one,
    below it constant (choked)."""
    eta = np.linspace(1e-4, 1 - 1e-6, 400_001)
    g = np.sqrt(np.maximum(-2 * (omega * np.log(eta) + (omega - 1) * (1 - eta)), 0)) / (
        omega * (1 / eta - 1) + 1)
    i = int(np.argmax(g))
    assert liquid.critical_ratio(omega) == pytest.approx(eta[i], abs=3e-4)
    assert liquid.omega_flux(eta[i] / 2, omega) == pytest.approx(g[i], rel=1e-6)
    assert liquid.omega_flux(0.5 * (eta[i] + 1), omega) == pytest.approx(
        g[(i + len(eta)) // 2], rel=1e-3)


def test_mixture_factor_limits():
    """No liquid volume (alpha = 1): the gas's own flux (factor 1).  Liquid-laden
    (alpha -> 0) at a small pressure drop: the liquid through the nozzle law times the
    factor is the orifice's A sqrt(2 rho_l dp) (through the split of .oil: gas
    F sqrt(alpha) R / sqrt(1 + X), liquid X times that)."""
    x, k = np.array([0.3, 0.7, 0.99]), 1.4
    np.testing.assert_allclose(liquid.mixture_factor(x, k, 1.2, 50.0, 0.0), 1.0, rtol=1e-12)
    p1, rho_g, rho_l, X = 5e5, 6.0, 998.0, 1e9
    xs = 0.99  # (above ~0.995 the nozzle law's own smoothing at x -> 1 takes over)
    F = math.sqrt(p1 * rho_g) * flows.nozzle_f(np.array([xs]), k)[0]  # per m2 of gap
    liquid_flux = X * F / math.sqrt(1 + X) * liquid.mixture_factor(xs, k, rho_g, X, 1 / rho_l)
    # 1e-4: the gas nozzle and the omega method's gas (omega = 1 / kappa) differ by
    # 2e-5 here, both sqrt(2 (1 - x)) to first order
    assert liquid_flux == pytest.approx(math.sqrt(2 * rho_l * p1 * (1 - xs)), rel=1e-4)


RHO_L, MU_L, H, P1 = 998.0, 1.0e-3, 100e-6, 5e5


def _centrifuged(kind, X, x=0.9, land=2e-3, forward=True, rho_g=6.0, e_l=4.2e4):
    """One leakage flow through a path of ``kind`` (1 m of sealing line of gap H, or 1 m2
    of orifice) from the node holding X kg of liquid per kg of gas (specific energy e_l)
    at P1 and rho_g to the other at x P1: the gas-only flow F0 through the same area,
    and what centrifuged_leakage makes of it (gas, liquid, the liquid's energy flow)."""
    measure = "area" if kind == "blow-hole" else "length"
    law = SimpleNamespace(path=SimpleNamespace(name="gap", kind=kind, measure=measure),
                          gap_m=H, land_m=land)
    model = SimpleNamespace(fast={}, laws=(law,), inv_rho_liquid=1.0 / RHO_L,
                            op=SimpleNamespace(liquid_viscosity_Pa_s=MU_L))
    ia, ib = (np.array([1]), np.array([0])) if forward else (np.array([0]), np.array([1]))
    seg = SimpleNamespace(index=0, names=("gap",), n_leak=1, ia=ia, ib=ib)
    area = np.array([[H if measure == "length" else 1.0]])
    F0 = math.sqrt(P1 * rho_g) * flows.nozzle_f(np.array([x]), 1.4)[0] * area[0, 0]
    F = np.array([[F0 if forward else -F0]])
    Fo, Eo = liquid.centrifuged_leakage(
        model, seg, F, np.array([[0.0, X]]), np.array([[0.0, X * e_l]]),
        np.array([[forward]]), np.array([[x]]), np.array([[P1]]), np.array([[rho_g]]), area)
    return F0, F[0, 0], Fo[0, 0], Eo[0, 0]


def _x_of(liquid_share, rho_g=6.0):
    """Liquid per gas mass X of a node whose liquid takes ``liquid_share`` of its volume."""
    return liquid_share * RHO_L / ((1 - liquid_share) * rho_g)


def _series_root(dp, land):
    """The laminar channel with entry and exit losses, m / m_v + (m / m_i)^2 = 1, solved
    numerically per m of line (independently of liquid_flux's closed form)."""
    m_v = RHO_L * H**3 * dp / (12 * MU_L * land)
    m_i = H * math.sqrt(2 * RHO_L * dp)
    return brentq(lambda m: m / m_v + (m / m_i) ** 2 - 1, 0.0, min(m_v, m_i))


@pytest.mark.parametrize("x", [0.3, 0.9, 0.99])
def test_centrifuged_tip_gaps_pass_the_liquid_by_its_own_law(x):
    """A tip line of a chamber with 30 % liquid passes no gas and the liquid's laminar
    channel with entry and exit losses (solved by root-finding here); the liquid's
    energy is its own plus its flow work P1 / rho_l.  An orifice on the bores (the
    blow-hole) passes the orifice's sqrt(2 rho_l dp) per m2.  Tolerance: the orifice
    takes the nozzle's smoothed drop at x -> 1 (flows._x_eff), which lowers dp by
    (DELTA_X / (1 - x))^2 / 2 relative, so the flux by less than (DELTA_X / (1 - x))^2."""
    dp, e_l = P1 * (1 - x), 4.2e4
    tol = max((flows.DELTA_X / (1 - x)) ** 2, 1e-12)
    _, gas, liq, energy = _centrifuged("tip", _x_of(0.3), x=x)
    assert gas == 0.0
    assert liq == pytest.approx(_series_root(dp, 2e-3), rel=tol)
    assert energy == pytest.approx(liq * (e_l + P1 / RHO_L), rel=1e-12)
    _, gas, liq, _ = _centrifuged("blow-hole", _x_of(0.3), x=x)
    assert gas == 0.0 and liq == pytest.approx(math.sqrt(2 * RHO_L * dp), rel=tol)


def test_the_liquids_law_tends_to_poiseuille_and_to_the_orifice():
    """A long land: plane Poiseuille flow rho h^3 dp / (12 mu L) per m, linear in dp
    down to x = 1 - 1e-5 (where the nozzle's smoothed drop, flows._x_eff, would be 10 %
    of dp: it is the orifice's only); a short one: the orifice h sqrt(2 rho dp)."""
    for x in (0.9, 1.0 - 1e-5):
        dp = P1 * (1.0 - x)
        assert _centrifuged("tip", _x_of(0.3), x=x, land=1.0)[2] == pytest.approx(
            RHO_L * H**3 * dp / (12 * MU_L * 1.0), rel=1e-3)
    dp = P1 * 0.1
    assert _centrifuged("tip", _x_of(0.3), land=1e-9)[2] == pytest.approx(
        H * math.sqrt(2 * RHO_L * dp), rel=1e-3)


@pytest.mark.parametrize("alpha", [0.25, 0.9])
@pytest.mark.parametrize("forward", [True, False])
def test_centrifuged_leakage_shares_the_other_gaps_by_volume(alpha, forward):
    """Interlobe and end-face gaps span the groove's depth: the gas passes alpha of the
    gap by its own law, the liquid the rest by its own; a flow from node b to node a
    takes b's liquid and runs negative."""
    sign = 1.0 if forward else -1.0
    for kind in ("interlobe", "end-face"):
        F0, gas, liq, _ = _centrifuged(kind, _x_of(1 - alpha), forward=forward)
        assert gas == pytest.approx(sign * alpha * F0, rel=1e-12)
        assert liq == pytest.approx(sign * (1 - alpha) * _series_root(P1 * 0.1, 2e-3),
                                    rel=1e-6)  # (x = 0.9: the smoothing's 1e-6, above)


def test_a_drained_casing_gap_fades_to_the_gas():
    """Below LAYER_FILL of liquid the tip gap's liquid share falls linearly: at half of
    it the gas takes half of its volume share; a dry chamber's tip passes its gas."""
    share = liquid.LAYER_FILL / 2
    F0, gas, liq, _ = _centrifuged("tip", _x_of(share))
    assert gas == pytest.approx(0.5 * (1 - share) * F0, rel=1e-9)
    assert liq == pytest.approx((1 - 0.5 * (1 - share)) * _series_root(P1 * 0.1, 2e-3),
                                rel=1e-6)  # (x = 0.9: the smoothing's 1e-6)
    F0, gas, liq, _ = _centrifuged("tip", 0.0)
    assert gas == F0 and liq == 0.0


def test_centrifuged_leakage_needs_a_liquid_with_a_volume():
    """Without a liquid that takes chamber volume there is no layer: refused by name."""
    raw, table = pump()
    raw = copy.deepcopy(raw)
    raw["leakage"]["mixture"] = "centrifuged"
    raw["operating"]["gas_volume_fraction"] = 1.0
    with pytest.raises(CaseError, match="centrifuged"):
        pm.point(raw, table, str(pm.EXAMPLE))


def test_centrifuged_leakage_refuses_walls_that_drag():
    """Walls that drag flow against the pressure (the internal gear's interlobe lines
    with wall_motion) would carry liquid out of a dry chamber: refused by name."""
    path = pm.ROOT / "examples" / "default.toml"
    raw = load_toml(path)
    table = chamber_table(case_from_raw(raw, path), build_machine(case_from_raw(raw, path)))
    raw["operating"].update(gas_volume_fraction=0.8, liquid_density_kg_m3=998.0)
    raw.setdefault("leakage", {}).update(mixture="centrifuged", wall_motion=True)
    with pytest.raises(CaseError, match="wall_motion"):
        pm.point(raw, table, str(path))


# --- the pump with its liquid ------------------------------------------------------------

@functools.cache
def pump():
    raw = load_toml(pm.EXAMPLE)
    case = case_from_raw(raw, pm.EXAMPLE)
    return raw, chamber_table(case, build_machine(case))


@pytest.mark.parametrize("beta", [0.6, 0.9])
def test_sealed_adiabatic_pump_is_the_ideal_cycle_with_the_liquids_volume(beta):
    """No leakage, no heat, no gas-liquid exchange, a constant-cp gas: the indicated
    power is the ideal cycle of built-in volume ratio vi whose gas is squeezed by the
    incompressible liquid: suction of V_t at p_s (gas beta V_t), isentropic compression
    of the gas to V_o - (1 - beta) V_t, back-flow to p_d, push-out of V_o = V_t / vi.
    Measured 4e-5 (beta 0.6) and 3e-6 (0.9); 2e-4 leaves room for the sudden ports'
    numerics at other tolerances."""
    raw, table = pump()
    raw = copy.deepcopy(raw)
    raw["leakage"] = {"model": "none"}
    raw["operating"].update(gas_volume_fraction=beta, heat_transfer_W_m2K=0.0,
                            oil_time_constant_ms=1e12, heat_capacity="constant",
                            cp_J_kgK=1004.5, p_discharge_bar=6.0, speed_rpm=1801)
    fig = pm.point(raw, table, str(pm.EXAMPLE))
    R = 8.314462618 / (AIR_MOLAR_MASS_G_MOL * 1e-3)  # the case's gas: air's molar mass
    k, vi, ps, pd = 1004.5 / (1004.5 - R), 2.0, 1e5, 6e5
    Vt = table.volume_max_m3
    Vo = Vt / vi
    Vgo = Vo - (1 - beta) * Vt
    pi = ps * (beta * Vt / Vgo) ** k
    work = pd * Vo - ps * Vt + (pi * Vgo - ps * beta * Vt) / (k - 1)
    assert fig["indicated_kW"] * 1e3 == pytest.approx(work * 1801 / 60, rel=2e-4)
    assert fig["eta_v"] == pytest.approx(beta, rel=1e-5)
    # the liquid delivered is what came in with the gas, (1 - beta) / beta of its volume
    # (named as the pump's liquid, not as injected oil)
    rho_l = raw["operating"]["liquid_density_kg_m3"]
    assert fig["liquid_flow_kg_s"] == pytest.approx(
        rho_l * fig["flow_m3_min"] / 60 * (1 - beta) / beta, rel=1e-5)


def test_a_liquid_that_fills_the_chamber_is_refused():
    raw, table = pump()
    raw = copy.deepcopy(raw)
    raw["operating"]["gas_volume_fraction"] = 0.45  # vi = 2 leaves half the volume
    with pytest.raises(CaseError, match="hydraulic lock"):
        pm.point(raw, table, str(pm.EXAMPLE))


def test_a_liquid_that_leaves_the_gas_no_room_at_the_discharge_is_refused():
    """beta = 1 - 1 / vi: the liquid alone fills what the chamber has left when the
    discharge opens (the gas squeezed to nothing).  It ran until its step size underflowed
    (exit 1) instead of naming the input; a little more gas runs."""
    table = sin2_table(rows=241)
    base = {"p_suction_bar": 1.0, "p_discharge_bar": 4.0, "T_suction_K": 300.0,
            "speed_rpm": 3000.0, "volume_ratio": 2.0, "liquid_density_kg_m3": 998.0,
            "liquid_cp_J_kgK": 4180.0}
    with pytest.raises(CaseError) as e:
        simulate(table, Operating.from_section({**base, "gas_volume_fraction": 0.5}, "t"),
                 Leakage(model="none"), Ports())
    assert "hydraulic lock" in str(e.value) and "gas_volume_fraction 0.5" in str(e.value)
    assert "50.0% of" in str(e.value)
    ok = simulate(table, Operating.from_section({**base, "gas_volume_fraction": 0.52}, "t"),
                  Leakage(model="none"), Ports())
    assert ok.converged


@pytest.mark.parametrize("keys, word", [
    ({"gas_volume_fraction": 1.2, "liquid_density_kg_m3": 998}, "gas_volume_fraction"),
    ({"gas_volume_fraction": 0.0, "liquid_density_kg_m3": 998}, "gas_volume_fraction"),
    ({"gas_volume_fraction": 0.8}, "liquid_density_kg_m3"),
    ({"gas_volume_fraction": 0.8, "liquid_density_kg_m3": 998, "oil_mass_ratio": 2},
     "oil_mass_ratio"),
])
def test_bad_liquid_keys_are_named(keys, word):
    base = {"p_suction_bar": 1, "p_discharge_bar": 4, "T_suction_K": 293, "speed_rpm": 1500}
    with pytest.raises(CaseError, match=word):
        Operating.from_section({**base, **keys}, "test")


def test_bad_liquid_fraction_exits_2_with_one_line(tmp_path):
    case = tmp_path / "case.toml"
    case.write_text(re.sub(r"(?m)^gas_volume_fraction = [0-9.]+", "gas_volume_fraction = 1.5",
                           pm.EXAMPLE.read_text()))
    out = run_cli("simulate", case, "--json")
    assert out.returncode == 2 and out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "gas_volume_fraction" in lines[0], out.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]
