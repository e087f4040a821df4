"""The twin-screw pair meshes at every height of a variable-lead sweep (issue 13).

Built without the generator's contact search: the two profiles as fine polygons, each
turned about its own axis by the twist the sweep law gives at z (written here: the male
at phi - tau(z), the female the other way at the lobe ratio times that), then the
smallest signed distance between the polygons (point-to-segment, even-odd inside test:
:func:`..polygons.polygon_gap`).  The sections the solids are swept from
(:class:`..export.surface.SweptSurface`, placed as the assembly places them) must be
these very polygons.  A female twisted by tau(z) itself (not by the ratio times it)
must fail the same measure at the heights where the two laws part.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from rotorflow.geometry.curves import sample
from rotorflow.geometry.export.surface import SweptSurface
from rotorflow.geometry.polygons import polygon_gap
from rotorflow.geometry.sweep import Sweep
from rotorflow.geometry.twin_screw.family import build

#: Seed 004's 4/6 machine (C assumed 78 mm elsewhere; the pin-cycloid at 80 mm).
PAIRS = {"circular": ("circular", 4, 6, 0.078, 0.100, 0.096),
         "pin-cycloid": ("pin-cycloid", 4, 6, 0.080, 0.100, 0.096)}
LENGTH, WRAP = 0.13, math.radians(300.0)
#: Chordal tolerance of the polygons: 0.05 um, 20x below the 1 um contact tolerance;
#: edges no longer than MAX_EDGE so that the closest segment of a point near the other
#: polygon has a vertex among NEAREST nearest vertices (as tests/test_twin_screw_profiles).
POLY_TOL, MAX_EDGE, NEAREST = 5e-8, 2e-4, 16
#: Issue 13: touch (smallest distance below 1 um) and no interference (overlap below
#: 1 um).  The polygons lie within POLY_TOL of their curves, so a gap or overlap the
#: curves do not have shows up as at most ~2 POLY_TOL = 0.1 um here.
TOUCH_TOL = 1e-6
HEIGHTS = np.linspace(0.0, LENGTH, 6)
ANGLES = (0.0, 0.31, 1.07)


def tau(z, lead_ratio):
    """The male's twist at z: lead linear along z from lead_0 at z = 0 to lead_ratio
    lead_0 at z = L, tau(L) = WRAP; tau' = 2 pi / lead integrated by hand."""
    zeta = np.asarray(z, dtype=float) / LENGTH
    if lead_ratio == 1.0:
        return WRAP * zeta
    return WRAP * np.log(1.0 + (lead_ratio - 1.0) * zeta) / math.log(lead_ratio)


@functools.cache
def pair(name):
    return build(*PAIRS[name])


@functools.cache
def polygons(name):
    """(u, points) of the male and the female profile in their own frames."""
    out = []
    for profile in (pair(name).male, pair(name).female):
        u = sample(profile, POLY_TOL, max_step=MAX_EDGE)
        out.append((u, profile.point(u)))
    return tuple(out)


def rot(points, angle):
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]])


def placed(name, phi, z, lead_ratio, female_factor=None):
    """Both sections at height z, machine angle phi: the male turned counter-clockwise by
    phi - tau(z) about the origin, the female clockwise by female_factor (default the
    lobe ratio N1/N2) times that about (C, 0).  A wrong female_factor turns the female
    by -ratio phi + female_factor tau(z) instead."""
    p = pair(name)
    ratio = p.gearing.lobes_male / p.gearing.lobes_female
    t = float(tau(z, lead_ratio))
    (_, male), (_, female) = polygons(name)
    female_twist = ratio * t if female_factor is None else female_factor * t
    return (rot(male, phi - t),
            rot(female, -ratio * phi + female_twist) + [p.gearing.centre_distance, 0.0])


def smallest_gap(male, female, reach):
    """Smallest signed distance between the two placed polygons (negative: overlap),
    each polygon's points near the other measured against it."""
    c = female.mean(axis=0)
    near_f = np.linalg.norm(male - c, axis=1) < reach[1]
    near_m = np.linalg.norm(female, axis=1) < reach[0]
    return min(polygon_gap(male[near_f], female, NEAREST).min(),
               polygon_gap(female[near_m], male, NEAREST).min())


def reaches(name):
    (_, m), (_, f) = polygons(name)
    return (np.linalg.norm(m, axis=1).max() + 1e-4, np.linalg.norm(f, axis=1).max() + 1e-4)


@pytest.mark.parametrize("name", sorted(PAIRS))
@pytest.mark.parametrize("lead_ratio", [1.0, 2.0, 0.5])
def test_sections_touch_and_never_overlap_at_every_height(name, lead_ratio):
    """At six heights and three machine angles the sections touch within TOUCH_TOL and
    overlap by less than it; the solids' own swept flanks at z are these polygons."""
    p = pair(name)
    sweep = Sweep("helical", LENGTH, WRAP, 1.0, lead_ratio)
    male_rotor, female_rotor = p.rotors
    (um, _), (uf, _) = polygons(name)
    gaps = []
    for phi in ANGLES:
        # the assembly's placement (export/assembly.py): theta0 = speed ratio phi
        surfaces = [SweptSurface(r.profile, sweep, r.speed_ratio * phi, r.speed_ratio, r.axis)
                    for r in (male_rotor, female_rotor)]
        for z in HEIGHTS:
            m, f = placed(name, phi, z, lead_ratio)
            for surf, u, mine in zip(surfaces, (um, uf), (m, f), strict=True):
                theirs = surf.point(u, np.full_like(u, z))
                assert np.allclose(theirs[:, 2], z)
                assert np.abs(theirs[:, :2] - mine).max() < 1e-12
            gaps.append(smallest_gap(m, f, reaches(name)))
    gaps = np.array(gaps)
    assert gaps.min() > -TOUCH_TOL, f"overlap {-gaps.min() * 1e6:.3f} um"
    assert gaps.max() < TOUCH_TOL, f"no contact: gap {gaps.max() * 1e6:.3f} um"


@pytest.mark.parametrize("name", sorted(PAIRS))
@pytest.mark.parametrize("error", [None, 1e-4], ids=["ratio forgotten", "ratio 1e-4 off"])
def test_a_female_twisted_by_another_law_interferes(name, error):
    """Negative controls: the female turned by tau(z) itself (the lobe ratio forgotten:
    millimetres of overlap) or by (1 + 1e-4) ratio tau(z) (at z = L 3.5e-4 rad off,
    ~10 um at the female's flanks) agrees with the right law at z = 0 only; at the top
    the measure sees the overlap."""
    ratio = pair(name).gearing.lobes_male / pair(name).gearing.lobes_female
    factor = 1.0 if error is None else ratio * (1.0 + error)
    gaps = np.array([[smallest_gap(*placed(name, phi, z, 2.0, female_factor=factor),
                                   reaches(name)) for phi in ANGLES] for z in HEIGHTS])
    assert np.abs(gaps[0]).max() < TOUCH_TOL  # z = 0: no twist yet, the laws agree
    assert gaps[-1].min() < -3 * TOUCH_TOL
    if error is None:
        assert (gaps[1:].min(axis=1) < -100 * TOUCH_TOL).all()
