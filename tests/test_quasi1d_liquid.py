"""A liquid that fills chamber volume (quasi1d/liquid.py): the omega method's limits, the
sealed pump's work against the ideal cycle with the liquid's volume, conservation, and
the bad input of the liquid keys."""

from __future__ import annotations

import copy
import functools
import math
import re
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.summary import build_machine, chamber_table
from rotorflow.postprocess import pump_multiphase as pm
from rotorflow.quasi1d import Operating, flows, liquid
from rotorflow.quasi1d.settings import AIR_MOLAR_MASS_G_MOL
from rotorflow.workflow.case import case_from_raw, load_toml

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


def _centrifuged(kind, X, x=0.99, p1=5e5, rho_g=6.0, rho_l=998.0, k=1.4, e_l=4.2e4):
    """One leakage flow from node 1 (upstream, X kg of liquid per kg of gas, its
    specific energy e_l) to node 0 through a path of ``kind``: the gas-only flux F0 of
    the gap per m2, and what centrifuged_leakage makes of it (gas, liquid, its energy)."""
    law = SimpleNamespace(path=SimpleNamespace(name="gap", kind=kind))
    model = SimpleNamespace(fast={}, laws=(law,), inv_rho_liquid=1.0 / rho_l)
    seg = SimpleNamespace(index=0, names=("gap",), n_leak=1, ia=np.array([1]),
                          ib=np.array([0]))
    F0 = math.sqrt(p1 * rho_g) * flows.nozzle_f(np.array([x]), k)[0]
    F = np.array([[F0]])
    Fo, Eo = liquid.centrifuged_leakage(
        model, seg, F, np.array([[0.0, X]]), np.array([[0.0, X * e_l]]),
        np.array([[True]]), np.array([[x]]), np.array([[p1]]), np.array([[rho_g]]), k)
    return F0, F[0, 0], Fo[0, 0], Eo[0, 0]


def test_centrifuged_leakage_fills_the_casing_gaps_with_liquid():
    """A tip gap of a chamber with liquid passes no gas and the liquid's orifice flux
    sqrt(2 rho_l dp) per m2 of gap (1e-4: the gas nozzle and the omega method's gas
    differ by 2e-5 at x = 0.99, as in test_mixture_factor_limits); the liquid's energy
    is its own plus its flow work p1 / rho_l.  A dry chamber's tip gap passes its gas."""
    p1, rho_l, xs, e_l = 5e5, 998.0, 0.99, 4.2e4
    X = 0.3 * rho_l / (0.7 * 6.0)  # 30 % liquid by volume
    _, gas, liq, energy = _centrifuged("tip", X)
    assert gas == 0.0
    assert liq == pytest.approx(math.sqrt(2 * rho_l * p1 * (1 - xs)), rel=1e-4)
    assert energy == pytest.approx(liq * (e_l + p1 / rho_l), rel=1e-12)
    F0, gas, liq, _ = _centrifuged("blow-hole", 0.0)
    assert gas == F0 and liq == 0.0


@pytest.mark.parametrize("alpha", [0.25, 0.9])
def test_centrifuged_leakage_shares_the_other_gaps_by_volume(alpha):
    """Interlobe and end-face gaps span the groove's depth: the gas passes alpha of the
    gap by its own law, the liquid the rest as through an orifice."""
    p1, rho_g, rho_l, xs = 5e5, 6.0, 998.0, 0.99
    X = (1 - alpha) * rho_l / (alpha * rho_g)
    for kind in ("interlobe", "end-face"):
        F0, gas, liq, _ = _centrifuged(kind, X)
        assert gas == pytest.approx(alpha * F0, rel=1e-12)
        assert liq == pytest.approx((1 - alpha) * math.sqrt(2 * rho_l * p1 * (1 - xs)),
                                    rel=1e-4)


def test_centrifuged_leakage_needs_a_liquid_with_a_volume():
    """Without a liquid that takes chamber volume there is no layer: refused by name."""
    raw, table = pump()
    raw = copy.deepcopy(raw)
    raw["leakage"]["mixture"] = "centrifuged"
    raw["operating"]["gas_volume_fraction"] = 1.0
    with pytest.raises(CaseError, match="centrifuged"):
        pm.point(raw, table, str(pm.EXAMPLE))


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


def test_a_liquid_that_fills_the_chamber_is_refused():
    raw, table = pump()
    raw = copy.deepcopy(raw)
    raw["operating"]["gas_volume_fraction"] = 0.45  # vi = 2 leaves half the volume
    with pytest.raises(CaseError, match="hydraulic lock"):
        pm.point(raw, table, str(pm.EXAMPLE))


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
    out = subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", "simulate",
                          str(case), "--json"], capture_output=True, text=True)
    assert out.returncode == 2 and out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "gas_volume_fraction" in lines[0], out.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]
