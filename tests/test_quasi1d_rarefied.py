"""The rarefied leakage law (quasi1d/rarefied.py) against its limits and the network's needs.

Limits: the continuum one is the isothermal compressible Poiseuille flow
m = h^3 l (p1^2 - p2^2) / (24 mu R T L) with Maxwell's first-order slip (1 + 6 s Kn) at
the mean pressure (Beskok & Karniadakis 1999); the free-molecular one the effusion flux
times the slot's transmission probability, W h l (p1 - p2) / sqrt(2 pi R T) (Clausing
1932), W itself checked by an independent test-particle Monte Carlo simulation.  The
network needs a flux that is antisymmetric, zero at equal pressure, monotone and
continuous; the cycle must converge and balance at a vacuum pump's suction pressure.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from rotorflow.errors import CaseError
from rotorflow.quasi1d import Leakage, Numerics, Operating, Ports, simulate
from rotorflow.quasi1d.flows import nozzle_f
from rotorflow.quasi1d.rarefied import (
    ALPHA1,
    BETA,
    RarefiedLaw,
    flow_flux,
    mean_free_path,
    slot_transmission,
)

MU = 1.8e-5  # air near 300 K (Leakage's default)
RT = 287.0 * 300.0
GAMMA = 1.4
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _law(land_over_gap=20.0, gap=100e-6, **kw):
    return RarefiedLaw(gap, land_over_gap * gap, MU, **kw)


def _p_at_kn(law, kn):
    """The pressure at which Kn = lambda / h is ``kn``."""
    return float(mean_free_path(MU, 1.0, RT)) / (kn * law.gap_m)


def _flux(law, p1, p2):
    return float(law.mass_flux(p1, p1 / RT, p2, p2 / RT, GAMMA))


# -- free-molecular transmission probability of the slot ------------------------------------
def _monte_carlo_W(l: float, n: int, seed: int) -> float:
    """Test particles through a slot of length l (gap 1) between diffuse plates: entering
    and re-emitted with the in-plane projection of Lambert's law (sin of the angle from the
    normal uniform in [-1, 1]); each flight from a wall ends on the opposite wall tan(psi)
    further on, or leaves through an end."""
    rng = np.random.default_rng(seed)
    u = rng.uniform(-1.0, 1.0, n)
    y0 = rng.uniform(0.0, 1.0, n)
    # from the inlet (u = sin of the angle from the axis) to the first wall: the height
    # left to it times |cot|
    x = np.where(u > 0, 1.0 - y0, y0) * np.sqrt(1.0 - u * u) / np.maximum(np.abs(u), 1e-300)
    out = x >= l
    alive = ~out
    x = x[alive]
    while x.size:
        u = rng.uniform(-1.0, 1.0, x.size)  # sin of the angle from the wall's normal
        x = x + u / np.sqrt(1.0 - u * u)
        out_n = np.count_nonzero(x >= l)
        out = np.append(out, np.ones(out_n, bool))
        x = x[(x > 0.0) & (x < l)]
    return np.count_nonzero(out) / n


@pytest.mark.parametrize("l", [1.0, 5.0])
def test_slot_transmission_matches_monte_carlo(l):
    n = 400_000
    W = slot_transmission(l)
    mc = _monte_carlo_W(l, n, seed=int(10 * l))
    sigma = math.sqrt(W * (1.0 - W) / n)  # binomial standard error, ~7e-4
    assert abs(mc - W) < 4.0 * sigma, (mc, W)
    # the comparison resolves the wall re-emission: the line-of-sight part alone
    # (crossed strings, sqrt(1 + l^2) - l) is many standard errors below
    assert W - (math.sqrt(1.0 + l * l) - l) > 50.0 * sigma


def test_slot_transmission_limits():
    assert slot_transmission(0.0) == 1.0  # an orifice
    ls = [0.01, 0.1, 1.0, 10.0, 100.0, 200.0, 400.0]
    W = [slot_transmission(v) for v in ls]
    assert abs(W[0] - 1.0) < 0.01  # a thin slot passes nearly all
    assert all(a > b for a, b in zip(W, W[1:], strict=False))
    # a long slot is diffusive with a logarithmically growing diffusivity (Clausing):
    # l W - ln l tends to a constant; it moves by ~0.015 between l = 100 and 200
    c = [v * w - math.log(v) for v, w in zip(ls[-3:], W[-3:], strict=True)]
    assert abs(c[1] - c[0]) < 0.03 and 0.0 < c[0] < 0.3
    # beyond the directly solved length the diffusive form joins without a jump
    below = slot_transmission(200.0 * (1 - 1e-9))
    assert abs(slot_transmission(200.0 * (1 + 1e-9)) / below - 1.0) < 1e-6


# -- the integral over the land --------------------------------------------------------------
def test_land_integral_matches_adaptive_quadrature():
    law = _law(accommodation=0.8)
    for kn1 in (1e-4, 1e-2, 1.0, 1e2, 1e4):
        for x in (1e-4, 0.01, 0.099, 0.1, 0.3, 0.9, 0.999):  # (0.1: the fewer nodes)
            exact = quad(lambda xi, k=kn1: xi * float(law.rarefaction(k / xi)), x, 1.0,
                         epsabs=0.0, epsrel=1e-13, limit=400)[0]
            scale = (law.gap_m / law.land_m) * math.sqrt(0.5 * math.pi) / (12.0 * kn1)
            got = float(law.viscous_flux(np.array(x), kn1))
            # 16 Gauss nodes in ln p: 1e-11 down to x = 1e-4, 8 from x = 0.1: 4e-13
            # (tolerance with margin)
            assert abs(got / (scale * exact) - 1.0) < 1e-9, (kn1, x)


def test_one_flow_at_a_time_is_the_array_law():
    """flow_flux (the compiled kernel's: one flow, the land's nodes summed in a loop)
    against the law over arrays (reduced_flux: the nodes an array axis), from continuum
    to free-molecular flow, across both node counts, for sealing lines and orifices:
    the same arithmetic, so round-off apart."""
    rng = np.random.default_rng(3)
    p1 = 10.0 ** rng.uniform(-1.0, 6.0, 400)  # Kn ~ 1e-3 .. 1e4 on a 100 um gap
    x = np.concatenate([10.0 ** rng.uniform(-6.0, 0.0, 398), [1.0, 0.1]])
    rho1 = p1 / RT
    for law in (_law(accommodation=0.8), _law(orifice=True), _law(land_over_gap=3.0)):
        fn = nozzle_f(x, GAMMA)
        ref = law.reduced_flux(fn, x, p1, rho1)
        par = law.per_flow(x.size)
        got = np.array([flow_flux(fn[i], x[i], p1[i], rho1[i], *par[1:, i], par[0, i] > 0)
                        for i in range(x.size)])
        assert np.all(got >= 0.0) and np.all(np.isfinite(got))
        assert np.max(np.abs(got - ref) / np.maximum(np.abs(ref), 1e-300)) < 1e-12


# -- continuum limit -------------------------------------------------------------------------
@pytest.mark.parametrize("sigma", [1.0, 0.8])
def test_continuum_limit_is_poiseuille_with_first_order_slip(sigma):
    law = _law(accommodation=sigma)
    x = np.array([0.2, 0.5, 0.9, 0.99])
    kn_mean = 1e-4
    kn1 = kn_mean * (1.0 + x) / 2.0  # Kn at p1 for the mean pressure's 1e-4
    poiseuille = (law.gap_m / law.land_m) * math.sqrt(0.5 * math.pi) / (12 * kn1) * (
        1 - x * x) / 2
    ratio = law.viscous_flux(x, kn1) / poiseuille
    # the continuum law within 1e-3 (the brief's figure) ...
    assert np.all(np.abs(ratio - 1.0) < 1e-3)
    # ... and the departure is Maxwell's slip, 6 s Kn at the mean pressure, to O(alpha Kn)
    # (alpha(1e-4) Kn = 1.7 * 0.064 * 1e-4 ~ 1e-5)
    s = (2 - sigma) / sigma
    assert np.all(np.abs(ratio - (1.0 + 6.0 * s * kn_mean)) < 3e-5)


def test_continuum_limit_in_mass_flow_and_the_inertial_hand_over():
    # a long land, so that the Reynolds number is low: the entry's inertial resistance is
    # (m_v / m_i)^2 ~ 1e-4 of the viscous one (at L/h = 200 it is 1.3 %, Re ~ 60)
    law = _law(land_over_gap=2000.0, gap=20e-6)
    p1 = _p_at_kn(law, 1e-4)  # ~33 bar: Kn 1e-4 at the inlet
    p2 = 0.999 * p1
    poiseuille = law.gap_m**3 * (p1**2 - p2**2) / (24 * MU * RT * law.land_m)
    m = _flux(law, p1, p2) * law.gap_m  # per unit length of sealing line
    assert abs(m / poiseuille - 1.0) < 1e-3
    # at a large pressure drop through a short land the gap is inertia-limited: the flux
    # hands over to the isentropic nozzle's (within 1 %: the viscous resistance left)
    short = _law(land_over_gap=0.5, gap=200e-6)
    p1 = 10e5
    nozzle = float(nozzle_f(np.array(0.1), GAMMA)) * math.sqrt(p1 * p1 / RT)
    assert abs(_flux(short, p1, 0.1 * p1) / nozzle - 1.0) < 0.01
    # and the series law stays below both of its parts everywhere
    for p2 in (0.1 * p1, 0.9 * p1):
        x = p2 / p1
        fv = float(short.viscous_flux(np.array(x), short.knudsen(p1, RT)))
        assert _flux(short, p1, p2) < math.sqrt(p1 * p1 / RT) * min(
            fv, float(nozzle_f(np.array(x), GAMMA)))


# -- free-molecular limit --------------------------------------------------------------------
@pytest.mark.parametrize("l", [1.0, 10.0, 50.0])
def test_free_molecular_limit_is_clausing(l):
    law = _law(land_over_gap=l)
    for kn, tol in ((1e3, 0.02), (1e5, 0.002)):
        p_mean = _p_at_kn(law, kn)
        p1, p2 = 1.5 * p_mean, 0.5 * p_mean
        clausing = slot_transmission(l) * (p1 - p2) / math.sqrt(2 * math.pi * RT)
        ratio = _flux(law, p1, p2) / clausing
        # alpha(Kn) reaches alpha_inf as 1 - (2/pi) / (alpha1 Kn^beta): 1.0 % short at
        # Kn 1e3, 0.16 % at 1e5; the slip factor 1 + 6 Kn / (1 + Kn) adds 6 / (7 Kn)
        deficit = (2 / math.pi) / (ALPHA1 * kn**BETA)
        assert abs(ratio - 1.0) < tol
        assert abs(ratio - (1.0 - deficit)) < 0.3 * deficit


def test_orifice_limits_are_nozzle_and_effusion():
    hole = RarefiedLaw(100e-6, 0.0, MU, orifice=True)
    p1 = _p_at_kn(hole, 1e3)
    effusion = 0.5 * p1 / math.sqrt(2 * math.pi * RT)
    # w = 1 / (1 + Kn) leaves 1e-3 of the nozzle's flux, ~1.7e-3 of the effusion
    assert abs(_flux(hole, p1, 0.5 * p1) / effusion - 1.0) < 3e-3
    p1 = _p_at_kn(hole, 1e-4)
    nozzle = float(nozzle_f(np.array(0.5), GAMMA)) * math.sqrt(p1 * p1 / RT)
    assert abs(_flux(hole, p1, 0.5 * p1) / nozzle - 1.0) < 1e-3


# -- what the network needs ------------------------------------------------------------------
@pytest.mark.parametrize("law", [_law(), _law(land_over_gap=2.0, accommodation=0.7),
                                 RarefiedLaw(100e-6, 0.0, MU, orifice=True)],
                         ids=["slot", "short-slot", "orifice"])
def test_flux_is_antisymmetric_zero_at_equal_pressure_and_linear_near_it(law):
    pa = np.array([1e5, 5e3, 10.0, 0.1, 3e3])
    pb = np.array([2e4, 1e4, 1.0, 0.2, 3e3])
    ra, rb = pa / RT, pb / (1.3 * RT)  # the sides at different temperatures
    F = law.mass_flux(pa, ra, pb, rb, GAMMA)
    assert np.all(F[:-1] != 0) and F[-1] == 0.0
    assert np.array_equal(F, -law.mass_flux(pb, rb, pa, ra, GAMMA))
    # near equal pressure the flux is linear in the difference (a finite conductance)
    for p in (1e5, 1e3, 1.0):
        g = [_flux(law, p * (1 + d), p) / (p * d) for d in (1e-6, 1e-7)]
        assert g[0] > 0 and abs(g[1] / g[0] - 1.0) < 1e-3


@pytest.mark.parametrize("law", [_law(), _law(land_over_gap=2.0),
                                 RarefiedLaw(100e-6, 0.0, MU, orifice=True)],
                         ids=["slot", "short-slot", "orifice"])
def test_flux_is_monotone_and_continuous_across_the_regimes(law):
    # upstream pressure from free-molecular (Kn ~ 1e4) to continuum (Kn ~ 1e-5) at fixed
    # pressure ratios: the flow rises strictly, and between neighbouring points (0.5 %
    # apart) its log-slope stays below that of viscous flow (m ~ p^2): a jump at a
    # hand-over would break the bound.  (It dips below 1, that of free-molecular and
    # inertial flow, through the Knudsen minimum.)
    p1 = np.geomspace(_p_at_kn(law, 1e4), _p_at_kn(law, 1e-5), 4000)
    for x in (0.01, 0.5, 0.95):
        m = law.mass_flux(p1, p1 / RT, x * p1, x * p1 / RT, GAMMA)
        slope = np.diff(np.log(m)) / np.diff(np.log(p1))
        assert np.all(slope > 0.0) and np.all(slope < 2.01), (x, slope.min(), slope.max())
    # downstream pressure from p1 down to 1e-4 p1 at fixed p1 in each regime: the flow
    # rises as the back pressure falls
    for kn in (1e-4, 1e-2, 1.0, 1e2):
        p1 = _p_at_kn(law, kn)
        p2 = p1 * np.linspace(1.0, 1e-4, 3000)
        m = law.mass_flux(p1, p1 / RT, p2, p2 / RT, GAMMA)
        assert m[0] == 0.0 and np.all(np.diff(m) > 0), kn


def test_one_law_over_several_gaps_is_each_gaps_own():
    # The model evaluates a segment's sealing lines in one call (network._groups:
    # RarefiedLaw.of_flows, the gaps' parameters arrays over the flows): each column must
    # be what its own law gives, whatever the others' lands, gaps and accommodation.
    laws = [_law(20.0), _law(50.0, gap=60e-6), _law(20.0, accommodation=0.8), _law(20.0)]
    group = RarefiedLaw.of_flows(laws, orifice=False)
    assert np.ndim(group.land_m) == 1 and group.viscosity_Pa_s == MU  # (one value kept)
    rng = np.random.default_rng(3)
    x = rng.uniform(1e-3, 1.0, (5, len(laws)))
    p1 = 10.0 ** rng.uniform(1.0, 5.0, (5, len(laws)))
    r1 = p1 / RT
    f_n = nozzle_f(x, GAMMA)
    got = group.reduced_flux(f_n, x, p1, r1)
    for i, law in enumerate(laws):
        own = law.reduced_flux(f_n[:, i], x[:, i], p1[:, i], r1[:, i])
        np.testing.assert_allclose(got[:, i], own, rtol=1e-14)


def test_slot_has_a_knudsen_minimum_near_kn_1():
    # Gaede (1913) measured the minimum of a channel's conductance near Kn = 1 (quoted by
    # Beskok & Karniadakis); the slot's conductance m / (p1 - p2) at a small pressure drop
    # falls from the free-molecular value towards Kn ~ 1 and rises again to the viscous
    law = _law()
    kn = np.geomspace(1e-3, 1e3, 601)
    p = np.array([_p_at_kn(law, k) for k in kn])
    c = law.mass_flux(1.01 * p, 1.01 * p / RT, 0.99 * p, 0.99 * p / RT, GAMMA) / (0.02 * p)
    i = int(np.argmin(c))
    assert 0 < i < kn.size - 1 and 0.1 < kn[i] < 10.0, kn[i]
    # a shallow minimum, as measured and computed for channels (tens of per cent)
    assert 0.5 < c[i] / c[-1] < 0.98


# -- a vacuum pump's cycle -------------------------------------------------------------------
def test_vacuum_cycle_converges_and_balances():
    from rotorflow.geometry.summary import chamber_table
    from rotorflow.workflow.case import load_case

    case = load_case(EXAMPLES / "default.toml")  # the internal gear: the fastest example
    raw = dict(case.raw["operating"], p_suction_bar=0.05, p_discharge_bar=1.0)
    op = Operating.from_section(raw, "default.toml")
    leak = Leakage.from_section({"gap_um": 30, "model": "rarefied", "land_mm": 2.0},
                                "default.toml")
    res = simulate(chamber_table(case), op, leak, Ports("ideal"), Numerics())
    f = res.summary()
    assert res.converged, f.get("message")
    # issue 3's figures: mass to 1e-6 of throughput, energy to 1e-6 of work
    assert f["mass_balance_error"] < 1e-6
    assert f["energy_balance_error"] < 1e-6
    assert res.solution.conservation_mass < 1e-11
    assert res.solution.conservation_energy < 1e-11
    # 30 um at 20 times the suction pressure: leakage on every path, positive gross flows
    assert all(v > 0 for v in f["leakage_kg_s"].values())


# -- bad input ---------------------------------------------------------------------------------
@pytest.mark.parametrize("d, words", [
    ({"gap_um": 50, "model": "rarefeid"}, ["'model'", "[leakage]", '"rarefied"']),
    ({"gap_um": 50, "model": "rarefied", "accommodation": 0}, ["'accommodation'", "positive"]),
    ({"gap_um": 50, "model": "rarefied", "accommodation": -0.5},
     ["'accommodation'", "positive"]),
    ({"gap_um": 50, "model": "rarefied", "accommodation": 1.5}, ["'accommodation'", "at most 1"]),
    ({"gap_um": 50, "model": "rarefied", "land_mm": 0}, ["'land_mm'", "positive"]),
    ({"gap_um": 50, "tip": {"model": "rarefid"}}, ["'model'", "[leakage.tip]"]),
])
def test_bad_input_is_one_line_naming_the_key(d, words):
    with pytest.raises(CaseError) as e:
        Leakage.from_section(d, "case.toml")
    msg = str(e.value)
    assert "\n" not in msg and "case.toml" in msg
    for w in words:
        assert w in msg
