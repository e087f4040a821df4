"""Twin-screw profiles from a rack (seed 003 Eqs. 1-5), checked by constructions that do
not use the generation: the two polygons turned at the lobe ratio touch and do not
overlap; the common normal at the contact passes through the pitch point; Green's area
against the polygon's; a straight rack gives an involute; bad arcs are named."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from rotorflow.errors import CaseError
from rotorflow.geometry.curves import closest, sample, sample_polygon
from rotorflow.geometry.planar import cross, rotate
from rotorflow.geometry.polygons import polygon_gap, signed_area
from rotorflow.geometry.twin_screw import (
    CircleArc,
    EllipseArc,
    Gearing,
    Line,
    MaleGenerated,
    OnRotor,
    ParabolaArc,
    RackGenerated,
    TwinProfile,
    rack_pair,
    symmetric_circular_pair,
    symmetric_circular_rack,
)
from rotorflow.geometry.twin_screw.asymmetric import asymmetric_pair
from rotorflow.geometry.twin_screw.meshing import check_no_undercut
from rotorflow.geometry.twin_screw.profiles import check_no_interference, check_no_loop

#: The 4/6 compressor of seed 004 (Table 1a): outer diameters 100 and 96 mm.  The paper
#: gives no centre distance; 78 mm is assumed, which puts the female tip 1.2 mm and the
#: male tip 18.8 mm beyond their pitch circles.
C, D_MALE, D_FEMALE = 0.078, 0.100, 0.096
#: Chordal tolerance of the test polygons: 0.05 um, 20x below the 1 um contact tolerance.
POLY_TOL = 5e-8
#: Issue 13 asks for touch (gap below 1 um) and no overlap beyond 1 um; each polygon lies
#: within POLY_TOL of its curve and a vertex within ~POLY_TOL of the contact, so 4
#: POLY_TOL = 0.2 um is the tighter bound the polygons can be held to (measured: 0.09 um).
TOUCH_TOL = 4 * POLY_TOL
#: Gap at a contact located on the true curves (curves.closest, analytic pieces): 1 nm
#: is far above the measured 1e-13 m and far below any clearance.
CURVE_TOL = 1e-9
#: Distance of the pitch point from the contact normal: the contact is located to
#: ~1e-9 of the curve along a flat (quadratic) gap, so the normal points to ~1e-6 rad
#: over |c - P| ~ 20 mm: 0.1 um (measured: 0.027 um at most).
PITCH_TOL = 1e-7
#: Longest polygon edge (0.2 mm) and nearest vertices searched for the closest segment:
#: with edges this short the closest segment of a point within 1 mm of the polygon has
#: one of its ends among the 16 nearest vertices.
MAX_EDGE, NEAREST = 2e-4, 16


def gearing(n1=4, n2=6):
    return Gearing(C, n1, n2)


#: Rack depths (male addendum h_m, female addendum h_f) per lobe combination.  4/6:
#: seed 004's outer diameters at the assumed C.  3/5 and 5/6 have no published
#: dimensions; these are chosen inside the no-undercut range (a 5-lobe male with the
#: 4/6 depth undercuts its own flanks: the check says so).
DEPTHS = {(4, 6): (D_MALE / 2 - 0.4 * C, D_FEMALE / 2 - 0.6 * C),
          (3, 5): (0.0176, 0.0012), (5, 6): (0.014, 0.0012)}


def addenda(g):
    return DEPTHS[(g.lobes_male, g.lobes_female)]


def centred_tip_radius(g, hm, hf):
    """The male tip radius that puts the female tip's circle on the pitch line."""
    half, h = 0.5 * g.pitch, hm + hf
    return (h * h + half * half) / (2.0 * h) - hf


@functools.cache
def circular_pair(n1, n2, deeper=0.0):
    """The symmetric circular pair of DEPTHS, the male tip ``deeper`` further out."""
    g = gearing(n1, n2)
    hm, hf = addenda(g)
    hm += deeper
    return (g, *symmetric_circular_pair(g, hm, hf, centred_tip_radius(g, hm, hf)))


@functools.cache
def asymmetric_4_6():
    """The asymmetric rack of asymmetric.py on the 4/6 depths, its male tip circle 10 %
    smaller than the symmetric one's so that the straight trailing flank exists."""
    g = gearing()
    hm, hf = addenda(g)
    return (g, *asymmetric_pair(g, hm, hf, 0.9 * centred_tip_radius(g, hm, hf)))


@pytest.fixture(scope="module", params=["4/6", "3/5", "5/6", "asymmetric 4/6"])
def pair(request):
    if request.param.startswith("asymmetric"):
        return asymmetric_4_6()
    return circular_pair(*(int(n) for n in request.param.split("/")))


