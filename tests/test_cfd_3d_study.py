"""The cfd.machine stage without OpenFOAM (cases/machine_setup.py, cases/machine_study.py,
postprocess/machine_compare.py, issue 16).

Checked against what the code does not compute itself: the quasi-1D model's chambers
mapped onto the CFD's slots conserve mass slot by slot and carry the total leakage
across every cut between the plenums; a Richardson table of values built from a known
exact value and a known order gives that value back and each model's error against it;
a bad [cfd_machine] section stops the run with one line and exit status 2.
"""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from rotorflow.cases.machine_setup import (
    Grid,
    case_table,
    frozen_models,
    model_flows,
    slot_of,
    table_origin,
)
from rotorflow.cases.machine_study import StudySettings
from rotorflow.errors import CaseError
from rotorflow.postprocess import machine_compare
from rotorflow.workflow.case import load_case

from .conftest import CASES

CASE = load_case(CASES / "cfd_machine.toml")


@pytest.fixture(scope="module")
def states():
    table = case_table(CASE)
    out = {}
    for deg in CASE.raw["cfd_machine"]["angles_deg"]:
        phi = math.radians(deg)
        out[deg] = frozen_models(CASE, table, phi, ["nozzle", "fanno"]), phi
    return table, out


def test_mapped_model_flows_conserve_mass_slot_by_slot(states):
    """Every closed chamber's pairs balance (the model's own balance, seen through the
    mapping onto slots), and the total leakage into the suction side equals what leaves
    the discharge side through the pairs that join the two sides."""
    table, by_angle = states
    period, origin = float(CASE.pair.period), table_origin(CASE)
    paths = {p.name: p for p in table.paths}
    for deg, (models, phi) in by_angle.items():
        for name, state in models.items():
            pairs, total = model_flows(state, phi, period, origin, paths)
            slots = slot_of(state, phi, period, origin)
            closed = [s for s, c in zip(slots, state.closed, strict=True) if c]
            assert closed, (deg, name)
            scale = max(abs(f) for f in pairs.values())
            for s in closed:
                net = sum(f if b == s else -f for (a, b), f in pairs.items() if s in (a, b))
                assert abs(net) < 1e-8 * scale, (deg, name, s, net)
            # The cut around the suction side: every slot younger than the closed ones
            # (open to suction or not yet born) against every older one.
            cut = sum(f for (a, b), f in pairs.items() if a < min(closed) <= b)
            assert total > 0.0 and cut == pytest.approx(-total, rel=1e-9), (deg, name)


def test_the_slots_of_the_model_are_the_grids_chambers(states):
    """The model's chamber volumes at each angle against the machine's chamber volume
    curve at the slots' machine ages (the geometry the CFD's zones are cut from): the
    table's angle starts at the chamber's planar birth, not at the machine's zero: a
    mapping off by that origin (15.6 deg here) is off by 12-13 % of the largest volume
    (measured at the four angles); the volumes agree to round-off (1e-12)."""
    from rotorflow.geometry.summary import build_machine

    machine = build_machine(CASE)
    period, origin = float(CASE.pair.period), table_origin(CASE)
    v_max = float(machine.curves.volume.max())
    for _, (models, phi) in states[1].items():
        state = models["nozzle"]
        for s, v in zip(slot_of(state, phi, period, origin), state.volumes, strict=True):
            assert float(machine.volume_at(phi + s * period)[0]) == pytest.approx(
                float(v), abs=1e-6 * v_max)


def _record(exact: dict, order: float, ratio: float, models: dict) -> dict:
    """An angle's record whose CFD values are exact * (1 + c h^order) on three grids."""
    h = np.array([1.0, 1.0 / ratio, 1.0 / ratio**2])

    def grids(v, c):
        return v * (1.0 + c * h**order)

    runs = []
    for k in range(3):
        runs.append({"chamber_p": {"4": grids(exact["p4"], 0.03)[k]},
                     "seals": [[3, 4, grids(exact["f34"], 0.2)[k]],
                               [4, 5, grids(exact["f45"], 0.2)[k]],
                               [1, 2, 1e-9],
                               [6, 7, grids(exact.get("f67", 0.0), 0.2)[k]]],
                     "leakage_kg_s": grids(exact["total"], 0.1)[k]})
    return {"angle_deg": 15.0, "ratio": ratio, "closed": [4], "runs": runs, "models": models}


