"""The interlobe contact line (seed 004 Fig. 2) from the rack, against the sections.

Two constructions that share nothing but the profile: the rack's path of contact with
its meshing angle (contact_line.py) and the Clipper-cut sections' contacts, each
snapped where the law of gearing holds (regions.py, boundaries.py).
"""

import math

import numpy as np
import pytest

from rotorflow.geometry.machine import SweptMachine
from rotorflow.geometry.sweep import Sweep
from rotorflow.geometry.twin_screw.contact_line import contact_line_length
from rotorflow.geometry.twin_screw.family import build

L = 0.13


@pytest.fixture(scope="module")
def pair():
    return build("circular", 4, 6, 0.078, 0.100, 0.096)


def _section_contacts(pair, theta):
    found = []
    for part in pair.cutter.cut(theta):
        for c in part.contacts:
            if not any(np.linalg.norm(c - d) < 1e-7 for d in found):
                found.append(c)
    return found


def test_straight_rotors_touch_along_lines_through_the_section_contacts(pair):
    for theta in np.radians([5.0, 20.0, 40.0, 60.0, 80.0]):
        n = len(_section_contacts(pair, theta))
        # Straight rotors: every section contact is a line along the whole rotor.
        assert contact_line_length(pair, pair.rack, Sweep("straight", L), theta) == \
            pytest.approx(n * L, rel=1e-12)


def test_helical_line_tends_to_the_straight_one(pair):
    straight = contact_line_length(pair, pair.rack, Sweep("straight", L), 0.3)
    errors = [abs(contact_line_length(pair, pair.rack, Sweep("helical", L, w), 0.3)
                  / straight - 1) for w in (0.05, 0.025)]
    # Each branch runs the whole length, tilted by the twist: its length grows like
    # sqrt(1 + (r twist')^2), second order in the wrap (half the wrap, a quarter).
    assert 3.5 < errors[0] / errors[1] < 4.5, errors


def _fold(m, ppp, lines):
    """Interlobe lines of every chamber present at each rotation: one chamber's lines
    at ages one period apart."""
    n = len(m.curves.phi)
    total = np.zeros(-(-n // ppp) * ppp)
    for (name, d), x in lines.items():
        if name.startswith("interlobe") and d > 0:
            total[:n] += x
    return total.reshape(-1, ppp).sum(0)


@pytest.mark.parametrize("profile", ["circular", "line-circle"])
def test_chamber_lines_add_up_to_the_contact_line(profile):
    """The chamber table's interlobe lines, summed over the chambers present, are the
    whole contact line: every contact parts two chambers.  Measured at 48 points per
    period: 2e-7 (circular rack), 3e-5 (line-circle rack, whose joint between arcs
    the cubics between nodes take at O(h^4)); at 24, 5e-5 and 1e-3.

    Without the bridges (the arcs along which the rotors touch all at once, 3.3 mm each
    on the circular pair, three or four along the rotor) the sum falls 5 % short: the
    5 % that the swept section points lacked before issue 13.
    """
    from rotorflow.geometry.lines import line_lengths, stretches

    pair = build(profile, 4, 6, 0.078, 0.100, 0.096)
    sweep = Sweep("helical", L, math.radians(325.0))
    ppp = 48
    m = SweptMachine(pair, sweep, ppp)
    sec = m.section
    bare = {}
    for t in sec.tracks:
        st = stretches(sec.psi, t.points, t.rates, t.present, t.offset, t.ids, t.cuts,
                       start=t.start)
        for d, v in line_lengths(st, sweep, m.curves.phi).items():
            bare[(t.name, d)] = bare.get((t.name, d), 0.0) + v
    fold, fold_bare = _fold(m, ppp, m.track_lines), _fold(m, ppp, bare)
    for j in range(0, ppp, 6):
        whole = contact_line_length(pair, pair.rack, sweep, float(m.curves.phi[j]))
        assert fold[j] == pytest.approx(whole, rel=1e-4), j
        if profile == "circular":
            assert fold_bare[j] < 0.97 * whole, j
