"""The "cfd-calibrated" leakage model: the nozzle times the CFD-fitted flow coefficient,
with the wall drag of the fit on the interlobe lines when the walls move."""

import json

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.postprocess.leakage import LeakagePoint
from rotorflow.quasi1d import Leakage, Operating, Ports, simulate
from rotorflow.quasi1d.calibrated import FlowCoefficientFit
from rotorflow.quasi1d.chamber import prepare
from rotorflow.quasi1d.flows import nozzle_psi
from rotorflow.quasi1d.model import build
from rotorflow.quasi1d.perfect_gas import PerfectGas
from rotorflow.quasi1d.synthetic import scaled_table, sin2_table

OP = {"p_suction_bar": 1.0, "p_discharge_bar": 4.0, "T_suction_K": 300.0, "speed_rpm": 3000.0,
      "volume_ratio": 2.5}


def fit_file(tmp_path, cd0, viscous=0.0):
    # A = 1 / Cd0^2 with no viscous term: Cd is the constant cd0 everywhere.
    fit = FlowCoefficientFit(inertial_features=("1",), inertial=(1.0 / cd0**2,),
                             viscous=viscous)
    path = tmp_path / "fit.json"
    path.write_text(fit.to_json())
    return path


def run(leak_section, where):
    table = scaled_table(2e-4, 5)
    return simulate(table, Operating.from_section(OP, where),
                    Leakage.from_section(leak_section, where)).summary()


def test_constant_coefficient_fit_equals_the_nozzle_with_that_coefficient(tmp_path):
    where = str(tmp_path / "case.toml")
    path = fit_file(tmp_path, 0.7)
    cal = run({"gap_um": 40, "model": "cfd-calibrated", "correlation": str(path)}, where)
    noz = run({"gap_um": 40, "model": "nozzle", "coefficient": 0.7}, where)
    for key in ("mass_flow_kg_s", "indicated_power_W"):
        assert cal[key] == pytest.approx(noz[key], rel=1e-6), key


def test_viscous_term_reduces_leakage(tmp_path):
    where = str(tmp_path / "case.toml")
    inviscid = run({"gap_um": 40, "model": "cfd-calibrated",
                    "correlation": str(fit_file(tmp_path, 0.9))}, where)
    viscous = run({"gap_um": 40, "model": "cfd-calibrated", "land_mm": 2.0,
                   "correlation": str(fit_file(tmp_path, 0.9, viscous=0.6))}, where)
    # More friction in the gap: less leakage back to suction, more delivered mass.
    assert viscous["mass_flow_kg_s"] > inviscid["mass_flow_kg_s"]


def test_inviscid_limit_of_the_fit_form_is_a_nozzle():
    # b = 0, A = 1/0.8^2: Cd = 0.8 whatever the Reynolds number.
    nozzle_only = FlowCoefficientFit(("1",), (1 / 0.64,), 0.0)
    assert nozzle_only.flow_coefficient(10.0, 2.0, 50.0) == pytest.approx(0.8)


def test_missing_or_malformed_fit_is_a_case_error(tmp_path):
    where = str(tmp_path / "case.toml")
    with pytest.raises(CaseError, match="not found"):
        Leakage.from_section({"gap_um": 5, "model": "cfd-calibrated",
                              "correlation": "nope.json"}, where)
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"inertial_features": ["sin"], "inertial": [1], "viscous": 0}))
    with pytest.raises(CaseError, match="malformed"):
        Leakage.from_section({"gap_um": 5, "model": "cfd-calibrated",
                              "correlation": str(bad)}, where)


# --- moving walls: the fit's own drag term on the interlobe lines ------------------------
#
# The fit models A Cd|Cd| + b X (Cd - w W) = 1 (rotorflow.quasi1d.calibrated): with a
# wall term w the drag flow is part of the correlation, so the quasi-1D model passes the
# wall speed to it on the interlobe lines and adds no Couette term of its own there.  The
# checks below evaluate the chamber model's path flows at chosen states and compare them
# with the fit evaluated directly on LeakagePoints (flow_coefficient * ideal_mass_flow, a
# separate code path from the model's finite form FlowCoefficientFit.reduced_flux).

GAS = PerfectGas(molar_mass_kg_kmol=28.97, cp_J_kgK=1006.43)
# Coefficients of the order of the CFD matrix's fit (w = 1.31 as fitted on moving walls).
INERTIAL, VISCOUS, WALL = (0.91, 0.23), 0.57, 1.31
GAP, LAND, MU = 20e-6, 1e-3, 1.8e-5


