"""STEP solids through gmsh/OpenCASCADE: one valid solid per rotor and the fluid core,
re-imported and checked against the analytic volume and flank (geometry/step.py), and
OpenCASCADE's own mass properties (what a CAD user sees) against the analytic volume.

The analytic volumes here are built independently of the export: each profile's area
by the shoelace formula on a dense sampling of the analytic curve (clearance offset
included), times the integral of the squared section scale along the rotor (scipy's
quad of the sweep's scale law; the length for a straight or helical rotor)."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from rotorflow.geometry.export.assembly import assemble
from rotorflow.geometry.export.driver import _step_entry, export
from rotorflow.geometry.export.settings import Export
from rotorflow.geometry.export.step import StepCheck, check_step, hermite_net, write_rotor_step
from rotorflow.geometry.export.step_fluid import write_fluid_step
from rotorflow.geometry.export.surface import SweptSurface
from rotorflow.geometry.internal_gear.profiles import inner_profile
from rotorflow.geometry.summary import build_machine
from rotorflow.workflow.case import load_case

from .conftest import CASES

pytestmark = pytest.mark.gmsh
TOL = 5e-6
#: The issue's held-out case: OCC read its straight inner rotor 1.9 % too large.
HELD_OUT = """
[machine]
type = "internal-gear"
lobes_outer = 4
lambda = 1.25
sigma_bar = 0.8
diameter_mm = 60
length_mm = 70

