"""The corners of the sealed region's sweep (geometry/footprint.py) on the circular 4/6
pair, where its discharge areas erred most: along the path of contact below the line of
centres the chamber's tip is a film thinner than a micrometre between the conformal
arcs (the female tip circle in the male root circle), and it runs into the cusp line.

Independent reference: the chamber's own sections at every 0.05 deg.  Each is a real
section, so each of its vertices lies in the region the chamber sweeps; the sweep of
the section grid's samples (48 per period) must hold them up to its corners' interpolated paths.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from rotorflow.geometry import footprint as FP
from rotorflow.geometry.machine import SweptMachine
from rotorflow.workflow.case import load_case

from .conftest import CASES

DEG = math.pi / 180.0
STEP = 1.875  # deg: the section grid of 24 points per period (48 samples)


@functools.cache
def circular():
    case = load_case(CASES / "twin_screw_export.toml")
    return SweptMachine(case.pair, case.sweep(None), 24)


def _sweeper(m):
    return FP.Sweeper(FP.Surfaces(m.pair), m.pair.chamber_polygons, *FP.crop_region(m.pair))


def test_a_film_between_conformal_arcs_keeps_each_side_on_its_rotor():
    """17.8 deg after the chamber's birth its tip is a film between the arcs, under the
    classifying profiles' chord error (0.4 um) for ~0.3 mm: every piece's profile
    parameter runs one way along it, and the male piece ends at the film's tip, where
    the female piece begins.  Told by the chords alone the male side's last three
    vertices went to the female piece, which folded round the tip; the bands' corners
    then lagged the tip by 0.3 mm (a sample's vertex farther than 60 um outside the
    sweep of the test below).  Both pieces are then carried on to the section's contact
    beyond the film's tip (footprint.CONTACT_REACH), the same point for both."""
    m = circular()
    smp = _sweeper(m).sample(m.section.phi_i + 17.8125 * DEG)
    for c in smp.chains:
        steps = np.diff(c.par)
        assert np.all(steps >= 0.0) or np.all(steps <= 0.0), (c.rotor, c.par)
    ring, _ = smp.rings[0]
    box = (np.abs(ring[:, 0] - 0.0472) < 1e-3) & (np.abs(ring[:, 1] + 0.0084) < 1e-3)
    tip = ring[np.nonzero(box)[0][np.argmin(ring[box, 1])]]
    near = [c for c in smp.chains if np.min(np.linalg.norm(c.points - tip, axis=1)) < 1e-3]
    ends, contacts = {}, {}
    for c in near:
        # the ring's own vertices at the piece's ends, and the contacts beyond them
        own = [1 if c.contact_ends[0] else 0, -2 if c.contact_ends[1] else -1]
        ends[c.rotor] = min(np.linalg.norm(c.points[own] - tip, axis=1))
        contacts[c.rotor] = [tuple(c.points[k]) for k, e in ((0, 0), (-1, 1))
                             if c.contact_ends[e]]
    assert ends[0] == 0.0 and 0.0 < ends[1] < 5e-5, ends
    assert set(contacts[0]) & set(contacts[1]), contacts


def _outside(region, points):
    """Distance of each point outside ``region`` (0 inside)."""
    return np.maximum(_signed(region, points), 0.0)


def _signed(region, points):
    """Distance of each point to ``region``'s boundary, positive outside it."""
    from matplotlib.path import Path

    rings = region.to_polygons()
    inside = np.zeros(len(points), dtype=bool)
    far = np.full(len(points), np.inf)
    for r in rings:
        inside ^= Path(r).contains_points(points)
        a, ab = r, np.roll(r, -1, 0) - r
        t = np.clip(np.einsum("pek,ek->pe", points[:, None] - a, ab)
                    / np.einsum("ek,ek->e", ab, ab), 0.0, 1.0)
        far = np.minimum(far, np.linalg.norm(points[:, None] - (a + t[..., None] * ab),
                                             axis=-1).min(1))
    return np.where(inside, -far, far)


def _worst(m, lo, hi, box, every=0.05, within=None):
    """The farthest any vertex in ``box`` of the sections every ``every`` deg in [lo, hi)
    (or ``within``) lies outside the sweep of the grid's samples from lo to hi (deg
    after birth)."""
    phi = m.section.phi_i
    swept = _sweeper(m).sweep(phi + np.arange(lo, hi + 1e-9, STEP) * DEG)
    worst = 0.0
    for a in np.arange(*(within or (lo, hi)), every):
        for q in m.pair.chamber_polygons(float(phi + a * DEG)):
            q = np.asarray(q)
            q = q[np.all((q > box[0]) & (q < box[1]), axis=1)]
            if len(q):
                worst = max(worst, float(_outside(swept, q).max()))
    return worst