def test_comparison_extrapolates_and_finds_the_closest_model(tmp_path):
    # 6 -> 7: a path between two chambers open to ports (neither is closed), carrying
    # leakage from the discharge side to the suction side: it is compared too.
    exact = {"p4": 2.0e5, "f34": -4.0e-4, "f45": -4.0e-4, "f67": 3.0e-4, "total": 8.0e-4}

    def model(scale):
        return {"pressures": {"4": exact["p4"] * scale}, "total": exact["total"] * scale,
                "pairs": {"3,4": exact["f34"] * scale, "4,5": exact["f45"] * scale,
                          "6,7": exact["f67"] * scale}}

    record = _record(exact, 2.0, 1.5, {"near": model(1.01), "far": model(1.2)})
    rows = machine_compare.quantities(record)
    # The stray pair (1, 2) carries nothing: not compared.
    assert [r["name"] for r in rows] == ["chamber 4", "chamber 3 -> 4", "chamber 4 -> 5",
                                         "chamber 6 -> 7", "total"]
    for r in rows:
        assert r["convergence"] == "monotone" and r["order"] == pytest.approx(2.0, rel=1e-9)
    result = machine_compare.write([record], tmp_path)
    assert result["closest_model"] == "near"
    assert result["closest_by_kind"] == dict.fromkeys(("pressure", "path", "leakage"), "near")
    assert result["models"]["near"]["all"]["max_abs"] == pytest.approx(0.01, rel=1e-9)
    assert result["models"]["far"]["leakage"]["rms"] == pytest.approx(0.2, rel=1e-9)
    text = (tmp_path / "machine_errors.csv").read_text().splitlines()
    assert len(text) == 1 + len(rows)


def test_the_closest_model_is_named_per_kind_too(tmp_path):
    """Over all quantities the paths outnumber the pressures: a model exact on the paths
    and the total but 10 % off in pressure is closest overall, one exact in pressure
    and 50 % off on the paths is closest on pressures."""
    exact = {"p4": 2.0e5, "f34": -4.0e-4, "f45": -4.0e-4, "f67": 3.0e-4, "total": 8.0e-4}

    def model(p_scale, f_scale):
        return {"pressures": {"4": exact["p4"] * p_scale}, "total": exact["total"] * f_scale,
                "pairs": {"3,4": exact["f34"] * f_scale, "4,5": exact["f45"] * f_scale,
                          "6,7": exact["f67"] * f_scale}}

    record = _record(exact, 2.0, 1.5, {"flows": model(1.1, 1.0), "pressure": model(1.0, 1.5)})
    result = machine_compare.write([record], tmp_path)
    assert result["closest_model"] == "flows"
    assert result["closest_by_kind"] == {"pressure": "pressure", "path": "flows",
                                         "leakage": "flows"}
    assert "pressure pressure" in (tmp_path / "machine_errors.md").read_text()


