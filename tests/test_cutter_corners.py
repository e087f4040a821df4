"""Disc cutters of profiles with corners (geometry/export/cutter_corners.py) and the
interference check's distances (geometry/export/cutter_check.py).

The 4/6 pin-cycloid's male has right-angle concave corners at its root (the cusps of
the cycloids the female's land corners trace) and convex ones at its tips; its female
has convex corners at its lands.  Until 2026-11-30 `rotorflow export` of that pair (the
seed 004 machine) refused the male's cutter (its far tip took the next lobe's slope, so
no tool circle met it) and, past that, measured 32 um of round trip and 35 um of
interference at the root (one spline through the tool's corner); the female's check
reported 20-56 um of interference or none as the setting angle moved by a quarter
degree (Newton feet converging on the land beside points that lay on the flank).
"""

import math

import numpy as np
import pytest

from rotorflow.geometry.export.cutter import CutterSetup, _Turned, form_cutter, round_trip
from rotorflow.geometry.export.driver import _setup, check
from rotorflow.geometry.export.settings import Export
from rotorflow.geometry.polygons import PolygonDistance
from rotorflow.workflow.case import load_case

from .conftest import CASES

TOL = 5e-6


@pytest.fixture(scope="module")
def pin_cycloid():
    case = load_case(CASES / "twin_screw_4_6.toml")
    settings = Export.from_section({"formats": ["cutter"], "tolerance_um": 5})
    return case, settings, check(case, settings)


@pytest.mark.parametrize("rotor", ["male", "female"])
def test_pin_cycloid_cutters_regenerate_their_rotors(pin_cycloid, rotor):
    """Each tool, as written (9 decimals of mm), enveloped back onto its rotor: the
    flank within 1 um and nowhere cut deeper than 1 um (both measured near 0.1 um)."""
    _, _, asm = pin_cycloid
    part = next(p for p in asm.holes if p.name == rotor)
    cut = form_cutter(part.curve, _setup(asm, rotor), TOL)
    axial = np.round(cut.axial * 1e3, 9) * 1e-3
    radius = np.round(cut.radius * 1e3, 9) * 1e-3
    rt = round_trip(part.curve, cut, axial, radius)
    assert rt["round_trip_max_m"] < 1e-6
    assert rt["interference_m"] < 1e-6


def test_the_command_makes_the_pin_cycloid_cutters(pin_cycloid):
    """`rotorflow run`'s check makes both tools and refuses nothing."""
    case, settings, _ = pin_cycloid
    check(case, settings, cutters=True)


def test_the_male_tool_has_one_corner_per_root_corner(pin_cycloid):
    """The male's root corners turn its profile by -90 deg; the tool's profile turns
    sharply there too, once per corner, and each flank's tool profile stops at the
    corner: the two flanks' profiles do not cross each other anywhere."""
    _, _, asm = pin_cycloid
    part = next(p for p in asm.holes if p.name == "male")
    cut = form_cutter(part.curve, _setup(asm, "male"), TOL)
    d = np.column_stack([np.diff(cut.axial), np.diff(cut.radius)])
    turn = np.degrees(np.arctan2(d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0],
                                 np.sum(d[:-1] * d[1:], -1)))
    assert np.sum(np.abs(turn) > 30.0) == 2
    pts = np.column_stack([cut.axial, cut.radius])
    for c in np.nonzero(np.abs(turn) > 30.0)[0] + 1:
        before, after = pts[max(c - 40, 0):c + 1], pts[c:c + 41]
        assert not _polylines_cross(before[:-1], after[1:])


def test_a_straight_rotor_tool_is_its_profile_corners_included(pin_cycloid):
    """No lead and the tool axis normal to the rotor's: the tool profile is the rotor
    profile (axial = y, radius = C - x, tooth space on +x), corners and all."""
    _, _, asm = pin_cycloid
    part = next(p for p in asm.holes if p.name == "male")
    cut = form_cutter(part.curve, CutterSetup(0.0, 0.1, 0.0), TOL)
    p = _Turned(part.curve, cut.root).point(cut.u)
    np.testing.assert_allclose(cut.axial, p[:, 1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(cut.radius, 0.1 - p[:, 0], rtol=0, atol=1e-12)
    rt = round_trip(part.curve, cut)
    assert rt["round_trip_max_m"] < 1e-6 and rt["interference_m"] < 1e-6


@pytest.mark.parametrize("point, expected", [
    ((0.5, 0.5), -0.5),          # centre
    ((2.1, 0.5), 0.1),           # beside an edge
    ((2.1, -0.1), math.hypot(0.1, 0.1)),  # beyond a convex corner: to the vertex
    ((1.97, 0.99), -0.01),       # inside next to a convex corner: to the nearer edge
    ((0.97, 0.99), -math.hypot(0.03, 0.01)),  # inside, off the concave corner: to it
    ((1.5, 1.5), 0.5),           # in the L's notch, off its concave corner
    ((1.01, 1.05), 0.01),        # just outside, beside the concave corner
    ((0.99, 1.3), -0.01),        # just inside the upright, above the concave corner
])
def test_polygon_distance_is_signed_and_exact(point, expected):
    """An L (unit squares at (0, 0), (1, 0), (0, 1)) drawn with many vertices: signed
    distances (negative inside) by hand, at and beside its convex and concave corners."""
    corners = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)
    ring = np.concatenate([np.linspace(a, b, 50, endpoint=False)
                           for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True)])
    got = PolygonDistance(ring)(np.array([point]))[0]
    assert got == pytest.approx(expected, abs=1e-12)


def _polylines_cross(a, b) -> bool:
    for p0, p1 in zip(a[:-1], a[1:], strict=True):
        for q0, q1 in zip(b[:-1], b[1:], strict=True):
            r, s, w = p1 - p0, q1 - q0, q0 - p0
            den = r[0] * s[1] - r[1] * s[0]
            if den == 0.0:
                continue
            t = (w[0] * s[1] - w[1] * s[0]) / den
            v = (w[0] * r[1] - w[1] * r[0]) / den
            if 0.0 < t < 1.0 and 0.0 < v < 1.0:
                return True
    return False


def test_a_corner_flank_that_meets_no_tool_circle_leaves_the_corner_to_the_other(
        pin_cycloid):
    """0.04 deg below the male's default setting angle the flank ends at one root
    corner's first entry and at the mirror corner's second meet no tool circle; each
    corner keeps its other flank's point, and the tool still regenerates the rotor
    (it was refused: 'no contact')."""
    _, _, asm = pin_cycloid
    part = next(p for p in asm.holes if p.name == "male")
    base = _setup(asm, "male")
    setup = CutterSetup(base.setting_angle - math.radians(0.04), base.centre_distance, base.k)
    cut = form_cutter(part.curve, setup, TOL)
    rt = round_trip(part.curve, cut)
    assert rt["round_trip_max_m"] < 1e-6 and rt["interference_m"] < 1e-6


def test_polygon_distance_of_no_points():
    ring = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert PolygonDistance(ring)(np.zeros((0, 2))).shape == (0,)
