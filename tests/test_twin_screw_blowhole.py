"""The twin-screw blow-hole (geometry/twin_screw/blowhole.py).

Independent references: the sections' Boolean cuts (Clipper on the grown polygons) and
a ray along the cusp line against the plain polygons give one width; a tip's crossing
of the cusp is a closed form, and the opening lives exactly between two of them; a
helical sweep of constant lead turns the swept area into an integral over the angle
(the area is constant while the whole triangle lies inside the rotors); the circular
rack is symmetric, so the blow-hole where the lobes come apart mirrors the one where
they go in; in seed 004's plane the triangle's apex is the contact line's end.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.sweep import Sweep
from rotorflow.geometry.twin_screw.blowhole import (
    NAMES,
    CuspRay,
    _towards_contact,
    openings_of,
    tip_crossings,
)
from rotorflow.geometry.twin_screw.family import build
from rotorflow.geometry.twin_screw.section import _scan, chamber_index

SIZE = (4, 6, 0.078, 0.100, 0.096)  # seed 004's 4/6 machine, C assumed 78 mm
LENGTH, WRAP = 0.130, math.radians(325.0)
PPP = 24


@functools.cache
def pair(profile="circular", blow_hole="cusp-plane"):
    import dataclasses

    return dataclasses.replace(build(profile, *SIZE), blow_hole=blow_hole)


@functools.cache
def machine(profile="circular", blow_hole="cusp-plane"):
    return SweptMachine(pair(profile, blow_hole), Sweep("helical", LENGTH, WRAP), PPP)


@pytest.mark.parametrize("profile", ["circular", "line-circle"])
def test_section_cuts_and_the_ray_give_one_width(profile):
    p = pair(profile)
    ray = CuspRay(p)
    psis, scans = _scan(p, 16)
    seen = 0
    for psi, parts in zip(psis, scans, strict=True):
        qs = [chamber_index(p, q, psi, p.female_shift) for q in parts]
        for _, name, _, width in openings_of(parts, qs):
            # The sections' rotors are grown 2e-6 C along their normals, which moves a
            # cut met at a grazing angle by more (measured 1.0e-5 C at worst).
            assert width == pytest.approx(ray.width(psi, name == NAMES[True])[0],
                                          abs=3e-5 * p.gearing.centre_distance)
            seen += 1
    assert seen > 10


def test_opening_lives_between_the_tip_crossings():
    p = pair()
    sec = machine().section
    for o in sec.openings:
        top = o.name == NAMES[True]
        events = tip_crossings(p, sec.psi[0], sec.psi[-1], top)
        for a, b in o.intervals:
            for end in (a, b):
                if sec.psi[0] < end < sec.psi[-1]:
                    assert np.min(np.abs(events - end)) < 1e-12
        # every node the sections booked lies inside one of the intervals
        h = sec.psi[1] - sec.psi[0]
        assert np.all(o.at(sec.psi[(sec.psi > o.intervals[0, 0] + h)
                                    & (sec.psi < o.intervals[0, 1] - h)]) >= 0.0)


def test_helical_area_is_the_width_integral_over_the_lead():
    """With twist k z, A(phi) = (1/k) int w(psi) d psi over the part of the interval in
    [phi - wrap, phi]: while it lies wholly inside, a constant."""
    p, m = pair(), machine()
    o = next(o for o in m.section.openings if o.name == NAMES[False] and o.offset == 1)
    (a, b), = o.intervals
    x = np.linspace(a, b, 20001)[:-1] + 0.5 * (b - a) / 20000
    exact = np.sum(CuspRay(p).width(x, False)) * (b - a) / 20000 * LENGTH / WRAP
    area = m.opening_areas[(NAMES[False], 1)]
    inside = (m.curves.phi - WRAP >= a) & (m.curves.phi <= b) | (
        (m.curves.phi >= b) & (m.curves.phi - WRAP <= a))
    assert inside.any()
    # The midpoint rule errs by up to half the jump times a cell in the cell holding
    # the jump (4.9 mm x 2e-5 rad / 2: 6e-5 of the integral; measured 2.4e-5, the
    # table 1.2e-5 against 3.2e5 cells).
    assert area[inside] == pytest.approx(exact, rel=1e-4)
    assert area.max() == pytest.approx(exact, rel=1e-4)
    # ... and it is constant while the triangle lies inside (exact for the pieces)
    assert np.ptp(area[inside]) < 1e-12 * exact


def test_symmetric_rack_blow_holes_mirror_each_other():
    areas = machine().opening_areas
    bottom = max(a.max() for (n, d), a in areas.items() if n == NAMES[False])
    # y -> -y with time reversed maps the circular pair onto itself; the top opening
    # between chambers two periods apart is the bottom one's mirror image.
    top = areas[(NAMES[True], 2)].max()
    assert top == pytest.approx(bottom, rel=1e-6)


def test_seed004_plane_ends_at_the_contact_line_or_before():
    p, m = pair(blow_hole="plane"), machine(blow_hole="plane")
    ray = CuspRay(p)
    cusp = ray.cusp_point(False)
    tracks = [t for t in m.section.tracks if t.kind == "interlobe"]
    direction = _towards_contact(cusp, m.section.tracks)
    assert direction @ direction == pytest.approx(1.0)
    dist, psi = min((np.linalg.norm(t.points[i] - cusp), m.section.psi[i])
                     for t in tracks for i in np.nonzero(t.present)[0])
    # Where the rotors touch the ray cannot pass: at that angle the plane's region next
    # to the cusp line ends at the contact line's nearest point or before (for the
    # circular rack before: a lobe hides it, 12.7 of 17.3 mm out).
    reach = ray.width(psi, False, direction)[0]
    assert 0.0 < reach <= dist + 1e-6
    area = max(a.max() for (n, d), a in m.opening_areas.items() if n == NAMES[False])
    assert area > 0.0


def test_table_declares_the_blow_holes_as_orifices():
    from rotorflow.geometry.twin_screw.leakage import twin_screw_paths

    m = machine()
    paths = {q.name: q for q in twin_screw_paths(m.track_lines, m.opening_areas)}
    hole = paths["blow-hole+1"]
    assert hole.kind == "blow-hole" and hole.measure == "area"
    assert hole.mirror == "area_blow-hole-1_m2"


def test_the_asymmetric_profile_shrinks_the_blow_hole():
    """Why asymmetric profiles exist (seed 004: the blow-hole is "the very basis for
    evolving symmetrical profile into a asymmetrical one"; Stosic et al. 2011: the
    asymmetric profile "substantially reduced the blow-hole area"): at seed 004's
    diameters the pin-cycloid's discharge-side blow-hole is a fraction of the circular
    rack's (measured 4.8 against 18.1 mm2)."""
    import dataclasses

    pin = build("pin-cycloid", 4, 6, 0.080, 0.100, 0.096)
    m = SweptMachine(dataclasses.replace(pin), Sweep("helical", LENGTH, WRAP), PPP)

    def hole(machine):
        return max(a.max() for (n, d), a in machine.opening_areas.items() if n == NAMES[False])

    assert 0.0 < hole(m) < 0.5 * hole(machine())


@pytest.mark.parametrize("profile", ["circular", "line-circle"])
def test_the_ray_tests_only_the_edges_facing_it_and_loses_none(profile, monkeypatch):
    """The ray's width per angle tests only the rotor edges turned into its polar window
    (CuspRay._facing): the same widths as testing every edge, to the last bit, on both
    cusps, along the cusp line and along a slanted plane, at scattered angles."""
    ray = CuspRay(pair(profile))
    psi = np.random.default_rng(7).uniform(-4.0, 4.0, 600)
    slant = np.array([0.6, -0.8])
    fast = [ray.width(psi, top, d) for top in (True, False) for d in (None, slant)]
    monkeypatch.setattr(CuspRay, "_facing", lambda self, r, *_: self.edges[r][:2])
    every = [ray.width(psi, top, d) for top in (True, False) for d in (None, slant)]
    for a, b in zip(fast, every, strict=True):
        assert np.array_equal(a, b)
