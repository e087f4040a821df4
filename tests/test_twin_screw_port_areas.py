"""The table's port areas of a twin screw (geometry/ports.py, geometry/footprint.py).

Independent references: the chamber's coverage of points of the end plane, counted
section by section (where a point is covered twice, the section at the port's own angle
does not tell its part in the port, and the swept region must); unions of the family's
sections at finely spaced angles (real footprints, so inside the swept region, and
filling it as the spacing shrinks); the machine's own volume quadrature for the timing.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from rotorflow.geometry import footprint as FP
from rotorflow.geometry import ports as P
from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.scalar import minimum
from rotorflow.geometry.summary import case_port_timing
from rotorflow.workflow.case import load_case

from .conftest import CASES

#: The 4/6 pairs of seed 004 on the pin-cycloid and the circular profiles, at the
#: coarsest resolution the bench runs.
EXAMPLES = ("twin_screw_4_6.toml", "twin_screw_export.toml")
PPP = 24
DEG = math.pi / 180.0


@functools.cache
def built(name: str):
    case = load_case(CASES / name)
    machine = SweptMachine(case.pair, case.sweep(None), PPP)
    return case, machine, case_port_timing(case, machine)


def _fresh(name: str):
    """(case, machine) of example ``name`` at PPP built afresh: no caches, so that the
    polygons' settings in force are the ones it is cut with."""
    import dataclasses

    case = load_case(CASES / name)
    case = dataclasses.replace(case, pair=dataclasses.replace(case.pair))
    return case, SweptMachine(case.pair, case.sweep(None), PPP)


def _finer_polygons(monkeypatch):
    """Sections cut with polygons 16 times finer in chord error and growth."""
    from rotorflow.geometry.twin_screw import regions

    monkeypatch.setattr(regions, "SAMPLE_TOL", regions.SAMPLE_TOL / 16.0)
    monkeypatch.setattr(regions, "GROW", regions.GROW / 16.0)


def _box(lo, hi):
    from manifold3d import CrossSection

    return CrossSection([np.array([lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]])])


def _sections_union(m, ages, box):
    """The union of machine m's real chamber sections at ``ages``, within ``box``."""
    from manifold3d import CrossSection, FillRule

    return FP._union([CrossSection([np.ascontiguousarray(q)], FillRule.Positive)
                      for a in ages for q in m.pair.chamber_polygons(float(m.section.phi_i + a))
                      if len(q) >= 3]) ^ box


def _coverage(machine, points):
    """(angles, covered[angle, point]) of the chamber's section on the section grid over
    its life: whether each point lies in it."""
    from matplotlib.path import Path

    sec = machine.section
    psi = sec.psi[sec.psi <= sec.phi_f]
    covered = np.zeros((len(psi), len(points)), dtype=bool)
    for i, p in enumerate(psi):
        for q in machine.pair.chamber_polygons(float(p)):
            if len(q) >= 3:
                covered[i] |= Path(q).contains_points(points)
    return psi, covered


@pytest.mark.parametrize("name", EXAMPLES)
def test_points_covered_twice_lie_where_both_rotors_pass(name):
    """The exact two-section formula holds where the chamber covers a point in one
    interval of angles; the sweep is cut to the region both rotors' surfaces pass
    (crop_region).  Points of the bores, sampled: outside that region none is covered
    twice; inside it (the lens between the bores) many are, so the sweep is needed."""
    from matplotlib.path import Path

    case, m, _ = built(name)
    rng = np.random.default_rng(13)
    (x0, y0), (x1, y1) = np.reshape(FP.crop_region(m.pair)[0].bounds(), (2, 2))
    c = m.pair.gearing.centre_distance
    r = max(m.pair.male_radius, m.pair.female_radius)
    points = np.column_stack([rng.uniform(-r, c + r, 3000), rng.uniform(-r, r, 3000)])
    # and as many in the crop's box, where the twice-covered points are
    points = np.vstack([points, np.column_stack([rng.uniform(x0, x1, 3000),
                                                 rng.uniform(y0, y1, 3000)])])
    _, covered = _coverage(m, points)
    intervals = np.sum(covered[1:] & ~covered[:-1], axis=0) + covered[0]
    inside = np.zeros(len(points), dtype=bool)
    for ring in FP.crop_region(m.pair)[0].to_polygons():
        inside ^= Path(ring).contains_points(points)
    assert intervals.max() == 2
    assert not np.any(intervals[~inside] > 1)
    assert np.sum(intervals[inside] == 2) > 0.3 * np.sum(intervals[inside] >= 1)


