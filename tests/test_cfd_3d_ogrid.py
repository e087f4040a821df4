"""The O-grid written as an OpenFOAM polyMesh and checked by checkMesh (issue 16).

checkMesh is an independent implementation of the quality measures of
:mod:`rotorflow.cases.ogrid_quality` and of the mesh's volume, so agreement is a test of
both the grid's measures and the polyMesh writer.  Skipped without OpenFOAM.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotorflow.cases import foam
from rotorflow.cases.foam_files import ensure_system_files
from rotorflow.cases.foam_mesh import parse_check_mesh
from rotorflow.cases.grid3d_quality import measure3d, stack_nodes
from rotorflow.cases.ogrid import make_ogrid, walls
from rotorflow.cases.polymesh import helical_stack, section_thickness, write_polymesh
from rotorflow.geometry.internal_gear.family import examples
from rotorflow.geometry.sweep import Sweep

pytestmark = [
    pytest.mark.openfoam,
    pytest.mark.skipif(not foam.is_available(),
                       reason="OpenFOAM not installed: run `make openfoam`"),
]

PAIR = examples()["table1"]  # examples/default.toml's pair
GAP = 20e-6
#: checkMesh prints 6 significant digits.
PRINTED = 1e-5


def _exact_area() -> float:
    outer, inner = walls(PAIR, 0.0, GAP)
    return outer.curve.area - inner.curve.area


def _check(case):
    ensure_system_files(case)
    log = foam.run(case, "checkMesh")
    text = log.read_text()
    volume = float(text.split("Total volume = ")[1].split(".  ")[0])
    return parse_check_mesh(text), text, volume


@pytest.mark.parametrize("deg", [0.0, 29.0])
def test_section_passes_check_mesh_with_our_measures(tmp_path, deg):
    grid, q = make_ogrid(PAIR, math.radians(deg), GAP)
    dz = section_thickness(grid)
    counts = write_polymesh(tmp_path, [grid, grid], np.array([0.0, dz]))
    m, _, volume = _check(tmp_path)
    assert m.ok, m.failed_checks
    assert m.cells == q.cells == counts["cells"]
    # Same definitions (primitiveMeshTools), computed independently.
    assert m.max_non_orthogonality_deg == pytest.approx(q.max_non_orthogonality_deg, rel=PRINTED)
    assert m.max_skewness == pytest.approx(q.max_skewness, rel=PRINTED)
    assert volume == pytest.approx(q.total_area * dz, rel=PRINTED)
    # The wall polygons' chords cut the curved walls: 1.2e-5 of the area at 0 deg with
    # the columns placed for the chord sag relative to the first cell (not for area).
    assert volume == pytest.approx(_exact_area() * dz, rel=2e-5)


def test_helical_slice_is_a_valid_3d_mesh(tmp_path):
    """5 mm of the default machine (its lead: 136 deg over 100 mm) in 12 layers."""
    length = 0.005
    sweep = Sweep("helical", length, math.radians(136.0) * length / 0.1)
    sections, z = helical_stack(PAIR, math.radians(13.0), GAP, sweep, 12)
    write_polymesh(tmp_path, sections, z)
    m, text, volume = _check(tmp_path)
    # checkMesh passes it: skewness 3.8 against its limit 4 (24.6 before the columns
    # were anchored, 5.4 with the first cells of the wide chambers 2 mm tall).
    assert m.ok, m.failed_checks
    assert "Cell volumes OK" in text
    # Straight edges between sections chord the helical walls: -8.6e-3 with 4 layers
    # (1.7 deg of twist each), -4.3e-4 with 12 (measured); 1e-3 bounds the 12-layer one.
    assert volume == pytest.approx(_exact_area() * length, rel=1e-3)
    # Our 3D measures (OpenFOAM's definitions, computed independently) agree with it.
    X = stack_nodes(sections, z)
    q = measure3d(X)
    assert m.cells == q.cells
    assert m.max_non_orthogonality_deg == pytest.approx(q.max_non_orthogonality_deg, rel=PRINTED)
    assert m.max_skewness == pytest.approx(q.max_skewness, rel=PRINTED)
    assert volume == pytest.approx(q.volume, rel=PRINTED)


def test_stacked_nodes_travel_at_about_the_helix_speed():
    """A cell face leans by its nodes' travel per unit height; the walls' own helices set
    the least (the rotors' tips: 1.2 to 1.3 m/m here).  Columns that slid along the walls
    with a law normalised over the whole annulus travelled at 16.7 m/m (87 deg faces);
    anchored per segment they stay within twice the fastest tip's helix."""
    length = 0.005
    sweep = Sweep("helical", length, math.radians(136.0) * length / 0.1)
    sections, z = helical_stack(PAIR, math.radians(13.0), GAP, sweep, 6)
    X = stack_nodes(sections, z)
    speed = np.linalg.norm(np.diff(X[..., :2], axis=0), axis=-1) / np.diff(z)[:, None, None]
    twist_rate = math.radians(136.0) / 0.1
    outer, inner = PAIR.rotors
    tips = max(np.linalg.norm(outer.axis) + 0.5 * PAIR.diameter,
               inner.speed_ratio * float(np.max(np.linalg.norm(
                   walls(PAIR, 0.0, GAP)[1].curve.point(np.linspace(0, 5, 5001)), axis=1))))
    helix = twist_rate * tips
    assert 1.0 < helix < 1.5  # the figure the docstring quotes
    assert speed.max() < 2.0 * helix
