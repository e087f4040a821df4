"""Oil in the leakage of an oil-flooded machine: a homogeneous gas-oil mixture
(rotorflow.quasi1d.oil; Wallis 1969, ch. 2).

The frozen checks evaluate the path flows at a constructed state (no integration): per
leakage path the gas flow is the gas-only flow over sqrt(1 + X), X the oil per gas mass of
the node the flow comes from, and the oil flow X times the gas flow.  The cycle checks run
the synthetic CRC.60-sized table (rotorflow.quasi1d.synthetic) to a periodic state.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.quasi1d import Leakage, Numerics, Operating, Ports, simulate
from rotorflow.quasi1d.chamber import prepare
from rotorflow.quasi1d.model import build
from rotorflow.quasi1d.network import ACC_H_DIS, ACC_H_SUC, ACC_M_DIS, ACC_M_SUC, ACC_Q, ACC_W
from rotorflow.quasi1d.perfect_gas import PerfectGas
from rotorflow.quasi1d.simulate import build_model
from rotorflow.quasi1d.synthetic import sin2_table

from .conftest import CASES, run_cli

GAS = PerfectGas(molar_mass_kg_kmol=28.97, cp_J_kgK=1006.43)  # seed 001's perfect-gas air
OIL_RATIO = 3.0
OP = Operating(p_suction_Pa=1e5, p_discharge_Pa=4e5, T_suction_K=300.0, speed_rpm=3000.0,
               volume_ratio=2.5, oil_mass_ratio=OIL_RATIO)
# Chamber pressures (bar): apart from each other and from both plenums (outside the flux's
# smoothing band), the youngest below suction so that dry gas flows in from it, some
# below the 4 bar discharge so that the discharge's mixture flows back into them.
P_BAR = (0.8, 1.9, 3.3, 2.6, 5.0, 6.2, 7.4, 8.5, 9.5)


@pytest.fixture(scope="module")
def table():
    return sin2_table(rows=721)


def _op(**kw):
    d = {"p_suction_bar": 1.0, "p_discharge_bar": 8.0, "T_suction_K": 300.0,
         "speed_rpm": 3000.0, "volume_ratio": 4.6}
    d.update(kw)
    return Operating.from_section(d, "test")


def frozen(table, leak, op=OP, ports=None):
    """Model, its fullest segment, the segment's mid angle and a state with the chambers
    at P_BAR, each with its own oil load X_k = 0.5 + 0.4 k and oil temperature."""
    geo = prepare(table, op.volume_ratio, None, None, op.speed_rpm, 1e-3)
    model = build(geo, GAS, op, leak, ports or Ports("ideal"))
    seg = max(model.segments, key=lambda s: s.n_act)
    theta = 0.5 * (seg.start + seg.end)
    n = model.n
    y = np.zeros(model.n_state)
    V = geo.evaluate(theta + seg.kP)[0]
    for k, pk in enumerate(P_BAR[:seg.n_act]):
        rho, u, _ = GAS.state_pT(1e5 * pk, 300.0 * pk**0.25)
        y[k] = rho * V[k]
        y[n + k] = rho * V[k] * u
        if model.oil:
            y[2 * n + k] = (0.5 + 0.4 * k) * y[k]
            y[3 * n + k] = y[2 * n + k] * op.oil_cp_J_kgK * (320.0 + 5.0 * k)
    return model, seg, theta, y


def upstream_oil(model, seg, y, F):
    """Per leakage flow: X and the oil's specific enthalpy of the node it leaves, and
    which kind of node that is (0 suction, 1 slot, 2 discharge), from the state itself."""
    n, na, op = model.n, seg.n_act, model.op
    X, ho, kind = [], [], []
    for f in range(seg.n_leak):
        node = int(seg.ia[f] if F[f] >= 0 else seg.ib[f])
        if node == 0:
            X.append(0.0), ho.append(0.0), kind.append(0)
        elif node == na + 1:
            X.append(op.oil_mass_ratio)
            # (the oil's energy counts from its injection temperature)
            ho.append(op.oil_cp_J_kgK * (model.dis.T - model.liquid_datum_K))
            kind.append(2)
        else:
            k = node - 1
            X.append(y[2 * n + k] / y[k])
            ho.append(y[3 * n + k] / y[2 * n + k])
            kind.append(1)
    return np.array(X), np.array(ho), np.array(kind)


@pytest.mark.parametrize("model", ["nozzle", "fanno"])
def test_gas_leakage_falls_by_the_root_of_one_plus_x_and_the_oil_leaks_x_times(table, model):
    base = {"gap_um": 10, "model": model, "coefficient": 0.8}
    mg, seg_g, theta, yg = frozen(table, Leakage.from_section({**base, "mixture": "gas"}, "t"))
    mh, seg_h, _, yh = frozen(table, Leakage.from_section(base, "t"))
    assert seg_h.names == seg_g.names
    Fg, Eg, Fo0, _ = mg.path_flows(theta, yg, seg_g, enthalpy=True, oil_flows=True)
    Fh, Eh, Fo, Eo = mh.path_flows(theta, yh, seg_h, enthalpy=True, oil_flows=True)
    nl = seg_h.n_leak
    X, ho, kind = upstream_oil(mh, seg_h, yh, Fg)
    # the state reaches every case on paths that carry flow (1e-7 kg/s; an end face's
    # sealing line may be of zero length here): oil from slots and from the discharge
    # plenum, dry gas from suction, flows leaving their second node (ib) and their first
    live = np.abs(Fg[:nl]) > 1e-7
    assert live.sum() >= 10 and set(kind[live]) == {0, 1, 2}
    assert np.any(Fg[:nl][live] < 0) and np.any(Fg[:nl][live] > 0)
    # the gas-only flow divided by one root: equal to the last bit or two
    np.testing.assert_allclose(Fh[:nl], Fg[:nl] / np.sqrt(1.0 + X), rtol=1e-14, atol=0)
    np.testing.assert_allclose(Fo, X * Fh[:nl], rtol=1e-14, atol=0)
    # the oil carries its own enthalpy (Ho / mo of a slot, c_oil T of the plenum) ...
    np.testing.assert_allclose(Eo, Fo * ho, rtol=1e-13, atol=0)
    # ... and the gas its own, per kg as before
    np.testing.assert_allclose(Eh[:nl], Eg[:nl] / np.sqrt(1.0 + X), rtol=1e-14, atol=0)
    # ports keep carrying gas only (their oil is the discharge's, see test below)
    np.testing.assert_array_equal(Fh[nl:], Fg[nl:])
    # gas only: no oil on any path
    assert not np.any(Fo0)


def test_without_oil_the_mixture_setting_changes_nothing(table):
    dry = dataclasses.replace(OP, oil_mass_ratio=0.0)
    leak = {"gap_um": 10, "model": "fanno"}
    mg, seg_g, theta, yg = frozen(table, Leakage.from_section({**leak, "mixture": "gas"}, "t"),
                                  dry)
    mh, seg_h, _, yh = frozen(table, Leakage.from_section(leak, "t"), dry)
    np.testing.assert_array_equal(mh.path_flows(theta, yh, seg_h), mg.path_flows(theta, yg, seg_g))
    op = _op()
    a = simulate(table, op, Leakage(gap_m=20e-6, model="fanno", wall_motion=True)).figures
    b = simulate(table, op, Leakage(gap_m=20e-6, model="fanno", wall_motion=True,
                                    mixture="gas")).figures
    assert a == b  # bitwise: no oil, no oil state, the same equations
    assert set(a["oil_leakage_kg_s"].values()) == {0.0}


def test_gas_only_leakage_reproduces_the_model_before_oil_leaked(table):
    # Figures of this case computed by the code before the oil entered the leakage
    # (commit a064b86, RMS error norm, rtol 1e-4): mixture = "gas" must leave every
    # equation as it was. Compared here at rtol 1e-7, where the figures are converged
    # (issue 19 changed the error norm, so the old steps cannot be replayed): the pinned
    # mass flow, power and temperatures then differ only by their own integration error,
    # measured 2.8e-7 and 4e-7 (1e-5 holds it; a leakage term 1 % off moves the mass flow
    # by ~2e-2). The pinned interlobe leakage carried 1.9e-3 of integration error (the
    # leakage accumulator converges slowly: 7.7e-4 off at rtol 1e-4, 3.5e-4 at 1e-5), so
    # it is held to 3e-3.
    op = _op(heat_transfer_W_m2K=200.0, T_wall_K=330.0, oil_mass_ratio=2.0, T_oil_K=320.0)
    f = simulate(table, op, Leakage(gap_m=10e-6, model="nozzle", mixture="gas"),
                 numerics=Numerics(rtol=1e-7)).figures
    before = {"mass_flow_kg_s": 0.0030667555823466128, "indicated_power_W": 1060.130152909353,
              "discharge_mixture_temperature_K": 381.5989798347078,
              "oil_flow_kg_s": 0.006748418897234983}
    for key, value in before.items():
        assert f[key] == pytest.approx(value, rel=1e-5), key
    assert f["leakage_kg_s"]["interlobe"] == pytest.approx(0.0050368234791712315, rel=3e-3)


@pytest.mark.parametrize("ports", [Ports("ideal"), Ports("nozzle", 0.3)],
                         ids=["ideal", "nozzle"])
def test_the_right_hand_side_moves_gas_and_oil_without_loss(table, ports):
    # At any state the rates of the stored gas and oil (slots) equal the rates of what the
    # accumulators book as coming in and going out: every flow leaves one place and
    # arrives at another.  Frozen, because an oil-flooded cycle with nozzle ports takes a
    # minute (its Rosenbrock Jacobian has twice the columns of a dry one).
    leak = Leakage(gap_m=20e-6, model="fanno", wall_motion=True)
    op = dataclasses.replace(OP, heat_transfer_W_m2K=200.0)
    model, seg, theta, y = frozen(table, leak, op, ports)
    dy = model.rhs(theta, y[None], seg)[0]
    n, a, c = model.n, model.acc(dy), model.acc_cols
    stored_m = dy[:n].sum() + dy[2 * n:3 * n].sum()
    booked_m = a[ACC_M_SUC] + a[c.oil_m_in] - a[ACC_M_DIS] - a[c.oil_m_out]
    stored_e = dy[n:2 * n].sum() + dy[3 * n:4 * n].sum()
    booked_e = (a[ACC_H_SUC] + a[ACC_W] + a[ACC_Q] + a[c.oil_h_in] - a[ACC_H_DIS]
                - a[c.oil_h_out])
    gross_m = sum(a[c.leak(k)] + a[c.oil_leak(k)] for k in c.leak_keys)
    gross_e = np.abs(dy[n:2 * n]).sum() + np.abs(dy[3 * n:4 * n]).sum()
    assert gross_m > 0 and np.any(dy[2 * n:3 * n] != 0)
    # round-off of sums of some tens of terms
    assert abs(stored_m - booked_m) < 1e-13 * gross_m
    assert abs(stored_e - booked_e) < 1e-13 * gross_e


@pytest.mark.parametrize("leak", [Leakage(gap_m=10e-6, model="nozzle"),
                                  Leakage(gap_m=20e-6, model="fanno", wall_motion=True)],
                         ids=["nozzle", "fanno-wall"])
def test_oil_flooded_cycle_conserves_gas_and_oil(table, leak):
    op = _op(heat_transfer_W_m2K=200.0, T_wall_K=330.0, oil_mass_ratio=4.0, T_oil_K=320.0)
    res = simulate(table, op, leak)
    f = res.summary()
    assert res.converged, f.get("message")
    # as without oil in the leakage (test_quasi1d_cycle): balances to 1e-6, and the
    # Runge-Kutta steps conserve mass and energy (gas and oil) to round-off
    assert f["mass_balance_error"] < 1e-6 and f["energy_balance_error"] < 1e-6
    assert res.solution.conservation_mass < 1e-11
    assert res.solution.conservation_energy < 1e-11
    # each on its own: gas in = gas out, oil in = oil out over the periodic cycle, so the
    # oil per kg of gas delivered is the oil per kg drawn in
    model = res.solution.model
    a, c = model.acc(res.solution.run.y[0]), model.acc_cols
    assert abs(a[ACC_M_SUC] / a[ACC_M_DIS] - 1.0) < 1e-6
    assert abs(a[c.oil_m_in] / a[c.oil_m_out] - 1.0) < 1e-6
    assert all(v > 0 for v in f["oil_leakage_kg_s"].values())
    assert set(f["oil_leakage_kg_s"]) == set(f["leakage_kg_s"])
    json.dumps(f, allow_nan=False)


def test_oil_in_the_leakage_raises_the_volumetric_efficiency(table):
    op = _op(oil_mass_ratio=4.0, T_oil_K=320.0)
    gas = simulate(table, op, Leakage(gap_m=10e-6, model="fanno", mixture="gas")).figures
    wet = simulate(table, op, Leakage(gap_m=10e-6, model="fanno")).figures
    # X ~ 4-5 in the compressing chambers: each path leaks gas at ~1/sqrt(5.5) of what it
    # leaked alone (at similar pressures), which is well below 0.7 on every path
    for key, g in gas["leakage_kg_s"].items():
        assert wet["leakage_kg_s"][key] < 0.7 * g, key
    assert wet["volumetric_efficiency"] > gas["volumetric_efficiency"] + 0.02
    # the oil that leaks is the oil of the leaking mixture: several times its gas
    total = sum(wet["leakage_kg_s"].values())
    oil = sum(wet["oil_leakage_kg_s"].values())
    assert 3.0 * total < oil < 6.0 * total
    assert set(gas["oil_leakage_kg_s"].values()) == {0.0}


@pytest.mark.parametrize("value", ['"foam"', "true"])
def test_a_bad_mixture_is_an_error_naming_the_key(table, value, tmp_path):
    case = tmp_path / "case.toml"
    case.write_text((CASES / "crc60.toml").read_text().replace(
        "[leakage]", f"[leakage]\nmixture = {value}"))
    out = run_cli("simulate", case, "--json")
    assert out.returncode == 2 and out.stdout == ""
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and "'mixture'" in lines[0] and "[leakage]" in lines[0], out.stderr
    with pytest.raises(CaseError, match="mixture 'slip'"):  # the Python interface
        build_model(table, _op(oil_mass_ratio=1.0), Leakage(gap_m=1e-5, mixture="slip"))
