"""`rotorflow map`: a performance map through the product's quasi-1D model."""

import csv
import json
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from rotorflow.workflow.cli import main
from rotorflow.workflow.sweep_points import dumps_toml

from .conftest import run_cli

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = ROOT / "examples" / "default.toml"


def _case(tmp_path, name, section):
    raw = tomllib.loads(DEFAULT.read_text())
    raw["map"] = section
    path = tmp_path / f"{name}.toml"
    path.write_text(dumps_toml(raw))
    return path, raw


def _rows(tmp_path, name):
    with open(tmp_path / "build" / "map" / name / "map.csv") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture(scope="module")
def discharge_map(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("map")
    case, raw = _case(tmp, "m", {"speed_rpm": [2000, 4000], "p_discharge_bar": [2.0, 3.2],
                                 "points": [3, 3]})
    code = main(["map", str(case), "--serial", "--no-progress", "--build", str(tmp / "build")])
    return tmp, raw, code


def test_map_points_converge_and_balance(discharge_map):
    tmp, _, code = discharge_map
    rows = _rows(tmp, "m")
    assert code == 0 and len(rows) == 9
    for r in rows:
        assert r["converged"] == "True", r["message"]
        assert abs(float(r["mass_balance_error"])) <= 1e-6
        assert abs(float(r["energy_balance_error"])) <= 1e-6
    folder = tmp / "build" / "map" / "m"
    assert (folder / "shaft_power_W.png").stat().st_size > 1000
    assert "9 points" in (folder / "report.html").read_text()


def test_map_trends(discharge_map):
    # Leakage falls as a share of displacement with speed and grows with pressure: the
    # delivered flow rises with speed, the volumetric efficiency falls with discharge
    # pressure and the indicated power rises with it.
    tmp, _, _ = discharge_map
    grid = {(float(r["speed_rpm"]), float(r["p_discharge_bar"])): r for r in _rows(tmp, "m")}
    speeds, pressures = sorted({k[0] for k in grid}), sorted({k[1] for k in grid})
    for p in pressures:
        flows = [float(grid[n, p]["suction_volume_flow_m3_min"]) for n in speeds]
        assert flows == sorted(flows)
    for n in speeds:
        eta = [float(grid[n, p]["volumetric_efficiency"]) for p in pressures]
        power = [float(grid[n, p]["indicated_power_W"]) for p in pressures]
        assert eta == sorted(eta, reverse=True) and power == sorted(power)


def test_map_point_is_the_simulate_command(discharge_map, tmp_path, capsys):
    # The point's figures against `rotorflow simulate` of a case file written with that
    # speed and pressure: the map runs the product's model, not a copy of it.
    tmp, raw, _ = discharge_map
    row = next(r for r in _rows(tmp, "m") if float(r["speed_rpm"]) == 4000.0
               and float(r["p_discharge_bar"]) == 2.6)
    point = {k: v for k, v in raw.items() if k != "map"}
    point["operating"] = {**raw["operating"], "speed_rpm": 4000.0, "p_discharge_bar": 2.6}
    path = tmp_path / "point.toml"
    path.write_text(dumps_toml(point))
    capsys.readouterr()
    assert main(["simulate", str(path), "--json"]) == 0
    fig = json.loads(capsys.readouterr().out)
    assert float(row["mass_flow_kg_s"]) == pytest.approx(fig["mass_flow_kg_s"], rel=1e-12)
    assert float(row["shaft_power_W"]) == pytest.approx(fig["shaft_power_W"], rel=1e-12)


def test_vacuum_axis_efficiency_rises_with_suction_pressure(tmp_path):
    case, _ = _case(tmp_path, "v", {"speed_rpm": [3000, 3001], "p_suction_bar": [0.4, 0.9],
                                    "points": [2, 3]})
    assert main(["map", str(case), "--serial", "--no-progress",
                 "--build", str(tmp_path / "build")]) == 0
    for n in (3000.0, 3001.0):
        rows = sorted((r for r in _rows(tmp_path, "v") if float(r["speed_rpm"]) == n),
                      key=lambda r: float(r["p_suction_bar"]))
        eta = [float(r["volumetric_efficiency"]) for r in rows]
        assert len(eta) == 3 and eta == sorted(eta)


def test_a_pressure_axis_over_decades_is_spaced_in_its_logarithm():
    """A vacuum map from 0.1 to 100 mbar: evenly spaced, three of four points would lie
    above 33 mbar; evenly in the logarithm they are the decades.  A range within a
    decade stays evenly spaced."""
    from rotorflow.workflow.perf_map import log_pressures, map_spec

    raw = tomllib.loads((ROOT / "examples" / "screw_pump_vacuum.toml").read_text())
    vac = map_spec({**raw, "map": {"p_suction_bar": [0.0001, 0.1], "points": [2, 4]}}, "x")
    assert vac.pressures == pytest.approx((0.0001, 0.001, 0.01, 0.1), rel=1e-12)
    assert log_pressures(vac)
    raw = tomllib.loads(DEFAULT.read_text())
    lin = map_spec({**raw, "map": {"p_discharge_bar": [1.5, 4.0], "points": [2, 6]}}, "x")
    assert lin.pressures == pytest.approx((1.5, 2.0, 2.5, 3.0, 3.5, 4.0), rel=1e-12)
    assert not log_pressures(lin)


@pytest.mark.parametrize("section, needle", [
    ({"points": [1, 3]}, "two integers from 2 to 100"),
    ({"p_discharge_bar": [0.5, 3.0]}, "leaves no pressure rise"),
    ({"speed_rpm": [3000, 1000]}, "must rise from a positive low"),
    ({"p_suction_bar": [0.5, 0.9], "p_discharge_bar": [2, 3]}, "not both"),
    ({"speed": [1, 2]}, "unknown key 'speed'"),
])
def test_bad_map_is_one_line_exit_2_nothing_written(tmp_path, section, needle):
    case, _ = _case(tmp_path, "bad", section)
    out = subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", "map", str(case),
                          "--serial", "--build", str(tmp_path / "build")],
                         capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 2
    assert needle in out.stderr and len(out.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "build").exists()