@functools.cache
def samples(curve):
    """Parameters of the curve's polygon to POLY_TOL, edges no longer than MAX_EDGE
    (cached: the profiles are frozen; nothing here mutates the arrays)."""
    return sample(curve, POLY_TOL, max_step=MAX_EDGE)


def polygon(curve):
    return curve.point(samples(curve))


def turned(g, male_poly, female_poly, theta):
    """Both polygons in the fixed frame at male angle theta; the female turns the other
    way by the lobe ratio N1/N2 (not by the gearing's pitch radii)."""
    ratio = g.lobes_male / g.lobes_female
    return (rotate(male_poly, theta),
            rotate(female_poly, -theta * ratio) + np.array([g.centre_distance, 0.0]))


def test_profiles_are_closed_counter_clockwise_and_lobed(pair):
    g, male, female = pair
    hm, hf = addenda(g)
    for p, n_lobes, radius in ((male, g.lobes_male, g.r1 + hm),
                               (female, g.lobes_female, g.r2 + hf)):
        poly = sample_polygon(p, POLY_TOL)
        assert signed_area(poly) > 0.0  # counter-clockwise, material inside
        # outer radius: the rack's tips (male tip at a = h_m, female tip at a = -h_f)
        # (a vertex lies within the chordal tolerance of the tip, never beyond it)
        r_max = np.linalg.norm(poly, axis=1).max()
        assert radius - POLY_TOL <= r_max <= radius + 1e-12
        per = p.n // n_lobes
        u = np.linspace(0.0, per, 50, endpoint=False)
        assert np.allclose(p.point(u + per), rotate(p.point(u), 2 * math.pi / n_lobes),
                           atol=1e-12)
        # consecutive pieces join (the chain is continuous, lobe to lobe too)
        j = np.arange(p.n)
        assert np.abs(p.point(j + 1 - 1e-13) - p.point((j + 1) % p.n)).max() < 1e-9


def smallest_gaps(g, male, female, angles=60):
    """The polygons' smallest signed distance (either way) at male angles over one lobe."""
    pm, pf = polygon(male), polygon(female)
    reach = np.linalg.norm(pf, axis=1).max() + 1e-4
    gaps = []
    for theta in np.linspace(0.0, 2 * math.pi / g.lobes_male, angles, endpoint=False):
        m, f = turned(g, pm, pf, theta)
        near = np.linalg.norm(m - [g.centre_distance, 0.0], axis=1) < reach
        local = np.linalg.norm(f, axis=1) < np.linalg.norm(m, axis=1).max() + 1e-4
        gaps.append(min(polygon_gap(m[near], f, NEAREST).min(),
                           polygon_gap(f[local], m, NEAREST).min()))
    return np.array(gaps)


def test_turned_profiles_touch_and_never_overlap(pair):
    """At 60 male angles over one lobe the polygons' smallest signed distance is within
    TOUCH_TOL of zero: they touch (conjugate) and do not interfere."""
    g, male, female = pair
    gaps = smallest_gaps(g, male, female)
    assert gaps.min() > -TOUCH_TOL, f"overlap {-gaps.min() * 1e6:.3f} um"
    assert gaps.max() < TOUCH_TOL, f"no contact: gap {gaps.max() * 1e6:.3f} um"


@pytest.mark.parametrize("deeper", [-5e-6, 5e-6], ids=["shallower", "deeper"])
def test_the_touch_check_fails_on_a_female_from_another_rack(deeper):
    """The same measure sees a female cut 5 um shallower (an overlap) or deeper (a gap
    beyond TOUCH_TOL where the male tip should touch): it can fail."""
    g, male, _ = circular_pair(4, 6)
    _, _, other = circular_pair(4, 6, deeper)
    gaps = smallest_gaps(g, male, other, angles=12)
    if deeper < 0:
        assert gaps.min() < -TOUCH_TOL
    else:
        assert gaps.max() > TOUCH_TOL


def contact(g, male, female, theta, um):
    """The male parameter of the contact at male angle theta: the smallest signed gap
    from the male curve to the true female curve (curves.closest), refined on a fine
    grid around the best sample."""
    uf = samples(female)
    tree = cKDTree(polygon(female))

    def gaps(u):
        x = rotate(rotate(male.point(u), theta) - [g.centre_distance, 0.0],
                   theta * g.lobes_male / g.lobes_female)
        _, k = tree.query(x)
        return closest(female, x, uf[k], iterations=30)[2]

    # the best male vertex by the polygon measure, then the true curves around it
    pm = rotate(male.point(um), theta)
    near = np.linalg.norm(pm - [g.centre_distance, 0.0], axis=1) < female.radius_max + 1e-4
    pf = rotate(polygon(female), -theta * g.lobes_male / g.lobes_female) + [
        g.centre_distance, 0.0]
    u = um[near][int(np.argmin(polygon_gap(pm[near], pf, NEAREST)))]
    h = float(np.max(np.diff(um)))
    for _ in range(3):
        fine = u + np.linspace(-2 * h, 2 * h, 81)
        u, h = fine[int(np.argmin(gaps(fine)))], h / 20
    return u, float(gaps(np.array([u]))[0])


