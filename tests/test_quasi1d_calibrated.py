"""The "cfd-calibrated" leakage model: the nozzle times the CFD-fitted flow coefficient."""

import json

import pytest

from rotorflow.errors import CaseError
from rotorflow.postprocess.leakage import FlowCoefficientFit
from rotorflow.quasi1d import Leakage, Operating, simulate
from rotorflow.quasi1d.synthetic import scaled_table

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