def wall_fit(wall=WALL):
    return FlowCoefficientFit(("1", "ln(PR)"), INERTIAL, VISCOUS, gamma=GAS.gamma, wall=wall)


def chamber_model(fit, wall_motion=True):
    """The chamber model of a sin^2 table with the ideal gas the fit was made for, and the
    segment with the most chambers at its mid angle."""
    op = Operating(p_suction_Pa=1e5, p_discharge_Pa=4e5, T_suction_K=300.0,
                   speed_rpm=3000.0, volume_ratio=2.5)
    geo = prepare(sin2_table(rows=721), op.volume_ratio, None, None, op.speed_rpm, 1e-3)
    leak = Leakage(gap_m=GAP, model="cfd-calibrated", wall_motion=wall_motion,
                   correlation=fit, land_m=LAND, viscosity_Pa_s=MU)
    model = build(geo, GAS, op, leak, Ports("ideal"))
    seg = max(model.segments, key=lambda s: s.n_act)
    return model, seg, 0.5 * (seg.start + seg.end)


def state(model, seg, theta, pT):
    """State vector with the active slots at the given (p, T)."""
    y = np.zeros(model.n_state)
    V = model.geo.evaluate(theta + seg.kP)[0]
    for k, (p, T) in enumerate(pT):
        rho, u, _ = GAS.state_pT(p, T)
        y[k] = rho * V[k]
        y[model.n + k] = rho * V[k] * u
    return y


def node_pT(model, seg, pT):
    """(p, T) of every node: suction plenum, the slots, discharge plenum."""
    return [(model.suc.p, model.suc.T), *pT, (model.dis.p, model.dis.T)]


def wall_speed(model):
    """Half the outer rotor's tip speed: the mean speed of the walls along a line."""
    return 0.5 * model.geo.omega_outer * model.geo.radius


def path_length(model, seg, theta, f):
    """Sealing-line length of leakage path f (its area over gap * coefficient)."""
    flat = model.geo.evaluate(theta + seg.kP)[2].ravel()
    return float(seg.area[f] @ flat) / (model.leak.gap_m * model.leak.coefficient)


def fit_flow(fit, p_up, T_up, p_down, wall_speed):
    """The fit's mass flow per metre of line, evaluated directly at one point."""
    pt = LeakagePoint("q1d", GAP, LAND, p_up, T_up, p_down, MU, GAS.R, GAS.gamma,
                      wall_speed_m_s=wall_speed)
    return fit.model()(pt)


def expected_flow(model, seg, theta, pT, f, fit, wall=True):
    """Flow of path f (node ia -> ib) from the fit: upstream the high-pressure node, the
    wall speed along the flow +U where the upstream node is the older chamber of an
    interlobe line (flows 0..n_act), -U where it is the younger, 0 on the end faces."""
    nodes = node_pT(model, seg, pT)
    a, b = int(seg.ia[f]), int(seg.ib[f])
    (pa, Ta), (pb, Tb) = nodes[a], nodes[b]
    chain = f <= seg.n_act
    u = wall_speed(model) if (wall and chain) else 0.0
    if pa >= pb:
        m = fit_flow(fit, pa, Ta, pb, -u)
    else:
        m = -fit_flow(fit, pb, Tb, pa, u)
    return m * path_length(model, seg, theta, f)


def slot_states(seg):
    # Pressures away from 1 across every path (the nozzle's smoothing below a relative
    # difference of 1e-4 then changes the flux by less than 1e-7); slot 2 above slot 3,
    # and the oldest above the discharge plenum: there the walls drag against the
    # pressure difference.
    p = [1.4, 1.9, 3.3, 2.6, 5.0, 6.2, 7.4, 8.5, 9.5][:seg.n_act]
    return [(1e5 * pk, 300.0 * pk**0.25) for pk in p]