def test_common_normal_passes_through_the_pitch_point(pair):
    """Law of gearing: at the contact found at each of 12 angles, the male normal passes
    within PITCH_TOL of the pitch point."""
    g, male, female = pair
    um = samples(male)
    pitch = np.array([g.centre_distance * g.lobes_male / (g.lobes_male + g.lobes_female), 0.0])
    residuals, gaps = [], []
    for theta in np.linspace(0.0, 2 * math.pi / g.lobes_male, 12, endpoint=False):
        u, gap = contact(g, male, female, theta, um)
        c = rotate(male.point(np.array([u]))[0], theta)
        n = rotate(male.normal(np.array([u]))[0], theta)
        residuals.append(abs(cross(pitch - c, n)))
        gaps.append(gap)
    assert max(abs(x) for x in gaps) < CURVE_TOL
    assert max(residuals) < PITCH_TOL, f"pitch-point residual {max(residuals) * 1e6:.3f} um"


def test_green_area_against_the_polygon_area(pair):
    """PieceCurve.area (Green's theorem, Gauss panels on the closed forms) against the
    polygon's shoelace area: the difference is bounded by tol x perimeter and falls in
    proportion to the chordal tolerance (first order in tol, second in the spacing)."""
    _, male, female = pair
    for p in (male, female):
        errs = []
        for tol in (4e-7, 1e-7):
            err = abs(p.area - signed_area(sample_polygon(p, tol)))
            assert err < tol * p.length
            errs.append(err)
        assert 2.5 < errs[0] / errs[1] < 6.0  # ~4 for a quarter of the tolerance


def test_straight_rack_generates_an_involute():
    """A straight rack flank at pressure angle alpha (inclined by alpha from the line of
    centres) generates on each rotor an involute of base radius r cos(alpha): every
    generated normal is tangent to the base circle.  The flank stays within 3 mm of the
    pitch line, short of the interference point r1 sin^2(alpha) = 3.6 mm."""
    g = gearing()
    alpha = math.radians(20.0)
    half = 0.003 / math.cos(alpha)
    flank = Line("flank", (-half * math.cos(alpha), -half * math.sin(alpha)),
                 (half * math.cos(alpha), half * math.sin(alpha)))
    t = np.linspace(0.0, 1.0, 101)
    for rotor, r in (("male", g.r1), ("female", g.r2)):
        piece = RackGenerated(flank, g, rotor)
        check_no_undercut(piece)
        p, d = piece.eval(t, 0), piece.eval(t, 1)
        base = np.abs(np.sum(p * d, -1)) / np.linalg.norm(d, axis=1)  # O to the normal
        assert np.allclose(base, r * math.cos(alpha), rtol=0, atol=1e-12)


def test_male_arc_mate_wraps_the_turning_arc():
    """The female arc generated from a circle on the male touches that circle at every
    angle of its contact range and never enters it (distance to a circle is exact)."""
    g = gearing()
    arc = CircleArc("male flank", (g.r1 - 0.006, 0.0), 0.015, -0.8, 0.8)
    mate = MaleGenerated(arc, g, reverse=True)
    check_no_undercut(mate)
    x = mate.eval(np.linspace(0.0, 1.0, 20001), 0)
    angles = mate.rolling_angle(np.linspace(0.05, 0.95, 15))
    for phi in angles:
        # the mate's samples in the fixed frame; the male circle's centre turned by phi
        f = rotate(x, -phi * g.r1 / g.r2) + [g.centre_distance, 0.0]
        centre = rotate(np.asarray(arc.centre), phi)
        d = np.linalg.norm(f - centre, axis=1) - arc.radius
        assert d.min() > -1e-9 and d.min() < 1e-7  # 20001 samples: spacing ~2 um


def test_a_too_small_tip_circle_undercuts_and_is_named():
    g = gearing()
    hm, hf = addenda(g)
    rack = symmetric_circular_rack(g, hm, hf, 0.6 * centred_tip_radius(g, hm, hf))
    with pytest.raises(CaseError, match=r"undercut: the male arc generated by rack arc "
                                        r"'male tip' turns back .* male rolling angle"):
        rack_pair(g, rack)


