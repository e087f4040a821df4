"""`rotorflow export`: what it writes, and bad input (exit 2, one line, nothing written)."""

import json
import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial import cKDTree

from rotorflow.geometry.curves import closest, sample
from rotorflow.geometry.export import csvfile, dxf, ply
from rotorflow.geometry.internal_gear.profiles import inner_profile, outer_profile
from rotorflow.workflow.case import load_case

from .conftest import CASES

HELICAL = """
[machine]
type = "internal-gear"
lobes_outer = 5
lambda = 1.4
sigma_bar = 0.95
diameter_mm = 60
length_mm = 40

[sweep]
kind = "helical"
wrap_outer_deg = 120
"""


def run(*args):
    return subprocess.run([sys.executable, "-m", "rotorflow.workflow.cli", *map(str, args)],
                          capture_output=True, text=True)


def write_case(tmp_path, export_section, machine=HELICAL):
    path = tmp_path / "case.toml"
    path.write_text(machine + "\n[export]\n" + export_section)
    return path


def test_export_writes_what_is_asked_and_only_that(tmp_path):
    case = write_case(tmp_path, 'formats = ["stl", "dxf", "csv", "ply", "cutter"]\n'
                                "tolerance_um = 20\nclearance_um = 10\n")
    out = tmp_path / "a" / "b"
    res = run("export", case, "--out", out)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == str(out)
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted([
        "export.json", "outer.stl", "inner.stl", "outer_profile.csv", "inner_profile.csv",
        "outer_profile.dxf", "inner_profile.dxf", "outer_cloud.csv", "inner_cloud.csv",
        "outer_cloud.ply", "inner_cloud.ply", "inner_cutter.csv", "inner_cutter.json"])
    assert not any(p.name.startswith(".export-") for p in (tmp_path / "a").iterdir())
    man = json.loads((out / "export.json").read_text())
    assert man["units"] == "mm"
    for name in ("outer.stl", "inner.stl"):
        assert man["files"][name]["volume_rel_error"] < 1e-4
        assert man["files"][name]["max_deviation_m"] <= 20e-6
    c = load_case(case)
    # profiles: closed polylines whose vertices lie on the analytic profile (clearance
    # included: the outer one is offset by 10 um) and whose chords stay within 20 um
    for name, prof in (("outer", outer_profile(c.pair)), ("inner", inner_profile(c.pair))):
        pts = csvfile.read_profile_csv(out / f"{name}_profile.csv") * 1e-3
        assert np.array_equal(pts[0], pts[-1])
        poly, closed = dxf.read(out / f"{name}_profile.dxf")
        assert closed
        np.testing.assert_allclose(poly * 1e-3, pts[:-1], rtol=0, atol=1e-12)
        u0 = sample(prof, 1e-6)
        _, i = cKDTree(prof.point(u0)).query(pts)
        _, d, _ = closest(prof, pts, u0[i], iterations=12)
        offset = 10e-6 if name == "outer" else 0.0
        assert np.abs(d - offset).max() < 1e-9  # 9 decimals of mm in the file
    # point clouds: CSV and PLY hold the same points, unit normals
    for name in ("outer", "inner"):
        csv = np.loadtxt(out / f"{name}_cloud.csv", delimiter=",", skiprows=1)
        cloud = ply.read(out / f"{name}_cloud.ply")
        np.testing.assert_allclose(csv, cloud, rtol=0, atol=1e-8)
        np.testing.assert_allclose(np.linalg.norm(cloud[:, 3:], axis=1), 1.0, atol=1e-8)
        assert len(cloud) == man["files"][f"{name}_cloud.ply"]["points"]
    # the cutter: a tool profile and its round trip within the tolerance
    tool = np.loadtxt(out / "inner_cutter.csv", delimiter=",", skiprows=1)
    side = json.loads((out / "inner_cutter.json").read_text())
    assert tool.shape[1] == 5 and len(tool) == side["points"]
    assert side["round_trip_max_m"] <= 20e-6 and side["interference_m"] <= 20e-6
    assert side["hand"] == "left"
    # a second export replaces the folder whole
    case.write_text(HELICAL + '\n[export]\nformats = ["dxf"]\ntolerance_um = 20\n')
    assert run("export", case, "--out", out).returncode == 0
    assert sorted(p.name for p in out.iterdir()) == ["export.json", "inner_profile.dxf",
                                                     "outer_profile.dxf"]


def test_export_without_section_writes_the_rotor_stls(tmp_path):
    out = tmp_path / "o"
    res = run("export", CASES / "default.toml", "--out", out)
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in out.iterdir()) == ["export.json", "inner.stl", "outer.stl"]


SIGMA_TOO_BIG = HELICAL.replace("sigma_bar = 0.95", "sigma = 0.9")  # above sigma_lim
DEFAULT_MACHINE = (CASES / "default.toml").read_text().split("[operating]")[0]


@pytest.mark.parametrize("machine, section, words", [
    (HELICAL, 'formats = ["stl"]\ntolerance_um = 0\n', "tolerance_um"),
    (HELICAL, 'formats = ["stl"]\ntolerance_um = -5\n', "tolerance_um"),
    (HELICAL, 'formats = ["stl"]\nclearance_um = 20000\n', "above 2000 um"),
    (DEFAULT_MACHINE, 'formats = ["stl"]\nclearance_um = 5\nclearance_on = "inner"\n', "folds"),
    (HELICAL, 'formats = ["stl"]\nclearance_um = [5, -1]\n', "clearance_um"),
    (HELICAL, 'formats = ["fluid"]\n', "clearance"),
    (HELICAL, 'formats = ["stl", "obj"]\n', "'obj'"),
    (HELICAL, 'formats = ["stl"]\ncolour = "red"\n', "colour"),
    (HELICAL, 'formats = ["stl"]\nbore_diameter_mm = 50\n', "bore_diameter_mm"),
    (SIGMA_TOO_BIG, 'formats = ["stl"]\n', "undercut"),
    ((CASES / "crc60.toml").read_text().split("[operating]")[0], 'formats = ["cutter"]\n',
     "conical"),
])
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, machine, section, words):
    case = write_case(tmp_path, section, machine)
    out = tmp_path / "new" / "out"
    res = run("export", case, "--out", out)
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("rotorflow: error:"), res.stderr
    assert words in lines[0]
    assert res.stdout == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case.toml"]


def test_an_occupied_folder_is_not_replaced(tmp_path):
    case = write_case(tmp_path, 'formats = ["dxf"]\n')
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("keep me")
    res = run("export", case, "--out", out)
    assert res.returncode == 2
    assert "not a rotorflow export" in res.stderr
    assert [p.name for p in out.iterdir()] == ["notes.txt"]
