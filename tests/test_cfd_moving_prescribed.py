"""Issue 17's route for moving rotors in stock OpenFOAM v1912, verified first.

``uniformInterpolatedDisplacement`` on every patch of a one-cell-thick mesh must move
every point exactly as prescribed (a non-rigid shear and stretch, linear in time between
key frames, so the linear time interpolation is exact). The negative control, two cells
thick, has interior points that the Laplacian motion solver places itself: the
prescription's x^2 term is not harmonic, so they miss, which shows the comparison can
fail.
"""

from __future__ import annotations

import pytest

from rotorflow.cases import foam, prescribed_motion

pytestmark = [
    pytest.mark.openfoam,
    pytest.mark.skipif(not foam.is_available(),
                       reason="OpenFOAM not installed: run `make openfoam`"),
]

#: Points are written with 17 significant digits: agreement to round-off of O(1) values.
ROUND_OFF = 1e-12


def test_one_cell_thick_mesh_follows_the_prescribed_motion_exactly(tmp_path):
    out = prescribed_motion.verify(tmp_path / "one")
    assert set(out["errors"]) == {0.25, 0.5, 0.75, 1.0}
    assert out["max_error"] <= ROUND_OFF


def test_interior_points_do_not_follow_it(tmp_path):
    out = prescribed_motion.verify(tmp_path / "two", layers=2)
    assert out["max_error"] > 1e-4