def test_coolprop_map_shares_one_table_and_matches_per_point_tables(tmp_path, monkeypatch,
                                                                     capsys):
    # One table over the union of the corners' ranges serves every point; a point then
    # agrees with `rotorflow simulate` on its own table to the tables' interpolation
    # error (the stress bench measured 1.3e-4 between shared and own tables).
    from rotorflow.quasi1d.coolprop_fluid import TabulatedFluid

    raw = tomllib.loads((ROOT / "examples" / "refrigeration_r134a.toml").read_text())
    raw["map"] = {"speed_rpm": [2000, 4000], "p_discharge_bar": [7.0, 11.0], "points": [2, 2]}
    case = tmp_path / "r.toml"
    case.write_text(dumps_toml(raw))
    builds = []
    real_build = TabulatedFluid.build.__func__
    monkeypatch.setattr(TabulatedFluid, "build", classmethod(
        lambda cls, *a, **k: builds.append(a) or real_build(cls, *a, **k)))
    assert main(["map", str(case), "--serial", "--no-progress",
                 "--build", str(tmp_path / "build")]) == 0
    assert len(builds) == 1
    monkeypatch.undo()
    row = next(r for r in _rows(tmp_path, "r") if float(r["speed_rpm"]) == 4000.0
               and float(r["p_discharge_bar"]) == 11.0)
    point = {k: v for k, v in raw.items() if k != "map"}
    point["operating"] = {**raw["operating"], "speed_rpm": 4000.0, "p_discharge_bar": 11.0}
    path = tmp_path / "point.toml"
    path.write_text(dumps_toml(point))
    capsys.readouterr()
    assert main(["simulate", str(path), "--json"]) == 0
    fig = json.loads(capsys.readouterr().out)
    assert float(row["mass_flow_kg_s"]) == pytest.approx(fig["mass_flow_kg_s"], rel=2e-3)
    assert float(row["indicated_power_W"]) == pytest.approx(fig["indicated_power_W"], rel=2e-3)


def test_coolprop_map_whose_suction_range_enters_the_dome_is_refused(tmp_path):
    # R290 at 278.15 K: saturated at 5.5 bar.  The shared table's corners bypassed the
    # single point's refusals; the 6 bar corner's liquid suction, squeezed along its
    # isentrope, ended in a traceback from CoolProp's melting line (exit 1)
    raw = tomllib.loads((ROOT / "examples" / "heat_pump_r290.toml").read_text())
    raw["map"] = {"speed_rpm": [2000, 4000], "p_suction_bar": [3.0, 6.0], "points": [2, 3]}
    case = tmp_path / "hp.toml"
    case.write_text(dumps_toml(raw))
    out = run_cli("map", case, "--serial", "--build", tmp_path / "build")
    assert out.returncode == 2, out.stderr
    assert len(out.stderr.strip().splitlines()) == 1, out.stderr
    assert "6 bar" in out.stderr and "subcooled liquid" in out.stderr, out.stderr
    assert not (tmp_path / "build").exists()
