"""Twin-screw sections cut into groove parts: what must hold whatever the profile.

Independent references: the free area of a section is the two bores' union (a closed
form of the lens) less both rotors' areas (Green's theorem on the analytic profiles),
whatever the rotors' positions; every rotor's boundary is wetted all round, so at one
pressure everywhere the parts' forces and torques on each rotor sum to nothing; a whole
groove is its bore less its rotor shared by the lobes.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from rotorflow.geometry.twin_screw.family import build

#: Seed 004's 4/6 machine (male 100 mm, female 96 mm); the centre distance, not given
#: there, assumed 78 mm.
SIZE = (4, 6, 0.078, 0.100, 0.096)
ANGLES = 12


@functools.cache
def pair(profile):
    return build(profile, *SIZE)


@functools.cache
def scans(profile):
    p = pair(profile)
    psi = np.linspace(0.0, 2.0 * math.pi / 4, ANGLES, endpoint=False) + 0.0123
    return [(x, p.cutter.cut(float(x))) for x in psi]


@pytest.mark.parametrize("profile", ["circular", "line-circle"])
def test_parts_fill_the_free_area(profile):
    p = pair(profile)
    free = p.working_area - p.male.area - p.female.area
    for _, parts in scans(profile):
        # Polygons sampled to 1e-6 C with each edge's sliver to the true curve added:
        # what is left is the ends of runs at cuts and contacts (measured 2e-8).
        assert sum(q.area for q in parts) == pytest.approx(free, rel=1e-7)


@pytest.mark.parametrize("profile", ["circular", "line-circle"])
def test_uniform_pressure_loads_no_rotor_in_any_section(profile):
    p = pair(profile)
    for psi, parts in scans(profile):
        force = sum(q.force for q in parts)
        torque = sum(q.torque for q in parts)
        scale = p.male_radius
        # Wetted arcs meet end to end at tips, cuts and contacts (both ends of the
        # rotors' overlap take one snapped point): rounding, 1e-16 measured.  (It was
        # 5e-6 of the radius, line-circle, until the pockets along a conformal band
        # stopped taking the female tip's bore for theirs: the test below.)
        assert np.abs(force).max() < 1e-9 * scale, (psi, force)
        assert np.abs(torque).max() < 1e-9 * scale * scale, (psi, torque)


@pytest.mark.parametrize("profile", ["circular", "line-circle"])
def test_whole_grooves_are_the_bore_less_the_rotor(profile):
    p = pair(profile)
    g = p.gearing
    whole = {0: (math.pi * p.male_radius ** 2 - p.male.area) / g.lobes_male,
             1: (math.pi * p.female_radius ** 2 - p.female.area) / g.lobes_female}
    seen = 0
    for _, parts in scans(profile):
        for q in parts:
            if q.side == "" and len(q.tips) == 2 and not q.contacts:
                assert q.area == pytest.approx(whole[q.rotor], rel=1e-6)
                seen += 1
    assert seen


def test_chamber_section_tables_sum_to_the_free_area():
    p = pair("circular")
    ppp = 24
    sec = p.section(ppp)
    n = len(sec.psi)
    k = -(-n // ppp) * ppp
    area = np.zeros(k)
    area[:n] = sec.area
    free = p.working_area - p.male.area - p.female.area
    # Every part of every section is booked to exactly one chamber's node.
    assert area.reshape(-1, ppp).sum(0) == pytest.approx(np.full(ppp, free), rel=1e-7)


@functools.cache
def pin_cycloid():
    """The pin-cycloid pair of examples/twin_screw_4_6.toml (female lands 0.44 rad wide
    on its bore, the male's tip an arc within a micron of its bore for 0.004 rad)."""
    from rotorflow.workflow.case import load_case

    from .conftest import CASES

    return load_case(CASES / "twin_screw_4_6.toml").pair


def _unbalanced(p, psi, parts=None):
    """Largest force and torque per unit pressure left on either rotor by all the parts
    of the section at psi, against the largest part's force (and it times the radius)."""
    parts = p.cutter.cut(float(psi)) if parts is None else parts
    force = sum(q.force for q in parts)
    torque = sum(q.torque for q in parts)
    largest = max(np.abs(q.force).max() for q in parts)
    return np.abs(force).max() / largest, np.abs(torque).max() / (largest * p.male_radius)


def test_uniform_pressure_loads_no_rotor_as_the_pin_cycloid_tip_passes_the_top_cusp():
    """The male tip and the female land's corner reach the top cusp together (closed
    form below).  In the 0.0052 rad before, the female land lies across the lens from
    its contact with the male to the cusp in one chord; its wetted arc there was taken
    for the bore, and 29 % of the largest part's force was left on the female (22 % of
    the largest female part's).  In the 0.004 rad after, a cut 0.2 um under the bore
    0.0024 rad behind the male tip did not reach the tip (its band near the bore was
    read off the samples, 0.1 mm apart): 0.12 mm of the male arc went to nobody (0.15
    %).  Every rotor boundary is wetted all round, so at one pressure nothing is left:
    0.006 rad either side of those windows, every 2.5e-4 rad."""
    p = pin_cycloid()
    event = (math.atan2(p.cusp[1], p.cusp[0]) - p.tip_angle(0)) % p.period
    for psi in event + np.arange(-0.012, 0.010, 2.5e-4):
        force, torque = _unbalanced(p, psi)
        # rounding (1e-16 measured)
        assert force < 1e-9 and torque < 1e-9, (psi - event, force, torque)


def test_chamber_polygons_of_nanometre_slivers():
    """Where the female groove is born as a sliver (2.1215 deg after the table's birth
    node) the cut holds a piece a few nanometres across whose area rounded to zero about
    the axis: its centroid was NaN and chamber_polygons raised (a male one at psi =
    1.3138).  Every piece of the section is booked to exactly one chamber, so the
    chambers' polygons at one angle fill the free area (the polygons alone: up to the
    rotors' growth and the chords' slivers, 2e-5 of it)."""
    from rotorflow.geometry.twin_screw.ages import centroid
    from rotorflow.geometry.twin_screw.section import _beta0

    p = pin_cycloid()
    free = p.working_area - p.male.area - p.female.area
    for phi in (p.section(24).phi_i + math.radians(2.1215), 1.3138296457087806):
        rings = [q for k in range(-12, 13) for q in p.chamber_polygons(phi + k * p.period)]
        assert all(np.all(np.isfinite(centroid(q))) for q in rings)
        area = sum(abs(0.5 * np.sum(q[:, 0] * np.roll(q[:, 1], -1)
                                    - np.roll(q[:, 0], -1) * q[:, 1])) for q in rings)
        assert area == pytest.approx(free, rel=1e-4)
        base = -_beta0(p)
        residue = base + (phi - base) % p.period
        assert len(rings) == sum(len(q.polygons) for q in p.cutter.cut(float(residue)))


def test_centroid_of_a_tiny_ring_far_from_the_origin():
    """A triangle's centroid is its vertices' mean, however small and far out; a ring of
    collinear vertices (no area) is located by that mean too."""
    from rotorflow.geometry.twin_screw.ages import centroid

    tri = np.array([[41.641871265769, -15.062076148391], [41.641871708632, -15.062075865269],
                    [41.641870036125, -15.062076922655]]) * 1e-3
    assert np.allclose(centroid(tri), tri.mean(0), rtol=0.0, atol=1e-3 * np.ptp(tri))
    line = np.array([[0.04, 0.01], [0.041, 0.011], [0.042, 0.012]])
    assert np.allclose(centroid(line), line.mean(0), rtol=0.0, atol=1e-15)


#: Windows (male angle, rad) where the female tip rolls in the male root along a
#: conformal band, the polygons' crossings cutting it into a chain of pockets.
BAND_WINDOWS = {"circular": (0.778, 0.796), "line-circle": (0.846, 0.862)}


@pytest.mark.parametrize("profile", sorted(BAND_WINDOWS))
def test_uniform_pressure_loads_no_rotor_along_a_conformal_band(profile):
    """The female tip lies on its own bore, so the corners of the pockets along the
    band lie on the female's circle, inside the male bore.  Taken for bore corners, the
    female chord between two was booked as bore and the male run snapped to male tips:
    1.1e-3 of the largest part's force left on each rotor (equal and opposite) at psi
    0.7820 and 0.7886 on the circular pair, and a whole male groove's at 0.7817 and
    0.7890.  Every rotor boundary is wetted all round, so at one pressure the parts'
    loads sum to nothing on each rotor: to rounding (1e-16 measured, every 2.5e-4 rad;
    1e-9 leaves room for a lens's ends matched across the band, which no longer differ
    here).  The scan must see the band's pockets (parts between two contacts)."""
    p = pair(profile)
    pockets = 0
    for psi in np.arange(*BAND_WINDOWS[profile], 2.5e-4):
        parts = p.cutter.cut(float(psi))
        force, torque = _unbalanced(p, psi, parts)
        assert force < 1e-9 and torque < 1e-9, (psi, force, torque)
        pockets += sum(len(q.contacts) >= 2 for q in parts)
    assert pockets > 100


@pytest.mark.parametrize("profile", ["circular", "line-circle"])
def test_grooves_left_out_of_the_cut_are_booked_as_the_whole_cut_books_them(profile):
    """The grooves out of the mesh's reach are covered before Clipper's sweep and booked
    as a held whole groove turned (:mod:`.window`).  The same sections cut whole, every
    groove through the Boolean, give the same parts: groove, age, area, loads and tips
    (1e-12 of the whole groove's area and loads: the turned groove's bore vertices are
    not the bore polygon's, and nothing else differs), but for the specks Clipper
    leaves between a tip and the bore polygon (triangles of 1e-13 m2 on the
    line-circle pair, left out with a covered groove or not), which book nothing."""
    p = pair(profile)
    cutter = p.cutter
    cutter.cut(0.0123)  # (a whole groove of each rotor held)
    covered = 0
    for psi, _ in scans(profile):
        windowed = cutter.cut(float(psi))
        covered += sum(len(cutter.window.out_of_reach(r, psi)) for r in (0, 1))
        held, cutter.window.whole = cutter.window.whole, {}
        try:
            whole = cutter.cut(float(psi))
        finally:
            cutter.window.whole = held
        scale = max(q.area for q in whole)
        specks = [q for q in windowed + whole if q.area < 1e-9 * scale]
        assert all(not q.tips and not q.contacts and not q.force.any() for q in specks)
        key = lambda q: (q.rotor, q.groove, round(q.age, 9))  # noqa: E731
        a, b = (sorted((q for q in cut if q.area >= 1e-9 * scale), key=key)
                for cut in (windowed, whole))
        assert [key(q) for q in a] == [key(q) for q in b]
        for x, y in zip(a, b, strict=True):
            assert abs(x.area - y.area) < 1e-12 * scale
            assert np.allclose(x.force, y.force, rtol=0.0, atol=1e-12 * math.sqrt(scale))
            assert np.allclose(x.torque, y.torque, rtol=0.0, atol=1e-12 * scale)
            assert sorted((r, k) for r, k, _ in x.tips) == sorted((r, k) for r, k, _ in y.tips)
    assert covered >= 3 * len(scans(profile))  # (half the grooves, or more, left out)


def test_the_chamber_lives_with_its_fluid_not_with_a_stray_seal():
    """At 384 section points per period a contact on a film Clipper breaks into specks
    is booked (section._lives) to a life four periods past the 4/6 pin-cycloid
    chamber's death; that seal no longer extends the chamber's table (it ran 1,003
    nodes, 4.1 rad, past the fluid): its zero node lies within 3.5 steps of its last
    fluid (3 measured; 2 at 192: sealing points keep it alive only next to its fluid)."""
    from rotorflow.workflow.case import load_case

    from .conftest import CASES

    sec = load_case(CASES / "twin_screw_4_6.toml").pair.section(384)
    h = sec.psi[1] - sec.psi[0]
    last = sec.psi[np.nonzero(sec.area > 0.0)[0][-1]]
    assert sec.phi_f - last < 3.5 * h


@functools.cache
def pin_cycloid_pair(lobes_male, lobes_female, male_diameter, female_diameter=0.096):
    """A pin-cycloid pair off the shipped design (its centre distance from the female's
    pitch diameter, as the case files' diameters give it)."""
    c = female_diameter * (lobes_male + lobes_female) / (2.0 * lobes_female)
    return build("pin-cycloid", lobes_male, lobes_female, c, male_diameter, female_diameter)


@pytest.mark.parametrize("male_diameter", [0.100, 0.101, 0.102, 0.1024])
def test_the_pin_cycloid_female_tip_is_its_lands_pin_side_corner(male_diameter):
    """The female's largest radius is an arc (its land, piece 2 of each lobe), so the
    largest sample was rounding's pick: the pin-side corner (u 2.009 at a 100 mm male,
    2.001 at 102) or the trochoid-side one (u 2.999 at 101 and 102.4), and there the
    grooves' sectors, the tip lines and where the tips cross the cusps moved by a land
    (no blow-hole was booked, a pocket changed chambers: power balance 6.7e-3 against
    3.4e-4).  The tip is the land's clockwise end, the pin-side corner."""
    p = pin_cycloid_pair(4, 6, male_diameter)
    u, radius = p._tip(p.female)
    assert u == pytest.approx(2.0, abs=1e-9)
    assert radius == pytest.approx(0.048, rel=1e-14)
    a, b = p.female.point(np.array([2.0, 3.0]))
    land = (math.atan2(b[1], b[0]) - math.atan2(a[1], a[0])) % (2.0 * math.pi)
    assert p.tip_spans == (0.0, pytest.approx(land, abs=1e-9))


@pytest.mark.parametrize("lobes, diameters", [((3, 5), (0.096, 0.100)),
                                              ((3, 4), (0.104571428571, 0.0914285714286))])
def test_uniform_pressure_loads_no_female_whose_lands_are_wider_than_half_a_lobe(
        lobes, diameters):
    """The pin-cycloid female's land spans 38.5 of the 3/5's 72 deg lobe and 53.7 of the
    3/4's 90: a groove's corner at the land's far end from its tip point lies nearer
    the next lobe's tip, and both ends of a groove cut in the mesh took that tip (no
    load for it, where the whole groove books its two tips': 0.93-1.15 of the largest
    chamber's female force left over at uniform pressure; the 3/4's female tip lines
    were lost).  Each corner takes the tip of the land it lies on: nothing is left
    over, and every female tip bounds two parts."""
    p = pin_cycloid_pair(*lobes, *diameters)
    for psi in np.linspace(0.0, p.period, 24, endpoint=False):
        parts = p.cutter.cut(float(psi))
        force, torque = _unbalanced(p, psi, parts)
        assert force < 1e-9 and torque < 1e-9, (psi, force, torque)
        seen = {}
        for q in parts:
            for rotor, k, _ in q.tips:
                seen[(rotor, k)] = seen.get((rotor, k), 0) + 1
        assert all(n == 2 for (rotor, _), n in seen.items() if rotor == 1), (psi, seen)


def test_a_pocket_of_the_pin_cycloid_keeps_its_chamber():
    """The 4/6 with a 101 mm male (its female tip point was at the land's trochoid-side
    corner): the pocket left at the top of the mesh, across the ray through that corner,
    went a chamber older with its female part as it crossed (a jump of 0.65 of the
    largest area rate at 96 points per period), and no blow-hole was booked.  Per unit
    pressure the torques' power is the chamber's area rate (the kinks where a tip
    passes a cusp aside: 3.3e-2 on the shipped 4/6, 1.8e-2 here), and the blow-hole is
    there."""
    p = pin_cycloid_pair(4, 6, 0.101)
    sec = p.section(96)
    rate = sec.torque[:, 0] - p.gearing.lobes_male / p.gearing.lobes_female * sec.torque[:, 1]
    step = np.diff(sec.area) / np.diff(sec.psi)
    err = np.abs(step - 0.5 * (rate[1:] + rate[:-1])) / np.abs(rate).max()
    assert err.max() < 0.05
    assert {o.name for o in sec.openings} >= {"blow-hole"}
