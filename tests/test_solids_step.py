"""STEP solids through gmsh/OpenCASCADE: one valid solid per rotor, re-imported and
checked against the analytic volume and flank (geometry/step.py)."""

import numpy as np
import pytest

from rotorflow.geometry.export.driver import export
from rotorflow.geometry.export.settings import Export
from rotorflow.geometry.export.step import check_step, hermite_net, write_rotor_step
from rotorflow.geometry.export.surface import SweptSurface
from rotorflow.geometry.internal_gear.profiles import inner_profile
from rotorflow.geometry.summary import build_machine
from rotorflow.workflow.case import load_case

from .conftest import CASES

pytestmark = pytest.mark.gmsh
TOL = 5e-6


def test_helical_pair_step(tmp_path):
    case = load_case(CASES / "default.toml")
    man = export(case, Export(formats=("step",), tolerance_m=TOL), tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["export.json", "inner.step",
                                                           "outer.step"]
    for name in ("outer.step", "inner.step"):
        e = man["files"][name]
        assert e["solids"] == 1 and e["closed"], e
        assert e["volume_rel_error"] < 1e-4, e
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
