"""The chamber model's leakage network at a frozen angle (quasi1d.frozen, issue 16).

Checked against what the solve does not compute itself: each closed chamber's mass
balance summed path by path from the flows' own end nodes (not through the model's flow
maps); the steady energy balance of adiabatic throttling (every closed chamber fed only
from the discharge side holds the discharge plenum's enthalpy, so its temperature); and
the quasi-steady limit of the product's transient model: as the rotor speed falls, the
leakage relaxes each closed chamber faster than its volume changes, so the integrated
cycle's pressures tend to the frozen network's at every angle, at first order in speed.
"""

from __future__ import annotations

import dataclasses
import tomllib
from pathlib import Path

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.summary import chamber_table
from rotorflow.quasi1d.frozen import solve_frozen
from rotorflow.quasi1d.settings import Leakage
from rotorflow.quasi1d.simulate import build_model, case_settings, simulate
from rotorflow.quasi1d.transient import simulate_transient
from rotorflow.workflow.case import load_case

CASE = Path(__file__).resolve().parents[1] / "examples" / "default.toml"
#: Fractions of the lobe period: the segments with one and with two closed chambers.
FRACTIONS = (0.1, 0.35, 0.6, 0.85)


@pytest.fixture(scope="module")
def setup():
    case = load_case(CASE)
    raw = tomllib.loads(CASE.read_text())
    op, leak, ports, num, _ = case_settings(raw, "default.toml")
    table = chamber_table(case, SweptMachine(case.pair, case.sweep(None)))
    return table, op, leak, ports, num


def _enthalpy(fluid, p, T):
    """h = u + p / rho of the (rho, u) state the model builds from (p, T)."""
    rho, u, _ = fluid.state_pT(p, T)
    return u + fluid.props(np.array([rho]), np.array([u]))[0][0] / rho


def _angles(model):
    return model.geo.birth + model.geo.period * np.array(FRACTIONS)


@pytest.mark.parametrize("model_name", ["nozzle", "fanno"])
def test_closed_chambers_balance_and_hold_the_discharge_enthalpy(setup, model_name):
    table, op, leak, ports, num = setup
    leak = dataclasses.replace(leak, model=model_name)
    model = build_model(table, op, leak, ports, num)
    for theta in _angles(model):
        fs = solve_frozen(model, theta)
        k = np.flatnonzero(fs.closed)
        assert k.size >= 1
        # Mass: summed from each flow's own end nodes, not through the model's maps.
        scale = np.abs(fs.flows).max()
        for slot in k:
            net = fs.flows[fs.ib == slot + 1].sum() - fs.flows[fs.ia == slot + 1].sum()
            assert abs(net) < 1e-9 * scale, (theta, slot)
        # Pressures between the plenums and rising with the chamber's age.
        p = fs.p[k]
        assert np.all(p > model.suc.p) and np.all(p < model.dis.p)
        assert np.all(np.diff(p) > 0.0)
        # Steady adiabatic throttling: every closed chamber is fed from the discharge side
        # only (the plenum through the end face, the open chambers through the lines), so
        # its enthalpy, in the model's own h = u + p / rho of its (rho, u) state, is a mix
        # of theirs: it lies between them (they differ by the dry-air table's round trip
        # T -> u -> p, ~5e-9), and its temperature is T_dis to that table's T(u).
        h = [_enthalpy(model.fluid, fs.p[s], fs.T[s]) for s in range(fs.p.size)]
        sources = [model.dis.h, *h[k[-1] + 1:]]
        lo, hi = min(sources), max(sources)
        for slot in k:
            assert lo * (1 - 1e-12) <= h[slot] <= hi * (1 + 1e-12), (lo, h[slot], hi)
        np.testing.assert_allclose(fs.T[k], model.dis.T, rtol=1e-7)


def test_wall_motion_moves_the_closed_pressures(setup):
    """The rotors' drag carries gas from the older chamber into the younger one, so with
    wall motion a closed chamber next to suction holds less of the discharge's pressure
    than its older neighbour pushes at it: the pressures change, the balance holds."""
    table, op, leak, ports, num = setup
    still = build_model(table, op, leak, ports, num)
    moving = build_model(table, op, dataclasses.replace(leak, wall_motion=True), ports, num)
    theta = _angles(still)[0]
    a, b = solve_frozen(still, theta), solve_frozen(moving, theta)
    k = np.flatnonzero(a.closed)
    assert np.all(np.abs(b.p[k] / a.p[k] - 1.0) > 1e-4)
    assert b.residual < 1e-10


def test_the_transient_model_tends_to_the_frozen_network_as_speed_falls(setup):
    """Quasi-steady limit: the closed chambers' pressures of the converged cycle at 10 and
    5 rpm (instead of 3000) against the frozen network at four angles.  The lag of a
    chamber relaxing with time constant tau behind a volume changing at omega is
    ~ omega tau, so the difference halves with the speed (order 1; measured 1.0) and at
    5 rpm is ~0.6 % (tau ~ 30 ms against a 2 s lobe period)."""
    table, op, leak, ports, num = setup
    worst = []
    for rpm in (10.0, 5.0):
        o = dataclasses.replace(op, speed_rpm=rpm)
        sol = simulate(table, o, leak, ports, num).solution
        angles = _angles(sol.model)
        tr = simulate_transient(table, o, angles, leak, ports, num, y0=sol.y_start)
        err = 0.0
        for i, theta in enumerate(angles):
            fs = solve_frozen(sol.model, theta)
            k = np.flatnonzero(fs.closed)
            err = max(err, float(np.abs(tr.p_Pa[i][k] / fs.p[k] - 1.0).max()))
        worst.append(err)
    order = np.log(worst[0] / worst[1]) / np.log(2.0)
    assert 0.8 < order < 1.2, worst
    assert worst[1] < 0.01, worst


def test_oil_is_refused(setup):
    table, op, leak, ports, num = setup
    oily = dataclasses.replace(op, oil_mass_ratio=1.0)
    model = build_model(table, oily, leak, ports, num)
    with pytest.raises(CaseError, match="oil"):
        solve_frozen(model, _angles(model)[0])


def test_sealed_machine_has_no_closed_unknown_to_fail_on(setup):
    """Without leakage a closed chamber has no flow to balance: the network is singular,
    which the solve must say rather than return an arbitrary pressure."""
    table, op, _, ports, num = setup
    model = build_model(table, op, Leakage(model="none"), ports, num)
    with pytest.raises(CaseError, match="frozen leakage network"):
        solve_frozen(model, _angles(model)[0])