def test_plain_unions_fill_the_sweep_of_a_born_sliver(monkeypatch):
    """The pin-cycloid pair's female groove is born as a sliver between flanks that
    touched along an arc (2.1 deg after the table's birth node), thin (its gap grows
    like the square of the angle) and moving fast: a union of sections misses the
    points it passes between them.  The sweep is the same with the sections' polygons
    16 times finer in chord error and growth (1.6719 and 1.6714 mm2 in this window and
    box, measured: each vertex is swept from where the true surfaces touch; from where
    the grown ones met it was 1.127 mm2, and a union of the finer sections every 0.001
    deg already held 1.142).  Unions of sections with the finer polygons (whose grown
    rotors part nearer the touching; the shipped ones' unions tend to what the grown
    sliver sweeps) at 0.02 and 0.005 deg lie inside the sweep (their sections are
    real), and their deficit shrinks as measured: 1.51 and 1.06 mm2 (0.165 and 0.616
    held; 1.142 at 0.001 deg).  A sweep 50 % too large would leave the unions more than
    70 % short with a ratio under 1.3; one too small would not hold them."""
    from manifold3d import CrossSection, FillRule

    from rotorflow.geometry.twin_screw import regions

    box = CrossSection([np.array([[0.0405, -0.0160], [0.0455, -0.0160],
                                  [0.0455, -0.0120], [0.0405, -0.0120]])])
    lo, hi = 2.0 * DEG, 2.6 * DEG

    def sweep():
        case = load_case(CASES / EXAMPLES[0])
        m = SweptMachine(case.pair, case.sweep(None), PPP)  # (a fresh pair: no caches)
        pair = m.pair
        sweeper = FP.Sweeper(FP.Surfaces(pair), pair.chamber_polygons, *FP.crop_region(pair))
        swept = sweeper.sweep(m.section.phi_i + np.array([lo, hi])) ^ box
        assert [k for k, _ in sweeper.events] == ["sliver"]
        return pair, m.section, swept

    shipped = sweep()[2]
    monkeypatch.setattr(regions, "SAMPLE_TOL", regions.SAMPLE_TOL / 16.0)
    monkeypatch.setattr(regions, "GROW", regions.GROW / 16.0)
    pair, sec, swept = sweep()
    assert abs(shipped.area() - swept.area()) < 1e-2 * swept.area()
    deficits = []
    for step in (0.02, 0.005):
        ages = np.arange(lo, hi + 1e-12, step * DEG)
        pieces = [CrossSection([np.ascontiguousarray(q)], FillRule.Positive)
                  for a in ages for q in pair.chamber_polygons(float(sec.phi_i + a))
                  if len(q) >= 3]
        union = FP._union(pieces) ^ box
        # Inside the sweep up to the chords of the sections' boundaries (a sliver's
        # width is microns: 1e-3 mm2 over its 20 mm).
        assert (union - swept).area() < 1e-9
        deficits.append(swept.area() - union.area())
    ratio = deficits[0] / deficits[1]
    assert 0.0 < deficits[1] < 0.7 * swept.area() and 1.3 < ratio < 2.6, (deficits, ratio)


