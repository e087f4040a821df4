"""The recorded frozen-angle study of issue 16 re-checked offline (no OpenFOAM).

examples/cfd_machine.toml's runs (4 angles x 3 grids, the default helical machine at
20 um) are kept in git as each run's result and key (tests/data/cfd/machine_runs); here
the stage's own per-angle code runs on them with the solver replaced by a look-up that
fails the test if a run is missing or its key no longer matches (the case or the code
that makes the grid changed: the study must be rerun).  Checked against the issue's
criteria, not against the code's own output: every run converged with its mass balance
within 0.5 %; the total leakage converges monotonically; the quick estimate (coarse and
medium grids, two-grid Richardson at the formal order 2) lies within 2 % of the
three-grid extrapolation at every angle, and a 5 % error in the coarse grid's leakage
would break that (the check can fail).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from rotorflow.cases import machine_study
from rotorflow.cases.chamber_case import _resolve
from rotorflow.cases.machine_run import Controls, case_key, recorded_run
from rotorflow.cases.machine_setup import Grid, case_table, frozen_machine
from rotorflow.postprocess import machine_compare
from rotorflow.postprocess.richardson import richardson, two_grid
from rotorflow.workflow.case import load_case

from .conftest import CASES

CASE_FILE = CASES / "cfd_machine.toml"
#: The issue's mass balance over all patches for a run to be used.
BALANCE = 5e-3
#: The issue's target: within 2 % of the extrapolated total leakage.
TARGET = 0.02


def _recorded(m, case_dir, controls, decomposition=None, **_):
    run = recorded_run(m, case_dir, controls)
    assert run is not None, f"no recorded run with this key in {case_dir}: rerun the study"
    return run


@pytest.fixture(scope="module")
def records():
    case = load_case(CASE_FILE)
    settings = machine_study.StudySettings.from_section(case.raw["cfd_machine"],
                                                        str(CASE_FILE))
    runs = _resolve(settings.runs_dir, CASE_FILE)
    correlation = _resolve(settings.flow_coefficient, CASE_FILE)
    table = case_table(case)
    gap = float(case.raw["leakage"]["gap_um"]) * 1e-6
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(machine_study, "run_machine_case", _recorded)
        return [machine_study.run_angle(case, table, math.radians(deg), settings, gap, runs,
                                        correlation, str(CASE_FILE))
                for deg in settings.angles_deg]


def test_every_run_converged_and_balances(records):
    assert len(records) == 4
    for r in records:
        assert [g["level"] for g in r["grids"]] == ["coarse", "medium", "fine"]
        for run in r["runs"]:
            assert run["status"] == "converged", (r["angle_deg"], run["message"])
            assert run["imbalance"] < BALANCE, (r["angle_deg"], run["imbalance"])


def test_quick_estimate_within_two_percent_of_the_three_grid_leakage(records):
    for r in records:
        leak = [run["leakage_kg_s"] for run in r["runs"]]
        three = richardson(leak, r["ratio"])
        assert three.kind == "monotone", (r["angle_deg"], leak)
        quick = two_grid(leak[:2], r["ratio"])
        assert abs(quick.extrapolated / three.extrapolated - 1) < TARGET, r["angle_deg"]
        # A coarse grid 5 % higher (its own error against the limit is ~20 %) moves
        # the estimate by 0.8 x 5 % x 1.2 = 4.8 %: the check above would fail.
        bent = [1.05 * leak[0], leak[1], leak[2]]
        assert abs(two_grid(bent[:2], r["ratio"]).extrapolated
                   / richardson(bent, r["ratio"]).extrapolated - 1) > TARGET


def test_the_stage_tabulates_the_quick_estimate_and_the_models(records, tmp_path):
    result = machine_compare.write(records, tmp_path)
    assert result["two_grid"]["leakage"]["count"] == 4
    assert result["two_grid"]["leakage"]["max_abs"] < TARGET
    assert set(result["models"]) == {"nozzle", "fanno", "cfd-calibrated"}
    assert (tmp_path / "machine_errors.md").read_text().count("\n") > 4


def test_a_runs_key_follows_its_port_timing_not_its_polygons_last_bits():
    """The recorded keys must hold on any CPU: the ports' polygons moved by 0.37 um
    between numpy's AVX-512 and AVX2 sine and cosine (Clipper's integer grid), and a key
    that hashed them matched the recorded study on one kind of machine only.  A port cut
    elsewhere is another run, so the timing still keys it."""
    case = load_case(CASE_FILE)
    fm = frozen_machine(case, case_table(case), 0.0, 20e-6, Grid(768, 4, 16))
    controls = Controls()
    moved = tuple([np.asarray(ring) + 5e-7 for ring in region] for region in fm.ports)
    assert case_key(replace(fm, ports=moved), controls) == case_key(fm, controls)
    later = (*fm.port_cut[:2], fm.port_cut[2] + 1e-6, *fm.port_cut[3:])
    assert case_key(replace(fm, port_cut=later), controls) != case_key(fm, controls)
    finer = (2 * fm.port_cut[0], *fm.port_cut[1:])
    assert case_key(replace(fm, port_cut=finer), controls) != case_key(fm, controls)