def test_the_sweep_holds_the_tip_where_it_reaches_the_cusp_line():
    """26 deg after the chamber's birth its tip (the film's closing, running along the
    contact path) reaches the cusp line and its corner turns up the line within one
    step: the bands' corners joined by a parabola cut off the turn, and sections in
    between lay up to 163 um outside the sweep (0.13 mm2 of it, 5e-4 of the largest
    discharge area).  Samples homed in on the turn (footprint_events.Events._home)
    leave 30 um (measured), about the film's own tip path's (the next test)."""
    m = circular()
    box = (np.array([0.039, -0.013]), np.array([0.044, -0.011]))
    assert _worst(m, 22.5, 30.0, box) < 45e-6


def test_the_sweep_holds_a_films_tip_along_the_contact_path():
    """15 to 22.5 deg after the chamber's birth its tip runs 1.3 mm per step along the
    contact path; the vertices of the sections in between lie within 25 um of the
    sweep (measured; the tip's path jitters by microns as the grown polygons' vertices
    pass each other).  With the film's male side taken for the female rotor (the
    chords' classification), 61 um, and 110 um with the turns' samples."""
    m = circular()
    box = (np.array([0.0455, -0.010]), np.array([0.0485, -0.007]))
    assert _worst(m, 15.0, 22.5, box) < 40e-6


def test_a_slivers_end_on_the_cusp_line_is_not_carried_to_its_contact():
    """A sliver born 116 deg after the chamber's birth, below the line of centres, runs
    from its contact to the cusp line, where its male and female pieces meet across a
    few microns of the line.  For its first 0.006 rad the contact lies within
    CONTACT_REACH of the cusp-line ends too: each piece's end there was carried back
    to it, and each piece closed on itself (contact, cusp end, ..., contact); the
    bands of such pieces left 0.05 mm2 of the sliver's sweep out at 3072 samples per
    period.  Each contact is one end's: the nearer."""
    m = circular()
    smp = _sweeper(m).sample(-1.3391606)  # rad: 0.0056 after the sliver is first held
    xc = m.pair.cusp[0]
    near = [c for c in smp.chains if np.any(np.abs(c.points[:, 0] - xc) < 1e-9)
            and -0.0125 < c.points[:, 1].min() and c.points[:, 1].max() < -0.0115]
    assert sorted(c.rotor for c in near) == [0, 1]
    for c in near:
        assert np.linalg.norm(c.points[0] - c.points[-1]) > 5e-4
        cusp = 0 if abs(c.points[0, 0] - xc) < 1e-9 else 1
        assert not c.contact_ends[cusp] and c.contact_ends[1 - cusp], c.contact_ends


def test_a_sliver_by_the_cusp_line_is_swept_from_where_it_touched_the_male():
    """The sliver born 116 deg after the chamber's birth runs from its contact to the
    cusp line, where the ring is cut: the female piece's vertices next to the line
    never see their gap to the ring close (the male beyond the line is another ring's),
    and were swept as far as their neighbours, too short: the vertices of the sections
    every 0.01 deg from 114 to 117 deg lay up to 127 um outside the sweep at 24 points
    per period (0.076 mm2 of their union every 1e-5 rad).  Swept from where each
    touched the male's true surface (footprint_gaps.Gaps._mate_touching), none lies
    outside it (measured 2026-11-30)."""
    m = circular()
    box = (np.array([0.0393, -0.0126]), np.array([0.04025, -0.0116]))
    assert _worst(m, 112.5, 120.0, box, 0.01, (114.0, 117.0)) < 10e-6


def test_the_contact_path_between_samples_is_followed_to_a_micron():
    """From 120 to 142.5 deg after the chamber's birth its contact runs 1 mm a step up
    the contact path, which bends 3 to 25 um off each step's chord and bounds the
    region the chamber sweeps.  The bands' corners follow the mean of the parabolas
    through the step's two samples and the one either side, at five points a step: the
    contacts of the real sections a quarter, a half and three quarters of a step on lie
    within 0.7 um of the sweep's boundary, outside or inside it (measured; 1.5 allows
    the five-point chords' sag, ~0.4).  Joined by the midpoint of one parabola they lay
    up to 4.0 um outside it, and the circular's discharge area erred by 2.0e-4 of its
    largest at 24 points per period (5.2e-5 now); joined by one parabola at five
    points, up to 3.0 um inside it (the discharge area -1.2e-4)."""
    m = circular()
    sweeper = _sweeper(m)
    lo, hi = 120.0, 142.5
    phi = m.section.phi_i
    swept = sweeper.sweep(phi + np.arange(lo - STEP, hi + STEP + 1e-9, STEP) * DEG)
    box = (np.array([0.0315, -0.0118]), np.array([0.0385, -0.0010]))
    contacts = []
    steps = np.arange(round((hi - lo) / STEP))[:, None] + [0.25, 0.5, 0.75]
    for a in (lo + STEP * steps).ravel():
        for c in sweeper.sample(float(phi + a * DEG)).chains:
            contacts += [c.points[k] for k, e in ((0, 0), (-1, 1)) if c.contact_ends[e]
                         and np.all((c.points[k] > box[0]) & (c.points[k] < box[1]))]
    assert len(contacts) >= 30
    assert np.abs(_signed(swept, np.array(contacts))).max() < 1.5e-6