@pytest.mark.parametrize("name", EXAMPLES)
def test_timing_between_the_nodes(name):
    """Suction closes at the volume maximum: on the Hermite of the table's volume and
    its derivative, within 0.01 deg of the maximum of the machine's own quadrature
    (golden section); a node would be off by up to half a step (1.9 deg).  The discharge
    opens where that volume has fallen to V_max / volume_ratio (less the early opening),
    to 1e-6 of it by the quadrature."""
    case, m, t = built(name)
    phi0 = m.curves.phi[0]
    k = int(np.argmax(m.curves.volume))
    x, least = minimum(lambda p: -float(m.volume_at(p)[0]), m.curves.phi[k - 1],
                       m.curves.phi[k + 1], xtol=1e-12)
    assert abs(phi0 + t.suction_close - x) < 0.01 * DEG
    early = math.radians(case.raw["operating"]["discharge_early_opening_deg"])
    v_open = float(m.volume_at(phi0 + t.discharge_open + early)[0])
    assert v_open == pytest.approx(-least / case.volume_ratio, rel=1e-6)


@pytest.mark.parametrize("name", EXAMPLES)
def test_open_areas_close_and_open_at_the_timing(name):
    """Zero where the port is closed, and from the port's own angle the areas grow from
    nothing (the section at that angle is all sealed), not from a node: the two open
    nodes nearest the edge, extended by their chord, reach zero within a quarter step
    of it (measured 0.02 to 0.3 of a step)."""
    _, m, t = built(name)
    ages = m.curves.phi - m.curves.phi[0]
    lp, hp = P.open_areas(m, t, ages)
    assert not lp[ages >= t.suction_close].any() and not hp[ages <= t.discharge_open].any()
    step = ages[1] - ages[0]
    for area, edge, nodes in (
            (lp, t.suction_close, np.searchsorted(ages, t.suction_close) - np.array([1, 2])),
            (hp, t.discharge_open, np.searchsorted(ages, t.discharge_open, "right")
             + np.array([0, 1]))):
        (a0, a1), (v0, v1) = ages[nodes], area[nodes]
        assert v0 > 0.0 and v1 > v0
        zero = a0 - v0 * (a1 - a0) / (v1 - v0)
        assert abs(zero - edge) < 0.25 * step, (math.degrees(zero), math.degrees(edge))


@pytest.mark.parametrize("name", EXAMPLES)
def test_discharge_areas_are_the_nodes_own(name):
    """The discharge face's sections lie off the section grid (shifted by the wrap):
    the table's areas there, interpolated where the grid shows the area smooth and cut
    at the node where it shows a kink (port_areas.KINK_TOL), against every node's own
    section less the same sealed region (an independent cut per node), within 5e-5 of
    the largest area (the interpolation's bound where the grid shows no kink).  As the
    grid's Hermite everywhere they were 5.8e-4 (pin-cycloid) and 1.1e-3 (circular) off."""
    from rotorflow.geometry import port_areas as PA

    _, m, t = built(name)
    ages = m.curves.phi - m.curves.phi[0]
    _, hp = P.open_areas(m, t, ages)
    sec, sw = m.section, m.sweep
    sweeper = FP.Sweeper(FP.Surfaces(m.pair), m.pair.chamber_polygons, *FP.crop_region(m.pair))
    h = float(sec.psi[1] - sec.psi[0])
    b_open = t.discharge_open - sw.wrap
    sealed = PA._sealed_region(m.pair.chamber_polygons, sec, sweeper, b_open, (0.0, b_open), h)
    planar = ages - sw.wrap
    inside = (planar > b_open) & (planar < min(t.death - sw.wrap, sec.phi_f - sec.phi_i))
    own = PA._areas_outside(m.pair.chamber_polygons, sec, sealed, planar[inside],
                            float(sw.scale(sw.length)))
    assert np.abs(hp[inside] - own).max() < 5e-5 * own.max()