def test_quick_estimate_of_two_grids_against_the_three_grid_value(tmp_path):
    """The coarse and medium grids alone, extrapolated at order 2: exact where the
    grids' true order is 2; where it is 1.5 (the layers' order measured along the
    rotors), off by (r^2 - r^1.5) / (r^2 - 1) of the medium grid's error, which the
    table reports against the three-grid value (here order 1.5, observed exactly).  A
    study of two grids compares the models against the quick estimate."""
    exact = {"p4": 2.0e5, "f34": -4.0e-4, "f45": -4.0e-4, "total": 8.0e-4}
    models = {"m": {"pressures": {"4": 2.0e5}, "total": 8.8e-4,
                    "pairs": {"3,4": -4.0e-4, "4,5": -4.0e-4}}}
    at2 = machine_compare.quantities(_record(exact, 2.0, 1.5, models))
    assert all(abs(r["two_grid_error"]) < 1e-12 for r in at2)
    record = _record(exact, 1.5, 1.5, models)
    rows = machine_compare.quantities(record)
    total = rows[-1]
    share = (1.5**2 - 1.5**1.5) / (1.5**2 - 1)
    assert total["two_grid_error"] == pytest.approx(share * 0.1 / 1.5**1.5, rel=1e-6)
    result = machine_compare.write([record], tmp_path)
    assert result["two_grid"]["leakage"]["max_abs"] == pytest.approx(
        abs(total["two_grid_error"]), rel=1e-12)
    # grids = 2: only coarse and medium ran; the models are held to the quick estimate.
    record["runs"] = record["runs"][:2]
    quick = machine_compare.quantities(record)[-1]
    assert quick["convergence"] == "two-grid"
    assert quick["extrapolated"] == pytest.approx(total["two_grid"], rel=1e-12)
    assert machine_compare.errors([quick])["m"]["leakage"][0] == pytest.approx(
        8.8e-4 / total["two_grid"] - 1, rel=1e-12)
    machine_compare.write([record], tmp_path)
    assert "two-grid" in (tmp_path / "machine_errors.csv").read_text()


def test_a_model_matching_the_finest_grid_is_not_exact(tmp_path):
    """The comparison is against the extrapolation, not the finest grid: a model equal
    to the finest grid's values carries the finest grid's own error (here the order-1
    sequence's 1/(r-1) share of the last difference)."""
    exact = {"p4": 2.0e5, "f34": -4.0e-4, "f45": -4.0e-4, "total": 8.0e-4}
    base = _record(exact, 1.0, 2.0, {})
    fine = base["runs"][2]
    base["models"] = {"fine": {"pressures": {"4": fine["chamber_p"]["4"]},
                               "total": fine["leakage_kg_s"],
                               "pairs": {"3,4": fine["seals"][0][2],
                                         "4,5": fine["seals"][1][2]}}}
    rows = machine_compare.quantities(base)
    errors = machine_compare.errors(rows)["fine"]
    assert errors["leakage"][0] == pytest.approx(0.1 * 0.25, rel=1e-9)


def test_grids_refine_every_direction_by_the_ratio():
    s = StudySettings.from_section(CASE.raw["cfd_machine"])
    coarse, medium, fine = s.grids()
    assert (medium.columns, medium.cells_across_gap, medium.layers) == (1152, 6, 24)
    assert (fine.columns, fine.cells_across_gap, fine.layers) == (1728, 9, 36)
    assert fine.end_layer_m == pytest.approx(coarse.end_layer_m / 2.25)
    assert Grid(512, 4, 4).label == "c512-x4-l4"
    quick = StudySettings.from_section({**CASE.raw["cfd_machine"], "grids": 2})
    assert quick.grids() == (coarse, medium)


@pytest.mark.parametrize("old, new, word", [
    ("refinement_ratio = 1.5", "refinement_ratio = 1.4", "not a whole number"),
    ("angles_deg = [0, 15, 30, 45]", "angles_deg = [400]", "angles_deg"),
    ("models = [", "mesh = 2\nmodels = [", "mesh"),
    ('models = ["nozzle", "fanno", "cfd-calibrated"]', 'models = ["orifice"]', "models"),
    ("columns = 768", "columns = 768.5", "whole number"),
    ("columns = 768", "columns = 768\ngrids = 1", "grids"),
])
def test_bad_cfd_machine_section_exits_2_with_one_line(tmp_path, old, new, word):
    text = (CASES / "cfd_machine.toml").read_text()
    assert old in text
    case = tmp_path / "case.toml"
    case.write_text(text.replace(old, new))
    with pytest.raises(CaseError, match=word):
        load_case(case)
    out = subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", "run", str(case),
                          "--build", str(tmp_path / "build")], capture_output=True, text=True)
    assert out.returncode == 2
    assert len(out.stderr.strip().splitlines()) == 1 and word in out.stderr
    assert not (tmp_path / "build").exists()
