"""Sealing lines of the twin-screw chamber table: exact ends, a measured order.

A track's line is its section point swept along the rotors over the angles where it
seals (geometry/lines.py), between ends the family finds exactly (twin_screw/
track_ends.py): a tip's cusp crossing in closed form, a contact's crossing of the cusp
line by a root, and the joints and bands of the profile's arcs.  Looked up at the
nearest table node instead, a line's ends were known to half a step, and the tip lines
of seed 004's 4/6 pair stayed 1e-3 off at any resolution (bench/results/twin_screw.csv
before issue 13).
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.sweep import Sweep
from rotorflow.geometry.twin_screw.family import examples

#: Seed 004's 4/6 machine: rotor length and male wrap.
SWEEP = Sweep("helical", 0.13, math.radians(325.0))


@functools.cache
def machine(profile: str, ppp: int) -> SweptMachine:
    return SweptMachine(examples()[f"{profile}-4-6"], SWEEP, ppp)


def _total(lines: dict, kind: str):
    """A chamber's lines of one kind, each counted once (from the younger side)."""
    return sum(v for (name, d), v in lines.items() if name.startswith(kind) and d > 0)


def test_tip_lines_are_their_closed_form():
    """A tip runs on its bore at radius R, turning at w per male radian (1 male, N1/N2
    female), from the cusp where it leaves the other bore to the one where it enters
    it: 2 pi - 2 alpha of its own turn (alpha the cusp's angle from the line of centres
    seen from its axis).  On a helical rotor its line is the part of that span within
    the wrap, times sqrt(1 / twist'^2 + (w R)^2), exactly (its rate is w R, constant)."""
    m = machine("circular", 24)
    pair = m.pair
    g = pair.gearing
    xc, yc = pair.cusp
    twist_rate = SWEEP.wrap / SWEEP.length
    for rotor, radius, axis, w in (("male", pair.male_radius, 0.0, 1.0),
                                   ("female", pair.female_radius, g.centre_distance,
                                    g.lobes_male / g.lobes_female)):
        span = (2.0 * math.pi - 2.0 * math.atan2(yc, abs(xc - axis))) / w
        exact = min(span, SWEEP.wrap) * math.hypot(1.0 / twist_rate, w * radius)
        for side, d in (("lead", 1), ("trail", -1)):
            # The rate's direction is interpolated by cubics between nodes 3.75 deg
            # apart: 1e-9 (its h^4 error), not rounding.
            assert m.track_lines[(f"tip-{rotor}-{side}", d)].max() == \
                pytest.approx(exact, rel=1e-8), (rotor, side)


def test_interlobe_lines_converge_at_fourth_order():
    """The contact and its rate are known at the nodes and the line between them is
    the cubic Hermite interpolant's: its derivative errs by O(h^3), but over a whole
    cell that error integrates to the points' own, zero at both ends, so the line errs
    by O(h^4).  Measured on the line-circle pair (a joint between arcs and a band each
    period): 9.6e-4, 3.0e-5 at 24, 48 points per period against 96, order 5.0.
    """
    ref = machine("line-circle", 96)
    errors = []
    for ppp in (24, 48):
        m = machine("line-circle", ppp)
        here = _total(m.track_lines, "interlobe")
        there = _total(ref.track_lines_at(m.curves.phi), "interlobe")
        errors.append(np.abs(here - there).max() / there.max())
    order = math.log2(errors[0] / errors[1])
    assert order > 3.5, errors
    assert errors[1] < 1e-4, errors


@pytest.mark.parametrize("ppp", [24, 48, 96])
def test_an_interlobe_contact_parts_two_lives_of_one_groove(ppp):
    """Both sides of an interlobe contact are one groove, newborn and dying: N1 lobe
    periods apart on the male side of the cusp line, N2 on the female side, never
    anything else (the section's polygons once booked a contact within a lens of the
    cusp line to a male part on one side and a female part on the other: offset 5)."""
    sec = machine("line-circle", ppp).section
    for track in sec.tracks:
        if track.kind == "interlobe":
            assert set(np.abs(track.offset[track.present])) <= {4, 6}, track.name


@pytest.mark.parametrize("sweep", [SWEEP, Sweep("conical", 0.13, math.radians(325.0), 0.7, 0.5)],
                         ids=["helical", "conical"])
def test_lines_are_the_integral_of_their_stretches(sweep):
    """However the line is summed (one cumulative integral on a helical rotor, each
    stretch at each angle on a conical one), it is the length of the curve the
    stretches' point traces along z: here by adaptive quadrature in z over each
    stretch's heights (scipy quad, 1e-12)."""
    from scipy.integrate import quad

    from rotorflow.geometry.lines import line_lengths, stretches

    sec = examples()["line-circle-4-6"].section(48)
    track = next(t for t in sec.tracks if t.name == "interlobe-lead")
    st = stretches(sec.psi, track.points, track.rates, track.present, track.offset,
                   track.ids, track.cuts, start=track.start)
    phi = sec.psi[0] + np.array([0.7, 4.1, 8.2])
    lines = line_lengths(st, sweep, phi)

    def elem(z, p, m):
        c, dc = st.at(m, p - sweep.twist(z))
        tang = sweep.dscale(z) * c - sweep.scale(z) * sweep.dtwist(z) * dc
        return math.sqrt(1.0 + float(tang @ tang))

    for j, p in enumerate(phi):
        brute = {}
        lo, hi = np.maximum(st.a, p - sweep.wrap), np.minimum(st.b, p)
        for m in np.nonzero(hi > lo)[0]:
            z0, z1 = sweep.z_of_twist(p - hi[m]), sweep.z_of_twist(p - lo[m])
            d = int(st.offset[m])
            brute[d] = brute.get(d, 0.0) + quad(elem, z0, z1, args=(p, m), epsabs=1e-13)[0]
        for d, v in brute.items():
            # Gauss with 4 nodes per stretch against adaptive quadrature: 5e-10 measured.
            assert lines[d][j] == pytest.approx(v, rel=1e-9, abs=1e-12), (j, d)