def test_reduced_flux_is_the_fit_times_psi_and_finite_at_equal_pressure():
    fit = wall_fit()
    pr = np.array([1.001, 1.05, 1.5, 2.5, 6.0])
    S = np.sqrt(2e5 * 2e5 / (GAS.R * 300.0))
    psi = nozzle_psi(1.0 / pr, GAS.gamma)
    re = GAP * psi * S / MU
    K = 24 * LAND * MU / (GAP**2 * S)
    for v in (0.0, 0.02, -0.02):
        direct = fit.flow_coefficient(re, pr, LAND / GAP, v) * psi
        np.testing.assert_allclose(fit.reduced_flux(psi, pr, K, v), direct, rtol=1e-12)
    # At PR = 1 the fit's Cd is 0/0 but Cd psi is the drag flow, odd in V, and the limit
    # of the direct evaluation at PR -> 1.
    g0 = fit.reduced_flux(0.0, 1.0, K, 0.02)
    assert g0 > 0 and fit.reduced_flux(0.0, 1.0, K, -0.02) == pytest.approx(-g0, rel=1e-14)
    near = 1.0 + 1e-9
    psi_n = nozzle_psi(1.0 / near, GAS.gamma)
    assert fit.flow_coefficient(GAP * psi_n * S / MU, near, LAND / GAP, 0.02) * psi_n == (
        pytest.approx(g0, rel=1e-6))
    assert fit.reduced_flux(0.0, 1.0, K, 0.0) == 0.0


def test_fit_without_wall_term_keeps_the_couette_term(tmp_path):
    # A fit with w = 0 (fitted to static walls, or saved before the wall term existed)
    # says nothing about moving walls: the model keeps its Couette term, so a constant-Cd
    # fit behaves as the nozzle with that coefficient, with and without wall motion.
    where = str(tmp_path / "case.toml")
    path = fit_file(tmp_path, 0.7)
    cal = {}
    for wall in (False, True):
        cal[wall] = run({"gap_um": 40, "model": "cfd-calibrated", "correlation": str(path),
                         "wall_motion": wall}, where)
        noz = run({"gap_um": 40, "model": "nozzle", "coefficient": 0.7, "wall_motion": wall},
                  where)
        for key in ("mass_flow_kg_s", "indicated_power_W"):
            assert cal[wall][key] == pytest.approx(noz[key], rel=1e-6), (wall, key)
    # the Couette term is there: the walls change the delivery by far more than 1e-6
    assert cal[True]["mass_flow_kg_s"] != pytest.approx(cal[False]["mass_flow_kg_s"], rel=1e-4)


def test_wall_term_enters_only_with_wall_motion():
    # Without wall motion a fit's w is immaterial: the static flows, to round-off.
    pT = None
    flows = []
    for fit in (wall_fit(0.0), wall_fit()):
        model, seg, theta = chamber_model(fit, wall_motion=False)
        pT = slot_states(seg)
        flows.append(model.path_flows(theta, state(model, seg, theta, pT), seg))
    np.testing.assert_allclose(flows[1], flows[0], rtol=1e-13, atol=0.0)
    # and they are the fit's static flows
    model, seg, theta = chamber_model(wall_fit(), wall_motion=False)
    for f in range(seg.n_leak):
        assert flows[1][f] == pytest.approx(
            expected_flow(model, seg, theta, pT, f, wall_fit(), wall=False), rel=1e-6), f


def test_wall_drag_is_the_fits_own_and_not_counted_twice():
    fit = wall_fit()
    model, seg, theta = chamber_model(fit)
    assert model.drag_in_fit
    pT = slot_states(seg)
    F = model.path_flows(theta, state(model, seg, theta, pT), seg)
    nodes = node_pT(model, seg, pT)
    assert seg.n_leak > seg.n_act + 1  # interlobe lines and end faces
    checked_couette = 0
    for f in range(seg.n_leak):
        want = expected_flow(model, seg, theta, pT, f, fit)
        assert F[f] == pytest.approx(want, rel=1e-6), f
        if f <= seg.n_act:
            # The separate Couette term (half the tip speed times the gap, older chamber's
            # density) on top would be a double count, far outside the tolerance above.
            p_old, T_old = nodes[int(seg.ib[f])]
            cou = (wall_speed(model) * GAP * path_length(model, seg, theta, f)
                   * p_old / (GAS.R * T_old))
            assert abs(cou) > 1e-3 * abs(want)
            checked_couette += 1
    assert checked_couette == seg.n_act + 1
    # The same fit without its wall term (w = 0): the model's own Couette term instead.
    static = wall_fit(0.0)
    model0, seg0, theta0 = chamber_model(static)
    assert not model0.drag_in_fit
    F0 = model0.path_flows(theta0, state(model0, seg0, theta0, pT), seg0)
    for f in range(seg0.n_act + 1):
        p_old, T_old = nodes[int(seg0.ib[f])]
        cou = (wall_speed(model0) * GAP * path_length(model0, seg0, theta0, f)
               * p_old / (GAS.R * T_old))
        want = expected_flow(model0, seg0, theta0, pT, f, static, wall=False) - cou
        assert F0[f] == pytest.approx(want, rel=1e-6), f


