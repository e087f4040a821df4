"""A clearance offset of a profile with sharp corners (geometry/offset_corners.py): the
pieces' offsets are cut where they cross and joined by the clearance's arc where they
part, so the offset is the set of points at the clearance from the profile.

Checked on a square and an L (everything in closed form), on the trochoidal pump
profile, whose tip corners turn by 135 deg, and on the pin-cycloid male, whose root
corners turn by -90 deg, against constructions that do not use the offset code:
distances to a finely sampled base polygon, and Clipper's offset of that polygon
(manifold3d)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotorflow.errors import CaseError
from rotorflow.geometry.curves import PieceCurve, sample, sample_polygon
from rotorflow.geometry.offsets import Clearance, offset_profile
from rotorflow.geometry.polygons import check_simple, polygon_gap, signed_area
from rotorflow.geometry.twin_screw.meshing import Gearing
from rotorflow.geometry.twin_screw.pump_profiles import trochoidal_pair

C = 0.078


def corner_turn(curve, u, h=1e-5):
    """The profile's turn (rad) at its piece joint u, from its points alone (not from
    the pieces' end tangents, which the offset code reads): second-order one-sided
    differences either side, whose O(h^2) error is ~1e-11 rad at h = 1e-5 here."""
    p = curve.point(u + h * np.array([-2.0, -1.0, 0.0, 1.0, 2.0]))
    before = p[0] - 4.0 * p[1] + 3.0 * p[2]
    after = -3.0 * p[2] + 4.0 * p[3] - p[4]
    return math.atan2(before[0] * after[1] - before[1] * after[0], before @ after)


class Polygon(PieceCurve):
    """A polygon, counter-clockwise, one piece a side (t along the side)."""

    lobes, material_inside = 1, True

    def __init__(self, name, corners):
        self.name, self._corners = name, np.asarray(corners, dtype=float)

    @property
    def n(self):
        return len(self._corners)

    def _eval(self, u, order):
        j, t = self._split(u)
        a, b = self._corners[j], self._corners[(j + 1) % self.n]
        return a + t[..., None] * (b - a) if order == 0 else b - a


def Square():
    return Polygon("square", [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def LShape():
    """[0, 2]^2 less [1, 2]^2: five corners turning +90 deg, one (at (1, 1)) -90 deg."""
    return Polygon("L", [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]])


@pytest.mark.parametrize("c", [0.01, 0.2, 0.45])
def test_a_shrunk_square_is_the_square_of_side_one_less_two_clearances(c):
    off = offset_profile(Square(), Clearance((c,)), -1)
    assert np.asarray(off.trims) == pytest.approx(np.array([[c, 1.0 - c]] * 4), abs=1e-12)
    assert off.area == pytest.approx((1.0 - 2.0 * c) ** 2, rel=1e-12)
    assert off.length == pytest.approx(4.0 * (1.0 - 2.0 * c), rel=1e-12)
    corners = off.point(np.arange(4.0))
    assert corners == pytest.approx(np.array([[c, c], [1 - c, c], [1 - c, 1 - c],
                                              [c, 1 - c]]), abs=1e-12)


def test_a_clearance_that_eats_a_side_is_refused():
    with pytest.raises(CaseError, match="consumes the whole piece"):
        offset_profile(Square(), Clearance((0.5,)), -1)


@pytest.mark.parametrize("c", [0.01, 0.3])
def test_a_grown_square_goes_round_its_corners_on_quarter_circles(c):
    """Grown, the square's offsets part at its corners: the points at c from it are its
    sides moved out and four quarter circles of radius c about the corners (Steiner's
    formula for a convex region, 1 + 4 c + pi c^2, is then exact)."""
    off = offset_profile(Square(), Clearance((c,)), +1)
    assert off.trims is None and off.arcs == pytest.approx((0.5 * math.pi,) * 4, abs=1e-12)
    assert off.n == 8  # an arc before each side
    assert off.area == pytest.approx(1.0 + 4.0 * c + math.pi * c * c, rel=1e-12)
    assert off.length == pytest.approx(4.0 + 2.0 * math.pi * c, rel=1e-12)
    u = np.linspace(0.0, off.n, 801, endpoint=False)
    square = Square().point(np.linspace(0.0, 4.0, 40000, endpoint=False))
    assert polygon_gap(off.point(u), square) == pytest.approx(np.full(len(u), c), abs=1e-12)
    mid = off.point(np.array([0.5]))[0]  # the first arc's middle: out along the diagonal
    assert mid == pytest.approx(-c / math.sqrt(2.0) * np.ones(2), abs=1e-12)


@pytest.mark.parametrize("c", [0.05, 0.2])
def test_a_shrunk_l_is_cut_at_its_convex_corners_and_rounded_at_its_reflex_one(c):
    """The L shrunk by c is the two arms' rectangles shrunk, (1 - 2c)(3 - 2c) together,
    and the part of the square [1 - c, 1]^2 farther than c from the reflex corner (1, 1),
    c^2 (1 - pi / 4): 3 - 8 c + c^2 (5 - pi / 4); its boundary 8 - 10 c + pi c / 2."""
    off = offset_profile(LShape(), Clearance((c,)), -1)
    assert off.arcs == pytest.approx((0, 0, 0, -0.5 * math.pi, 0, 0), abs=1e-12)
    assert off.area == pytest.approx(3.0 - 8.0 * c + c * c * (5.0 - 0.25 * math.pi), rel=1e-12)
    assert off.length == pytest.approx(8.0 - 10.0 * c + 0.5 * math.pi * c, rel=1e-12)
    u = np.linspace(0.0, off.n, 1401, endpoint=False)
    shape = LShape().point(np.linspace(0.0, 6.0, 60000, endpoint=False))
    assert polygon_gap(off.point(u), shape) == pytest.approx(np.full(len(u), -c), abs=1e-12)
    check_simple(off.point(u), "offset")


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
    # The female's tip corners (at 3 and at 4 = 0) turn by 134.8 deg each.
    turns = np.array([corner_turn(trochoidal, 4.0), corner_turn(trochoidal, 3.0)])
    assert np.all((turns > 0.5 * math.pi) & (turns < math.pi))  # real convex corners
    tip = trochoidal.point(np.array([0.0, 3.0]))
    far = np.linalg.norm(off.point(np.array([0.0, 3.0])) - tip, axis=-1)
    assert far == pytest.approx(c / np.sin(0.5 * (math.pi - turns)), rel=3e-3)


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
    corners = sum(math.tan(0.5 * t) - 0.5 * t
                  for t in (corner_turn(trochoidal, 3.0), corner_turn(trochoidal, 4.0)))
    c2 = (trochoidal.area - off.area - c * trochoidal.length) / (c * c)
    assert c2 == pytest.approx(-(math.pi + corners), rel=2e-3)


@pytest.fixture(scope="module")
def pin_cycloid_male():
    from pathlib import Path

    from rotorflow.workflow.case import load_case

    return load_case(Path(__file__).parents[1] / "examples" / "twin_screw_4_6.toml").pair.male


@pytest.mark.parametrize("c", [5e-6, 20e-6])
def test_the_pin_cycloid_male_offset_goes_round_its_root_corners(pin_cycloid_male, c):
    """Shrunk by c (the clearance on the male), the 4/6 pin-cycloid male's offsets part at
    its root corners (-90 deg, 8 of them) and cross at its 37.5-deg ones (4): every point,
    the arcs included, lies at c from the profile (a chord across each arc would pass
    0.71 c from its corner), and the area taken off is Clipper's erosion (round joins)
    of the base polygon.  The area's tolerance, 2e-6 where the trochoidal's holds 1e-6:
    the male's generated pieces start with a curvature that grows as t^-1/2 (radius
    2.3 mm at t = 0.01, 36 um at the joint), which its Gauss panels (and the offset's)
    integrate to 5.8e-8 of its area, measured against 8 times the panels; in the
    difference that leaves 1.2e-6 of the clearance's area at 20 um (7.5e-7 with the
    finer panels).  The chord would be off by 2.3 c^2, 3.6e-5 at 5 um."""
    from manifold3d import CrossSection, JoinType

    male = pin_cycloid_male
    off = offset_profile(male, Clearance((c,)), -1)
    assert sum(1 for t in off.arcs if t) == 8 and off.trims is not None
    u = sample(off, 2e-8)
    check_simple(off.point(u), "offset")
    base = male.point(sample(male, 1e-9, max_step=2e-5))
    assert np.abs(polygon_gap(off.point(u), base) + c).max() < 2e-9
    base = male.point(sample(male, 1e-9))
    scale = 1e3
    eroded = CrossSection([base * scale]).offset(-c * scale, JoinType.Round,
                                                 circular_segments=4096)
    taken = signed_area(base) - eroded.area() / scale ** 2
    assert male.area - off.area == pytest.approx(taken, rel=2e-6)


PROFILES = ("circular", "line-circle", "pin-cycloid", "involute", "trochoidal")


@pytest.fixture(scope="module")
def shipped_pairs():
    """Each profile kind the twin-screw family ships, on an example's machine (4/6 for
    the compressor profiles, 1-1 for the pump ones)."""
    from pathlib import Path

    from rotorflow.workflow.case import case_from_raw, load_toml

    examples = Path(__file__).parents[1] / "examples"
    files = {"circular": "twin_screw_export.toml", "line-circle": "twin_screw_export.toml",
             "pin-cycloid": "twin_screw_4_6.toml", "involute": "screw_pump_involute.toml",
             "trochoidal": "screw_pump_trochoidal.toml"}
    pairs = {}
    for name in PROFILES:
        raw = load_toml(examples / files[name])
        raw["machine"]["profile"] = name
        pairs[name] = case_from_raw(raw, examples / files[name]).pair
    return pairs


@pytest.mark.parametrize("profile", PROFILES)
def test_every_shipped_profile_offset_keeps_the_clearance(shipped_pairs, profile):
    """Each shipped profile's male and female, shrunk by 10 um (a clearance into the
    rotor), corners cut or rounded as they come: every point at the clearance from a
    1-nm polygon of the profile (2e-9 m) and a simple polygon."""
    pair = shipped_pairs[profile]
    for rotor in (pair.male, pair.female):
        off = offset_profile(rotor, Clearance((10e-6,)), -1)
        u = sample(off, 2e-8)
        check_simple(off.point(u), f"{profile} {rotor.name} offset")
        base = rotor.point(sample(rotor, 1e-9, max_step=2e-5))
        worst = np.abs(polygon_gap(off.point(u), base) + 10e-6).max()
        assert worst < 2e-9, (profile, rotor.name, worst)
