"""A clearance offset of a profile with sharp corners (geometry/offset_corners.py): the
pieces' offsets are cut where they cross, so the offset is the set of points at the
clearance from the profile.

Checked on a square (everything in closed form) and on the trochoidal pump profile,
whose tip corners turn by 135 deg, against constructions that do not use the offset
code: distances to a finely sampled base polygon, and Clipper's offset of that polygon
(manifold3d)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.curves import Clearance, PieceCurve, offset_profile, sample, sample_polygon
from rotorflow.geometry.polygons import check_simple, polygon_gap, signed_area
from rotorflow.geometry.twin_screw.meshing import Gearing
from rotorflow.geometry.twin_screw.pump_profiles import trochoidal_pair

C = 0.078
#: The trochoidal female's turn at its tip corners (rad; 135 deg), measured from its
#: pieces' end tangents (the offset code measures it the same way, so it is not checked)
TURN = 2.3533845580


class Square(PieceCurve):
    """The unit square, counter-clockwise, one piece a side (t along the side)."""

    name, lobes, material_inside = "square", 1, True
    _corners = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])

    @property
    def n(self):
        return 4

    def _eval(self, u, order):
        j, t = self._split(u)
        a, b = self._corners[j], self._corners[(j + 1) % 4]
        return a + t[..., None] * (b - a) if order == 0 else b - a


@pytest.mark.parametrize("c", [0.01, 0.2, 0.45])
def test_a_shrunk_square_is_the_square_of_side_one_less_two_clearances(c):
    off = offset_profile(Square(), Clearance((c,)), -1)
    assert np.asarray(off.trims) == pytest.approx(np.array([[c, 1.0 - c]] * 4), abs=1e-12)
    assert off.area == pytest.approx((1.0 - 2.0 * c) ** 2, rel=1e-12)
    assert off.length == pytest.approx(4.0 * (1.0 - 2.0 * c), rel=1e-12)
    corners = off.point(np.arange(4.0))
    assert corners == pytest.approx(np.array([[c, c], [1 - c, c], [1 - c, 1 - c],
                                              [c, 1 - c]]), abs=1e-12)


def test_a_clearance_that_eats_a_side_is_refused_and_one_that_opens_corners_not_cut():
    """Grown, the square's offsets part at its corners (the true offset's arcs are not
    built, geometry/offset_corners.py): its sides are left whole."""
    assert offset_profile(Square(), Clearance((0.01,)), +1).trims is None
    with pytest.raises(CaseError, match="consumes the whole piece"):
        offset_profile(Square(), Clearance((0.5,)), -1)


@pytest.fixture(scope="module")
def trochoidal():
    male, female = trochoidal_pair(Gearing(C, 1, 1), 0.055)
    return female


@pytest.mark.parametrize("c", [20e-6, 100e-6])
def test_the_trochoidal_profile_offset_keeps_the_clearance_everywhere(trochoidal, c):
    """Every point of the offset lies at the clearance from the profile (to 2e-9 m:
    the base polygon's chord error and the offset's sampling), its corners included,
    where the two pieces' offsets meet 1 / sin(beta / 2) = 2.6 clearances from the
    corner; it is a simple polygon."""
    off = offset_profile(trochoidal, Clearance((c,)), -1)
    assert off.trims is not None
    cut = [k for k, (lo, hi) in enumerate(off.trims) if lo > 0.0 or hi < 1.0]
    assert cut == [0, 2, 3]  # the tip arc (3) at both corners, each flank at its own
    u = sample(off, 2e-8)
    pts = off.point(np.concatenate([u, np.arange(4.0)]))
    check_simple(off.point(u), "offset")
    base = trochoidal.point(sample(trochoidal, 1e-9, max_step=2e-5))
    gap = polygon_gap(pts, base)
    assert np.abs(gap + c).max() < 2e-9  # inside, at c
    # the corners: the crossing lies 1 / sin(beta / 2) clearances from the base's corner,
    # as at a corner of straight sides, to O(c kappa) (the pieces curve: 1.1e-3 off at
    # 100 um, 5.5e-5 at 5 um, measured)
    tip = trochoidal.point(np.array([0.0, 3.0]))
    far = np.linalg.norm(off.point(np.array([0.0, 3.0])) - tip, axis=-1)
    assert far == pytest.approx(c / math.sin(0.5 * (math.pi - TURN)), rel=3e-3)


@pytest.mark.parametrize("c", [20e-6, 100e-6])
def test_the_trochoidal_offset_area_is_clippers_erosion(trochoidal, c):
    """The area the offset takes off (the moments' sum that the solids' analytic volumes
    use) is what Clipper's erosion (round joins) takes off the base polygon, within
    1e-6 of itself.  Differences, because a polygon sampled to a chord error of 1 nm
    holds 2e-8 less than its curve (the sagittas: 2/3 x 1 nm x 0.26 m)."""
    from manifold3d import CrossSection, JoinType

    off = offset_profile(trochoidal, Clearance((c,)), -1)
    base = trochoidal.point(sample(trochoidal, 1e-9))
    scale = 1e3  # Clipper works on fixed point: millimetres keep its resolution
    eroded = CrossSection([base * scale]).offset(-c * scale, JoinType.Round,
                                                 circular_segments=4096)
    taken = signed_area(base) - eroded.area() / scale ** 2
    assert trochoidal.area - off.area == pytest.approx(taken, rel=1e-6)
    own = signed_area(base) - signed_area(sample_polygon(off, 1e-9))
    assert trochoidal.area - off.area == pytest.approx(own, rel=1e-6)
    # Steiner's formula with corners: c P less c^2 (pi + sum(tan(t / 2) - t / 2)) over
    # the corners' turns t (each keeps c^2 tan(t / 2) where a smooth turn keeps c^2 t / 2),
    # to O(c kappa) of the c^2 term (6.3e-4 at 100 um, 3e-5 at 5 um, measured)
    corners = 2.0 * (math.tan(0.5 * TURN) - 0.5 * TURN)
    c2 = (trochoidal.area - off.area - c * trochoidal.length) / (c * c)
    assert c2 == pytest.approx(-(math.pi + corners), rel=2e-3)