def test_leakage_is_continuous_through_equal_pressures_with_moving_walls():
    fit = wall_fit()
    model, seg, theta = chamber_model(fit)
    base = slot_states(seg)
    j = 1  # the interlobe line between slots 0 (younger, node 1) and 1 (older, node 2)
    assert (seg.ia[j], seg.ib[j]) == (1, 2)
    p0, Ta, Tb = 1e5, 300.0, 330.0  # the two chambers at different temperatures
    length = path_length(model, seg, theta, j)

    def flow(s, enthalpy=False):
        pT = list(base)
        pT[0], pT[1] = (p0, Ta), (p0 * (1.0 + s), Tb)
        F, E = model.path_flows(theta, state(model, seg, theta, pT), seg, enthalpy=True)
        return (F[j], E[j]) if enthalpy else F[j]

    # At equal pressures: the drag flow of the older chamber (the side the walls drag
    # from), from the older into the younger: negative along ia -> ib.  It is the limit of
    # the fit at PR -> 1, and close to lubrication theory's w rho U h (the inertial term
    # takes about 1 % off here).
    F0 = flow(0.0)
    assert F0 < 0
    limit = -fit_flow(fit, p0, Tb, p0 / (1 + 1e-9), wall_speed(model)) * length
    assert F0 == pytest.approx(limit, rel=1e-6)
    rho_b = p0 / (GAS.R * Tb)
    assert F0 == pytest.approx(-WALL * rho_b * wall_speed(model) * GAP * length, rel=0.03)
    # Continuous from both sides (the upstream side changes at s = 0) ...
    steps = np.array([1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-8])
    for sign in (1.0, -1.0):
        gaps = np.array([abs(flow(sign * s) - F0) for s in steps])
        assert gaps[-1] < 1e-6 * abs(F0)
        assert np.all(np.diff(gaps) < 0)
    # ... and monotone: more pressure in the older chamber, more flow out of it.
    ss = np.concatenate([-steps, [0.0], steps[::-1]])
    values = np.array([flow(s) for s in ss])
    assert np.all(np.diff(values) < 0)
    # The younger chamber 1 % above the older: the walls still win, the flow runs
    # against the pressure difference, with the gas of the side it comes from (the older
    # chamber's density at the upstream pressure; the upstream density would be 10 % off).
    s = -1e-2
    F, E = flow(s, enthalpy=True)
    assert F < 0
    assert E == pytest.approx(F * GAS.cp_J_kgK * Tb, rel=1e-12)  # the older chamber's enthalpy
    p_down = p0 * (1 + s)
    rho_down = p_down / (GAS.R * Tb)
    want = fit_flow(fit, p0, p0 / (GAS.R * rho_down), p_down, -wall_speed(model)) * length
    assert F == pytest.approx(want, rel=1e-4)
    upstream = fit_flow(fit, p0, Ta, p_down, -wall_speed(model)) * length
    assert abs(upstream / want - 1) > 1e-2
    # 10 % above: the pressure wins, the flow runs from the younger into the older.
    assert flow(-0.1) > 0


def test_calibrated_cycle_with_moving_walls_balances():
    table = sin2_table(rows=721)
    op = Operating.from_section({"p_suction_bar": 1.0, "p_discharge_bar": 8.0,
                                 "T_suction_K": 300.0, "speed_rpm": 3000.0,
                                 "volume_ratio": 4.6}, "test")
    figs = {}
    for wall in (False, True):
        leak = Leakage(gap_m=GAP, model="cfd-calibrated", wall_motion=wall,
                       correlation=wall_fit(), land_m=LAND, viscosity_Pa_s=MU)
        res = simulate(table, op, leak)
        f = res.summary()
        assert res.converged, f.get("message")
        # issue 3: a converged cycle closes mass to 1e-6 of throughput, energy to 1e-6 of
        # the work; (m, U) states keep both invariants to round-off
        assert f["mass_balance_error"] < 1e-6
        assert f["energy_balance_error"] < 1e-6
        assert res.solution.conservation_mass < 1e-11
        assert res.solution.conservation_energy < 1e-11
        assert all(v >= 0 for v in f["leakage_kg_s"].values())
        figs[wall] = f
    # The drag carries gas back toward suction: less is delivered (the walls do act).
    assert figs[True]["mass_flow_kg_s"] < figs[False]["mass_flow_kg_s"] * (1 - 1e-4)
