"""Rotor STL solids for every sweep law: closed, oriented, manifold, with the analytic
volume and within the tolerance of the analytic flank (geometry/solids.py, export.py)."""

import math

import numpy as np
import pytest
import trimesh

from rotorflow.geometry.export import stl
from rotorflow.geometry.export.driver import export
from rotorflow.geometry.export.settings import Export
from rotorflow.geometry.export.solids import build_flank, rotor_mesh, validate_mesh
from rotorflow.geometry.export.surface import SweptSurface, foot_points
from rotorflow.geometry.internal_gear.profiles import inner_profile, outer_profile
from rotorflow.geometry.internal_gear.space import PinSpace
from rotorflow.geometry.summary import build_machine
from rotorflow.workflow.case import load_case

from .conftest import CASES

STRAIGHT = """
[machine]
type = "internal-gear"
lobes_outer = 5
lambda = 1.4
sigma_bar = 1.0
diameter_mm = 80
length_mm = 60
"""
STRAIGHT_ARC = """
[machine]
type = "internal-gear"
lobes_outer = 4
lambda = 1.3
sigma_bar = 0.9
diameter_mm = 80
length_mm = 50
fillet = "arc"
fillet_apex_diameter_mm = 90
"""
CASE_FILES = ["default", "table1_outer_ev2", "table1_outer_ev5", "table1_inner_ev5", "crc60"]
TOL = 5e-6  # the default tolerance_um


def _case(name, tmp_path):
    if name in ("straight", "straight_arc"):
        path = tmp_path / f"{name}.toml"
        path.write_text(STRAIGHT if name == "straight" else STRAIGHT_ARC)
        return load_case(path)
    return load_case(CASES / f"{name}.toml")


def _analytic(case, bore_radius):
    """Rotor volumes from the PinSpace closed forms: area x integral of scale^2."""
    p = case.pair
    sp = PinSpace(p)
    e = p.pin_edge
    inside_outer = p.lobes_outer * (sp.pin_arc_integral(0, e, -e) + sp.fillet_full_integral)
    inner = -sp.inner_lobe_integral * p.lobes_inner
    i2 = build_machine(case).sweep.scale_squared_integral
    return (math.pi * bore_radius ** 2 - inside_outer) * i2, inner * i2


@pytest.mark.parametrize("name", CASE_FILES + ["straight", "straight_arc"])
def test_rotor_stl_is_a_closed_solid_within_tolerance(name, tmp_path):
    case = _case(name, tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    manifest = export(case, Export(formats=("stl",), tolerance_m=TOL), out)
    v_outer, v_inner = _analytic(case, manifest["bore_radius_m"])
    for fname, v in (("outer.stl", v_outer), ("inner.stl", v_inner)):
        # read the file back: binary STL is single precision, so compare volumes at
        # 1e-4 (the acceptance) and topology exactly
        verts, faces = stl.read(out / fname)
        tm = trimesh.Trimesh(vertices=verts, faces=faces, process=False)
        assert tm.is_watertight, fname
        assert tm.is_winding_consistent, fname
        assert tm.volume > 0.0  # outward normals
        assert abs(tm.volume * 1e-9 / v - 1.0) < 1e-4, (fname, tm.volume * 1e-9 / v - 1.0)
        validate_mesh(verts, faces, fname, with_trimesh=True)
        entry = manifest["files"][fname]
        # every vertex, edge midpoint and facet centroid of the flank, measured
        assert entry["max_deviation_m"] <= TOL, entry["deviation_m"]
        assert entry["measured_points"] > len(faces) // 2
        assert entry["bytes"] == (out / fname).stat().st_size


def test_foot_points_measure_a_known_distance():
    # Points moved off the flank along its analytic normal by delta are found delta
    # away (started from a wrong parameter): the measurement itself is right.
    case = load_case(CASES / "default.toml")
    p, sw = case.pair, build_machine(case).sweep
    rng = np.random.default_rng(3)
    for surf in (SweptSurface(outer_profile(p), sw, 0.3, 1.0, (0.0, 0.0)),
                 SweptSurface(inner_profile(p), sw, 0.3 * p.m21, p.m21, (0.0, p.E))):
        u = rng.uniform(0.0, surf.curve.n, 2000)
        z = rng.uniform(0.0, sw.length, 2000)
        delta = rng.uniform(-10e-6, 10e-6, 2000)
        x = surf.point(u, z) + delta[:, None] * surf.normal(u, z)
        d = foot_points(surf, x, u + 2e-3, np.clip(z + 2e-4, 0, sw.length), iterations=20)
        # 3e-3 relative: near the inner profile's sigma_bar = 1 point (radius ~ delta)
        # Gauss-Newton converges only linearly; elsewhere the match is ~1e-15 m.
        assert np.abs(d - np.abs(delta)).max() < 3e-3 * np.abs(delta).max()


def test_volume_error_is_second_order():
    # The normal shift of the vertices cancels the chords' first-order volume error:
    # the error falls at least like tol^1.5 (chords alone: tol^1).
    case = load_case(CASES / "default.toml")
    p, sw = case.pair, build_machine(case).sweep
    surf = SweptSurface(outer_profile(p), sw, 0.0, 1.0, (0.0, 0.0))
    bore = 0.0625
    exact = (math.pi * bore ** 2 - surf.curve.area) * sw.scale_squared_integral
    tols = np.array([40e-6, 20e-6, 10e-6])
    err = [abs(rotor_mesh(build_flank(surf, t), bore, t, "o").volume / exact - 1) for t in tols]
    slope = np.polyfit(np.log(tols), np.log(err), 1)[0]
    assert slope > 1.5, err
    assert max(err) < 1e-4


def test_validation_fails_on_a_broken_mesh():
    case = load_case(CASES / "default.toml")
    p, sw = case.pair, build_machine(case).sweep
    surf = SweptSurface(inner_profile(p), sw, 0.0, p.m21, (0.0, p.E))
    mesh = rotor_mesh(build_flank(surf, 50e-6), None, 50e-6, "inner")
    validate_mesh(mesh.vertices, mesh.faces, "inner", with_trimesh=True)
    with pytest.raises(RuntimeError, match="not a closed"):
        validate_mesh(mesh.vertices, mesh.faces[1:], "open")  # a hole
    flipped = mesh.faces.copy()
    flipped[7] = flipped[7, ::-1]
    with pytest.raises(RuntimeError, match="not a closed"):
        validate_mesh(mesh.vertices, flipped, "flipped")  # one facet turned over
    with pytest.raises(RuntimeError, match="not a closed"):
        validate_mesh(mesh.vertices, mesh.faces[:, ::-1], "inside out")  # negative volume


def test_stl_round_trip_is_exact_to_single_precision(tmp_path):
    rng = np.random.default_rng(0)
    v = rng.uniform(-0.05, 0.05, (50, 3))
    f = rng.integers(0, 50, (80, 3))
    f = f[(f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 0] != f[:, 2])]
    v_in = v.copy()
    stl.write(tmp_path / "x.stl", v, f, 1e3)
    assert np.array_equal(v, v_in)  # input not mutated
    vr, fr = stl.read(tmp_path / "x.stl")
    # binary STL is single precision: 50 mm coordinates keep ~4e-6 mm
    np.testing.assert_allclose(vr[fr], v[f] * 1e3, rtol=0, atol=1e-5)