def test_kinks_are_told_from_smooth_curves():
    """port_areas._kinked: a smooth curve on a grid of 96 per turn has no cell flagged
    (its third differences, h^3 times its third derivative, are ~1.4e-5 of it, below
    KINK_TOL = 2.5e-4); a slope jump of 0.3 between nodes flags the cells whose stencils
    reach it (third differences ~0.3 h = 2e-2) and no cell farther; the Hermite errs
    by less than KINK_TOL / 20 of the curve on the cells not flagged, by more on some
    flagged."""
    from rotorflow.geometry import port_areas as PA

    h = 2.0 * math.pi / 96.0
    x = h * np.arange(40)
    xq = x[:-1] + 0.37 * h
    smooth = lambda a: 1.0 + 0.05 * np.sin(a)  # noqa: E731
    assert not PA._kinked(x, smooth(x), xq, h).any()
    kink = 17.5 * h
    f = lambda a: smooth(a) + 0.3 * np.maximum(a - kink, 0.0)  # noqa: E731
    flagged = PA._kinked(x, f(x), xq, h)
    near = np.abs(xq - kink) < 2.5 * h
    assert flagged[near].all() and not flagged[np.abs(xq - kink) > 4 * h].any()
    err = np.abs(PA._hermite(x, f(x), xq) - f(xq))
    assert err[~flagged].max() < PA.KINK_TOL / 20 * f(x).max()
    assert err[flagged].max() > PA.KINK_TOL / 20 * f(x).max()


def test_a_kink_not_flagged_errs_below_1e4():
    """port_areas._kinked across a slope jump (the discharge area's peak, 1 - s |x - a|):
    over slope jumps 2 s of 0.02 to 6 per radian, anywhere in a cell, on grids of 48 to
    384 per lobe period, the Hermite errs on the cells not flagged by at most 0.37
    KINK_TOL of the curve (its third difference up to KINK_TOL, the error up to 0.37
    of it), below the table's 1e-4 (with KINK_TOL 1e-3, 3.6e-4)."""
    from rotorflow.geometry import port_areas as PA

    worst = 0.0
    for h in 2.0 * math.pi / 4.0 / np.array([48, 96, 192, 384]):
        x = h * np.arange(60)
        xq = (x[:-1, None] + h * np.array([0.13, 0.37, 0.5, 0.71, 0.93])).ravel()
        for slope in np.geomspace(0.01, 3.0, 30):
            for at in (30.0 + np.linspace(0.01, 0.99, 15)) * h:
                f = 1.0 - slope * np.abs(x - at)
                flagged = PA._kinked(x, f, xq, h)
                err = np.abs(PA._hermite(x, f, xq) - (1.0 - slope * np.abs(xq - at)))
                worst = max(worst, float(err[~flagged].max(initial=0.0)))
    assert worst < 1e-4


def test_a_sliver_that_opens_onto_its_chamber_is_swept():
    """The circular pair's conformal arcs (the female tip circle in the male root
    circle) part along their length at once 148.3 deg after the chamber's birth, next to
    the chamber: the sliver joins a ring whose pieces are matched, and only the pieces'
    ends jump (a whole profile segment in one step).  Swept at the section grid's two
    steps (48 per period) in a box round the arc, the sweep holds 95 % of what 64 steps
    sweep (1.94 of 2.04 mm2, measured; with the band's chord alone 1.14, 56 %), and
    reaches past it by 6 % of it (0.13 mm2, the coarse bands' corners).  (Before the
    film's vertices were told by the true profiles, surfaces.Surfaces._films, the
    sweeps from 32 steps on took in 0.55 mm2 more: 2.59 mm2 at 64, against 2.04 at 16
    and 2.03 at 256 now.)"""
    _, m, _ = built(EXAMPLES[1])
    pair, sec = m.pair, m.section
    from manifold3d import CrossSection

    box = CrossSection([np.array([[0.0298, -0.0012], [0.0315, -0.0012],
                                  [0.0315, 0.0010], [0.0298, 0.0010]])])

    def swept(n):
        sweeper = FP.Sweeper(FP.Surfaces(pair), pair.chamber_polygons, *FP.crop_region(pair))
        return sweeper.sweep(sec.phi_i + np.linspace(146.25, 150.0, n + 1) * DEG) ^ box

    coarse, fine = swept(2), swept(64)
    assert (coarse ^ fine).area() > 0.9 * fine.area()
    assert (coarse - fine).area() < 0.08 * fine.area()