def test_impossible_and_broken_racks_are_named():
    g = gearing()
    hm, hf = addenda(g)
    with pytest.raises(CaseError, match="rack arc 'male tip'"):
        symmetric_circular_rack(g, hm, hf, 1.0)
    tip, root = symmetric_circular_rack(g, hm, hf, centred_tip_radius(g, hm, hf))
    short = CircleArc(root.name, root.centre, root.radius, root.angle0, root.angle1 + 0.1)
    with pytest.raises(CaseError, match="rack arc 'female tip' ends"):
        rack_pair(g, (tip, short))
    upright = Line("upright", (0.002, 0.0), (0.0, 0.0))  # across the pitch line
    with pytest.raises(CaseError, match="rack arc 'upright' is perpendicular"):
        RackGenerated(upright, g, "male").eval(np.array([0.5]))


def test_mismatched_rotors_interfere_and_the_check_says_where():
    """A female from a shallower rack (male tip 5 um lower) is entered by the male."""
    g, male, _ = circular_pair(4, 6)
    _, _, shallow = circular_pair(4, 6, -5e-6)
    with pytest.raises(CaseError, match=r"interference: at male angle .* deg the male arc "
                                        r"generated by rack arc '.*' enters the female"):
        check_no_interference(male, shallow, g)


def test_tangents_are_the_derivatives_of_the_points():
    """Every arc kind (first and second derivatives), and the arcs generated from them on
    both rotors (first), return the derivative of their points: central differences with
    step 1e-6 are exact to ~1e-11 of the speed; the closed forms must agree to 1e-8."""
    g = gearing()
    arcs = [Line("line", (-0.002, -0.004), (0.003, 0.006)),
            CircleArc("circle", (-0.004, 0.0), 0.015, -0.5, 0.6),
            EllipseArc("ellipse", (-0.003, 0.001), 0.012, 0.008, 0.3, -0.6, 0.5),
            ParabolaArc("parabola", (0.004, 0.0), 0.01, -math.pi / 2, -0.004, 0.005)]
    t, h = np.linspace(0.05, 0.95, 37), 1e-6

    def agree(piece, order):
        fd = (piece.eval(t + h, order - 1) - piece.eval(t - h, order - 1)) / (2 * h)
        d = piece.eval(t, order)
        return np.abs(fd - d).max() <= 1e-8 * max(np.abs(d).max(), 1e-2)  # 1e-2: these arcs' size

    for arc in arcs:
        assert agree(arc, 1) and agree(arc, 2), arc.name
    generated = [RackGenerated(a, g, rotor, reverse=rev) for a in arcs
                 for rotor in ("male", "female") for rev in (False, True)]
    generated.append(MaleGenerated(CircleArc("flank", (g.r1 - 0.006, 0.0), 0.015, -0.8, 0.8),
                                   g, reverse=True))
    for piece in generated:
        assert agree(piece, 1), piece.name


def test_a_lobe_that_crosses_itself_is_a_named_loop():
    """A bow-tie lobe of primary arcs on the rotor: its two diagonals cross."""
    corners = [(0.01, -0.01), (0.03, 0.01), (0.03, -0.01), (0.01, 0.01)]
    names = ["rising", "down", "diagonal", "back"]
    lines = [OnRotor(Line(n, corners[k], corners[(k + 1) % 4]), "male")
             for k, n in enumerate(names)]
    bow_tie = TwinProfile("male", tuple(lines), 1)
    with pytest.raises(CaseError, match=r"loop: the male profile crosses itself between the "
                                        r"male primary arc 'rising' .* and the male primary "
                                        r"arc 'diagonal'"):
        check_no_loop(bow_tie, C)


def test_an_undercut_names_the_tip_radii_that_avoid_it():
    """The circular 5/6 rack on these diameters undercuts at its default tip circle; the
    refusal names a window of tip_radius_mm, and the whole pair (loops and interference
    checked too) builds at its printed edges and middle and undercuts 0.05 mm outside
    either edge.  The 5/7 rack has no such window, and says so."""
    import re

    from rotorflow.geometry.twin_screw.family import build

    with pytest.raises(CaseError) as err:
        build("circular", 5, 6, C, D_MALE, D_FEMALE)
    found = re.search(r"tip_radius_mm from ([0-9.]+) to ([0-9.]+) gives", str(err.value))
    assert found and "the default tip_radius_mm is 16.95" in str(err.value), str(err.value)
    lo, hi = (float(v) for v in found.groups())
    for r in (lo, 0.5 * (lo + hi), hi):
        build("circular", 5, 6, C, D_MALE, D_FEMALE, tip_radius=r * 1e-3)
    for r in (lo - 0.05, hi + 0.05):
        with pytest.raises(CaseError, match="undercut"):
            build("circular", 5, 6, C, D_MALE, D_FEMALE, tip_radius=r * 1e-3)
    with pytest.raises(CaseError, match="no tip_radius_mm gives a circular rack without"):
        build("circular", 5, 7, C, D_MALE, D_FEMALE)