[sweep]
kind = "straight"
"""
#: The same machine conical, with a variable lead (a short, fast crc60).
CONICAL = HELD_OUT.replace('kind = "straight"', """kind = "conical"
wrap_outer_deg = 120
diameter_end_mm = 42
lead_ratio = 0.6""")
#: Samples per profile piece of the shoelace area (chord error ~1e-9 relative).
SHOELACE = 20000


def occ_volume(path) -> float:
    """OpenCASCADE's own volume [m^3] of the one solid in a STEP file, in a fresh
    gmsh session (BRepGProp, as FreeCAD's mass properties)."""
    from rotorflow.gmsh_session import gmsh_session

    with gmsh_session("occ_volume") as gmsh:
        ents = gmsh.model.occ.importShapes(str(path))
        gmsh.model.occ.synchronize()
        vols = [t for d, t in ents if d == 3]
        assert len(vols) == 1, ents
        return gmsh.model.occ.getMass(3, vols[0]) * 1e-9


def shoelace_area(curve, scale: float = 1.0) -> float:
    """Area of the section ``scale p(u) + w(u)`` (the clearance offset w is not scaled
    along a conical rotor: a gap is the same at every section)."""
    t = np.linspace(0.0, 1.0, SHOELACE, endpoint=False)
    u = (np.arange(curve.n)[:, None] + t[None, :]).ravel()
    base = getattr(curve, "base", curve)
    xy = scale * base.point(u)
    if base is not curve:
        xy = xy + curve.offset(u)[:, None] * base.normal(u)
    x, y = xy[:, 0], xy[:, 1]
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


def independent_volumes(asm) -> dict:
    """Each rotor's and the fluid core's volume (see above).  A section's area is a
    quadratic in the scale s, so three scales give its coefficients exactly and the
    volume is theirs times the integrals of s^2, s and 1 along the rotor."""
    sw = asm.machine.sweep

    def integral(f):
        return quad(f, 0.0, sw.length, epsabs=0.0, epsrel=1e-12, limit=200)[0]

    moments = np.array([integral(lambda z: float(sw.scale(z)) ** 2),
                        integral(lambda z: float(sw.scale(z))), sw.length])
    scales = np.array([0.5, 1.0, 1.5])
    fit = np.vander(scales, 3)  # columns s^2, s, 1

    def volume(curve):
        return float(moments @ np.linalg.solve(fit, [shoelace_area(curve, s) for s in scales]))

    out, enclosed = {}, {p.name: volume(p.curve) for p in asm.parts}
    for p in asm.parts:
        out[p.name] = enclosed[p.name] if p.material_inside else \
            math.pi * p.outside_radius ** 2 * moments[0] - enclosed[p.name]
    out["fluid_core"] = enclosed[asm.wall.name] - sum(enclosed[p.name] for p in asm.holes)
    return out


def _load(tmp_path, name):
    if name in ("held_out", "held_out_conical"):
        (tmp_path / f"{name}.toml").write_text(HELD_OUT if name == "held_out" else CONICAL)
        return load_case(tmp_path / f"{name}.toml")
    return load_case(CASES / f"{name}.toml")


@pytest.mark.parametrize("name, tol", [
    ("held_out", 5e-6),  # straight, the case at its tolerance
    ("default", 20e-6),  # helical (coarse: the check's figures hold at any tolerance)
    ("held_out_conical", 20e-6),
    pytest.param("crc60", 20e-6, marks=pytest.mark.slow),  # conical, variable lead
])
def test_step_occ_volume_of_rotors_and_fluid_core(tmp_path, name, tol):
    """OCC's mass properties of every solid written (both rotors, the fluid core with
    clearances) within 1e-4 of the independent analytic volume."""
    case = _load(tmp_path, name)
    asm = assemble(case, Export(formats=("step", "fluid"), tolerance_m=tol,
                                clearance_m=(30e-6,)))
    want = independent_volumes(asm)
    for p in asm.parts:
        path = tmp_path / f"{p.name}.step"
        write_rotor_step(path, p.surface, tol, p.outside_radius)
        assert occ_volume(path) == pytest.approx(want[p.name], rel=1e-4), p.name
    write_fluid_step(tmp_path / "fluid_core.step", asm, tol)
    assert occ_volume(tmp_path / "fluid_core.step") == pytest.approx(want["fluid_core"],
                                                                    rel=1e-4)


def test_step_export_judges_occ_volume_of_the_held_out_case(tmp_path):
    """The export records OCC's volume of the file it wrote and judges it: the figure a
    fresh import reads, within 1e-4 of the independent volume."""
    case = _load(tmp_path, "held_out")
    out = tmp_path / "out"
    out.mkdir()
    man = export(case, Export(formats=("step",), tolerance_m=TOL), out)
    want = independent_volumes(assemble(case, Export(formats=("step",), tolerance_m=TOL)))
    for name in ("outer", "inner"):
        e = man["files"][f"{name}.step"]
        assert e["occ_volume_m3"] == pytest.approx(occ_volume(out / f"{name}.step"), rel=1e-12)
        assert e["occ_volume_rel_error"] < 1e-4, e
        assert e["occ_volume_m3"] == pytest.approx(want[name], rel=1e-4), name


def test_step_occ_volume_off_the_analytic_is_an_error(tmp_path):
    """A file whose OCC volume is off is refused by name, even when the divergence
    theorem on its faces agrees (the 1.9 % of the held-out case)."""
    chk = StepCheck(volumes=1, volume_m3=78373e-9, occ_volume_m3=79827e-9, faces=5,
                    closed=True, deviation_m=0.0)
    with pytest.raises(RuntimeError, match=r"inner.step \(OpenCASCADE mass properties\).*1.86e-02"):
        _step_entry(tmp_path / "inner.step", chk, 78373e-9)
    good = StepCheck(1, 78373e-9, 78374e-9, 5, True, 0.0)
    assert _step_entry(tmp_path / "inner.step", good, 78373e-9)["occ_volume_rel_error"] < 1e-4


def test_helical_pair_step(tmp_path):
    case = load_case(CASES / "default.toml")
    man = export(case, Export(formats=("step",), tolerance_m=TOL), tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["export.json", "inner.step",
                                                           "outer.step"]
    for name in ("outer.step", "inner.step"):
        e = man["files"][name]
        assert e["solids"] == 1 and e["closed"], e
        assert e["volume_rel_error"] < 1e-4, e
        assert e["occ_volume_rel_error"] < 1e-4, e
        assert e["max_deviation_m"] <= TOL, e
        # the check is the file's own: re-import it once more here
        chk = check_step(tmp_path / name)
        assert chk.volumes == 1 and chk.closed
        assert chk.volume_m3 == pytest.approx(e["analytic_volume_m3"], rel=1e-4)
        assert (tmp_path / name).read_text(errors="replace").startswith("ISO-10303-21")


def test_conical_variable_lead_inner_rotor_step(tmp_path):
    case = load_case(CASES / "crc60.toml")
    m = build_machine(case)
    p = m.pair
    surf = SweptSurface(inner_profile(p), m.sweep, 0.0, p.m21, (0.0, p.E))
    path = tmp_path / "inner.step"
    write_rotor_step(path, surf, TOL, None)
    chk = check_step(path, surf, TOL)
    exact = inner_profile(p).area * m.sweep.scale_squared_integral
    assert chk.volumes == 1 and chk.closed
    assert chk.volume_m3 == pytest.approx(exact, rel=1e-4)
    assert chk.occ_volume_m3 == pytest.approx(exact, rel=1e-4)
    assert chk.deviation_m <= TOL


def test_hermite_net_interpolates_the_flank():
    # The control net puts the analytic points at the nodes (Bezier end points) and
    # the analytic tangents one third of a span away.
    case = load_case(CASES / "default.toml")
    m = build_machine(case)
    p = m.pair
    surf = SweptSurface(inner_profile(p), m.sweep, 0.0, p.m21, (0.0, p.E))
    u = np.linspace(0.0, 1.0, 9)
    z = np.linspace(0.0, m.sweep.length, 4)
    net = hermite_net(surf, u, z)
    assert net.shape == (3 * 8 + 1, 3 * 3 + 1, 3)
    U, Z = np.meshgrid(u, z, indexing="ij")
    nodes = surf.point(U, Z) * 1e3
    np.testing.assert_allclose(net[::3, ::3], nodes, rtol=0, atol=1e-9)
    _, su, _ = surf.evaluate(U[:-1], Z[:-1], jacobian=True)
    step = (u[1] - u[0]) / 3.0 * su * 1e3
    np.testing.assert_allclose(net[1::3, ::3][:8], nodes[:-1] + step, rtol=0, atol=1e-9)