def test_port_areas_do_not_depend_on_the_sections_polygons(monkeypatch):
    """The table's port areas with the shipped polygons and with polygons 16 times
    finer in chord error and growth (geometry/twin_screw/regions.py), at the same
    angle resolution, agree within issue 13's 1e-4 of each one's largest: 6.1e-5
    (suction) and 5.7e-5 (discharge) on the 4/6 pin-cycloid, measured.  (The suction's
    was 1.14e-4 while the pocket closing by the top cusp at the chamber's end was taken
    for a pocket handed over: swept to where its rigidly moved area is least, which
    moved with the polygons, 0.027 against 0.022 rad on;
    test_a_pocket_closing_between_contacts_is_swept_to_its_close.)"""

    from rotorflow.geometry.summary import chamber_table

    coarse = chamber_table(*_fresh(EXAMPLES[0]))
    _finer_polygons(monkeypatch)
    fine = chamber_table(*_fresh(EXAMPLES[0]))
    for mine, there in ((coarse.area_lp_m2, fine.area_lp_m2),
                        (coarse.area_hp_m2, fine.area_hp_m2)):
        assert np.abs(mine - there).max() <= 1e-4 * there.max()


def test_a_pocket_closing_between_contacts_is_swept_to_its_close(monkeypatch):
    """The pin-cycloid chamber's last fluid is a pocket by the top cusp, between two
    contacts that converge: at 10.014 rad after the chamber's birth (a table node) it
    holds 0.012 mm2, and it closes ~0.04 rad later, a film under a micrometre for its
    last 0.01 rad, crossing ~0.3 mm2 of a 0.9 x 0.6 mm box by the cusp.  Its rigidly
    moved ring's area never falls below a tenth of its own (the chords that close the
    ring join pieces' ends that move apart), so it was taken for a pocket handed over
    and swept only to that least area, within the step: the table's sweep held 3.08e-7
    m2 of the box, the sweep with polygons 16 times finer at 8 steps a table step
    2.24e-7 (its samples lose the film, THIN, and found no event at all), and a union
    of the real sections every 1e-4 rad reached 9.6e-9 m2 past the table's.  Swept as
    the sliver it is (each vertex to where its own surfaces touch), the two sweeps hold
    3.25e-7 and 3.37e-7 (measured), the table's inside the fine one, and the union
    (1.68e-7: a union of a moving film fills its sweep slowly) lies inside both."""
    box = _box([0.0412, 0.0272], [0.0421, 0.0278])

    def swept(div):
        m = _fresh(EXAMPLES[0])[1]
        pair, sec = m.pair, m.section
        h = float(sec.psi[1] - sec.psi[0])
        life = sec.phi_f - sec.phi_i
        ages = 305 * h + h / div * np.arange(int((life - 305 * h) * div / h) + 1)
        ages = np.append(ages[ages < life], life)  # the table's nodes from 9.98 rad on
        sweeper = FP.Sweeper(FP.Surfaces(pair), pair.chamber_polygons, *FP.crop_region(pair))
        return m, sweeper.sweep(sec.phi_i + ages) ^ box

    m, table = swept(1)
    union = _sections_union(m, np.arange(10.02, 10.06, 1e-4), box)
    _finer_polygons(monkeypatch)
    fine = swept(8)[1]
    # Real sections lie in the true sweep: the union inside both, up to the chords.
    assert (union - table).area() < 1e-3 * union.area()
    assert (union - fine).area() < 1e-3 * union.area()
    # The table's step is 8 of the fine sweep's: its corners' chords cut 3.7 % (1.3e-8
    # m2, measured); the pocket swept to its least area missed 38 % (8.5e-8).
    assert (table - fine).area() + (fine - table).area() < 0.08 * fine.area()


