"""Seed 003's vacuum pump (Table 2) against the quasi-1D model on six of its rows
(postprocess/pump_validation.py; examples/screw_pump_vacuum.toml states the geometry
and its one coefficient, the blow-holes' flow coefficient fitted on the 0.11 bar eta_v).

What holds is asserted; the issue's targets that the model misses are kept at their
value as strict xfails (the power target at every row, eta_v at 0.01 bar), so that a
fix shows up as an unexpected pass instead of the targets being loosened."""

from __future__ import annotations

import copy
import functools

import pytest

from rotorflow.geometry.summary import build_machine, chamber_table
from rotorflow.postprocess import pump_validation as pv
from rotorflow.workflow.case import case_from_raw, load_toml

#: Rows run here (bar): both ends, the fitted row, the two sides of the table's step at
#: 0.13 -> 0.15 bar and one in the upper half.  The full table: `python -m
#: rotorflow.postprocess.pump_validation` (~20 s more).
ROWS = (0.01, 0.03, 0.11, 0.15, 0.25, 0.39)


@functools.cache
def pump():
    raw = load_toml(pv.EXAMPLE)
    case = case_from_raw(raw, pv.EXAMPLE)
    return raw, chamber_table(case, build_machine(case))


@functools.cache
def results():
    raw, table = pump()
    rows = [r for r in pv.read_table() if round(r.p_suction_bar, 2) in ROWS]
    assert len(rows) == len(ROWS)
    res = pv.compare(rows, [pv.predict(raw, table, r) for r in rows])
    assert all(r["converged"] for r in res)
    return {round(r["p_suction_bar"], 2): r for r in res}


def test_the_recorded_coefficient_reproduces_its_row():
    """The example's fitted coefficient still gives the row it was fitted on (to the
    table's 3 figures): a geometry or model change that moves it makes it stale."""
    r = results()[pv.FITTED]
    assert not r["predicted"]
    assert r["eta_v_model"] == pytest.approx(r["eta_v_table"], abs=2e-3)


@pytest.mark.parametrize("p", [p for p in ROWS if p not in (pv.FITTED, 0.01)])
def test_predicted_volumetric_efficiency_within_target(p):
    r = results()[p]
    assert r["predicted"]
    assert abs(r["eta_v_error"]) <= pv.ETA_V_TOL, r


@pytest.mark.xfail(strict=True, reason="eta_v at 0.01 bar: model 0.77, table 0.62 (the "
                   "model's leakage hardly grows at the lowest pressure)")
def test_predicted_volumetric_efficiency_at_the_lowest_pressure():
    assert abs(results()[0.01]["eta_v_error"]) <= pv.ETA_V_TOL


@pytest.mark.xfail(strict=True, reason="power +18..29 %: the tip, interlobe and end-face "
                   "leakage through 100 um adds ~1.2 kW of recompression to the sealed "
                   "pump's 5.0 kW")
@pytest.mark.parametrize("p", [p for p in ROWS if p != pv.FITTED])
def test_predicted_power_within_target(p):
    assert abs(results()[p]["power_error"]) <= pv.POWER_TOL


def test_volumetric_efficiency_rises_with_suction_pressure():
    eta = [results()[p]["eta_v_model"] for p in ROWS]
    assert pv.rising(eta), eta


def test_power_falls_over_the_upper_rows_as_in_the_table():
    """Table 2's power falls by 9 % from 0.15 to 0.39 bar (5.237 -> 4.742 kW): the
    compression work shrinks as the chamber reaches the discharge pressure by itself."""
    lo, hi = results()[0.15], results()[0.39]
    assert hi["power_kW_table"] < lo["power_kW_table"]
    assert hi["power_kW_model"] < 0.95 * lo["power_kW_model"]


@pytest.mark.parametrize("p_s", [0.01, 0.39])
def test_sealed_adiabatic_pump_is_the_ideal_cycle_of_volume_ratio_two(p_s):
    """Without leakage and heat the pump's indicated power is the ideal cycle of built-in
    volume ratio vi = 2 (the discharge port where the volume has halved): isentropic
    compression of V from p_s, then push-out of V / vi at p_d after the back-flow fills
    the chamber.  1 %: the volume table's nodes and the sudden ports' numerics."""
    raw, table = pump()
    raw = copy.deepcopy(raw)
    raw["leakage"] = {"model": "none"}
    raw["operating"]["heat_transfer_W_m2K"] = 0.0
    row = next(r for r in pv.read_table() if round(r.p_suction_bar, 2) == p_s)
    got = pv.predict(raw, table, row)["indicated_kW"] * 1e3
    k, vi, p_d = 1.4, 2.0, 1e5
    v_dot = table.volume_max_m3 * row.speed_rpm / 60.0
    ps = p_s * 1e5
    ideal = (ps * v_dot * k / (k - 1) * (vi ** (k - 1) - 1)
             + (p_d - ps * vi**k) * v_dot / vi)
    assert got == pytest.approx(ideal, rel=1e-2)
