"""Seed 003's multiphase pump (Table 1) against the quasi-1D model on three of its rows
(postprocess/pump_multiphase.py; examples/screw_pump_multiphase.toml states the pump,
taken over from the vacuum pump of Table 2, and its one fitted value, the inlet gas
volume fraction, on the 8 bar / 1801 rpm row's measured eta_v).

What holds is asserted; the issue's targets that the model misses are kept at their
value as strict xfails, so that a fix shows up as an unexpected pass.  The rows run at
rtol 1e-3 (the example's 1e-4 costs twice the time; the figures move by < 1e-4).  The
fitted row (8 bar, 1801 rpm) is not run here (~12 s): `python -m bench.bench_pump_multiphase`
reports it with every row, and `--fit` re-fits it."""

from __future__ import annotations

import copy
import functools

import pytest

from rotorflow.geometry.summary import build_machine, chamber_table
from rotorflow.postprocess import pump_multiphase as pm
from rotorflow.workflow.case import case_from_raw, load_toml

#: Three corners: both pressures at 1501 rpm, both speeds at 14 bar.
ROWS = ((4.0, 1501.0), (14.0, 1501.0), (14.0, 2101.0))


@functools.cache
def pump():
    """The example's case (rows at rtol 1e-3) and its chamber table, built once."""
    raw = load_toml(pm.EXAMPLE)
    case = case_from_raw(raw, pm.EXAMPLE)
    raw.setdefault("numerics", {})["rtol"] = 1e-3
    return raw, chamber_table(case, build_machine(case))


@functools.cache
def results():
    raw, table = pump()
    rows = [r for r in pm.read_table() if r.key in ROWS]
    assert len(rows) == len(ROWS)
    figs = [pm.predict(raw, table, r) for r in rows]
    res = pm.compare(rows, figs)
    assert all(r["converged"] for r in res)
    return {r.key: (c, f) for r, c, f in zip(rows, res, figs, strict=True)}


@pytest.mark.parametrize("key", ROWS)
def test_every_row_conserves_gas_liquid_and_energy(key):
    _, f = results()[key]
    assert f["mass_balance_error"] < 1e-6 and f["energy_balance_error"] < 1e-6


@pytest.mark.parametrize("key", [(4.0, 1501.0), (14.0, 2101.0)])
def test_predicted_volumetric_efficiency_within_target(key):
    r, _ = results()[key]
    assert r["predicted"] and abs(r["eta_v_error"]) <= pm.ETA_V_TOL, r


@pytest.mark.xfail(strict=True, reason="eta_v at 14 bar / 1501 rpm: model 0.70, measured "
                   "0.63: the liquid seals the gaps and the model's eta_v hardly moves")
def test_predicted_volumetric_efficiency_at_high_pressure_and_low_speed():
    assert abs(results()[(14.0, 1501.0)][0]["eta_v_error"]) <= pm.ETA_V_TOL


def test_predicted_power_within_target_at_the_top_corner():
    r, _ = results()[(14.0, 2101.0)]
    assert r["predicted"] and abs(r["power_error"]) <= pm.POWER_TOL, r


@pytest.mark.parametrize("key", [(4.0, 1501.0), (14.0, 1501.0)])
def test_predicted_power_within_target(key):
    """At 1501 rpm the indicated power alone is 18-19 % short: the shaft also turns the
    water up to the rotors' speed (1.5 kW at 1501 rpm, Euler's equation; before it was
    modelled these rows were strict xfails); 14 bar stays the tightest row (-14.9 %)."""
    r, f = results()[key]
    assert f["power_kW"] - f["indicated_kW"] > 1.0  # bearings alone: ~0.2 kW
    assert abs(r["power_error"]) <= pm.POWER_TOL


def test_efficiency_trends_have_the_tables_sign():
    """eta_v rises with speed (14 bar) and falls with discharge pressure (1501 rpm)."""
    eta = {k: results()[k][0]["eta_v_model"] for k in ROWS}
    assert eta[(14.0, 2101.0)] > eta[(14.0, 1501.0)]
    assert eta[(4.0, 1501.0)] > eta[(14.0, 1501.0)]


@pytest.mark.xfail(strict=True, reason="the trends' size: the table's eta_v rises by 0.03 "
                   "from 1501 to 2101 rpm at 14 bar, the model's by ~0.002")
def test_efficiency_trends_have_the_tables_size():
    eta = {k: results()[k][0]["eta_v_model"] for k in ROWS}
    assert eta[(14.0, 2101.0)] - eta[(14.0, 1501.0)] > 0.015


def test_centrifuged_liquid_seals_the_tips_and_the_gas_takes_the_interlobe_gaps():
    """``[leakage] mixture = "centrifuged"`` on the 4 bar / 1501 rpm row: gas, liquid and
    energy conserved; the tip lines pass liquid and (but from the dry suction plenum)
    no gas; the interlobe lines, shared by volume, pass far more gas than the
    homogeneous mixture, mostly liquid by mass, lets through."""
    raw, table = pump()
    raw = copy.deepcopy(raw)
    raw["leakage"]["mixture"] = "centrifuged"
    row = next(r for r in pm.read_table() if r.key == (4.0, 1501.0))
    f = pm.predict(raw, table, row)
    homogeneous = results()[row.key][1]
    assert f["converged"]
    assert f["mass_balance_error"] < 1e-6 and f["energy_balance_error"] < 1e-6
    assert abs(f["leakage_kg_s"]["tip"]) < 1e-4 * f["mass_flow_kg_s"]
    assert f["liquid_leakage_kg_s"]["tip"] > 0.1
    assert f["leakage_kg_s"]["interlobe"] > 5 * homogeneous["leakage_kg_s"]["interlobe"]
