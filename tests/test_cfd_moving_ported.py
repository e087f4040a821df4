"""The quasi-1D side of the ported section in motion (issue 17), without OpenFOAM.

The model is the product's periodic cycle of the slab (:mod:`rotorflow.cases.
moving_ported`); what is checked here is what the comparison adds to it: the map from
the CFD's slots (the chamber of machine age phi + s P) to the model's one-chamber trace,
against the model's own per-slot traces of the period (a different route: the integrator's
states observed slot by slot, not the chamber's life joined by age); the start state it
hands the CFD; and the periodicity measure on traces built to be periodic or not.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from rotorflow.cases.moving_ported import (
    initial_state,
    periodicity,
    ported_models,
    slot_pressures,
)
from rotorflow.quasi1d.perfect_gas import PerfectGas
from rotorflow.workflow.case import case_from_raw, load_toml

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "examples" / "default.toml"


@pytest.fixture(scope="module")
def model():
    return ported_models(load_toml(CASE), CASE, 0.01, 100e-6, PerfectGas(), ["fanno"],
                         case_from_raw)["fanno"]


def test_slots_map_onto_the_models_own_per_slot_traces(model):
    mach = model.result.machine
    theta = np.asarray(mach["theta_rad"])
    # model slot k at table angle theta holds the chamber of table age theta + k P: the
    # CFD's slot k + 1 at machine angle theta + origin - P
    # (not the traces' first and last samples: there a chamber is born or dies at the
    # sample itself, and whether the mapped slot holds it turns on the angle's last bits,
    # which differ between machines: NaN at the first sample on an AVX2 one, 2026-12-01)
    pick = np.linspace(1, len(theta) - 2, 9).astype(int)
    got = slot_pressures(model, theta[pick] + model.origin - model.period)
    want = np.asarray(mach["p_Pa"])[pick]
    n = min(got.shape[1], want.shape[1])
    ok = np.isfinite(want[:, :n])
    assert ok.sum() >= 3 * len(pick)
    assert got[:, :n][ok] == pytest.approx(want[:, :n][ok], rel=2e-3)
    # the closed phase is in there: the check sees a compression, not only plenums
    ps, pd = model.plenums["suction"][0], model.plenums["discharge"][0]
    closed = got[:, :n][ok]
    assert np.any((closed > 1.05 * ps) & (closed < 0.95 * pd))


def test_the_start_state_holds_the_plenum_pressures_where_the_ports_are_open(model):
    p, T = initial_state(model, math.radians(13.0))
    assert set(p) == set(T) and len(p) >= model.chambers - 1
    ps, pd = model.plenums["suction"][0], model.plenums["discharge"][0]
    # ideal ports: an open chamber is at its plenum's pressure
    assert sum(abs(v - ps) < 1.0 for v in p.values()) >= 1
    assert sum(abs(v - pd) < 1.0 for v in p.values()) >= 1
    assert all(t > 0.0 for t in T.values())


def test_periodicity_is_zero_on_a_periodic_machine_and_sees_a_drift():
    period = math.radians(60.0)
    angles = np.arange(0.0, 120.5, 0.5)
    a = np.radians(angles)
    # slot s holds the chamber of age phi + s P: one chamber's trace f, shifted
    f = lambda age: 1e5 + 5e4 * np.sin(age) ** 2  # noqa: E731
    p = {str(s): list(f(a + s * period)) for s in range(1, 7)}
    assert periodicity(angles, p, period)["max"] < 1e-12
    drift = {c: list(np.asarray(v) * (1.0 + 0.01 * a / a[-1])) for c, v in p.items()}
    got = periodicity(angles, drift, period)["max"]
    assert 0.003 < got < 0.05


#: Recorded ported runs (tests/data/cfd/moving/record_ported.py): three lobe periods from
#: the model's periodic state, in chunks, fields written every 0.5 deg.
PORTED = {g: ROOT / "tests" / "data" / "cfd" / "moving" / f"ported_{g}um.json" for g in (100, 20)}


def _courant_limit(gap_um: int, chunk: dict) -> float:
    """A chunk at the first chunk's steps is PISO below Courant 1; one at fewer steps
    (the 20 um run from 63 deg) stays within the largest Courant number its clearance's
    step study ran at and found close to the first chunk (ported_<gap>um_pimple.json)."""
    moving = ROOT / "tests" / "data" / "cfd" / "moving"
    first = json.loads((moving / f"ported_{gap_um}um" / "chunks.json").read_text())[0]
    if chunk["time_steps"] / chunk["span_deg"] >= first["time_steps"] / first["span_deg"]:
        return 1.0
    study = json.loads((moving / f"ported_{gap_um}um_pimple.json").read_text())
    return max(r["max_courant"] for r in study["runs"] if r["outer_correctors"] == 1)


def _flat(errors: dict) -> dict:
    return {f"{c}.{k}": v for c, e in errors.items() for k, v in e.items()}


@pytest.mark.parametrize("gap_um", list(PORTED))
def test_the_recorded_ported_comparison_is_what_its_data_give(gap_um):
    from rotorflow.cases.moving_ported import comparison, differences, join

    rec = json.loads(PORTED[gap_um].read_text())
    run = rec["cfd"]
    chunks = run["chunks"]
    assert all(c["status"] == "completed" for c in chunks)
    # each chunk's mass against its port flows as the solver books them: the pressure
    # equation's residual and the tables' 11 digits (6e-11 measured), far below 1e-4
    assert max(c["mass_balance"] for c in chunks) <= 1e-8
    for c in chunks:  # PISO below Courant 1, or within what the step study validated
        assert c["max_courant"] <= _courant_limit(gap_um, c)
    assert sum(c["span_deg"] for c in chunks) == pytest.approx(run["span_deg"])
    cfd = run["chambers"]
    assert len(cfd["angles_deg"]) == int(round(run["span_deg"] * 2)) + 1
    period = math.radians(60.0)
    # the models' periodic state, rebuilt now: the record is still the product's
    models = ported_models(load_toml(CASE), CASE, run["depth_m"], run["gap_m"], PerfectGas(),
                           list(rec["models"]), case_from_raw,
                           ROOT / "tests" / "data" / "cfd" / "chamber" / "flow_coefficient.json")
    again = comparison(cfd, period, models)
    assert again["periodicity"]["pairs"] == pytest.approx(rec["periodicity"]["pairs"],
                                                          rel=1e-9)
    # (abs 1e-6 as well: the figures are pressure errors over the traces' swing, of the
    # order of the pressures themselves, and the models' periodic state is converged to
    # 1e-6 in p (Numerics.cycle_rtol), so a figure of 2e-3 may move by more than its own
    # 1e-6: 2.9e-8 between this AVX2 machine and the record's, 2026-12-01)
    for name, m in rec["models"].items():
        assert _flat(again["models"][name]["errors"]) == pytest.approx(_flat(m["errors"]),
                                                                       rel=1e-6, abs=1e-6)
    # a perturbed CFD trace changes the figures: the check can fail
    bad = {**cfd, "p": {k: [v * 1.01 for v in vals] for k, vals in cfd["p"].items()}}
    m = next(iter(rec["models"].values()))
    p = np.array(m["p"], dtype=float)
    last = np.radians(cfd["angles_deg"]) >= np.radians(cfd["angles_deg"][-1]) - period - 1e-9
    tail = {"angles_deg": list(np.asarray(bad["angles_deg"])[last]),
            "p": {c: list(np.asarray(v)[last]) for c, v in bad["p"].items()}}
    assert _flat(differences(tail, p[last])) != pytest.approx(_flat(m["errors"]), rel=1e-3)
    assert join([cfd]) == cfd


def test_chambers_are_told_apart_past_the_first_period():
    # The geometry repeats every lobe period: slot s at phi + P is slot s + 1 at phi.
    # Past one period the newborn chamber's raw slot is -1, which the column labelling
    # once read as "unlabelled" and gave to its neighbours (the dying chamber took its
    # cells at 113 deg).
    from rotorflow.cases.moving_case import chamber_cells
    from rotorflow.cases.moving_section import MovingSection
    from rotorflow.cases.ogrid import OGridSpec, make_ogrid
    from rotorflow.geometry.internal_gear.family import examples

    pair = examples()["table1"]
    spec = OGridSpec(columns=512, cells_across_gap=4)
    s = MovingSection(pair, 100e-6, spec, 0.0, 1.0, 1, 100.0)
    period = float(pair.period)
    n = int(round(2 * math.pi / period))
    for deg in (53.0, 29.0):
        phi = math.radians(deg)
        here, _ = chamber_cells(s, make_ogrid(pair, phi, s.gap, spec)[0], phi)
        there, _ = chamber_cells(s, make_ogrid(pair, phi + period, s.gap, spec)[0],
                                 phi + period)
        assert {(c - 2) % n + 1 for c in here} == set(there)
        for c, cells in here.items():
            # the O-grid's columns jitter along the walls: a few columns of 4 cells
            assert abs(len(there[(c - 2) % n + 1]) - len(cells)) <= 16


@pytest.mark.parametrize("gap_um", [100, 20])
def test_the_ported_runs_time_step_error_is_far_below_the_models_differences(gap_um):
    # the first chunk again at 1.5 times its steps per frame (100 um: 288 against 192,
    # 20 um: 240 against 160)
    moving = ROOT / "tests" / "data" / "cfd" / "moving"
    study = json.loads((moving / f"ported_{gap_um}um_dt.json").read_text())
    base = json.loads((moving / f"ported_{gap_um}um" / "chunks.json").read_text())[0]
    assert study["steps_per_frame"][1] == pytest.approx(1.5 * study["steps_per_frame"][0])
    base, fine = base["chambers"], study["fine"]
    assert np.allclose(fine["angles_deg"], base["angles_deg"], atol=1e-6)
    swing = max(np.nanmax(v) for v in fine["p"].values()) - min(
        np.nanmin(v) for v in fine["p"].values())
    for c, got in study["chambers"].items():
        a, b = np.array(base["p"][c], float), np.array(fine["p"][c], float)
        ok = np.isfinite(a) & np.isfinite(b)
        assert np.abs(a - b)[ok].max() / swing == pytest.approx(got, rel=1e-9)
    # below 1 % of the swing: the models differ from the run by 2.7-4 % (RMS) at 100 um
    assert study["max"] <= 0.01


def test_the_grid_error_is_the_richardson_error_of_a_known_expansion():
    from rotorflow.cases.moving_ported import grid_error

    # p = exact + C h^2 on h, h/2, h/4: the middle grid's error is C (h/2)^2 exactly;
    # a slot whose grids oscillate is charged the three's spread, not extrapolated
    angles = [13.0, 13.5, 14.0]
    exact = {"1": np.array([1.0e5, 1.1e5, 1.2e5]), "2": np.array([2.0e5, 2.5e5, 3.0e5])}
    c = np.array([0.0, 800.0, -1600.0])
    runs = [{"angles_deg": angles,
             "p": {"1": list(exact["1"] + c * h**2),
                   "2": list(exact["2"] + np.array([0.0, 300.0, 0.0]) * (-1) ** k)}}
            for k, h in enumerate((1.0, 0.5, 0.25))]
    out = grid_error(runs)
    swing = 3.0e5 - 1.0e5
    assert out["swing_Pa"] == pytest.approx(swing)
    assert out["chambers"]["1"] == pytest.approx(1600.0 * 0.25 / swing, rel=1e-9)
    assert out["chambers"]["2"] == pytest.approx(600.0 / swing, rel=1e-9)
    assert out["kinds"]["monotone"] == 2 and out["kinds"]["oscillatory"] == 1
    # the coarsest's error: C h^2
    assert grid_error(runs, of=0)["chambers"]["1"] == pytest.approx(1600.0 / swing)
    with pytest.raises(ValueError, match="same angles"):
        grid_error(runs[:2])


def _pimple(gap_um: int):
    """The recorded cost-control study and its runs by (steps, outer correctors), every
    figure checked against the stored pressures and the reference chunk."""
    moving = ROOT / "tests" / "data" / "cfd" / "moving"
    study = json.loads((moving / f"ported_{gap_um}um_pimple.json").read_text())
    base = json.loads((moving / f"ported_{gap_um}um" / "chunks.json").read_text())[0]
    base = base["chambers"]
    swing = max(np.nanmax(v) for v in base["p"].values()) - min(
        np.nanmin(v) for v in base["p"].values())
    assert study["swing_Pa"] == pytest.approx(swing, rel=1e-12)
    runs = {(r["steps_per_frame"], r["outer_correctors"]): r for r in study["runs"]}
    assert all(r["status"] == "completed" for r in runs.values())
    for r in runs.values():
        n = len(r["angles_deg"])
        assert r["angles_deg"] == pytest.approx(base["angles_deg"][:n], abs=1e-6)
        for c, got in r["chambers"].items():
            a, b = np.array(base["p"][c][:n], float), np.array(r["p"][c], float)
            ok = np.isfinite(a) & np.isfinite(b)
            assert np.abs(a - b)[ok].max() / swing == pytest.approx(got, rel=1e-9)
    return runs


def test_the_20um_runs_larger_step_is_within_half_a_percent_of_the_swing():
    # the 20 um run went on from 63 deg at 40 steps a frame instead of 160 (Courant 2.1
    # against 0.6): over the first chunk it stays within 0.5 % of the swing of the
    # 160-step run (whose own step error, three times its difference from 240 steps at
    # first order, is ~0.1 %), and 20 steps within 1 %: well below the grid's share and
    # the models' differences
    runs = _pimple(20)
    assert runs[40, 1]["max"] <= 0.005
    assert runs[20, 1]["max"] <= 0.01
    assert runs[40, 1]["run_time_s"] < 0.3 * json.loads(
        (ROOT / "tests" / "data" / "cfd" / "moving" / "ported_20um" / "chunks.json")
        .read_text())[0]["run_time_s"]


def test_larger_steps_err_at_first_order_and_outer_correctors_do_not_help():
    # The first 4 deg at 100 um again at 3, 6 and 12 times the recorded step, with and
    # without PIMPLE outer correctors (tests/data/cfd/moving/record_ported.py pimple).
    runs = _pimple(100)
    # the recorded step run again from the same start is the record (a restart is exact)
    assert runs[192, 1]["max"] <= 1e-9
    # converged outer loops leave the implicit Euler step's own error, A k^p at k times
    # the recorded step: the differences from the record at k = 3, 6, 12 give the
    # observed order, (d12 - d6) / (d6 - d3) = 2^p; Euler is first order (a second-order
    # scheme would show p = 2)
    d3, d6, d12 = runs[64, 3]["max"], runs[32, 5]["max"], runs[16, 5]["max"]
    assert 0.8 <= math.log2((d12 - d6) / (d6 - d3)) <= 1.5
    # PISO's single pass (the production runs') is no further from the record than the
    # converged outer loop at the same step, and costs 1.6-3.5 times less: outer
    # correctors buy nothing here
    for steps, most in ((64, 3), (32, 5), (16, 5)):
        assert runs[steps, 1]["max"] <= runs[steps, most]["max"]
        assert runs[steps, 1]["run_time_s"] < runs[steps, most]["run_time_s"]
    # more outer correctors than the converged loop needs change nothing
    assert runs[64, 2]["max"] == pytest.approx(runs[64, 3]["max"], rel=0.02)
    assert runs[32, 3]["max"] == pytest.approx(runs[32, 5]["max"], rel=0.02)


def test_differences_are_taken_at_the_angles_both_runs_were_written_at():
    from rotorflow.cases.moving_ported import largest_differences

    base = {"angles_deg": [13.0, 13.5, 14.0, 14.5], "p": {"1": [1.0, 2.0, 3.0, 4.0],
                                                          "2": [5.0, np.nan, 5.0, 5.0]}}
    # written every 0.25 deg from 13.5: only 13.5, 14.0 and 14.5 are common
    other = {"angles_deg": [13.5, 13.75, 14.0, 14.25, 14.5],
             "p": {"1": [2.0, 99.0, 3.5, 99.0, 4.0], "2": [7.0, 99.0, 5.0, 99.0, 5.0]}}
    assert largest_differences(base, other, 2.0) == {"1": 0.25, "2": 0.0}
    with pytest.raises(ValueError, match="no written angle"):
        largest_differences(base, {"angles_deg": [20.0], "p": {"1": [1.0]}}, 1.0)


#: Recorded grid studies (record_ported.py grid): the first degrees on three grids
#: refined by a constant ratio, the run's among them; and (mode opening) the same
#: through slot 2's discharge opening, where the runs differ most from every model.
GRIDS = {(g, kind): ROOT / "tests" / "data" / "cfd" / "moving" / f"ported_{g}um_{kind}.json"
         for g in (100, 20) for kind in ("grid", "grid_opening")}


@pytest.mark.parametrize("gap_um, kind", list(GRIDS))
def test_the_ported_runs_grid_error_is_what_its_three_grids_give(gap_um, kind):
    from rotorflow.cases.moving_ported import grid_error

    rec = json.loads(GRIDS[gap_um, kind].read_text())
    runs, ratio, of = rec["runs"], rec["ratio"], rec["run_grid"]
    # a constant ratio, the step with the cell
    for coarse, fine in zip(runs, runs[1:], strict=False):
        for key in ("columns", "cells_across", "steps_per_frame"):
            assert fine[key] == pytest.approx(ratio * coarse[key], rel=0.01)
    assert max(r["mass_balance"] for r in runs) <= 1e-8
    again = grid_error(rec["pressures"], ratio, of)
    assert again["chambers"] == pytest.approx(rec["chambers"], rel=1e-9)
    bad = [rec["pressures"][0], rec["pressures"][1],
           {**rec["pressures"][2], "p": {c: [x * 1.002 for x in v]
                                         for c, v in rec["pressures"][2]["p"].items()}}]
    assert grid_error(bad, ratio, of)["chambers"] != pytest.approx(rec["chambers"], rel=1e-3)
    if kind == "grid_opening":
        return
    # every chamber but one holds its grid error below 0.5 % of the swing; the one whose
    # pressure moves most over the span (the dying chamber, open to the discharge port:
    # the port's gas column rings in it, +-0.2 bar at 100 um) carries the largest, the
    # ringing's phase being what the grid moves most
    fine = rec["pressures"][2]["p"]
    ringing = max(fine, key=lambda c: np.nanmax(fine[c]) - np.nanmin(fine[c]))
    assert rec["max"] == rec["chambers"][ringing]
    assert max(v for c, v in rec["chambers"].items() if c != ringing) <= 0.005


@pytest.mark.parametrize("gap_um", (100, 20))
def test_the_discharge_openings_peak_is_the_runs_and_not_its_grids(gap_um):
    """Where each record differs most from every model (slot 2 at 170-171 deg, the
    models' ideal port holding it at the plenum's pressure from its opening), the CFD's
    chamber goes on compressing after its port opens (the port opens gradually:
    :func:`test_the_opening_peak_is_the_ports_gradual_opening`).  That peak is the
    CFD's, not its grid's: from the same start it stands above the plenum on each of
    the three grids by more than half the record's excess (the grid runs start from the
    model's state, 5 kPa below the record's at 166 deg at 100 um), and the run's grid's
    error there is a fraction of the difference from the models that the record
    reports."""
    rec = json.loads(GRIDS[gap_um, "grid_opening"].read_text())
    ported = json.loads(PORTED[gap_um].read_text())
    p_d = load_toml(CASE)["operating"]["p_discharge_bar"] * 1e5
    tail = np.asarray(ported["cfd"]["chambers"]["angles_deg"]) >= (
        ported["cfd"]["chambers"]["angles_deg"][-1] - 60.0 - 1e-9)
    excess = np.nanmax(np.asarray(ported["cfd"]["chambers"]["p"]["2"], float)[tail]) - p_d
    assert excess > 0.1 * (p_d - 1e5)  # the record's own peak: 47 kPa at 100 um
    for run in rec["pressures"]:
        assert np.nanmax(np.asarray(run["p"]["2"], float)) - p_d > 0.5 * excess
    for name, m in ported["models"].items():
        e = m["errors"]
        assert max(e, key=lambda c: e[c]["max"] if c != "all" else -1.0) == "2", name
        assert 170.0 <= e["2"]["max_at_deg"] <= 171.0
        # the grid's share: 7.5 kPa against 47 at 100 um
        assert rec["chambers"]["2"] * rec["swing_Pa"] < 0.25 * e["2"]["max"] * e["all"]["swing_Pa"]


def _blow_down(p0: float, T0: float, volume, area, p_d: float, column: float,
               degrees: np.ndarray, omega: float, gas) -> np.ndarray:
    """An independent construction of a chamber opening to its port: the chamber
    isentropic and uniform (``volume(deg)``, m3), its gas leaving through ``area(deg)``
    (m2) as a column ``column`` m long that the pressure difference less the exit loss
    (the jet's dynamic pressure, not recovered in the plenum) accelerates:
    rho L dw/dt = p - p_d - rho w |w| / 2.  Explicit steps of 1e-3 deg; the pressure at
    ``degrees``."""
    h = math.radians(1e-3) / omega
    deg, w = float(degrees[0]), 0.0
    rho = p0 / (gas.R * T0)
    mass, entropy = rho * volume(deg), p0 / rho ** gas.gamma
    out, k = [], 0
    while k < len(degrees):
        rho = mass / volume(deg)
        p = entropy * rho ** gas.gamma
        if deg >= degrees[k] - 1e-9:
            out.append(p)
            k += 1
        a = area(deg)
        w = w + h * (p - p_d - 0.5 * rho * w * abs(w)) / (rho * column) if a > 0 else 0.0
        mass -= h * rho * a * w
        deg += 1e-3
    return np.array(out)


@pytest.mark.parametrize("gap_um", (100, 20))
def test_the_opening_peak_is_the_ports_gradual_opening(gap_um):
    """Why the runs differ most from the models at slot 2's discharge opening.  The
    models open the port on the chamber's whole end-face section at the opening angle
    (the internal gear's table: area_hp is the section, 320 mm2 here; ideal ports then
    equalise at once, nozzle ports within 0.5 deg); the CFD's port is the product's
    polygon, whose overlap with the chamber grows from nothing (7 mm2 0.5 deg after the
    opening, 47 mm2 3.5 deg after).  A uniform isentropic chamber of the model's volume,
    started from the record's pressure 1 deg before the opening, blowing down through
    that overlap (the CFD's outline) with the slab's gas column (the one-cell slab's port
    face moves its cell's gas across the whole 10 mm depth) and exit loss, peaks where
    the record does: 2.82 / 3.10 bar against 2.86 / 3.07 at 20 / 100 um (2.80 / 3.09
    with a column a tenth as long: the column adds little).  Through the whole section
    from the opening it rises no further.  Leakage is left out of the construction, so
    it is held to 2.5 % of the swing."""
    from manifold3d import CrossSection, FillRule

    from rotorflow.cases.moving_ports import slab_machine, slab_ports
    from rotorflow.geometry.internal_gear.family import examples
    from rotorflow.geometry.ports import chamber_section

    rec = json.loads(PORTED[gap_um].read_text())
    run = rec["cfd"]
    depth = run["depth_m"]
    raw, gas, pair = load_toml(CASE), PerfectGas(), examples()["table1"]
    ports, _ = slab_ports(pair, depth, run["gap_m"], gas, raw, CASE, case_from_raw)
    _, machine, _ = slab_machine(pair, depth, run["gap_m"], gas, raw, CASE, case_from_raw)
    model = ported_models(raw, CASE, depth, run["gap_m"], gas, ["nozzle"],
                          case_from_raw)["nozzle"]
    outline = CrossSection([np.ascontiguousarray(q) for q in map(np.asarray, ports.discharge)],
                           FillRule.NonZero)
    period = float(pair.period)

    def overlap(deg):  # slot 2's section inside the discharge outline
        polys = chamber_section(machine, math.radians(deg) + 2 * period)
        return (CrossSection([np.ascontiguousarray(q) for q in polys], FillRule.Positive)
                ^ outline).area() if polys else 0.0

    grid = np.arange(167.5, 173.0, 0.05)
    areas = np.array([overlap(d) for d in grid])
    volumes = slot_pressures(model, np.radians(grid), "volume_m3")[:, 1]
    opening = grid[np.argmax(areas > 0.01 * areas.max())]  # past the outline's slivers
    cfd = run["chambers"]
    angles = np.asarray(cfd["angles_deg"])
    tail = angles >= angles[-1] - 60.0 - 1e-9
    seen = angles[tail]
    p_cfd = np.asarray(cfd["p"]["2"], float)[tail]
    start = float(seen[np.searchsorted(seen, opening - 1.0) - 1])
    at = seen[(seen >= start) & (seen <= start + 3.0)]
    p0 = float(np.interp(start, seen, p_cfd))
    T_m, p_m = (float(slot_pressures(model, [math.radians(start)], k)[0, 1])
                for k in ("T_K", "p_Pa"))
    T0 = T_m * (p0 / p_m) ** ((gas.gamma - 1.0) / gas.gamma)  # the model's, compressed on
    p_d = model.plenums["discharge"][0]
    omega = 2500.0 * 2.0 * math.pi / 60.0  # the recorded runs' speed (record_ported.py)

    def volume(d):
        return np.interp(d, grid, volumes)

    def blow_down(area):
        return _blow_down(p0, T0, volume, area, p_d, depth, at, omega, gas)

    gradual = blow_down(lambda d: np.interp(d, grid, areas))
    whole = blow_down(lambda d: volume(d) / depth if d >= opening else 0.0)
    want = np.interp(at, seen, p_cfd)
    swing = rec["models"]["nozzle"]["errors"]["all"]["swing_Pa"]
    assert want.max() - p_d > 0.1 * swing  # the record's peak stands above the plenum
    assert abs(gradual.max() - want.max()) < 0.025 * swing
    assert abs(at[np.argmax(gradual)] - at[np.argmax(want)]) <= 0.5 + 1e-9
    assert whole[at >= opening].max() <= np.interp(opening, at, whole) + 1e-3 * swing