def test_conformal_arcs_parting_are_swept_from_their_touching(monkeypatch):
    """The circular pair's conformal arcs part ~116 deg after the chamber's birth (2.02
    rad), by the cusp line at y = -12 mm: a film under 2 um thick that crosses a 1.5 x
    0.5 mm patch in its first 0.01 rad.  With polygons 16 times finer, moved back from
    the first sample that keeps it, the pieces' median gap bottoms out at 0.03 um of
    its 1 um without crossing (the finer grown rotors barely overlap), its area at 13
    %: no event was found, and the sweep at 8 samples a table step held 2.7e-8 of the
    patch's 1.43e-7 m2, of which the true profiles, tested point by point, put 1.40e-7
    outside both rotors in that while.  Taken as touching at the gap's least, the film
    is swept per vertex from there: 1.40e-7 (measured), and a union of the real
    sections every 1e-4 rad lies inside the sweep."""
    box = _box([0.0386, -0.0125], [0.0404, -0.0116])
    _finer_polygons(monkeypatch)
    m = _fresh(EXAMPLES[1])[1]
    pair, sec = m.pair, m.section
    h = float(sec.psi[1] - sec.psi[0]) / 8
    sweeper = FP.Sweeper(FP.Surfaces(pair), pair.chamber_polygons, *FP.crop_region(pair))
    swept = sweeper.sweep(sec.phi_i + np.arange(1.95, 2.10, h)) ^ box
    union = _sections_union(m, np.arange(2.025, 2.04, 1e-4), box)
    # Real sections lie in the true sweep: 4.4e-8 of this union's 9.6e-8 lay outside
    # it while the birth went unfound (measured).
    assert (union - swept).area() < 1e-3 * union.area()


def test_pieces_that_only_graze_across_the_pitch_point_bound_no_band():
    """The 1-1 involute pump (examples/screw_pump_involute.toml) at 48 points per period:
    its discharge areas swept on the section grid (96 samples per period) lie within
    1e-4 of the largest of those swept 192 times per period (2.3e-5 measured).  Where
    its contact crosses the cusp line at the pitch point, the male piece below it at
    one sample and the one above it at the next share a few hundredths of a degree of
    surface; matched, the band between them closed along paths from one's corners to
    the other's and covered 112 mm2 of the lens no section covers: 8.1e-3 of the
    largest area off (footprint.GRAZE)."""
    case = load_case(CASES / "screw_pump_involute.toml")
    m = SweptMachine(case.pair, case.sweep(None), 48)
    timing, ages = case_port_timing(case, m), m.curves.phi - m.curves.phi[0]
    grid = P.open_areas(m, timing, ages)[1]
    fine = P.open_areas(m, timing, ages, steps=192)[1]
    assert np.abs(grid - fine).max() < 1e-4 * fine.max()


def test_only_a_graze_between_pieces_matched_elsewhere_is_dropped():
    """The rule behind the test above, on chains of one surface (profile parameters):
    a graze (a share under GRAZE of the shorter piece) is dropped only when each of its
    two pieces shares at least GRAZE with another; a piece whose overlaps are all
    grazes keeps them, so that it is banded rather than taken for one that died."""
    from types import SimpleNamespace

    from rotorflow.geometry.footprint import Sweeper
    from rotorflow.geometry.surfaces import Chain

    def chain(lo, hi):
        return Chain(0, np.array([[lo, 0.0], [hi, 0.0]]), lo, hi, 0)

    surfaces = SimpleNamespace(rotors=[(None, 1.0, None, None, None, 100.0, 0.0)],
                               move=lambda p, r, h: p)
    sweeper = SimpleNamespace(periods=[100.0], surfaces=surfaces)

    def matched(ca, cb):
        pairs, born, dying = Sweeper._match(sweeper, ca, cb, 0.01)
        assert not born and not dying
        return {((x.lo, x.hi), (y.lo, y.hi)) for x, y in pairs}

    # below / above the pitch point: (0, 4) -> (0, 3.9) and (4.1, 8) -> (3.98, 8); the
    # first piece and the second's successor share 0.02 / 4: a graze, both partnered
    a, b = [chain(0.0, 4.0), chain(4.1, 8.0)], [chain(0.0, 3.9), chain(3.98, 8.0)]
    assert matched(a, b) == {((0.0, 4.0), (0.0, 3.9)), ((4.1, 8.0), (3.98, 8.0))}
    # a piece whose only overlaps are grazes keeps both
    a = [chain(0.0, 4.9), chain(5.0, 10.0), chain(10.1, 15.0)]
    b = [chain(0.0, 5.3), chain(9.7, 15.0)]
    assert ((5.0, 10.0), (0.0, 5.3)) in matched(a, b)
    assert ((5.0, 10.0), (9.7, 15.0)) in matched(a, b)
